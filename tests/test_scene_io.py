"""Scene files (contactqp.scene_io): TOML in and out, the example files, units, and bad files
that name the field and the value.
"""

from __future__ import annotations

import math
import re
import tomllib
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
from contactqp.scene import BarContact, Circle, DistributedLoad, HollowCircle, Rectangle
from contactqp.scene_io import load_scene

DOCS = Path(__file__).parent.parent / "docs" / "scene_files.md"

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
    assert len(a.bars) == len(b.bars)
    for bar_a, bar_b in zip(a.bars, b.bars):
        assert bar_a.lengths.tolist() == bar_b.lengths.tolist()
        assert bar_a.areas.tolist() == bar_b.areas.tolist()
        assert bar_a.youngs_modulus.tolist() == bar_b.youngs_modulus.tolist()
        assert bar_a.yield_stress == bar_b.yield_stress
    assert a.supports == b.supports
    assert a.loads == b.loads
    assert a.walls == b.walls
    assert a.distributed == b.distributed
    assert a.contacts == b.contacts
    assert (a.name, a.units) == (b.name, b.units)


def round_trip(scene: Scene, tmp_path: Path) -> tuple[Scene, str]:
    """The scene written with scene_to_toml and read back with load_scene, and the text."""
    text = contactqp.scene_to_toml(scene)
    path = tmp_path / "scene.toml"
    path.write_text(text, encoding="utf-8")
    return contactqp.load_scene(path), text


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


def wall_free_data() -> dict:
    """valid_data without its wall: with no support, nothing would hold the bar."""
    data = valid_data()
    del data["wall"]
    return data


def uniform_data() -> dict:
    """The same bar as one area over equal elements."""
    data = valid_data()
    data["bar"] = {"length": 1.0, "elements": 2, "area": 1e-4}
    return data


def rectangle_data() -> dict:
    """A rectangle tapered in width, of constant height."""
    data = valid_data()
    data["bar"] = {"length": 1.0, "elements": 2,
                   "section": {"shape": "rectangle", "width_start": 0.04, "width_end": 0.02,
                               "height": 0.01}}
    return data


def tube_data() -> dict:
    """A tube of constant outer and inner diameter."""
    data = valid_data()
    data["bar"] = {"length": 1.0, "elements": 2,
                   "section": {"shape": "hollow_circle", "outer_diameter": 0.04,
                               "inner_diameter": 0.03}}
    return data


