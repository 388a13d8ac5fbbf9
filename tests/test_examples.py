"""Every example script in examples/ runs, and one number of each matches a closed form or the
exact reference (as scikit-fem's tests run its examples). The documentation build runs the
same scripts (sphinx-gallery), so a page cannot show an example that this test has not run.

Glossary: k = EA/L the stiffness of a uniform bar; f_i the compliance Σ L/(EA) from the support
to node i; g a gap; λ a contact force; P, F a point load; q a distributed load (N/m).
"""

import math
import runpy
import sys
from pathlib import Path

import numpy as np
import pytest

import contactqp
from closed_forms import DEFAULT_F, DEFAULT_GAP, default_closed_form, default_compliance
from contactqp.reference import reference

EXAMPLES = Path(__file__).parent.parent / "examples"
SCRIPTS = sorted(EXAMPLES.glob("*.py"))


def run(name: str, monkeypatch: pytest.MonkeyPatch) -> dict:
    """Run examples/<name>.py as `python examples/<name>.py` would; its variables."""
    path = EXAMPLES / f"{name}.py"
    monkeypatch.setattr(sys, "argv", [str(path)])  # the scripts find their TOML beside argv[0]
    return runpy.run_path(str(path), run_name="__main__")


def two_springs(force: float, k0: float, k1: float, gap: float) -> float:
    """Two springs across a gap, the first pushed: λ = (F − k₀ g) k₁ / (k₀ + k₁)."""
    return (force - k0 * gap) * k1 / (k0 + k1)


def exact_forces(variables: dict) -> np.ndarray:
    return np.asarray(reference(variables["scene"]).contact_force, dtype=float)


# name -> (expected number from the script's variables, the closed form or exact reference)
# Tolerances: the exact methods are at round-off, 1e-9 relative leaves room for the solves'
# round-off on scenes with stiffnesses up to 1e9 N/m and forces up to 1e6 N.
CHECKS = {
    "course_problem": lambda v: (v["result"].contact_force[0], default_closed_form()[1]),
    "two_bars": lambda v: (v["result"].contact_force[0], two_springs(50e3, 2e8, 5e7, 1e-4)),
    "distributed_load": lambda v: (
        v["result"].contact_force[0],
        (50e3 * 1.0**2 / (2 * 210e9 * 1e-3) - 5e-5) * 210e9 * 1e-3 / 1.0),
    "held_by_contact": lambda v: (v["result"].contact_force[0], 20e3),
    "strap_and_rod": lambda v: (v["result"].contact_force[0], two_springs(
        60e3, 210e9 * 0.010 * 0.020 / (0.5 * math.log(2.0)), 70e9 * 2.5e-4 / 0.4, 2e-4)),
    "several_bars": lambda v: (v["result"].contact_force, exact_forces(v)),
    "wall_at_every_node": lambda v: (v["result"].contact_force, exact_forces(v)),
    "batches": lambda v: (v["batch"].contact_force[:, 0], np.maximum(
        v["loads"] * default_compliance(2) - DEFAULT_GAP, 0.0) / default_compliance(4)),
    "load_path": lambda v: (v["kink"], DEFAULT_GAP / (DEFAULT_F * default_compliance(2))),
    # the bed's closed form at the nodes, u = −τ(x_s − x)²/(2EA), written out here
    "frictional_bed": lambda v: (v["result"].u, -v["TAU"] * np.clip(
        v["F"] / v["TAU"] - v["x"], 0.0, None) ** 2 / (2.0 * v["E"] * v["A"])),
    # the Hertz numbers are checked in tests/test_fem.py; here: another method, same forces
    "hertz_cylinder": lambda v: (v["result"].contact_force, contactqp.solve(
        v["model"].problem, "semismooth_newton").contact_force),
    # Cattaneo's closed forms are checked in tests/test_friction_problem.py; here: another
    # method (the active set on Coulomb's sets), same friction forces at the last shear
    "cattaneo_cylinders": lambda v: (v["result"].friction_force, contactqp.solve(
        v["step"], "semismooth_newton", previous=v["pressed"]).friction_force),
}
NEEDS = {"hertz_cylinder": "skfem", "cattaneo_cylinders": "skfem"}  # optional extras


def test_every_example_is_checked():
    assert sorted(CHECKS) == sorted(path.stem for path in SCRIPTS)


@pytest.mark.parametrize("name", sorted(CHECKS))
def test_example(name: str, monkeypatch: pytest.MonkeyPatch):
    if name in NEEDS:
        pytest.importorskip(NEEDS[name], reason=f"{name} needs {NEEDS[name]}")
    variables = run(name, monkeypatch)
    actual, expected = CHECKS[name](variables)
    scale = np.max(np.abs(expected))
    assert scale > 0  # every check compares a number that is not zero
    np.testing.assert_allclose(actual, expected, rtol=0, atol=1e-9 * scale)


def test_the_tutorial_reproduces_the_penalty_table(monkeypatch: pytest.MonkeyPatch):
    """The tutorial's penalty table: at the textbook ε = 1e14 N/m the penetration is λ/ε, the
    penalty spring in series with the bar: λ_ε = (F f₂ − g)/(f₄ + 1/ε)."""
    variables = run("course_problem", monkeypatch)
    textbook = variables["textbook"]
    expected = default_closed_form(penalty=1e14)[1]
    assert textbook.contact_force[0] == pytest.approx(expected, rel=1e-9)
    assert textbook.penetration[0] == pytest.approx(expected / 1e14, rel=1e-6)
