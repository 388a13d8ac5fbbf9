"""Scene files (contactqp.scene_io): TOML in and out, the example files, units, and bad files
that name the field and the value.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import contactqp
from closed_forms import (
    DEFAULT_DIAMETERS_MM,
    DEFAULT_SCENE,
    EXAMPLES,
    valid_data,
    with_value,
)
from contactqp import (
    Bar,
    Load,
    Scene,
    SceneError,
    Support,
    Wall,
)
from contactqp.cli import main
from contactqp.scene_io import load_scene

# The scene-file example of the README, comments and all
EXAMPLE_TOML = """\
name = "my scene"             # optional

[material]
youngs_modulus = 210e9        # Pa
yield_stress = 200e6          # Pa, optional

[bar]
length = 1.0                  # m
elements = 4
section = { shape = "circle", diameter_start = 0.040, diameter_end = 0.020, area_rule = "midpoint" }
# or instead of elements/section: areas = [1.1e-3, 8.3e-4, 5.9e-4, 4.0e-4]
#   (m², one per element) with length (equal elements) or lengths = [...] (m, one per element)

[[support]]                   # one or more: a node held at u = 0
node = 0

[[load]]                      # any number: a point load, N, +x positive
node = 2
force = 565486.67

[[wall]]                      # any number
node = 4
gap = 1e-4                    # m, >= 0
side = "+"                    # "+": u4 <= gap; "-": u4 >= -gap
"""


def assert_same_scene(a: Scene, b: Scene) -> None:
    """Two scenes hold the same data, bit for bit (repr of a float round-trips exactly)."""
    assert a.bars[0].lengths.tolist() == b.bars[0].lengths.tolist()
    assert a.bars[0].areas.tolist() == b.bars[0].areas.tolist()
    assert a.bars[0].youngs_modulus.tolist() == b.bars[0].youngs_modulus.tolist()
    assert a.bars[0].yield_stress == b.bars[0].yield_stress
    assert a.supports == b.supports
    assert a.loads == b.loads
    assert a.walls == b.walls
    assert a.name == b.name


def two_sided_scene() -> Scene:
    """Explicit areas and lengths, two supports, loads both ways, walls on both sides."""
    bar = Bar.from_areas([1e-3, 7.5e-4, 5e-4, 2.5e-4], 7e10, lengths=[0.3, 0.2, 0.1, 0.4])
    return Scene(
        bar,
        supports=(Support(0), Support(4)),
        loads=(Load(1, -1.5e5), Load(2, 2e5), Load(2, 1e4)),
        walls=(Wall(1, 0.0, "-"), Wall(2, 3e-5, "+"), Wall(3, 1e-3, "-")),
        name="two-sided: fixed at both ends",
    )


def section_data() -> dict:
    """The same with a tapered circular section instead of explicit areas."""
    data = valid_data()
    data["bar"] = {"length": 1.0, "elements": 2,
                   "section": {"shape": "circle", "diameter_start": 0.02, "diameter_end": 0.01}}
    return data


BAD_DATA = [
    # (base, path, value, field the message names, value as the message shows it)
    (valid_data, ("material", "youngs_modulus"), 0.0, "material.youngs_modulus", "0.0"),
    (valid_data, ("material", "youngs_modulus"), -2e11, "material.youngs_modulus",
     "-200000000000.0"),
    (valid_data, ("material", "youngs_modulus"), math.nan, "material.youngs_modulus", "nan"),
    (valid_data, ("material", "youngs_modulus"), math.inf, "material.youngs_modulus", "inf"),
    (valid_data, ("material", "youngs_modulus"), "steel", "material.youngs_modulus", "'steel'"),
    (valid_data, ("material", "yield_stress"), -1.0, "material.yield_stress", "-1.0"),
    (valid_data, ("bar", "areas", 1), 0.0, "bar.areas[1]", "0.0"),
    (valid_data, ("bar", "areas", 1), -1e-4, "bar.areas[1]", "-0.0001"),
    (valid_data, ("bar", "areas", 0), math.nan, "bar.areas[0]", "nan"),
    (valid_data, ("bar", "areas", 0), math.inf, "bar.areas[0]", "inf"),
    (valid_data, ("bar", "length"), 0.0, "bar.length", "0.0"),
    (valid_data, ("bar", "length"), -1.0, "bar.length", "-1.0"),
    (valid_data, ("bar", "length"), math.nan, "bar.length", "nan"),
    (valid_data, ("bar", "length"), math.inf, "bar.length", "inf"),
    (section_data, ("bar", "length"), 0.0, "bar.length", "0.0"),
    (section_data, ("bar", "elements"), 0, "bar.elements", "0"),
    (section_data, ("bar", "section", "diameter_start"), 0.0, "bar.section.diameter_start",
     "0.0"),
    (section_data, ("bar", "section", "diameter_end"), -0.01, "bar.section.diameter_end",
     "-0.01"),
    (section_data, ("bar", "section", "diameter_end"), math.nan, "bar.section.diameter_end",
     "nan"),
    (section_data, ("bar", "section", "shape"), "square", "bar.section.shape", "'square'"),
    (section_data, ("bar", "section", "area_rule"), "trapezoid", "bar.section.area_rule",
     "'trapezoid'"),
    (valid_data, ("load", 0, "node"), 3, "load[0].node", "3"),
    (valid_data, ("load", 0, "node"), -1, "load[0].node", "-1"),
    (valid_data, ("load", 0, "force"), math.inf, "load[0].force", "inf"),
    (valid_data, ("support", 0, "node"), 5, "support[0].node", "5"),
    (valid_data, ("wall", 0, "node"), 7, "wall[0].node", "7"),
    (valid_data, ("wall", 0, "node"), 0, "wall[0].node", "0"),  # on the support
    (valid_data, ("wall", 0, "gap"), "1e-4", "wall[0].gap", "'1e-4'"),
    (valid_data, ("wall", 0, "gap"), math.nan, "wall[0].gap", "nan"),
    (valid_data, ("wall", 0, "side"), "left", "wall[0].side", "'left'"),
    (valid_data, ("support",), [], "support", None),  # no support: no value to show
    # unknown keys: the message names the key (the "value" is the key itself)
    (valid_data, ("walls",), [], "scene.walls", "unknown key"),
    (valid_data, ("material", "youngs_moduls"), 2e11, "material.youngs_moduls", "unknown key"),
    (valid_data, ("bar", "area"), [1e-4], "bar.area", "unknown key"),
    (section_data, ("bar", "section", "diameter"), 0.02, "bar.section.diameter", "unknown key"),
    (valid_data, ("support", 0, "nodes"), 1, "support[0].nodes", "unknown key"),
    (valid_data, ("load", 0, "forse"), 1.0, "load[0].forse", "unknown key"),
    (valid_data, ("wall", 0, "gapp"), 0.0, "wall[0].gapp", "unknown key"),
]


def test_a_scene_file_declares_its_units(tmp_path):
    """The default scene in mm, N, MPa: lengths in mm, areas in mm², E in MPa, gaps in mm."""
    text = contactqp.scene_to_toml(contactqp.convert_units(DEFAULT_SCENE, "mm-N-MPa"))
    assert 'units = "mm-N-MPa"' in text
    path = tmp_path / "mm.toml"
    path.write_text(text)
    scene = contactqp.load_scene(path)
    assert scene.units == "mm-N-MPa"
    assert scene.walls[0].gap == pytest.approx(0.1, rel=1e-15)  # 0.1 mm
    assert scene.bars[0].youngs_modulus[0] == pytest.approx(210e3, rel=1e-15)  # MPa
    assert scene.bars[0].lengths.sum() == pytest.approx(1000.0, rel=1e-15)  # mm


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_every_example_runs_and_round_trips(path, tmp_path):
    scene = load_scene(path)
    result = contactqp.solve(scene)
    assert result.verified, result.message
    copy = tmp_path / "copy.toml"
    copy.write_text(contactqp.scene_to_toml(scene))
    again = contactqp.solve(load_scene(copy))
    assert again.contact_force == pytest.approx(result.contact_force, rel=1e-12, abs=1e-9)
    assert main(["compare", str(path), "--no-charts"]) == 0


def test_examples_cover_every_feature():
    text = " ".join(p.read_text() for p in EXAMPLES)
    for table in ("[[bar]]", "[[contact]]", "[[distributed_load]]", "[[obstacle]]", "[bar.material]"):
        assert table in text


@pytest.mark.parametrize("make_scene", [contactqp.default_scene, two_sided_scene])
def test_toml_round_trip(tmp_path: Path, make_scene):
    scene = make_scene()
    path = tmp_path / "scene.toml"
    path.write_text(contactqp.scene_to_toml(scene), encoding="utf-8")
    assert_same_scene(contactqp.load_scene(path), scene)


def test_toml_round_trip_keeps_a_name_with_an_apostrophe(tmp_path: Path):
    scene = contactqp.default_scene()
    scene = Scene(scene.bars[0], scene.supports, scene.loads, scene.walls, name="O'Brien's bar")
    path = tmp_path / "scene.toml"
    path.write_text(contactqp.scene_to_toml(scene), encoding="utf-8")
    assert_same_scene(contactqp.load_scene(path), scene)


def test_example_toml_file_is_the_seed_scene(tmp_path: Path):
    path = tmp_path / "seed.toml"
    path.write_text(EXAMPLE_TOML, encoding="utf-8")
    scene = contactqp.load_scene(path)
    seed = contactqp.default_scene()
    assert scene.name == "my scene"
    assert scene.bars[0].lengths.tolist() == seed.bars[0].lengths.tolist()
    # the same diameters go through the same formula: bit-for-bit equal areas expected
    assert scene.bars[0].areas.tolist() == seed.bars[0].areas.tolist()
    assert scene.bars[0].yield_stress == 200e6
    assert (scene.supports, scene.loads, scene.walls) == (seed.supports, seed.loads, seed.walls)


def test_example_toml_file_with_the_exact_rule(tmp_path: Path):
    path = tmp_path / "exact.toml"
    path.write_text(EXAMPLE_TOML.replace('"midpoint"', '"exact"'), encoding="utf-8")
    scene = contactqp.load_scene(path)
    d = np.array(DEFAULT_DIAMETERS_MM) / 1000.0
    # π d_a d_b / 4 with diameters rounded differently (linspace vs literals): a few ulp
    np.testing.assert_allclose(scene.bars[0].areas, math.pi * d[:-1] * d[1:] / 4.0, rtol=1e-14)


def test_toml_file_with_explicit_areas_and_defaults(tmp_path: Path):
    text = """\
