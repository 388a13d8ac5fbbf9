"""contactqp.runs: what the check keeps per held set, and the running sum as its steps.

Every expected value is the same computation made without the kept sets (the cache bypassed)
or the running sum made by numpy over the whole chain; both must agree bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest

import contactqp
from contactqp import bounds, runs
from contactqp.builders import flat_patch
from contactqp.model import segment_reduce
from contactqp.random_scenes import random_scene

RESULT_ARRAYS = ("u", "contact_force", "reactions", "penetration", "element_force", "stress")


def _same(a: contactqp.Result, b: contactqp.Result, note: str) -> None:
    for name in RESULT_ARRAYS:
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), (name, note)
    assert a.residuals == b.residuals, note
    assert (a.verified, a.physical, a.force_error_bound, a.displacement_error_bound) == (
        b.verified, b.physical, b.force_error_bound, b.displacement_error_bound), note


def _uncached(monkeypatch: pytest.MonkeyPatch) -> None:
    def made(layout, kind, held, make):
        return make()

    monkeypatch.setattr(runs, "kept", made)
    monkeypatch.setattr(bounds, "kept", made)


@pytest.mark.parametrize("method", ["lagrange", "penalty", "lemke"])
def test_kept_sets_change_no_bit_of_a_result_on_random_scenes(method, monkeypatch):
    # the kept runs and stiffnesses are what the check would make again: a scene solved with
    # them kept (its second solve, and prepared solves with new values) and without any
    # must give the same Result; scenes of up to 300 elements a bar reach the running sum's
    # steps, several bars and bar contacts the stiffness keyed by the pushing rows too
    rng = np.random.default_rng()  # fresh scenes each run; the seed is in the message
    seed = int(rng.integers(2**32))
    rng = np.random.default_rng(seed)
    scenes = [random_scene(rng, max_elements=300 if i % 2 else 8, contacts=i % 3 != 0,
                           floating=0.5 if i % 4 == 0 else 0.0) for i in range(16)]
    kept_results = []
    for scene in scenes:
        try:
            first = contactqp.solve(scene, method)
        except contactqp.SolverError:
            kept_results.append(None)
            continue
        again = contactqp.solve(scene, method)  # its held sets kept from the first
        _same(first, again, f"seed {seed}")
        kept_results.append(again)
    with monkeypatch.context() as patched:
        _uncached(patched)
        for scene, kept in zip(scenes, kept_results):
            if kept is not None:
                fresh = contactqp.solve(contactqp.Scene(
                    scene.bars, scene.supports, scene.loads, scene.walls,
                    contacts=scene.contacts, distributed=scene.distributed), method)
                _same(kept, fresh, f"seed {seed}")


def test_a_prepared_scene_shares_its_kept_sets_and_they_stay_read_only():
    scene = contactqp.default_scene()
    prepared = contactqp.prepare(scene)
    prepared.solve([1.2 * scene.loads[0].force])
    cache = prepared.scene.layout.held_cache
    assert cache, "the check kept nothing"
    again = prepared.scene.with_values(loads=[0.8 * scene.loads[0].force])
    assert again.layout.held_cache is cache  # one topology, one set of kept runs
    for held, value, _ in cache.values():
        arrays = value.__dict__.values() if hasattr(value, "__dict__") else value
        for array in arrays:
            if isinstance(array, np.ndarray):
                assert not array.flags.writeable


def test_what_is_kept_stays_within_its_budget(monkeypatch):
    monkeypatch.setattr(runs, "KEPT_BYTES", 4096)
    scene = flat_patch(2000)
    contactqp.solve(scene)
    cache = scene.layout.held_cache
    assert sum(entry[2] for entry in cache.values()) <= 4096


@pytest.mark.parametrize("loaded", [1, 3, 40])
def test_the_running_sum_as_steps_is_the_running_sum(loaded):
    rng = np.random.default_rng(loaded)
    n = 1000
    nodes = rng.integers(0, n, loaded)
    nodes[0] = nodes[-1]  # a node loaded twice
    forces = rng.normal(0.0, 1e6, loaded)
    dense = np.cumsum(np.bincount(nodes, forces, minlength=n))
    steps = runs.Running.of(n, nodes, forces)
    assert steps.steps is not None
    links = rng.normal(0.0, 1e6, n - 1)
    assert np.array_equal(steps.plus(links), links + dense[:-1])
    probe = rng.integers(0, n, 50)
    assert np.array_equal(steps.at(probe), dense[probe])
    many = runs.Running.of(n, rng.integers(0, n, n), rng.normal(size=n))
    assert many.steps is None  # loads on most nodes: the running sum itself


@pytest.mark.parametrize("ufunc", [np.add, np.maximum, np.minimum])
def test_runs_of_mostly_one_element_reduce_as_reduceat_does(ufunc):
    # a pressed patch: every node held but a stretch at the free end, so all runs but one
    # are one element; the long run's reduction must be reduceat's, bit for bit
    layout = flat_patch(3000).layout
    n = layout.n_nodes
    held = np.concatenate((np.arange(0, n - 400), np.arange(n - 200, n - 150)))
    found = runs.runs(layout, held)
    assert 0 < found.long.size and found.long.size * runs.LONG_RUNS <= found.starts.size
    values = np.random.default_rng(5).normal(0.0, 1e3, layout.elements[0].size)
    assert np.array_equal(found.reduce(ufunc, values), ufunc.reduceat(values, found.starts))


@pytest.mark.parametrize("ufunc", [np.add, np.maximum, np.minimum])
def test_runs_of_one_short_length_reduce_as_reduceat_does(ufunc):
    # a batch of cases: the default scene side by side, each case's bar held at its support
    # and at its wall, so that every run is the same four elements; signed zeros and NaN
    # among the values, where the order of a maximum decides which comes out
    prepared = contactqp.prepare(contactqp.default_scene())
    layout = prepared.tiled(300).scene.layout
    held = np.sort(np.concatenate((layout.node_offsets[:-1], layout.node_offsets[1:] - 1)))
    found = runs.runs(layout, held)
    assert found.length == 4 and found.starts.size == 300
    values = -np.abs(np.random.default_rng(6).normal(0.0, 1e3, layout.elements[0].size))
    values[1::8], values[2::8], values[6::12] = 0.0, -0.0, np.nan  # ties at 0: the order
    assert np.array_equal(found.reduce(ufunc, values), ufunc.reduceat(values, found.starts),
                          equal_nan=True)
    mixed = runs.runs(layout, np.sort(np.append(held, layout.node_offsets[5] + 2)))
    assert mixed.length == 0  # one case held in the middle too: the runs differ


@pytest.mark.parametrize("ufunc", [np.add, np.maximum, np.minimum])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_segments_of_mostly_one_element_reduce_as_reduceat_does(ufunc, seed):
    # the held nodes of a pressed patch: nearly every segment one element, a few long ones,
    # some empty (two starts at one place), the last to the end
    rng = np.random.default_rng(seed)
    values = rng.normal(0.0, 1e3, 5000)
    values[rng.integers(0, values.size, 50)] = np.nan
    ones = np.delete(np.arange(0, 4000), rng.choice(np.arange(1, 4000), 30, replace=False))
    starts = np.sort(np.concatenate((ones, rng.integers(0, 4000, 20))))  # 2- and 3-element too
    found = segment_reduce(ufunc, values, starts)
    assert np.array_equal(found, ufunc.reduceat(values, starts), equal_nan=True)
    few = starts[::100]  # long segments on average: reduceat itself
    assert np.array_equal(segment_reduce(ufunc, values, few), ufunc.reduceat(values, few),
                          equal_nan=True)
