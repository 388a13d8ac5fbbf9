"""Walls given as arrays (contactqp.Walls) against the same walls given as Wall objects: the
same scene checks, the same Layout arrays, the same model (C, g, row names) and the same
Result bit for bit, on random scenes and on each builder; bad arrays one line each; the
scene-file form round trip.

The expected side of every comparison is the object path, which builds each wall as a Wall and
reads it field by field (contactqp.model.chain.numbering._wall_columns' loop); the builders' object
form is rebuilt here wall by wall, as they were written before they made arrays."""

from __future__ import annotations

import pickle
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

import contactqp
from contactqp.builders import (
    _tapered,
    channel,
    convert_units,
    flat_patch,
    minimal,
    obstacle,
    wall_at_every_node,
)
from contactqp.errors import SceneError
from contactqp.random_scenes import random_scene
from contactqp.scene import Bar, BarContact, Load, Scene, Support, Wall, Walls, row_names
from contactqp.scene_io import scene_from_dict, scene_to_toml

LAYOUT_ARRAYS = ("rows", "row_bars", "walls_by_side", "opposed_entries", "gaps",
                 "row_compliance", "press_fit_forces")


def as_objects(scene: Scene) -> Scene:
    """The same scene with its walls as a tuple of Wall objects."""
    return Scene(scene.bars, scene.supports, scene.loads, tuple(scene.walls), name=scene.name,
                 distributed=scene.distributed, contacts=scene.contacts, units=scene.units)


def as_arrays(scene: Scene) -> Scene:
    """The same scene with its walls as one Walls, built from plain lists."""
    walls = tuple(scene.walls)
    set_ = Walls([w.node for w in walls], [w.gap for w in walls], [w.side for w in walls],
                 [w.bar for w in walls])
    return Scene(scene.bars, scene.supports, scene.loads, set_, name=scene.name,
                 distributed=scene.distributed, contacts=scene.contacts, units=scene.units)


def assert_equal_arrays(a, b) -> None:
    """Nested tuples / dicts of arrays equal element for element, dtype and all."""
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for key in a:
            assert_equal_arrays(a[key], b[key])
    elif isinstance(a, tuple):
        assert len(a) == len(b)
        for x, y in zip(a, b):
            assert_equal_arrays(x, y)
    else:
        a, b = np.asarray(a), np.asarray(b)
        assert a.dtype == b.dtype and a.shape == b.shape
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


def assert_same_model(objects: Scene, arrays: Scene) -> None:
    assert isinstance(arrays.walls, Walls) and isinstance(objects.walls, tuple)
    for name in LAYOUT_ARRAYS:
        assert_equal_arrays(getattr(objects.layout, name), getattr(arrays.layout, name))
    a, b = contactqp.build_model(objects), contactqp.build_model(arrays)
    assert (a.C != b.C).nnz == 0 and a.C.shape == b.C.shape
    assert_equal_arrays(a.g, b.g)
    assert row_names(objects) == row_names(arrays)


def assert_same_result(objects: Scene, arrays: Scene, **options) -> None:
    a, b = contactqp.solve(objects, **options), contactqp.solve(arrays, **options)
    for name in ("u", "contact_force", "reactions", "penetration", "element_force", "stress"):
        assert_equal_arrays(getattr(a, name), getattr(b, name))
    assert (a.verified, a.physical, a.message) == (b.verified, b.physical, b.message)
    assert a.residuals == b.residuals
    assert (a.force_error_bound, a.displacement_error_bound) == (
        b.force_error_bound, b.displacement_error_bound)


@pytest.mark.parametrize("seed", range(12))
def test_random_scenes_give_the_same_model_and_result(seed):
    scene = random_scene(np.random.default_rng(seed))
    if not scene.walls:
        pytest.skip("no wall drawn")
    objects, arrays = as_objects(scene), as_arrays(scene)
    assert_same_model(objects, arrays)
    assert_same_result(objects, arrays)
    assert_same_result(objects, arrays, method="penalty")