def two_bars_data() -> dict:
    """Two [[bar]] tables, the second with its own material: a tube and a uniform bar."""
    data = valid_data()
    tube, uniform = tube_data()["bar"], uniform_data()["bar"]
    data["bar"] = [uniform, {**tube, "material": {"youngs_modulus": 7e10, "yield_stress": 1e8}}]
    data["support"].append({"bar": 1, "node": 0})
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
    (wall_free_data, ("support",), [], "support", None),  # nothing holds it: no value to show
    # sections: each dimension one number or its two ends, checked as the file spells it
    (tube_data, ("bar", "section", "inner_diameter"), 0.05, "bar.section.inner_diameter",
     "= 0.05 is not less than outer_diameter = 0.04"),
    (tube_data, ("bar", "section", "inner_diameter"), -0.01, "bar.section.inner_diameter",
     "-0.01"),
    (tube_data, ("bar", "section", "outer_diameter"), "40 mm", "bar.section.outer_diameter",
     "'40 mm'"),
    (tube_data, ("bar", "section", "outer_diameter"), [0.04, 0.05],
     "bar.section.outer_diameter must be one number", "outer_diameter_start"),
    (rectangle_data, ("bar", "section", "width_end"), 0.0, "bar.section.width_end", "0.0"),
    (rectangle_data, ("bar", "section", "height"), math.inf, "bar.section.height", "inf"),
    (rectangle_data, ("bar", "section", "width"), 0.03, "bar.section.width",
     "and bar.section.width_start are both given"),
    (rectangle_data, ("bar", "section", "shape"), 3, "bar.section.shape", "got 3"),
    (rectangle_data, ("bar", "section", "area_rule"), "exactly", "bar.section.area_rule",
     "'exactly'"),
    (rectangle_data, ("bar", "elements"), 1.5, "bar.elements", "1.5"),
    (rectangle_data, ("bar", "lengths"), [0.5, 0.5], "bar.lengths goes with", "bar.area"),
    # one area for every element
    (uniform_data, ("bar", "area"), 0.0, "bar.area", "0.0"),
    (uniform_data, ("bar", "area"), math.nan, "bar.area", "nan"),
    (uniform_data, ("bar", "area"), [1e-4, 1e-4], "bar.area must be one number",
     "[0.0001, 0.0001]"),
    (uniform_data, ("bar", "areas"), [1e-4, 1e-4], "bar: give one of", "got areas and area"),
    (uniform_data, ("bar", "elements"), -2, "bar.elements", "-2"),
    (uniform_data, ("bar", "lengths"), [0.5, 0.5], "bar: give length and elements, or lengths",
     "not both"),
    (valid_data, ("bar", "elements"), 2, "bar.elements goes with", "bar.areas"),
    # several bars: the message names the bar
    (two_bars_data, ("bar", 1, "section", "inner_diameter"), 0.05,
     "bar[1].section.inner_diameter = 0.05 is not less than outer_diameter = 0.04", None),
    (two_bars_data, ("bar", 0, "area"), -1e-4, "bar[0].area", "-0.0001"),
    (two_bars_data, ("bar", 0, "length"), 0.0, "bar[0].length", "0.0"),
    (two_bars_data, ("bar", 1, "material", "yield_stress"), 0.0,
     "bar[1].material.yield_stress", "0.0"),
    (two_bars_data, ("bar", 1, "section", "shape"), "tube", "bar[1].section.shape", "'tube'"),
    # unknown keys: the message names the key (the "value" is the key itself)
    (valid_data, ("wals",), [], "scene.wals", "unknown key"),
    (valid_data, ("material", "youngs_moduls"), 2e11, "material.youngs_moduls", "unknown key"),
    (valid_data, ("bar", "areas_mm2"), [1e-4], "bar.areas_mm2", "unknown key"),
    (section_data, ("bar", "section", "radius"), 0.01, "bar.section.radius", "unknown key"),
    (rectangle_data, ("bar", "section", "diameter"), 0.02, "bar.section.diameter",
     "unknown key"),
    (valid_data, ("support", 0, "nodes"), 1, "support[0].nodes", "unknown key"),
    (valid_data, ("load", 0, "forse"), 1.0, "load[0].forse", "unknown key"),
    (valid_data, ("wall", 0, "gapp"), 0.0, "wall[0].gapp", "unknown key"),
    # values TOML can hold that are not what the key means: refused, not turned into text
    # or flattened
    (valid_data, ("name",), 123, "name must be text", "123"),
    (valid_data, ("name",), [], "name must be text", "[]"),
    (valid_data, ("name",), {"a": 1}, "name must be text", "{'a': 1}"),
    (valid_data, ("units",), [], "units must be one of", "got []"),
    (valid_data, ("units",), {}, "units must be one of", "got {}"),
    (valid_data, ("bar", "areas"), [[1e-4, 1e-4], [1e-4, 1e-4]], "bar.areas must be a flat list",
     "shape (2, 2)"),
    (valid_data, ("contact",), [{"bar_a": 0, "node_a": 1, "bar_b": 0, "node_b": 2, "gap": 0.0}],
     "contact[0]: bar_a = bar_b = 0", "two different bars"),
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
    # compare takes no friction: a scene on a bed is refused in one line (exit code 2)
    assert main(["compare", str(path), "--no-charts"]) == (2 if scene.beds else 0)


def test_examples_cover_every_feature():
    text = " ".join(p.read_text() for p in EXAMPLES)
    for table in ("[[bar]]", "[[contact]]", "[[distributed_load]]", "[[obstacle]]", "[bar.material]",
                  "[[bed]]",
                  'shape = "rectangle"', "area = ", "width_start"):
        assert table in text


def test_strap_and_rod_example_is_its_closed_form():
    """examples/strap_and_rod.toml: a strap 0.5 m long, 10 mm thick, 40 → 20 mm wide (E =
    210 GPa), against a rod of 250 mm² and 0.4 m (E = 70 GPa), 0.2 mm apart, 60 kN on the
    strap's tip: λ = (F − k0 g)·k1/(k0 + k1), k0 the continuous taper's stiffness."""
    k0 = 210e9 * 0.010 * (0.020 - 0.040) / (0.5 * math.log(0.020 / 0.040))
    k1 = 70e9 * 2.5e-4 / 0.4
    force = (60e3 - k0 * 2e-4) * k1 / (k0 + k1)
    path = next(p for p in EXAMPLES if p.stem == "strap_and_rod")  # run by the example tests too
    result = contactqp.solve(load_scene(path))
    assert result.verified
    # the exact rule makes the four elements the continuous strap: round-off only
    assert result.contact_force[0] == pytest.approx(force, rel=1e-12)
    assert force == pytest.approx(9486.20, abs=0.005)  # the number the file's comment gives


