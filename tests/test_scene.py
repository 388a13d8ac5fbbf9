"""Scenes (contactqp.scene): the bars' arrays, the area rules, and bad scene objects that name the
field and the value.

Every expected number is computed here from the problem statement, never read back from the
library.
"""

from __future__ import annotations

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
from contactqp.scene import DistributedLoad


def cone_compliance_of(length: float, d_start: float, d_end: float, modulus: float) -> float:
    """∫₀ᴸ dx / (E·π·d(x)²/4) for d linear from d_start to d_end (m/N), by quadrature."""
    def compliance_density(x: float) -> float:
        d = d_start + (d_end - d_start) * x / length
        return 1.0 / (modulus * math.pi * d * d / 4.0)

    value, _ = quad(compliance_density, 0.0, length, epsabs=0.0, epsrel=1e-13)
    return value


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
