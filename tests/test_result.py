"""The Result (contactqp.result): its JSON, and the warning of a stress beyond yield.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
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

EXAMPLES_DIR = Path(__file__).parent.parent / "examples"


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


def test_repr_is_one_short_line():
    """method, contact, verdict and the largest force (the closed form, to 10 digits); not the
    1700-character dump of every field and the scene."""
    _, lam = default_closed_form()
    text = repr(contactqp.solve())
    assert "\n" not in text and len(text) < 120
    assert text == (f"<Result lagrange, inequality contact, verified, largest contact force "
                    f"{lam:.10g} N on wall[0]>")
    flagged = repr(contactqp.solve(method="penalty", penalty=1e8))  # ε f ≈ 1.3: far off
    assert "NOT verified" in flagged


def test_summary_says_what_the_check_guarantees():
    result = contactqp.solve()
    _, lam = default_closed_form()
    text = result.summary()
    lines = text.splitlines()
    assert lines[0] == f"scene: {DEFAULT_SCENE.name} (SI)"
    assert len(lines) <= 15 and max(map(len, lines)) <= 110
    assert f"within {result.force_error_bound:.1e} N" in text  # the bound, in words
    assert f"contact forces (N): wall[0] {lam:.10g}" in text
    assert f"support reactions (N): support[0] {-(DEFAULT_F - lam):.10g}" in text
    assert "largest penetration:" in text and "equilibrium" in text
    assert "stress beyond yield" in text


def test_summary_of_a_flagged_answer_gives_the_reason():
    """ε = 1e8 N/m leaves the penalty's force 57 % of λ: the summary says why it is not
    verified (the check's message), not a guarantee it does not have."""
    result = contactqp.solve(method="penalty", penalty=1e8)
    text = result.summary()
    assert "NOT verified: feasibility residual" in text.replace("\n    ", " ")
    assert "within" not in text


def test_summary_counts_the_walls_that_carry_no_force():
    """A wall beside each of 8 nodes, one pushing (the exact reference has one non-zero)."""
    from contactqp.reference import reference

    scene = contactqp.load_scene(EXAMPLES_DIR / "wall_at_every_node.toml")
    exact = reference(scene).contact_force
    pushing = int(np.argmax(exact))
    text = contactqp.solve(scene).summary()
    assert f"wall[{pushing}] {exact[pushing]:.10g}; 7 of 8 carry none" in text
    equality = contactqp.solve(scene, contact="equality").summary()
    assert "non-physical: a contact pulls" in equality


def test_html_repr_is_a_small_escaped_table():
    from html.parser import HTMLParser

    class Cells(HTMLParser):
        def __init__(self):
            super().__init__()
            self.cells, self.rows = [], 0

        def handle_starttag(self, tag, attrs):
            self.rows += tag == "tr"

        def handle_data(self, data):
            self.cells.append(data)

    scene = contactqp.Scene(DEFAULT_SCENE.bars, DEFAULT_SCENE.supports, DEFAULT_SCENE.loads,
                            DEFAULT_SCENE.walls, name="<b>cone</b> & wall")
    parsed = Cells()
    parsed.feed(contactqp.solve(scene)._repr_html_())
    assert 5 <= parsed.rows <= 12
    assert "<b>cone</b> & wall" in parsed.cells  # escaped in the HTML, the name again parsed
    _, lam = default_closed_form()
    assert any(f"{lam:.10g} N" in cell for cell in parsed.cells)
