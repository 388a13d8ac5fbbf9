"""A batch's values without a Python object per case: the tiled scene's walls as one
:class:`contactqp.Walls` (:meth:`Walls.tiled`), its loads' forces kept as an array
(:meth:`Scene.with_values` with ``load_objects=False``, :class:`ValuedLoads`), and the
walls-only no-conflict test from pairs of opposed walls kept once per placement.

Every expected value comes from the per-object path: the scene tiled with one Wall object per
wall (built here, as the batch built it before), and its values set by Load objects; these
paths must agree bit for bit, since they compute the same numbers in the same order.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import contactqp
from closed_forms import values
from contactqp.many.batch import tiled_scene
from contactqp.methods.load_cases import FEW_COLUMNS, row_reduce
from contactqp.model import build_model
from contactqp.random_scenes import random_scene
from contactqp.scene.scene import Scene, ValuedLoads

SEEDS = range(24)
CASES = 5
BATCH_ARRAYS = ("u", "contact_force", "reactions", "penetration", "verified", "physical",
                "force_error_bound", "displacement_error_bound", "force_scale",
                "displacement_scale", "iterations")


def object_tiled(scene: contactqp.Scene, cases: int) -> contactqp.Scene:
    """``scene`` repeated ``cases`` times with a Wall object per wall of every copy."""
    n = len(scene.bars)

    def moved(items: tuple, *names: str) -> tuple:
        return tuple(replace(item, **{name: getattr(item, name) + case * n for name in names})
                     for case in range(cases) for item in items)

    return contactqp.Scene(scene.bars * cases, moved(scene.supports, "bar"),
                           moved(scene.loads, "bar"), moved(tuple(scene.walls), "bar"),
                           name=f"{scene.name} x {cases} cases",
                           distributed=moved(scene.distributed, "bar"),
                           contacts=moved(scene.contacts, "bar_a", "bar_b"), units=scene.units)


def random_cases(seed: int) -> tuple[contactqp.Scene, np.ndarray, np.ndarray]:
    """A random scene (walls on either side, bar contacts) and cases of its values: loads
    scaled by −1.5..2, gaps by 0..2, one case in four at zero gap."""
    rng = np.random.default_rng(seed)
    scene = random_scene(rng, max_bars=3, max_elements=6)
    loads, gaps = values(scene)
    load_cases = loads * rng.uniform(-1.5, 2.0, (CASES, 1))
    gap_cases = gaps * rng.uniform(0.0, 2.0, (CASES, 1))
    gap_cases[rng.random(CASES) < 0.25] = 0.0
    return scene, load_cases, gap_cases


def batch_or_error(prepared, loads, gaps):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            return prepared.solve_many(loads, gaps)
        except contactqp.ContactqpError as error:
            return f"{type(error).__name__}: {error}"


def object_batch(scene, method, loads, gaps, monkeypatch):
    """The batch by the per-object path: the tiled model made from Wall objects, and every
    value set by making objects (Load, Wall) as :meth:`Scene.with_values` does by default."""
    prepared = contactqp.prepare(scene, method)
    tiled = build_model(object_tiled(scene, CASES))
    prepared._kept.update(cases=CASES, tiled=tiled)
    with_values = Scene.with_values
    with monkeypatch.context() as patch:
        patch.setattr(Scene, "with_values", lambda self, loads=None, gaps=None, **_:
                      with_values(self, loads, gaps))
        return batch_or_error(prepared, loads, gaps)


@pytest.mark.parametrize("method", ["lagrange", "penalty"])
def test_a_batch_by_arrays_is_the_batch_by_objects_bit_for_bit(method, monkeypatch):
    compared = 0
    for seed in SEEDS:
        scene, loads, gaps = random_cases(seed)
        if not contactqp.prepare(scene, method).together:
            continue
        arrays = batch_or_error(contactqp.prepare(scene, method), loads, gaps)
        objects = object_batch(scene, method, loads, gaps, monkeypatch)
        if isinstance(objects, str):  # bad values: the same message, naming the case
            assert arrays == objects, seed
            continue
        assert not isinstance(arrays, str), (seed, arrays)
        for name in BATCH_ARRAYS:
            assert np.array_equal(getattr(arrays, name), getattr(objects, name)), (seed, name)
        assert arrays.residuals.keys() == objects.residuals.keys()
        for name, value in objects.residuals.items():
            assert np.array_equal(arrays.residuals[name], value, equal_nan=True), (seed, name)
        assert arrays.alone.keys() == objects.alone.keys() and arrays.failures == objects.failures
        first, again = arrays[0], objects[0]
        assert np.array_equal(first.u, again.u) and first.residuals == again.residuals
        compared += 1
    assert compared >= len(SEEDS) // 2  # most random scenes are solved together


@pytest.mark.parametrize("seed", SEEDS)
def test_a_scene_tiled_by_arrays_has_the_model_of_one_tiled_by_objects(seed):
    scene = random_cases(seed)[0]
    by_arrays, by_objects = tiled_scene(scene, 3), object_tiled(scene, 3)
    assert isinstance(by_arrays.walls, contactqp.Walls) or not scene.walls
    assert by_arrays.walls == by_objects.walls
    for name in ("bars", "supports", "loads", "distributed", "contacts", "units"):
        assert getattr(by_arrays, name) == getattr(by_objects, name), name
    a, b = build_model(by_arrays), build_model(by_objects)
    assert np.array_equal(a.band, b.band) and np.array_equal(a.free, b.free)
    assert (a.C != b.C).nnz == 0 and a.C.shape == b.C.shape
    assert np.array_equal(a.g, b.g) and np.array_equal(a.P, b.P)
    for part_a, part_b in zip(a.layout.rows, b.layout.rows):
        assert np.array_equal(part_a, part_b) and part_a.dtype == part_b.dtype


def test_walls_tiled_are_their_copies_on_the_copies_bars():
    walls = contactqp.Walls([1, 2, 0], [1e-3, -2e-4, 0.0], ["+", "-", "+"], [0, 1, 1])
    tiled = walls.tiled(3, 2)
    expected = tuple(contactqp.Wall(w.node, w.gap, w.side, w.bar + 2 * copy)
                     for copy in range(3) for w in walls)
    assert tiled.items == expected


def test_loads_kept_as_an_array_read_as_the_load_objects():
    scene = contactqp.Scene(contactqp.Bar.from_areas([1e-4] * 3, 2e11, length=3.0),
                            (contactqp.Support(0),),
                            (contactqp.Load(1, 1e3), contactqp.Load(3, -2e3)),
                            (contactqp.Wall(3, 1e-4),))
    lazy = scene.with_values([5.0, -7.5], load_objects=False)
    made = scene.with_values([5.0, -7.5])
    assert isinstance(lazy.loads, ValuedLoads) and isinstance(made.loads, tuple)
    assert lazy.loads == made.loads and made.loads == tuple(lazy.loads)
    assert [p.force for p in lazy.loads] == [5.0, -7.5] and lazy.loads[1].node == 3
    assert np.array_equal(lazy.load_forces, [5.0, -7.5])
    assert np.array_equal(lazy.layout.nodal_loads, made.layout.nodal_loads)
    # a scene made again from it (dataclasses.replace) holds Load objects
    again = replace(lazy, name="again")
    assert isinstance(again.loads, tuple) and again.loads == made.loads


def test_bad_values_kept_as_an_array_are_refused_as_objects_are():
    scene = contactqp.default_scene()
    for bad in ([np.nan], [1.0, 2.0], ["x"]):
        with pytest.raises(contactqp.ContactqpError) as made:
            scene.with_values(bad)
        with pytest.raises(contactqp.ContactqpError) as lazy:
            scene.with_values(bad, load_objects=False)
        assert str(lazy.value) == str(made.value)


@pytest.mark.parametrize("as_walls", [True, False])
@pytest.mark.parametrize("nodes", [[7], list(range(2, 11))], ids=["2 walls", "18 walls"])
def test_walls_that_close_a_node_are_refused_with_the_message_of_a_fresh_scene(as_walls, nodes):
    """A wall on each side of one node, or of nodes 2..10 (more than 16 walls, which a new
    scene checks in numpy passes): gaps that sum below zero at node 7 are refused, with the
    message a scene built anew gives; gaps that sum to zero are not."""
    bar = contactqp.Bar.from_areas([1e-4] * 12, 2e11, length=1.2)
    walls = [contactqp.Wall(n, 1e-4, side) for n in nodes for side in "+-"]
    scene = contactqp.Scene(bar, (contactqp.Support(0),), (contactqp.Load(12, 1e3),),
                            contactqp.Walls.of(walls) if as_walls else walls)
    gaps = np.full(len(walls), 1e-4)
    closing = 2 * nodes.index(7) + 1
    gaps[closing] = -3e-4
    with pytest.raises(contactqp.SceneError) as fresh:
        contactqp.Scene(bar, scene.supports, scene.loads,
                        [replace(w, gap=float(g)) for w, g in zip(walls, gaps)])
    with pytest.raises(contactqp.SceneError) as valued:
        scene.with_values(gaps=gaps)
    assert str(valued.value) == str(fresh.value)
    assert "leave node 7 no position" in str(fresh.value)
    gaps[closing] = -1e-4  # the room is then 0: a touching fit, allowed
    assert contactqp.Walls.of(scene.with_values(gaps=gaps).walls).gaps[closing] == -1e-4


@pytest.mark.parametrize("columns", [1, 4, FEW_COLUMNS, FEW_COLUMNS + 1, 80])
def test_a_row_reduced_down_a_transposed_copy_is_numpys_row_reduction(columns):
    rng = np.random.default_rng(columns)
    values = rng.normal(size=(50, columns))
    values[3, columns // 2] = np.nan
    for reduce, method in ((np.maximum, "max"), (np.minimum, "min")):
        expected = getattr(values, method)(axis=1, initial=0.0)
        assert np.array_equal(row_reduce(reduce, values, initial=0.0), expected, equal_nan=True)
        assert np.isnan(row_reduce(reduce, values)[3])