@pytest.mark.parametrize("section, data", [
    (Circle(0.03), {"shape": "circle", "diameter": 0.03}),
    (Circle((0.04, 0.02)), {"shape": "circle", "diameter_start": 0.04, "diameter_end": 0.02}),
    (HollowCircle(0.05, 0.04), {"shape": "hollow_circle", "outer_diameter": 0.05,
                                "inner_diameter": 0.04}),
    (HollowCircle((0.05, 0.03), (0.02, 0.0)),
     {"shape": "hollow_circle", "outer_diameter_start": 0.05, "outer_diameter_end": 0.03,
      "inner_diameter_start": 0.02, "inner_diameter_end": 0.0}),
    (Rectangle(0.04, 0.01), {"shape": "rectangle", "width": 0.04, "height": 0.01}),
    (Rectangle((0.04, 0.02), (0.01, 0.03)),
     {"shape": "rectangle", "width_start": 0.04, "width_end": 0.02, "height_start": 0.01,
      "height_end": 0.03}),
    (Rectangle(0.04, (0.01, 0.03)),
     {"shape": "rectangle", "width": 0.04, "height_start": 0.01, "height_end": 0.03}),
], ids=lambda value: value["shape"] if isinstance(value, dict) else "")
@pytest.mark.parametrize("rule", ["midpoint", "exact"])
def test_a_section_in_a_file_is_the_section_in_python(section, data, rule):
    scene = contactqp.scene_from_dict(with_value(section_data(), ("bar", "section"),
                                                 {**data, "area_rule": rule}))
    bar = Bar.from_section(section, 2e11, length=1.0, elements=2, area_rule=rule)
    assert scene.bars[0].areas.tolist() == bar.areas.tolist()  # one code path: bit for bit


def test_a_rectangle_in_a_file_has_its_closed_form_areas():
    scene = contactqp.scene_from_dict(rectangle_data())
    # midpoint (the default): widths 35 and 25 mm at the elements' middles, times 10 mm
    np.testing.assert_allclose(scene.bars[0].areas, [0.035 * 0.01, 0.025 * 0.01], rtol=1e-14)


def test_a_tube_in_a_file_has_its_closed_form_area():
    scene = contactqp.scene_from_dict(tube_data())
    area = math.pi * (0.04**2 - 0.03**2) / 4.0  # 549.8 mm²
    np.testing.assert_allclose(scene.bars[0].areas, [area, area], rtol=1e-14)


@pytest.mark.parametrize("geometry, lengths", [
    ({"length": 0.9, "elements": 3}, [0.3, 0.3, 0.3]),
    ({"lengths": [0.2, 0.3, 0.4]}, [0.2, 0.3, 0.4]),
])
def test_one_area_for_every_element(geometry, lengths):
    data = valid_data()
    data["bar"] = {"area": 2e-4, **geometry}
    data["load"][0]["node"] = 3
    data["wall"][0]["node"] = 3
    bar = contactqp.scene_from_dict(data).bars[0]
    assert bar.areas.tolist() == [2e-4] * 3
    np.testing.assert_allclose(bar.lengths, lengths, rtol=1e-15)  # 0.9 / 3: one rounding


def test_several_bars_with_their_own_materials():
    scene = contactqp.scene_from_dict(two_bars_data())
    steel, aluminium = scene.bars
    assert steel.youngs_modulus.tolist() == [2e11, 2e11]  # the file's [material]
    assert steel.yield_stress == 2.5e8
    assert aluminium.youngs_modulus.tolist() == [7e10, 7e10]  # its own bar.material
    assert aluminium.yield_stress == 1e8