def old_wall_at_every_node(scene: Scene, gaps, side: str = "+", bar: int = 0) -> Scene:
    """wall_at_every_node as written with Wall objects (the object path)."""
    n = scene.bars[bar].n_nodes
    gaps = np.broadcast_to(np.asarray(gaps, dtype=float), (n,))
    held = {s.node for s in scene.supports if s.bar == bar}
    walls = list(scene.walls)
    existing = {w.node: i for i, w in enumerate(walls) if w.bar == bar and w.side == side}
    for node, i in existing.items():
        walls[i] = Wall(walls[i].node, min(walls[i].gap, float(gaps[node])), side, bar)
    walls += [Wall(i, float(gaps[i]), side, bar) for i in range(n)
              if i not in held and i not in existing]
    return Scene(scene.bars, scene.supports, scene.loads, tuple(walls), name=scene.name,
                 distributed=scene.distributed, contacts=scene.contacts)


def test_builders_give_the_same_model_and_result_as_wall_objects():
    x = np.linspace(0.0, 1.0, 41)
    gaps = 2e-4 * x**2 + 1e-5 * np.abs(np.sin(37.0 * x))
    old = old_wall_at_every_node(_tapered(40, point_load=True), gaps)
    new = obstacle(40)
    assert_same_model(old, new)
    assert_same_result(old, new)
    x = np.linspace(0.0, 1.0, 21)
    centre = 1e-4 * np.sin(3.0 * np.pi * x) + 1.5e-4 * x
    old = old_wall_at_every_node(old_wall_at_every_node(_tapered(20, point_load=True),
                                                        centre + 5e-6), 5e-6 - centre, "-")
    new = channel(40)
    assert_same_model(old, new)
    assert_same_result(old, new)
    patch = flat_patch(30)
    old = old_wall_at_every_node(Scene(patch.bars, patch.supports, (),
                                       distributed=patch.distributed), 1e-5)
    assert_same_model(old, patch)
    assert_same_result(old, patch)


def test_wall_at_every_node_keeps_the_nearer_of_an_existing_wall():
    base = _tapered(6, point_load=True)
    walls = (Wall(3, 2e-5, "+"), Wall(6, 1e-4, "+"), Wall(2, 3e-5, "-"))
    scene = base.with_walls(walls)
    gaps = np.linspace(1e-5, 7e-5, 7)
    old, new = old_wall_at_every_node(scene, gaps), wall_at_every_node(scene, gaps)
    # node 3: 2e-5 is nearer than 4e-5; node 6: 7e-5 nearer than 1e-4; the − wall is kept
    assert [w.gap for w in new.walls][:3] == [2e-5, gaps[6], 3e-5]
    assert_same_model(old, new)
    assert_same_result(old, new)


def test_walls_read_as_a_sequence_of_wall():
    walls = Walls(np.array([4, 2]), [1e-4, 2e-4], ["+", "-"])
    assert len(walls) == 2 and bool(walls) and not Walls([], [])
    assert walls[1] == Wall(2, 2e-4, "-") and list(walls) == [walls[0], walls[1]]
    assert walls == (Wall(4, 1e-4, "+"), Wall(2, 2e-4, "-"))
    assert walls[:1] + (Wall(3, 0.0),) == (Wall(4, 1e-4), Wall(3, 0.0))
    assert walls.signs.tolist() == [1.0, -1.0]
    with pytest.raises(ValueError):
        walls.gaps[0] = 1.0  # read-only: a scene does not change


def test_a_list_of_walls_and_wall_objects_is_joined_in_order():
    bar = Bar.uniform(1e-4, 2e11, length=1.0, elements=4)
    mixed = Scene(bar, (Support(0),), (Load(4, 1e3),),
                  [Wall(4, 1e-4), Walls([2, 3], 5e-5, "-"), Wall(1, 0.0, "-")])
    objects = Scene(bar, (Support(0),), (Load(4, 1e3),),
                    (Wall(4, 1e-4), Wall(2, 5e-5, "-"), Wall(3, 5e-5, "-"), Wall(1, 0.0, "-")))
    assert isinstance(mixed.walls, Walls) and mixed.walls == objects.walls
    assert_same_model(objects, mixed)
    assert_same_result(objects, mixed)