[material]
youngs_modulus = 70000000000

[bar]
areas = [2e-4, 1e-4]
lengths = [0.5, 1.5]

[[support]]
node = 2

[[load]]
node = 0
force = -1000

[[wall]]
node = 1
gap = 0
"""
    path = tmp_path / "explicit_areas.toml"
    path.write_text(text, encoding="utf-8")
    scene = contactqp.load_scene(path)
    assert scene.name == "explicit_areas"  # no name in the file: the file's stem
    assert scene.bars[0].areas.tolist() == [2e-4, 1e-4]
    assert scene.bars[0].lengths.tolist() == [0.5, 1.5]
    assert scene.bars[0].youngs_modulus.tolist() == [7e10, 7e10]
    assert scene.bars[0].yield_stress is None
    assert scene.supports == (Support(2),)
    assert scene.loads == (Load(0, -1000.0),)
    assert scene.walls == (Wall(1, 0.0, "+"),)  # side defaults to "+"


def test_toml_with_one_length_splits_it_equally():
    data = {"material": {"youngs_modulus": 2e11}, "bar": {"areas": [1e-4] * 4, "length": 2.0},
            "support": [{"node": 0}]}
    assert contactqp.scene_from_dict(data).bars[0].lengths.tolist() == [0.5] * 4  # exact in binary


@pytest.mark.parametrize(
    "base, path, value, field, shown", BAD_DATA,
    ids=[f"{'.'.join(map(str, p))}={v!r}" for _, p, v, _, _ in BAD_DATA],
)
def test_bad_scene_data_names_field_and_value(base, path, value, field, shown):
    with pytest.raises(SceneError) as caught:
        contactqp.scene_from_dict(with_value(base(), path, value))
    message = str(caught.value)
    assert field in message
    if shown is not None:
        assert shown in message


def test_lengths_with_a_section_is_a_scene_error():
    data = section_data()
    data["bar"]["lengths"] = [0.1, 0.9]
    with pytest.raises(SceneError, match=r"bar\.lengths"):
        contactqp.scene_from_dict(data)


@pytest.mark.parametrize("replace, by, field, shown", [
    ("youngs_modulus = 210e9", "youngs_modulus = nan", "material.youngs_modulus", "nan"),
    ("youngs_modulus = 210e9", "youngs_modulus = -inf", "material.youngs_modulus", "-inf"),
    ("gap = 1e-4 ", "gap = inf ", "wall[0].gap", "inf"),
    ("node = 2\nforce", "node = 9\nforce", "load[0].node", "9"),
    ("node = 0", "node = 4", "wall[0].node", "4"),  # the support moved under the wall
    ("area_rule", "area_rul", "bar.section.area_rul", "unknown key"),
])
def test_bad_toml_file_names_field_and_value(tmp_path: Path, replace, by, field, shown):
    assert replace in EXAMPLE_TOML  # guard: the replacement really changes the file
    path = tmp_path / "bad.toml"
    path.write_text(EXAMPLE_TOML.replace(replace, by), encoding="utf-8")
    with pytest.raises(SceneError) as caught:
        contactqp.load_scene(path)
    assert field in str(caught.value)
    assert shown in str(caught.value)


def test_broken_toml_file(tmp_path: Path):
    path = tmp_path / "broken.toml"
    path.write_text("[material\nyoungs_modulus = 210e9\n", encoding="utf-8")
    with pytest.raises(SceneError, match=r"broken\.toml.*not valid TOML"):
        contactqp.load_scene(path)


def test_missing_file(tmp_path: Path):
    path = tmp_path / "nowhere.toml"
    with pytest.raises(SceneError, match=r"nowhere\.toml.*does not exist"):
        contactqp.load_scene(path)
