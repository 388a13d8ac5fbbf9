"""Load paths with friction (contactqp.load_path on a problem with T, or a scene on a bed):
each step an increment from the state the step before reached, against closed forms.

Glossary: K stiffness, f load, C u ≤ g the normal rows, T the tangential rows, μ Coulomb's
coefficient, s Tresca's slip bound, t the load factor (0 to 1), λ_N ≥ 0 the normal and λ_T
the friction force, x_s = F/τ the slip length of a bar pulled by F on a bed of limit τ per
length.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import contactqp
from contactqp.cli import main

K_NODE = 10.0  # one node (u_t, u_n) on springs k in both directions, on the flat u_n ≥ 0
ON_FLAT = {"C": [[0.0, -1.0]], "g": [0.0], "T": [[1.0, 0.0]]}
E, A, L, ELEMENTS, TAU = 2e11, 1e-4, 1.0, 40, 4e4


@pytest.mark.parametrize("method", ["lagrange", "augmented", "qp"])
@pytest.mark.parametrize("pull", [0.3, 0.8])
def test_proportional_coulomb_path_on_a_node(method, pull):
    """Pressed by P = 1 and pulled by Q, both ramped by t (μ = ½). Q < μP: it sticks at every
    step (Mindlin and Deresiewicz: proportional loading below μ never slips), u = 0, λ_T = tQ,
    λ_N = tP. Q > μP: it slides on the flat from the first step, u_t = t(Q − μP)/k,
    λ_T = μtP (by hand). Every step past the unloaded one is verified. Each step's bound is
    on the exact increment from the state the step before reached (its slip is measured from
    that u, errors and all), so along the path the errors add up: step j is within the sum of
    the bounds of steps 1 … j (measured: Clarabel's 1e-11 at a step carried into the next)."""
    problem = contactqp.Problem(K_NODE * np.eye(2), [pull, -1.0], **ON_FLAT, mu=0.5)
    path = contactqp.load_path(problem, steps=5, methods={method: (method, "inequality", {})})
    assert not path.failed
    curve = path.methods[method]
    t = path.load_factor
    sticks = pull < 0.5
    u_t = np.zeros_like(t) if sticks else t * (pull - 0.5) / K_NODE
    friction = t * (pull if sticks else 0.5)
    assert curve.friction_force.shape == (t.size, 1, 1)
    moved = forced = 0.0  # the bounds of the steps so far, added
    for step in range(1, t.size):
        result = curve.results[step]
        assert result.verified, (step, result.message)
        moved += result.displacement_error_bound
        forced += result.force_error_bound
        assert abs(result.u[0] - u_t[step]) <= moved + 1e-15
        assert abs(result.u[1]) <= moved + 1e-15
        assert abs(curve.friction_force[step, 0, 0] - friction[step]) <= forced + 1e-12
        assert abs(curve.contact_force[step, 0] - t[step]) <= forced + 1e-12
        assert list(result.state) == ["stick" if sticks else "slip"]


def test_the_slip_of_a_step_is_measured_from_the_step_before():
    """Tresca s = 2 on the node, not pressed: pulled by t·3 with t = 0, ½, 1. Step ½ holds
    (1.5 < s: u = 0); step 1 slips by (3 − 2)/k = 0.1 from there. Solved at t = 1 from rest
    it is the same (a monotone path); but a path that pulls to 3 and back to 1.5 stays where
    the pull left it (1.5 < s sticks: u_t = 0.1), where a solve from rest at 1.5 gives 0."""
    problem = contactqp.Problem(K_NODE * np.eye(2), [3.0, 0.0], **ON_FLAT, slip_bound=2.0)
    path = contactqp.load_path(problem, steps=3, methods={"exact": ("lagrange", "inequality",
                                                                    {})})
    curve = path.methods["exact"]
    np.testing.assert_allclose([r.u[0] for r in curve.results], [0.0, 0.0, 0.1], atol=1e-14)
    back = contactqp.solve(problem.with_values(f=[1.5, 0.0]), previous=curve.results[-1])
    assert back.verified and back.u[0] == pytest.approx(0.1, abs=1e-14)
    assert contactqp.solve(problem.with_values(f=[1.5, 0.0])).u[0] == pytest.approx(0.0,
                                                                                  abs=1e-14)


def bed_scene(force: float) -> contactqp.Scene:
    bar = contactqp.Bar.uniform(A, E, length=L, elements=ELEMENTS)
    return contactqp.Scene(bar, (contactqp.Support(ELEMENTS),), (contactqp.Load(0, -force),),
                           beds=(contactqp.Bed(TAU),), name="bed")


def test_a_bar_on_its_bed_stepped_meets_the_closed_form_at_every_step():
    """The bar pulled by t·F (F = 0.8 τL) on its bed, t = 0, ¼, ½, ¾, 1: at t = ½ and 1 x_s =
    tF/τ falls on a node and u = −τ(x_s − x)²/(2EA) at every node (the closed form written
    out here); the slip zone only grows, so each step's answer is the one-shot answer at its
    load (another route: no previous state), within the bounds both state."""
    force = 0.8 * TAU * L
    path = contactqp.load_path(bed_scene(force), steps=5,
                               methods={"exact": ("lagrange", "inequality", {})})
    curve = path.methods["exact"]
    x = np.linspace(0.0, L, ELEMENTS + 1)
    for t, result in zip(path.load_factor[1:], curve.results[1:]):
        assert result.verified, result.message
        alone = contactqp.solve(bed_scene(t * force))
        reach = result.displacement_error_bound + alone.displacement_error_bound
        assert np.abs(result.u - alone.u).max() <= reach + 1e-18
        if t in (0.5, 1.0):
            exact = -TAU * np.clip(t * force / TAU - x, 0.0, None) ** 2 / (2.0 * E * A)
            assert np.abs(result.u - exact).max() <= 1e-9 * np.abs(exact).max()
    assert curve.friction_force.shape == (5, ELEMENTS + 1, 1)


def test_the_cli_curve_on_a_bed_scene(tmp_path, capsys):
    """`contactqp curve` on the bed example: the table without a first-contact line (no
    closed form with friction), and its JSON with each method's friction forces."""
    scene = Path(__file__).parent.parent / "examples" / "bar_on_bed.toml"
    assert main(["curve", str(scene), "--steps", "3", "--no-charts"]) == 0
    out = capsys.readouterr().out
    assert "each step an increment from the last" in out and "first contact" not in out
    assert main(["curve", str(scene), "--steps", "3", "--json"]) == 0
    found = json.loads(capsys.readouterr().out)
    assert set(found["methods"]) == set(contactqp.curve.FRICTION_CURVE_METHODS)
    for curve in found["methods"].values():
        assert len(curve["friction_force"]) == 3 and any(curve["verified"])