def test_with_values_changes_the_gaps_of_a_wall_set():
    scene = channel(20)
    gaps = np.linspace(-1e-6, 3e-5, scene.n_contacts)
    assert_same_model(as_objects(scene).with_values(gaps=gaps), scene.with_values(gaps=gaps))
    assert scene.with_values(gaps=gaps).walls.gaps.tolist() == gaps.tolist()


def test_bar_contacts_beside_a_wall_set():
    bars = (Bar.uniform(1e-4, 2e11, length=1.0, elements=4),
            Bar.uniform(2e-4, 2e11, length=1.0, elements=3))
    contacts = (BarContact(0, 4, 1, 0, 1e-5),)
    walls = Walls([2, 3, 1], [3e-5, 1e-3, 2e-5], ["+", "+", "-"], [0, 0, 1])
    arrays = Scene(bars, (Support(0, 0), Support(3, 1)), (Load(2, 5e5),), walls,
                   contacts=contacts)
    objects = as_objects(arrays)
    assert_same_model(objects, arrays)
    assert_same_result(objects, arrays)


BAR = Bar.uniform(1e-4, 2e11, length=1.0, elements=4)


def scene_with(walls) -> Scene:
    return Scene(BAR, (Support(0),), (Load(4, 1e3),), walls)


@pytest.mark.parametrize(("make", "message"), [
    (lambda: Walls([1, 2], [1e-4, 2e-4, 3e-4]), ("walls.gaps has 3 values: give one, or one per "
                                                "wall (2)")),
    (lambda: Walls([[1, 2]], 1e-4), ("walls.nodes must be one value or a flat list (one per "
                                    "wall), got an array of shape (1, 2)")),
    (lambda: Walls([1, 2.5], 1e-4), "walls.nodes[1] must be a whole number"),
    (lambda: Walls([1, True], 1e-4), "walls.nodes[1] must be a whole number"),
    (lambda: Walls(3, 1e-4), "walls.nodes must be a list of values (one per wall), got 3"),
    (lambda: Walls([1, 2], [1e-4, np.nan]), "walls.gaps[1] must be finite, got nan"),
    (lambda: Walls([1, 2], [np.inf, 0.0]), "walls.gaps[0] must be finite, got inf"),
    (lambda: Walls([1, 2], [1e31, 0.0]), "walls.gaps[0] = 1e+31 is outside the range"),
    (lambda: Walls([1, 2], ["a", 0.0]), "walls.gaps[0] must be a number"),
    (lambda: Walls([1, 2], 0.0, ["+", "x"]), "walls.sides[1] must be '+' or '-', got 'x'"),
    (lambda: Walls([1, 2], 0.0, "up"), "walls.sides must be '+' or '-', got 'up'"),
    (lambda: Walls([1, 2], 0.0, "+", [0, 1, 2]), "walls.bars has 3 values"),
    (lambda: scene_with(Walls([1, 5], 0.0)), "wall[1].node = 5: the bar has nodes 0 to 4"),
    (lambda: scene_with(Walls([1, -1], 0.0)), "wall[1].node = -1: the bar has nodes 0 to 4"),
    (lambda: scene_with(Walls([1, 2], 0.0, "+", [0, 1])),
     "wall[1].bar = 1: the scene has bars 0 to 0"),
    (lambda: scene_with(Walls([1, 2], 0.0, "+", -1)), "wall[0].bar must be a whole bar number"),
    (lambda: scene_with(Walls([1, 0], 0.0)), ("wall[1].node = 0 is support[0]: a wall there "
                                             "carries no force")),
    (lambda: scene_with(Walls([1, 3, 3], 0.0)), ("wall[2] repeats wall[1] (node 3, side '+'): "
                                                "keep the one with the smaller gap")),
    (lambda: scene_with([Wall(1, 0.0), Walls([2], 0.0), Wall(3, np.nan)]),
     "wall[2].gap must be finite, got nan"),
    (lambda: scene_with([Walls([1], 0.0), "wall"]), "wall[1] must be a contactqp.Wall or Walls"),
])
def test_bad_wall_arrays_are_one_line_naming_the_field(make, message):
    with pytest.raises(SceneError) as error:
        make()
    assert message in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize("walls", [
    (Wall(1, 0.0, "+"), Wall(1, -1e-5, "-")),  # no room between the node's two walls
    (Wall(2, 1e-4), Wall(3, 2e-4), Wall(3, 2e-4)),  # a repeat
    (Wall(1, 0.0), Wall(5, 0.0)),  # a node that does not exist
])
def test_a_bad_wall_set_says_what_the_same_wall_objects_say(walls):
    with pytest.raises(SceneError) as objects:
        scene_with(walls)
    with pytest.raises(SceneError) as arrays:
        scene_with(Walls.of(walls))
    assert str(objects.value) == str(arrays.value)


