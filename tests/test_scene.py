"""Scenes: the seed scene's numbers, the two area rules, TOML in and out, and bad input.

Every expected number is computed here from the problem statement (diameters, lengths, the
cone's flexibility by quadrature), never read back from the library.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

import contactqp
from contactqp import Bar, Load, Scene, SceneError, Support, Wall

E_STEEL = 210e9  # Pa
SEED_DIAMETERS_MM = [40.0, 35.0, 30.0, 25.0, 20.0]  # at nodes 0..4 of the seed scene

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


def cone_flexibility(length: float, d_start: float, d_end: float, modulus: float) -> float:
    """∫₀ᴸ dx / (E·π·d(x)²/4) for d linear from d_start to d_end (m/N), by quadrature."""
    def compliance_density(x: float) -> float:
        d = d_start + (d_end - d_start) * x / length
        return 1.0 / (modulus * math.pi * d * d / 4.0)

    value, _ = quad(compliance_density, 0.0, length, epsabs=0.0, epsrel=1e-13)
    return value


def assert_same_scene(a: Scene, b: Scene) -> None:
    """Two scenes hold the same data, bit for bit (repr of a float round-trips exactly)."""
    assert a.bar.lengths.tolist() == b.bar.lengths.tolist()
    assert a.bar.areas.tolist() == b.bar.areas.tolist()
    assert a.bar.youngs_modulus.tolist() == b.bar.youngs_modulus.tolist()
    assert a.bar.yield_stress == b.bar.yield_stress
    assert a.supports == b.supports
    assert a.loads == b.loads
    assert a.walls == b.walls
    assert a.name == b.name


# --------------------------------------------------------------------------------------------
# The seed scene


def test_seed_scene_numbers():
    scene = contactqp.seed_scene()
    d_nodes = np.array(SEED_DIAMETERS_MM) / 1000.0
    d_mid = (d_nodes[:-1] + d_nodes[1:]) / 2.0  # 37.5, 32.5, 27.5, 22.5 mm
    areas = math.pi * d_mid**2 / 4.0
    # same formula, diameters rounded differently (linspace vs literals): a few ulp
    np.testing.assert_allclose(scene.bar.areas, areas, rtol=1e-14)
    # 0.25 m and its multiples are exact in binary, so equality is exact
    assert scene.bar.lengths.tolist() == [0.25] * 4
    assert scene.bar.node_x.tolist() == [0.0, 0.25, 0.5, 0.75, 1.0]
    assert scene.bar.youngs_modulus.tolist() == [E_STEEL] * 4
    assert scene.bar.yield_stress == 200e6
    assert scene.n_nodes == 5
    # k = E A / L; one multiplication and division of the same operands: a few ulp
    np.testing.assert_allclose(scene.bar.stiffness, E_STEEL * areas / 0.25, rtol=1e-14)
    assert scene.supports == (Support(0),)
    assert scene.loads == (Load(2, 565486.67),)
    assert scene.walls == (Wall(4, 1e-4, "+"),)
    assert scene.nodal_loads().tolist() == [0.0, 0.0, 565486.67, 0.0, 0.0]


@pytest.mark.parametrize("elements", [2, 8, 64])
@pytest.mark.parametrize("area_rule", ["midpoint", "exact"])
def test_seed_scene_remeshed(elements, area_rule):
    scene = contactqp.seed_scene(elements, area_rule)
    d = 0.040 - 0.020 * np.arange(elements + 1) / elements  # diameter at every node (m)
    if area_rule == "midpoint":
        areas = math.pi * ((d[:-1] + d[1:]) / 2.0) ** 2 / 4.0
    else:
        areas = math.pi * d[:-1] * d[1:] / 4.0
    # same formulas, diameters rounded differently (linspace vs this line): a few ulp
    np.testing.assert_allclose(scene.bar.areas, areas, rtol=1e-14)
    # lengths 1/elements: the same division either way, or exact for powers of two
    np.testing.assert_allclose(scene.bar.lengths, 1.0 / elements, rtol=1e-15)
    assert scene.loads == (Load(elements // 2, 565486.67),)  # still at mid-length
    assert scene.walls == (Wall(elements, 1e-4, "+"),)  # still beyond the tip


@pytest.mark.parametrize("elements", [0, 3, 2.0, True])
def test_seed_scene_needs_an_even_number_of_elements(elements):
    with pytest.raises(SceneError, match=r"elements.*got"):
        contactqp.seed_scene(elements)


def test_wall_sign_folds_the_side():
    assert Wall(1, 0.0, "+").sign == 1.0
    assert Wall(1, 0.0, "-").sign == -1.0


# --------------------------------------------------------------------------------------------
# Area rules


@pytest.mark.parametrize("d_start, d_end", [(0.040, 0.020), (0.020, 0.040), (0.030, 0.030)])
def test_exact_rule_single_element_has_the_cone_flexibility(d_start, d_end):
    length = 1.0
    bar = Bar.tapered_circle(length, 1, d_start, d_end, E_STEEL, area_rule="exact")
    flexibility = bar.lengths[0] / (bar.youngs_modulus[0] * bar.areas[0])
    # quad on a smooth rational integrand converges to ~1e-15; the closed form is exact
    assert flexibility == pytest.approx(cone_flexibility(length, d_start, d_end, E_STEEL), rel=1e-12)


@pytest.mark.parametrize("elements", [1, 3, 4, 17])
def test_exact_rule_areas_and_total_flexibility(elements):
    d = np.linspace(0.040, 0.020, elements + 1)
    bar = Bar.tapered_circle(2.0, elements, 0.040, 0.020, E_STEEL, area_rule="exact")
    # same product π d_a d_b / 4 of the same diameters: a few ulp
    np.testing.assert_allclose(bar.areas, math.pi * d[:-1] * d[1:] / 4.0, rtol=1e-14)
    total = float(np.sum(bar.lengths / (bar.youngs_modulus * bar.areas)))
    # every element is exact, so the sum is the cone's integral up to summation round-off
    assert total == pytest.approx(cone_flexibility(2.0, 0.040, 0.020, E_STEEL), rel=1e-12)


def test_midpoint_rule_is_stiffer_and_converges_at_second_order():
    cone = cone_flexibility(1.0, 0.040, 0.020, E_STEEL)
    errors = []
    for elements in (4, 8, 16):
        bar = Bar.tapered_circle(1.0, elements, 0.040, 0.020, E_STEEL, area_rule="midpoint")
        d = np.linspace(0.040, 0.020, elements + 1)
        d_mid = (d[:-1] + d[1:]) / 2.0
        # same formula π d_mid² / 4: a few ulp
        np.testing.assert_allclose(bar.areas, math.pi * d_mid**2 / 4.0, rtol=1e-14)
        flexibility = float(np.sum(bar.lengths / (bar.youngs_modulus * bar.areas)))
        errors.append(cone - flexibility)
    # d_mid² >= d_a d_b (AM-GM): the midpoint area is larger, the bar stiffer than the cone
    assert all(error > 0.0 for error in errors)
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    # an O(h²) error quarters when h halves; the O(h⁴) remainder moves the ratio by < 5 %
    assert ratios == pytest.approx([4.0, 4.0], rel=0.05)


def test_unknown_area_rule_is_a_scene_error():
    with pytest.raises(SceneError, match=r"area_rule.*'trapezoid'"):
        Bar.tapered_circle(1.0, 2, 0.04, 0.02, E_STEEL, area_rule="trapezoid")


# --------------------------------------------------------------------------------------------
# TOML


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


@pytest.mark.parametrize("make_scene", [contactqp.seed_scene, two_sided_scene])
def test_toml_round_trip(tmp_path: Path, make_scene):
    scene = make_scene()
    path = tmp_path / "scene.toml"
    path.write_text(contactqp.scene_to_toml(scene), encoding="utf-8")
    assert_same_scene(contactqp.load_scene(path), scene)


def test_toml_round_trip_keeps_a_name_with_an_apostrophe(tmp_path: Path):
    scene = contactqp.seed_scene()
    scene = Scene(scene.bar, scene.supports, scene.loads, scene.walls, name="O'Brien's bar")
    path = tmp_path / "scene.toml"
    path.write_text(contactqp.scene_to_toml(scene), encoding="utf-8")
    assert_same_scene(contactqp.load_scene(path), scene)


def test_example_toml_file_is_the_seed_scene(tmp_path: Path):
    path = tmp_path / "seed.toml"
    path.write_text(EXAMPLE_TOML, encoding="utf-8")
    scene = contactqp.load_scene(path)
    seed = contactqp.seed_scene()
    assert scene.name == "my scene"
    assert scene.bar.lengths.tolist() == seed.bar.lengths.tolist()
    # the same diameters go through the same formula: bit-for-bit equal areas expected
    assert scene.bar.areas.tolist() == seed.bar.areas.tolist()
    assert scene.bar.yield_stress == 200e6
    assert (scene.supports, scene.loads, scene.walls) == (seed.supports, seed.loads, seed.walls)


def test_example_toml_file_with_the_exact_rule(tmp_path: Path):
    path = tmp_path / "exact.toml"
    path.write_text(EXAMPLE_TOML.replace('"midpoint"', '"exact"'), encoding="utf-8")
    scene = contactqp.load_scene(path)
    d = np.array(SEED_DIAMETERS_MM) / 1000.0
    # π d_a d_b / 4 with diameters rounded differently (linspace vs literals): a few ulp
    np.testing.assert_allclose(scene.bar.areas, math.pi * d[:-1] * d[1:] / 4.0, rtol=1e-14)


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
    assert scene.bar.areas.tolist() == [2e-4, 1e-4]
    assert scene.bar.lengths.tolist() == [0.5, 1.5]
    assert scene.bar.youngs_modulus.tolist() == [7e10, 7e10]
    assert scene.bar.yield_stress is None
    assert scene.supports == (Support(2),)
    assert scene.loads == (Load(0, -1000.0),)
    assert scene.walls == (Wall(1, 0.0, "+"),)  # side defaults to "+"


def test_toml_with_one_length_splits_it_equally():
    data = {"material": {"youngs_modulus": 2e11}, "bar": {"areas": [1e-4] * 4, "length": 2.0},
            "support": [{"node": 0}]}
    assert contactqp.scene_from_dict(data).bar.lengths.tolist() == [0.5] * 4  # exact in binary


# --------------------------------------------------------------------------------------------
# Bad input: the message names the field and the value


def valid_data() -> dict:
    """A valid scene as the parsed TOML structure: 2 elements, nodes 0, 1, 2."""
    return {
        "name": "valid",
        "material": {"youngs_modulus": 2e11, "yield_stress": 2.5e8},
        "bar": {"areas": [1e-4, 2e-4], "length": 1.0},
        "support": [{"node": 0}],
        "load": [{"node": 2, "force": 1e3}],
        "wall": [{"node": 2, "gap": 1e-4, "side": "+"}],
    }


def section_data() -> dict:
    """The same with a tapered circular section instead of explicit areas."""
    data = valid_data()
    data["bar"] = {"length": 1.0, "elements": 2,
                   "section": {"shape": "circle", "diameter_start": 0.02, "diameter_end": 0.01}}
    return data


def with_value(data: dict, path: tuple, value) -> dict:
    """A deep copy of ``data`` with the item at ``path`` (keys and list indices) set."""
    data = copy.deepcopy(data)
    target = data
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
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


def test_wall_on_a_supported_node_says_so():
    with pytest.raises(SceneError, match=r"wall\[0\]\.node = 0 is support\[0\]"):
        contactqp.scene_from_dict(with_value(valid_data(), ("wall", 0, "node"), 0))


BAD_OBJECTS = [
    (lambda: Bar.from_areas([1e-4], 0.0, length=1.0), "material.youngs_modulus", "0.0"),
    (lambda: Bar.from_areas([1e-4], -2e11, length=1.0), "material.youngs_modulus",
     "-200000000000.0"),
    (lambda: Bar.from_areas([1e-4], math.nan, length=1.0), "material.youngs_modulus", "nan"),
    (lambda: Bar.from_areas([1e-4], math.inf, length=1.0), "material.youngs_modulus", "inf"),
    (lambda: Bar.from_areas([1e-4, 0.0], 2e11, length=1.0), "bar.areas[1]", "0.0"),
    (lambda: Bar.from_areas([-1e-4], 2e11, length=1.0), "bar.areas[0]", "-0.0001"),
    (lambda: Bar.from_areas([math.nan], 2e11, length=1.0), "bar.areas[0]", "nan"),
    (lambda: Bar.from_areas([math.inf], 2e11, length=1.0), "bar.areas[0]", "inf"),
    (lambda: Bar.from_areas([1e-4], 2e11, length=0.0), "bar.length", "0.0"),
    (lambda: Bar.from_areas([1e-4], 2e11, length=-2.0), "bar.length", "-2.0"),
    (lambda: Bar.from_areas([1e-4], 2e11, length=math.nan), "bar.length", "nan"),
    (lambda: Bar.from_areas([1e-4], 2e11, length=math.inf), "bar.length", "inf"),
    (lambda: Bar.from_areas([1e-4, 1e-4], 2e11, lengths=[1.0, 0.0]), "bar.lengths[1]", "0.0"),
    (lambda: Bar.from_areas([1e-4], 2e11, lengths=[math.nan]), "bar.lengths[0]", "nan"),
    (lambda: Bar.tapered_circle(1.0, 2, 0.0, 0.01, 2e11), "bar.section.diameter_start", "0.0"),
    (lambda: Bar.tapered_circle(math.inf, 2, 0.02, 0.01, 2e11), "bar.length", "inf"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), ()), "support", None),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(0),), (Load(2, 1.0),)),
     "load[0].node", "2"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(2),)),
     "support[0].node", "2"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(0),),
                   walls=(Wall(3, 0.0, "-"),)), "wall[0].node", "3"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(0),),
                   walls=(Wall(0, 0.0, "+"),)), "wall[0].node", "0"),
]


@pytest.mark.parametrize("build, field, shown", BAD_OBJECTS,
                         ids=[f"{field}-{i}" for i, (_, field, _) in enumerate(BAD_OBJECTS)])
def test_bad_scene_objects_name_field_and_value(build, field, shown):
    with pytest.raises(SceneError) as caught:
        build()
    message = str(caught.value)
    assert field in message
    if shown is not None:
        assert shown in message


def test_bad_array_value_is_shown_as_the_user_wrote_it():
    with pytest.raises(SceneError) as caught:
        Bar.from_areas([0.0], 2e11, length=1.0)
    assert str(caught.value).endswith("got 0.0")


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


def test_scene_error_is_a_value_error_and_a_contactqp_error():
    assert issubclass(SceneError, ValueError)
    assert issubclass(SceneError, contactqp.ContactqpError)
