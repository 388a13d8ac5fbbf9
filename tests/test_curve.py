"""Load stepping (contactqp.curve): the force-displacement curve's kink at the closed-form load
factor, and each step the same as a separate solve.
"""

from __future__ import annotations

import numpy as np
import pytest

import contactqp
from closed_forms import (
    EXAMPLES,
)
from contactqp.curve import first_contact_factor, load_path
from contactqp.scene_io import load_scene


def test_load_path_kink_at_the_closed_form_load():
    """Default scene: the tip moves as node 2 does (nothing loads the elements past it), so the
    wall is reached at t* = g / (F Σ_{e<2} L_e/(E A_e)), areas at the mid-length diameters."""
    L_e, F, g = 0.25, 565486.67, 1e-4
    diameters = 0.040 - 0.020 * (np.array([0.5, 1.5]) * L_e)  # mid-length of elements 0 and 1
    flexibility = np.sum(L_e / (210e9 * np.pi * diameters**2 / 4))
    t_star = g / (F * flexibility)
    assert first_contact_factor(contactqp.default_scene()) == pytest.approx(t_star, rel=1e-12)
    path = load_path(steps=41)
    t = path.load_factor
    assert t[0] == 0.0 and t[-1] == 1.0 and t.size == 41
    for name in ("lagrange", "penalty", "augmented", "qp", "soft penalty"):
        curve = path.methods[name]
        before, after = t < t_star - 1e-9, t > t_star + 1e-9
        # before the kink: no contact force, u = t F φ₂; after: the wall pushes
        assert np.all(curve.contact_force[before, 0] == pytest.approx(0.0, abs=1e-6 * F))
        assert curve.load_point_displacement[before] == pytest.approx(t[before] * F * flexibility,
                                                                      rel=1e-7, abs=1e-12)
        assert np.all(curve.contact_force[after, 0] > 0)
        # the two straight branches meet at t*
        slope, intercept = np.polyfit(t[after], curve.load_point_displacement[after], 1)
        kink = intercept / (F * flexibility - slope)
        assert kink == pytest.approx(t_star, rel=1e-6), name
    equality = path.methods["equality"]
    assert np.all(equality.contact_force[t < t_star - 1e-9, 0] < 0)  # the textbook wall pulls
    assert not equality.physical[0] and equality.physical[-1]
    assert path.methods["soft penalty"].penetration[-1, 0] > 1e-5  # it shows: λ/ε is large
    assert [r.info["cache"] for r in path.methods["qp"].results[2:]] == ["hit"] * 39


def test_load_path_steps_match_separate_solves():
    scene = load_scene(next(p for p in EXAMPLES if p.stem == "several_bars"))
    path = load_path(scene, steps=5, methods={"lagrange": ("lagrange", "inequality", {})})
    for t, result in zip(path.load_factor, path.methods["lagrange"].results):
        alone = contactqp.solve(scene.scaled_loads(t))
        assert result.verified
        assert result.contact_force == pytest.approx(alone.contact_force, rel=1e-10, abs=1e-6)
        assert result.u == pytest.approx(alone.u, rel=1e-10, abs=1e-15)


def test_a_method_that_cannot_hold_the_scene_is_named_and_the_others_are_drawn():
    """A node between a "+" and a "−" wall, 0.1 mm each way: equality contact would fix the
    node twice, so it has no curve and says why; the others step as usual. k = EA/L =
    210e9·1e-3/1 N/m; the + wall is reached at t* = g k / F, and at t = 1 it pushes with
    F − k g (the − wall carries nothing)."""
    E, A, L, F, g = 210e9, 1e-3, 1.0, 5e4, 1e-4
    k = E * A / L
    scene = contactqp.Scene(contactqp.Bar.from_areas([A], E, length=L), contactqp.Support(0),
                            contactqp.Load(1, F),
                            (contactqp.Wall(1, g, "+"), contactqp.Wall(1, g, "-")))
    path = load_path(scene, steps=3)
    assert set(path.failed) == {"equality"}
    assert "equality" in path.failed["equality"] and "twice" in path.failed["equality"]
    assert "equality" not in path.methods and "lagrange" in path.methods
    assert path.to_dict()["failed"] == path.failed
    assert first_contact_factor(scene) == pytest.approx(g * k / F, rel=1e-12)
    lagrange = path.methods["lagrange"]
    assert lagrange.contact_force[-1] == pytest.approx([F - k * g, 0.0], rel=1e-10, abs=1e-6)
    assert lagrange.verified.all() and lagrange.physical.all()


@pytest.mark.parametrize(("scene", "steps", "message"), [
    (None, 10**8, r"^steps = 100000000: contactqp steps a load path 10000 times at most$"),
    (None, 10_001, r"^steps = 10001: .* 10000 times at most$"),
    (contactqp.default_scene(500_000), 21,
     r"^steps = 21: a scene of 500000 elements is stepped 20 times at most \(10000000 "),
])
def test_a_load_path_that_could_not_finish_is_refused_with_its_limit(scene, steps, message):
    """10⁵ steps took 586 s and 10⁸ had no bound; a big scene's steps are one batch of
    steps times its elements."""
    with pytest.raises(contactqp.OptionError, match=message):
        load_path(scene, steps=steps)


def test_a_load_path_tells_its_progress_over_every_method():
    seen = []
    path = load_path(steps=3, progress=lambda done, total: seen.append((done, total)))
    total = 3 * (len(path.methods) + len(path.failed))
    assert seen[-1] == (total, total)
    assert all(t == total for _, t in seen)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