def test_scene_file_round_trip_of_a_wall_set():
    for scene in (channel(30), obstacle(12)):
        text = scene_to_toml(scene)
        assert "[[walls]]" in text and "[[wall]]" not in text
        back = scene_from_dict(tomllib.loads(text))
        assert isinstance(back.walls, Walls) and back.walls == scene.walls
        assert back.walls.gaps.tolist() == scene.walls.gaps.tolist()  # bit for bit
        assert_same_result(as_objects(scene), back)


def test_scene_file_walls_tables_and_their_errors():
    data = tomllib.loads("""
        [bar]
        length = 1.0
        elements = 4
        area = 1e-4
        [bar.material]
        youngs_modulus = 2e11
        [[support]]
        node = 0
        [[load]]
        node = 4
        force = 1e3
        [[wall]]
        node = 4
        gap = 1e-4
        [[walls]]
        nodes = [1, 2, 3]
        gaps = [1e-3, 2e-3, 3e-3]
        sides = ["-", "-", "+"]
    """)
    scene = scene_from_dict(data)
    assert scene.walls == (Wall(4, 1e-4), Wall(1, 1e-3, "-"), Wall(2, 2e-3, "-"),
                           Wall(3, 3e-3, "+"))
    data["walls"][0]["gaps"] = [1e-3, "x", 3e-3]
    with pytest.raises(SceneError, match=r"^walls\[0\]\.gaps\[1\] must be a number, got 'x'$"):
        scene_from_dict(data)
    data["walls"][0]["gaps"] = 0.0
    data["walls"][0]["node"] = 1
    with pytest.raises(SceneError, match=r"walls\[0\]\.node: unknown key"):
        scene_from_dict(data)


def test_the_scene_file_reference_walls_block_reads_as_its_comment_says():
    text = (Path(__file__).parent.parent / "docs" / "scene_files.md").read_text(encoding="utf-8")
    block = next(b for b in re.findall(r"```toml\n(.*?)```", text, re.DOTALL) if "[[walls]]" in b)
    data = tomllib.loads(block)["walls"][0]
    walls = Walls(data["nodes"], data["gaps"], data["sides"])
    assert walls == (Wall(1, 1e-3, "-"), Wall(2, 2e-3, "-"), Wall(3, 3e-3, "+"))


def test_minimal_convert_units_and_pickle_keep_a_wall_set():
    scene = obstacle(12)
    objects = as_objects(scene)
    for make in (minimal, lambda s: convert_units(s, "mm-N-MPa"),
                 lambda s: pickle.loads(pickle.dumps(s))):
        new, old = make(scene), make(objects)
        assert isinstance(new.walls, Walls) and new.walls == old.walls
        assert_same_result(old, new)


