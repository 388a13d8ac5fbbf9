"""The Result (contactqp.result): its JSON, and the warning of a stress beyond yield.
"""

from __future__ import annotations

import json
import math

import pytest

import contactqp
from closed_forms import (
    DEFAULT_F,
    DEFAULT_SCENE,
    DEFAULT_YIELD,
    assert_normwise,
    default_areas,
    default_closed_form,
    hand_scene,
)


@pytest.mark.parametrize("method", ["lagrange", "penalty"])
@pytest.mark.parametrize("contact", ["inequality", "equality"])
def test_result_to_json(method, contact):
    result = contactqp.solve(hand_scene(), method, contact)
    data = json.loads(result.to_json())
    for key in ("u", "contact_force", "reactions", "penetration", "verified", "residuals",
                "method", "time"):
        assert key in data
    assert data["method"] == method
    assert data["contact"] == contact
    assert data["u"] == result.u.tolist()  # JSON round-trips a float exactly
    assert data["contact_force"] == result.contact_force.tolist()
    assert data["reactions"] == result.reactions.tolist()
    assert data["penetration"] == result.penetration.tolist()
    assert data["verified"] is result.verified is True
    assert set(data["residuals"]) == {"equilibrium", "feasibility", "complementarity", "sign",
                                      "force", "displacement", "natural_map"}
    assert data["force_error_bound"] == result.force_error_bound
    if contact == "equality":
        assert data["residuals"]["complementarity"] is None
        assert data["residuals"]["natural_map"] is None
    assert isinstance(data["time"], float) and data["time"] >= 0.0
    assert data == result.to_dict()


def test_seed_scene_warns_of_stress_beyond_yield():
    result = contactqp.solve()
    _, lam = default_closed_form()
    areas = default_areas("midpoint")
    # elements 0 and 1 carry F − λ in tension, 2 and 3 carry λ in compression
    forces = [DEFAULT_F - lam, DEFAULT_F - lam, -lam, -lam]
    stress = [force / area for force, area in zip(forces, areas)]
    worst = max(range(4), key=lambda e: abs(stress[e]))
    ratio = abs(stress[worst]) / DEFAULT_YIELD
    assert ratio > 1.0
    # κ(K) ~ 10 on four elements: a direct solve is exact to ~1e-15
    assert_normwise(result.stress, stress, rel=1e-12)
    assert result.stress_ratio == pytest.approx(ratio, rel=1e-12)  # as above
    assert len(result.warnings) == 1
    warning = result.warnings[0]
    assert "yield" in warning
    assert f"element {worst}" in warning
    assert f"{stress[worst] / 1e6:.1f} MPa" in warning
    assert result.verified  # a warning is not a failed check


def test_the_yield_check_works_in_both_unit_systems():
    """Element 1 carries F − λ (the wall takes λ, the support the rest) over its mid-length
    circle of 32.5 mm: 469.7 MPa against 200 MPa, in both unit systems."""
    E, F, gap = 210e9, 565486.67, 1e-4
    flexibility = [0.25 / (E * math.pi * d**2 / 4) for d in (0.0375, 0.0325, 0.0275, 0.0225)]
    lam = (F * sum(flexibility[:2]) - gap) / sum(flexibility)
    stress = (F - lam) / (math.pi * 0.0325**2 / 4)  # Pa
    for units in ("SI", "mm-N-MPa"):
        result = contactqp.solve(contactqp.convert_units(DEFAULT_SCENE, units))
        warning = next(w for w in result.warnings if w.startswith("stress beyond yield"))
        assert f"element 1 carries {stress / 1e6:.1f} MPa" in warning, warning
        assert result.stress_ratio == pytest.approx(stress / 200e6, rel=1e-12)  # ulps
