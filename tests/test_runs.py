"""contactqp.check.chain.spans: what the check keeps per held set, the running sum as its steps, and the
runs taken one by one.

Every expected value is the same computation made without the kept sets (the cache bypassed)
or the running sum made by numpy over the whole chain, and both must agree bit for bit; for
the runs one by one, the whole chain at once, to round-off; for long runs, an exact answer.
"""

from __future__ import annotations

import numpy as np
import pytest

import contactqp
from contactqp.builders import flat_patch
from contactqp.check.chain import certificate as bounds
from contactqp.check.chain import spans as runs
from contactqp.model import segment_reduce
from contactqp.model.chain import layout_of
from contactqp.random_scenes import random_scene
from contactqp.reference import reference

ROUND_OFF = 1e-11  # of F and U: where two orders of the same sums may differ (see below)
EPS = float(np.finfo(float).eps)
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
    cache = layout_of(prepared.scene).held_cache
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
    cache = layout_of(scene).held_cache
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
    layout = layout_of(prepared.tiled(300).scene)
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


@pytest.mark.parametrize("elements", [10**5, 2 * 10**5])
def test_a_long_run_bounds_the_hulls_own_round_off(elements):
    # a uniform bar loaded at its tip, its wall open: the exact answer is u_j = P·j/k, and
    # the hull's u, built from the running sum φ of the compliances, is off from it by φ's
    # round-off (9e-13 U at 10⁵ elements), which the check's bound must cover (a run read
    # through the same φ, tried this round, bounded it by 9e-16 U)
    bar = contactqp.Bar.uniform(1e-4, 2e11, length=1.0, elements=elements)
    load = 1e4
    scene = contactqp.Scene(bar, (contactqp.Support(0),), (contactqp.Load(elements, load),),
                            (contactqp.Wall(elements // 2, 1.0),))
    result = contactqp.solve(scene)
    assert not result.contact_force.any() and result.verified
    exact = load * np.arange(elements + 1, dtype=np.longdouble) / np.longdouble(
        bar.element_stiffness[0])
    error = float(np.max(np.abs(result.u.astype(np.longdouble) - exact)))
    assert error > 100 * EPS * result.displacement_scale  # the round-off to be bounded
    assert error <= result.displacement_error_bound


def test_a_press_fit_beside_a_long_run_is_verified_exact():
    # a wall pressed 1 mm into the tip of a bar of 10⁵ elements, two elements from a wall
    # that holds: the run between them carries 5·10⁴ times the load, and its mean force is
    # the mean of its cut residuals, not read from φ, whose round-off times that force made
    # the bound of the exact answer 5.7e-8 F here and flagged it at 10⁶ elements (1.4e-5 F)
    # in a version tried this round; the bound must stay at round-off
    n = 10**5
    bar = contactqp.Bar.uniform(1e-4, 2e11, length=1.0, elements=n)
    scene = contactqp.Scene(bar, (contactqp.Support(0),), (contactqp.Load(n // 2, 1e3),),
                            (contactqp.Wall(n - 2, 0.0, "+"), contactqp.Wall(n, -1e-3, "-")))
    result = contactqp.solve(scene)
    exact = reference(scene)
    assert result.verified, result.message
    assert np.max(np.abs(result.contact_force - exact.contact_force)) <= (
        result.force_error_bound) <= 1e-9 * result.force_scale


def _few_walls(scene: contactqp.Scene, rng: np.random.Generator) -> contactqp.Scene | None:
    """``scene`` with one or two of its walls, or None where that leaves a bar unheld."""
    keep = rng.permutation(len(scene.walls))[:int(rng.integers(1, 3))]
    try:
        return scene.with_walls(tuple(scene.walls[j] for j in keep))
    except contactqp.SceneError:
        return None


@pytest.mark.parametrize("method", ["lagrange", "penalty", "lemke"])
def test_runs_taken_one_by_one_bound_as_the_whole_chain_does(method, monkeypatch):
    # the check goes run by run where few runs sway; the same scenes checked over the whole
    # chain (every run reduced at once) must give the same bounds up to round-off, and the
    # runs one by one must have been taken
    rng = np.random.default_rng()  # fresh scenes each run; the seed is in the message
    seed = int(rng.integers(2**32))
    rng = np.random.default_rng(seed)
    taken = []
    real = runs._few_swaying
    monkeypatch.setattr(runs, "_few_swaying", lambda *a: taken.append(1) or real(*a))
    scenes = [random_scene(rng, max_elements=400 if i % 2 else 8, contacts=i % 3 != 0,
                           floating=0.5 if i % 4 == 0 else 0.0) for i in range(16)]
    # ... and each with at most two of its walls: few loads on the runs
    scenes += [thin for scene in scenes if (thin := _few_walls(scene, rng)) is not None]
    answers = []
    for scene in scenes:
        try:
            answers.append(contactqp.solve(scene, method))
        except (contactqp.SolverError, contactqp.SceneError):  # a free bar left unheld
            answers.append(None)
    assert taken, f"seed {seed}: no runs taken one by one"
    with monkeypatch.context() as patched:
        patched.setattr(runs, "FEW_SWAYING", -1)
        patched.setattr(runs, "LONG_RUNS", 2**62)
        for scene, one_by_one in zip(scenes, answers):
            if one_by_one is None:
                continue
            whole = contactqp.solve(contactqp.Scene(
                scene.bars, scene.supports, scene.loads, scene.walls,
                contacts=scene.contacts, distributed=scene.distributed), method)
            assert np.array_equal(whole.u, one_by_one.u), f"seed {seed}"
            # the two sum the same terms in other orders (a run's weighted mean by np.dot, its
            # running sum from its own start): measured over 75 seeds up to 5e-14 F and 1e-13
            # U apart (4e-13 U once), 10⁸ times below the check's tolerances (1e-5)
            F, U = whole.force_scale, whole.displacement_scale
            assert one_by_one.force_error_bound == pytest.approx(
                whole.force_error_bound, rel=1e-9, abs=ROUND_OFF * F), f"seed {seed}"
            if whole.displacement_error_bound == np.inf:  # a bar the answer leaves free
                assert one_by_one.displacement_error_bound == np.inf, f"seed {seed}"
                continue
            assert one_by_one.displacement_error_bound == pytest.approx(
                whole.displacement_error_bound, rel=1e-9, abs=ROUND_OFF * U), f"seed {seed}"