def test_with_values_refuses_crossing_gaps_as_the_wall_objects_do():
    walls = Walls([2, 2], [1e-4, 1e-4], ["+", "-"])
    arrays = scene_with(walls)
    objects = as_objects(arrays)
    gaps = [1e-5, -2e-5]  # the − wall now past the + wall: node 2 has no position
    with pytest.raises(SceneError) as expected:
        objects.with_values(gaps=gaps)
    with pytest.raises(SceneError) as got:
        arrays.with_values(gaps=gaps)
    assert str(got.value) == str(expected.value) and "no position" in str(got.value)


def test_scene_file_round_trip_of_walls_on_several_bars_and_sides():
    bars = (Bar.uniform(1e-4, 2e11, length=1.0, elements=4),
            Bar.uniform(2e-4, 2e11, length=1.0, elements=3))
    walls = Walls([4, 2, 3, 1], [1e-4, -1e-6, 0.1 + 0.2, 2e-5], ["+", "-", "+", "-"],
                  [0, 0, 1, 1])
    scene = Scene(bars, (Support(0, 0), Support(0, 1)), (Load(2, 5e5), Load(2, -1e5, 1)), walls)
    text = scene_to_toml(scene)
    assert 'sides = ["+", "-", "+", "-"]' in text and "bars = [0, 0, 1, 1]" in text
    back = scene_from_dict(tomllib.loads(text))
    assert_equal_arrays((back.walls.nodes, back.walls.gaps, back.walls.sides, back.walls.bars),
                        (walls.nodes, walls.gaps, walls.sides, walls.bars))
    assert_same_result(as_objects(scene), back)


def test_many_wall_objects_with_no_room_are_named_by_the_constraint_graph():
    from contactqp.feasibility import impossible_constraints

    bar = Bar.uniform(1e-4, 2e11, length=1.0, elements=30)
    walls = [Wall(i, 1e-4) for i in range(1, 31)] + [Wall(17, -2e-4, "-")]  # 17 walls or more
    with pytest.raises(SceneError) as error:
        Scene(bar, (Support(0),), (), walls)
    unchecked = object.__new__(Scene)  # the same scene, its constraints not yet checked
    unchecked.__dict__.update(bars=(bar,), supports=(Support(0),), loads=(), walls=tuple(walls),
                              contacts=(), distributed=(), units="SI", name="scene")
    assert str(error.value) == impossible_constraints(unchecked)
    assert "wall[16]" in str(error.value) and "wall[30]" in str(error.value)


@pytest.mark.parametrize(("change", "message"), [
    (lambda w: Wall(w.node, float("nan"), w.side), "wall[20].gap must be finite, got nan"),
    (lambda w: Wall(w.node, 2e30, w.side), "wall[20].gap = 2e+30 is outside the range"),
    (lambda w: Wall(40, w.gap, w.side), "wall[20].node = 40: the bar has nodes 0 to 30"),
    (lambda w: Wall(0, w.gap, w.side), "wall[20].node = 0 is support[0]"),
    (lambda w: Wall(3, w.gap, w.side), "wall[20] repeats wall[2] (node 3, side '+')"),
    (lambda w: Wall(w.node, 1, w.side), None),  # an int gap: taken as the loop takes it
])
def test_many_wall_objects_say_what_the_loop_says(change, message):
    """More than 16 Wall objects are checked in numpy passes; any fault is named by the loop
    over the objects, the first in row order."""
    bar = Bar.uniform(1e-4, 2e11, length=1.0, elements=30)
    walls = [Wall(i, 1e-4) for i in range(1, 31)]
    walls[20] = change(walls[20])
    walls[25] = Wall(walls[25].node, float("inf"))  # a later fault: not the one named
    if message is None:
        walls[25] = Wall(26, 1e-4)
        assert Scene(bar, (Support(0),), (), walls).walls[20].gap == 1
        return
    with pytest.raises(SceneError, match=re.escape(message)):
        Scene(bar, (Support(0),), (), walls)