@pytest.mark.parametrize("bar, written", [
    (Bar.uniform(2.5e-4, 7e10, length=0.9, elements=3), ["area = 0.00025", "elements = 3"]),
    # 0.1 × 3 / 3 is not 0.1 in binary: the lengths are written one by one
    (Bar.uniform(2.5e-4, 7e10, lengths=[0.1] * 3), ["area = 0.00025", "lengths = [0.1, "]),
    (Bar.from_section(Rectangle((0.04, 0.02), 0.01), 2e11, length=1.0, elements=5,
                      area_rule="exact"), ["areas = [", "length = 1.0"]),
    (Bar.from_section(HollowCircle(0.05, (0.04, 0.03)), 2e11, length=0.7, elements=3,
                      yield_stress=3e8), ["areas = [", "yield_stress = 300000000.0"]),
], ids=["uniform", "uniform-own-lengths", "rectangle", "tube"])
def test_round_trip_of_each_kind_of_bar(tmp_path: Path, bar, written):
    scene = Scene(bar, (Support(0),), (Load(bar.n_elements, 1e3),),
                  (Wall(bar.n_elements, 1e-4),), name="kind")
    again, text = round_trip(scene, tmp_path)
    assert_same_scene(again, scene)
    for line in written:
        assert line in text


def test_round_trip_of_several_bars_with_their_materials(tmp_path: Path):
    bars = (Bar.from_section(Rectangle((0.04, 0.02), 0.01), 2.1e11, length=0.5, elements=4,
                             area_rule="exact", yield_stress=3.55e8),
            Bar.uniform(2.5e-4, 7e10, length=0.4, elements=2))
    scene = Scene(bars, (Support(0, 0), Support(2, 1)), (Load(4, 6e4, 0),),
                  distributed=(DistributedLoad(-2e3, 1, 0, 1),),
                  contacts=(BarContact(0, 4, 1, 0, 2e-4),), name="strap and rod", units="SI")
    again, text = round_trip(scene, tmp_path)
    assert_same_scene(again, scene)
    assert text.count("[bar.material]") == 2


def code_blocks(language: str) -> list[str]:
    """Every ```language block of docs/scene_files.md."""
    return re.findall(rf"```{language}\n(.*?)```", DOCS.read_text(encoding="utf-8"), re.DOTALL)


def test_every_scene_in_the_scene_file_reference_runs(tmp_path: Path):
    """A block with a support is a whole scene: it loads and solves to a verified answer.
    Other blocks are pieces: each `section = {...}` line makes a bar."""
    scenes = sections = 0
    for i, block in enumerate(code_blocks("toml")):
        if "[[support]]" in block:
            path = tmp_path / f"block{i}.toml"
            path.write_text(block, encoding="utf-8")
            result = contactqp.solve(load_scene(path))
            assert result.verified, (block, result.message)
            scenes += 1
        for line in re.findall(r"^section = .*$", block, re.MULTILINE):
            data = with_value(section_data(), ("bar", "section"),
                              tomllib.loads(line)["section"])
            assert contactqp.scene_from_dict(data).bars[0].n_elements == 2
            sections += 1
    assert scenes >= 2 and sections >= 6  # guard: the page's examples are really read


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


@pytest.mark.parametrize("name", ["bar 🚀", 'quote " and back\\slash', "tab\tnew\nline\x7f\x00",
                                  "é, 中, ∑"])
def test_toml_round_trip_keeps_any_name(tmp_path: Path, name):
    """Characters beyond U+FFFF, quotes, backslashes and control characters come back as they
    went in (JSON's surrogate-pair escape of an emoji is not TOML)."""
    scene = contactqp.default_scene()
    scene = Scene(scene.bars[0], scene.supports, scene.loads, scene.walls, name=name)
    path = tmp_path / "scene.toml"
    path.write_text(contactqp.scene_to_toml(scene), encoding="utf-8")
    assert contactqp.load_scene(path).name == name


def test_a_byte_order_mark_is_read_past(tmp_path: Path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + EXAMPLE_TOML.encode("utf-8"))
    assert contactqp.load_scene(path).name == "my scene"


def test_an_empty_path_says_so():
    with pytest.raises(SceneError, match=r"^scene file path is empty \(''\)$"):
        contactqp.load_scene("")


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


def test_the_python_of_the_scene_file_reference_runs():
    (block,) = code_blocks("python")
    namespace: dict = {}
    exec(block, namespace)  # noqa: S102 - the page's own example
    assert namespace["result"].verified
    # the tube of the page's first scene: λ = F − (EA/L)·gap, A = π(0.040² − 0.030²)/4
    area = math.pi * (0.040**2 - 0.030**2) / 4.0
    assert namespace["result"].contact_force[0] == pytest.approx(
        100e3 - 210e9 * area / 1.0 * 5e-4, rel=1e-12)  # springs in series: round-off only
