"""Scenes (contactqp.scene): the bars' arrays, the area rules, and bad scene objects that name the
field and the value.

Every expected number is computed here from the problem statement, never read back from the
library.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import quad

import contactqp
from closed_forms import (
    E_STEEL,
    spring,
    valid_data,
    with_value,
)
from contactqp import (
    Bar,
    BarContact,
    Load,
    Scene,
    SceneError,
    Support,
    Wall,
)
from contactqp.scene import Circle, DistributedLoad, HollowCircle, Rectangle, section_areas


def cone_compliance_of(length: float, d_start: float, d_end: float, modulus: float) -> float:
    """∫₀ᴸ dx / (E·π·d(x)²/4) for d linear from d_start to d_end (m/N), by quadrature."""
    def compliance_density(x: float) -> float:
        d = d_start + (d_end - d_start) * x / length
        return 1.0 / (modulus * math.pi * d * d / 4.0)

    value, _ = quad(compliance_density, 0.0, length, epsabs=0.0, epsrel=1e-13)
    return value


def quad_compliance(area_at, length: float, modulus: float) -> float:
    """∫₀ᴸ dx / (E·A(x)) (m/N) by quadrature, for any section ``area_at(x)`` (m²)."""
    value, _ = quad(lambda x: 1.0 / (modulus * area_at(x)), 0.0, length, epsabs=0.0,
                    epsrel=1e-13)
    return value


def linear(start: float, end: float, length: float):
    """x -> the dimension tapering linearly from ``start`` at 0 to ``end`` at ``length``."""
    return lambda x: start + (end - start) * x / length


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
    (lambda: Bar.from_section(HollowCircle(0.04, 0.05), 2e11, length=1.0, elements=2),
     "bar.section.inner_diameter = 0.05 is not less than outer_diameter = 0.04", None),
    (lambda: Bar.from_section(HollowCircle((0.05, 0.04), 0.04), 2e11, length=1.0, elements=2),
     "bar.section.inner_diameter = 0.04 is not less than outer_diameter_end = 0.04", None),
    (lambda: Bar.from_section(HollowCircle(0.05, (0.0, -0.01)), 2e11, length=1.0, elements=2),
     "bar.section.inner_diameter_end must be >= 0", "-0.01"),
    (lambda: Bar.from_section(Rectangle(0.0, 0.01), 2e11, length=1.0, elements=2),
     "bar.section.width must be > 0", "0.0"),
    (lambda: Bar.from_section(Rectangle((0.02, -1.0), 0.01), 2e11, length=1.0, elements=2),
     "bar.section.width_end must be > 0", "-1.0"),
    (lambda: Bar.from_section(Rectangle(0.02, "1 cm"), 2e11, length=1.0, elements=2),
     "bar.section.height must be a number", "'1 cm'"),
    (lambda: Bar.from_section(Circle((0.04, 0.03, 0.02)), 2e11, length=1.0, elements=2),
     "bar.section.diameter must be one number or a pair (start, end)", "(0.04, 0.03, 0.02)"),
    (lambda: Bar.from_section("circle", 2e11, length=1.0, elements=2),
     "bar.section must be a contactqp.scene.Circle, HollowCircle or Rectangle", "'circle'"),
    (lambda: Bar.from_section(Circle(0.02), 2e11, length=1.0, elements=0), "bar.elements",
     "0"),
    (lambda: Bar.from_section(Circle(0.02), 2e11, length=1.0, elements=2, area_rule="mean"),
     "bar.section.area_rule", "'mean'"),
    (lambda: Bar.uniform(0.0, 2e11, length=1.0, elements=2), "bar.area must be > 0", "0.0"),
    (lambda: Bar.uniform([1e-4], 2e11, length=1.0, elements=2), "bar.area must be a number",
     "[0.0001]"),
    (lambda: Bar.uniform(1e-4, 2e11, length=1.0),
     "bar with one area needs length (m) and elements", "or lengths (m, one per element)"),
    (lambda: Bar.uniform(1e-4, 2e11, lengths=[0.5, -0.5]), "bar.lengths[1]", "-0.5"),
    (lambda: Bar.uniform(1e-4, 2e11, length=1.0, elements=2, name="bar[3]",
                         yield_stress=-1.0), "material.yield_stress", "-1.0"),
    (lambda: Bar.uniform(-1e-4, 2e11, length=1.0, elements=2, name="bar[3]"), "bar[3].area",
     "-0.0001"),
    (lambda: Bar.from_areas([1e-4, 0.0], 2e11, length=1.0, name="bar[2]"), "bar[2].areas[1]",
     "0.0"),
    (lambda: Bar.from_areas([1e-4, 1e-4], 2e11, lengths=[1.0], name="bar[2]"),
     "bar[2].lengths has 1 values but bar[2].areas has 2", None),
    (lambda: Bar.from_areas([], 2e11, length=1.0), "bar must have at least one element", "0"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), ()), "support", None),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(0),), (Load(2, 1.0),)),
     "load[0].node", "2"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(2),)),
     "support[0].node", "2"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(0),),
                   walls=(Wall(3, 0.0, "-"),)), "wall[0].node", "3"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(0),),
                   walls=(Wall(0, 0.0, "+"),)), "wall[0].node", "0"),
    # a table of numbers is refused, not flattened into more elements than were described
    (lambda: Bar.uniform(1e-4, 2e11, lengths=[[0.5, 0.5]]), "bar.lengths must be a flat list",
     "shape (1, 2)"),
    (lambda: Bar.from_areas([1e-4] * 4, np.full((1, 4), 2e11), length=1.0),
     "material.youngs_modulus must be a flat list", "shape (1, 4)"),
    (lambda: Bar.from_areas([[1e-4, 1e-4], [1e-4, 1e-4]], 2e11, length=1.0),
     "bar.areas must be a flat list", "shape (2, 2)"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(0),), units=[]),
     "units must be one of 'SI', 'mm-N-MPa'", "got []"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(0),), units={}),
     "units must be one of 'SI', 'mm-N-MPa'", "got {}"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(0),), name=123),
     "name must be text", "got 123"),
    (lambda: Scene(Bar.from_areas([1e-4], 2e11, length=1.0), (Support(0),), name="\ud800"),
     "name must be text UTF-8 can hold", "'\\ud800'"),
    (lambda: Scene(Bar.from_areas([1e-4] * 4, 2e11, length=1.0), (Support(0),),
                   contacts=(BarContact(0, 1, 0, 3, 0.0),)),
     "contact[0]: bar_a = bar_b = 0; a bar contact joins two different bars", None),
]


def test_scene_errors_name_the_field():
    one, two = spring(1e8), spring(2e8)
    cases = [
        (lambda: Scene((one, two), (Support(0, 0),)), r"support: bar\[1\] has no support"),
        (lambda: Scene((one, two), (Support(0, 0), Support(0, 2))),
         r"support\[1\].bar = 2: the scene has bars 0 to 1"),
        (lambda: Scene((one, two), (Support(0, 0), Support(5, 1))),
         r"support\[1\].node = 5: bar\[1\] has nodes 0 to 1"),
        (lambda: Scene((one, two), (Support(0, 0), Support(1, 1)),
                       contacts=(BarContact(0, 0, 1, 1, 1e-4),)),
         r"contact\[0\]: both nodes are supports"),
        (lambda: Scene((one, two), (Support(0, 0), Support(1, 1)),
                       contacts=(BarContact(0, 1, 1, 0, math.inf),)),
         r"contact\[0\].gap must be finite"),
        (lambda: Scene(one, (Support(0),), distributed=(DistributedLoad(1.0, start=1),)),
         r"distributed_load\[0\]: elements start = 1 to stop = 1"),
        (lambda: Scene(one, (Support(0),), distributed=(DistributedLoad(math.nan),)),
         r"distributed_load\[0\].intensity must be finite"),
        (lambda: Scene((one, "bar"), (Support(0),)), r"bar\[1\] must be a contactqp.Bar"),
    ]
    for build, message in cases:
        with pytest.raises(SceneError, match=message):
            build()


def test_wall_sign_folds_the_side():
    assert Wall(1, 0.0, "+").sign == 1.0
    assert Wall(1, 0.0, "-").sign == -1.0


@pytest.mark.parametrize("d_start, d_end", [(0.040, 0.020), (0.020, 0.040), (0.030, 0.030)])
def test_exact_rule_single_element_has_the_cone_flexibility(d_start, d_end):
    length = 1.0
    bar = Bar.tapered_circle(length, 1, d_start, d_end, E_STEEL, area_rule="exact")
    flexibility = bar.lengths[0] / (bar.youngs_modulus[0] * bar.areas[0])
    # quad on a smooth rational integrand converges to ~1e-15; the closed form is exact
    assert flexibility == pytest.approx(cone_compliance_of(length, d_start, d_end, E_STEEL), rel=1e-12)


@pytest.mark.parametrize("elements", [1, 3, 4, 17])
def test_exact_rule_areas_and_total_flexibility(elements):
    d = np.linspace(0.040, 0.020, elements + 1)
    bar = Bar.tapered_circle(2.0, elements, 0.040, 0.020, E_STEEL, area_rule="exact")
    # same product π d_a d_b / 4 of the same diameters: a few ulp
    np.testing.assert_allclose(bar.areas, math.pi * d[:-1] * d[1:] / 4.0, rtol=1e-14)
    total = float(np.sum(bar.lengths / (bar.youngs_modulus * bar.areas)))
    # every element is exact, so the sum is the cone's integral up to summation round-off
    assert total == pytest.approx(cone_compliance_of(2.0, 0.040, 0.020, E_STEEL), rel=1e-12)


def test_midpoint_rule_is_stiffer_and_converges_at_second_order():
    cone = cone_compliance_of(1.0, 0.040, 0.020, E_STEEL)
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


def test_wall_on_a_supported_node_says_so():
    with pytest.raises(SceneError, match=r"wall\[0\]\.node = 0 is support\[0\]"):
        contactqp.scene_from_dict(with_value(valid_data(), ("wall", 0, "node"), 0))


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


def test_scene_error_is_a_value_error_and_a_contactqp_error():
    assert issubclass(SceneError, ValueError)
    assert issubclass(SceneError, contactqp.ContactqpError)


# --- sections: element areas and stiffnesses against closed forms written here. Glossary:
# w, h a rectangle's width and height, D, d a tube's outer and inner diameter (m), n the
# number of equal elements of length l = L/n, k_e = E·A_e/l an element's stiffness (N/m).
@pytest.mark.parametrize("elements", [1, 3, 8])
def test_exact_rectangle_tapered_in_width_has_the_closed_form_stiffness(elements):
    length, h, w0, w1 = 0.5, 0.01, 0.040, 0.020
    bar = Bar.from_section(Rectangle((w0, w1), h), E_STEEL, length=length, elements=elements,
                           area_rule="exact")
    w = [w0 + (w1 - w0) * e / elements for e in range(elements + 1)]
    piece = length / elements
    # ∫ dx/(E h w(x)) over an element = l·ln(w_b/w_a)/(E h (w_b − w_a)): its inverse
    closed = [E_STEEL * h * (wb - wa) / (piece * math.log(wb / wa))
              for wa, wb in itertools.pairwise(w)]
    # the library writes the log mean through log1p, the closed form through log: a few ulp
    np.testing.assert_allclose(bar.element_stiffness, closed, rtol=1e-13)


@pytest.mark.parametrize("section, area_at", [
    (Rectangle((0.040, 0.020), (0.010, 0.030)),
     lambda x: linear(0.040, 0.020, 2.0)(x) * linear(0.010, 0.030, 2.0)(x)),
    (Rectangle(0.030, (0.012, 0.004)),
     lambda x: 0.030 * linear(0.012, 0.004, 2.0)(x)),
    (HollowCircle((0.050, 0.030), (0.040, 0.010)),
     lambda x: math.pi * (linear(0.050, 0.030, 2.0)(x) ** 2
                          - linear(0.040, 0.010, 2.0)(x) ** 2) / 4.0),
    (HollowCircle(0.050, (0.048, 0.0)),
     lambda x: math.pi * (0.050**2 - linear(0.048, 0.0, 2.0)(x) ** 2) / 4.0),
    (Circle((0.020, 0.060)), lambda x: math.pi * linear(0.020, 0.060, 2.0)(x) ** 2 / 4.0),
], ids=["rectangle-both", "rectangle-height", "tube-both", "tube-to-solid", "circle"])
@pytest.mark.parametrize("elements", [1, 5])
def test_exact_rule_gives_every_element_the_compliance_of_its_taper(section, area_at,
                                                                      elements):
    bar = Bar.from_section(section, E_STEEL, length=2.0, elements=elements, area_rule="exact")
    edges = np.linspace(0.0, 2.0, elements + 1)
    for e, (a, b) in enumerate(itertools.pairwise(edges)):
        piece, _ = quad(lambda x: 1.0 / (E_STEEL * area_at(x)), a, b, epsabs=0.0,
                        epsrel=1e-13)
        # quad on a smooth rational integrand: ~1e-15; a thin wall (48 of 50 mm) costs the
        # closed form D² − d² a few more digits, still far inside 1e-11
        assert 1.0 / bar.element_stiffness[e] == pytest.approx(piece, rel=1e-11)
    assert bar.compliance[-1] == pytest.approx(quad_compliance(area_at, 2.0, E_STEEL),
                                               rel=1e-11)


@pytest.mark.parametrize("section, area_at", [
    (Rectangle((0.040, 0.020), (0.010, 0.030)),
     lambda x: linear(0.040, 0.020, 1.0)(x) * linear(0.010, 0.030, 1.0)(x)),
    (HollowCircle((0.050, 0.030), (0.040, 0.010)),
     lambda x: math.pi * (linear(0.050, 0.030, 1.0)(x) ** 2
                          - linear(0.040, 0.010, 1.0)(x) ** 2) / 4.0),
    (Circle((0.040, 0.020)), lambda x: math.pi * linear(0.040, 0.020, 1.0)(x) ** 2 / 4.0),
], ids=["rectangle", "tube", "circle"])
def test_midpoint_rule_takes_the_section_at_mid_element(section, area_at):
    bar = Bar.from_section(section, E_STEEL, length=1.0, elements=4, area_rule="midpoint")
    # the library forms c·p·q with p, q the linear factors, here w·h and D² − d²: a few ulp
    np.testing.assert_allclose(bar.areas, [area_at(x) for x in (0.125, 0.375, 0.625, 0.875)],
                               rtol=1e-14)


@pytest.mark.parametrize("rule", ["midpoint", "exact"])
def test_uniform_sections_give_their_one_area_by_either_rule(rule):
    cases = [(Circle(0.02), math.pi * 0.02**2 / 4.0), (Rectangle(0.03, 0.01), 0.03 * 0.01),
             (HollowCircle(0.05, 0.04), math.pi * (0.05**2 - 0.04**2) / 4.0)]
    for section, area in cases:
        # π/4·(D − d)(D + d) against π/4·(D² − d²), rounded apart: a few ulp
        np.testing.assert_allclose(section_areas(section, 3, rule), [area] * 3, rtol=1e-14)


def test_a_tube_without_a_hole_is_the_circle():
    solid = Bar.from_section(HollowCircle((0.04, 0.02), 0.0), E_STEEL, length=1.0,
                             elements=4, area_rule="exact")
    d = np.linspace(0.04, 0.02, 5)
    np.testing.assert_allclose(solid.areas, math.pi * d[:-1] * d[1:] / 4.0, rtol=1e-14)


def test_uniform_bar_tip_moves_f_l_over_e_a():
    force, length, area = 3e4, 1.5, 2.5e-4
    bar = Bar.uniform(area, 7e10, length=length, elements=6)
    assert bar.areas.tolist() == [area] * 6
    assert bar.lengths.sum() == pytest.approx(length, rel=1e-15)
    result = contactqp.solve(Scene(bar, (Support(0),), (Load(6, force),)))
    # a free bar: u_tip = F L / (E A) = 2.571 mm, and u at node j is j/6 of it
    tip = force * length / (7e10 * area)
    np.testing.assert_allclose(result.u, tip * np.arange(7) / 6, rtol=1e-13, atol=1e-20)


def test_uniform_bar_with_its_own_element_lengths():
    bar = Bar.uniform(1e-4, E_STEEL, lengths=[0.2, 0.3, 0.5])
    assert bar.areas.tolist() == [1e-4] * 3
    np.testing.assert_allclose(bar.element_stiffness, E_STEEL * 1e-4 / np.array([0.2, 0.3, 0.5]),
                               rtol=1e-15)


def test_tapered_circle_is_the_circle_section():
    tapered = Bar.tapered_circle(1.0, 4, 0.04, 0.02, E_STEEL, area_rule="exact")
    section = Bar.from_section(Circle((0.04, 0.02)), E_STEEL, length=1.0, elements=4,
                               area_rule="exact")
    assert tapered.areas.tolist() == section.areas.tolist()
