"""Studies (contactqp.studies): the penalty sweep shows the augmented method beating the penalty;
the Nitsche sweep shows how γ₀ and θ decide Nitsche's answer where the end node is loaded.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import contactqp
from closed_forms import DEFAULT_SCENE, cone_like_f, default_closed_form
from contactqp.studies import compare, nitsche_sweep, penalty_sweep

EXAMPLES_DIR = Path(__file__).parent.parent / "examples"


def test_penalty_sweep_shows_augmentation_beating_the_penalty():
    sweep = penalty_sweep()
    middle = list(sweep.penalties).index(1e10)
    # with ε f ≈ 75 the penalty is ~1 % off; the augmented updates remove the error
    assert sweep.force_error[middle] == pytest.approx(1 / (1 + 1e10 * cone_like_f()), rel=1e-3)
    assert sweep.augmented_error[middle] < 1e-10
    assert sweep.augmented_iterations[middle] > 1


def test_nitsche_sweep_shows_its_errors_falling_as_one_over_gamma0():
    """The default scene with 200 kN more at the wall's node (nitsche_scene): for θ = 0 and −1
    the force error and for every θ the penetration fall tenfold per decade of γ₀ (the end
    node's load over γ), the answer is flagged at small γ₀ and verified at large; the
    symmetric form's system at γ₀ = 1 is singular (no answer)."""
    sweep = nitsche_sweep()
    gamma0 = sweep.gamma0
    large = gamma0 >= 1e3
    for i, theta in enumerate(sweep.thetas):
        depth = sweep.penetration[i][large]
        np.testing.assert_allclose(depth[1:] / depth[:-1], 0.1, rtol=0.02)
        if theta != 1.0:
            error = sweep.force_error[i][large & (gamma0 <= 1e6)]
            np.testing.assert_allclose(error[1:] / error[:-1], 0.1, rtol=0.02)
        assert not sweep.verified[i][gamma0 <= 1e3].any() and sweep.verified[i][-1]
    assert np.isnan(sweep.force_error[0][0])  # θ = 1, γ₀ = 1


@pytest.fixture(scope="module")
def sweep():
    return penalty_sweep()


def test_the_sweep_reports_the_augmented_results_it_draws(sweep):
    """The JSON carries the augmented method's force, penetration, updates, whether it stopped
    at its cap and its verdict at every ε. At ε = 1 N/m an update shrinks the error by
    1/(1 + ε f) ≈ 1 − 1e-8: 100 updates cannot converge (capped, flagged); at ε = 1e10 N/m
    (ε f ≈ 75) the force is the closed form's."""
    _, lam = default_closed_form()
    data = sweep.to_dict()
    n = len(data["penalty"])
    for key in ("augmented_contact_force", "augmented_penetration", "augmented_capped",
                "augmented_verified", "augmented_iterations", "augmented_force_error"):
        assert len(data[key]) == n, key
    first, middle = 0, data["penalty"].index(1e10)
    assert data["augmented_capped"][first] is True and data["augmented_verified"][first] is False
    assert data["augmented_capped"][middle] is False and data["augmented_verified"][middle]
    # augmented to its tolerance 1e-10 of λ (the update stops there)
    assert data["augmented_contact_force"][middle][0] == pytest.approx(lam, rel=1e-9)
    assert data["augmented_penetration"][middle][0] == pytest.approx(0.0, abs=1e-12)
    assert data["converged_up_to"] == sweep.penalties[sweep.best]
    assert data["summary"] == sweep.summary()


def test_the_sweep_summary_names_both_methods(sweep):
    """The penalty: best where the force error 1/(1 + ε f) meets round-off; the augmented
    method: verified from the first ε whose 100 updates, each shrinking the error by
    1/(1 + ε f), reach its tolerance 1e-10 (ε f >= 0.26: 1e8 N/m, f = 7.5e-9 m/N), and
    stopped at its cap below it."""
    text = sweep.summary()
    penalty, augmented = text.splitlines()
    assert penalty.startswith("penalty: converges up to ε = ")
    assert "round-off takes over" in penalty
    first = next(eps for eps in sweep.penalties
                 if 100 * np.log1p(eps * cone_like_f()) >= np.log(1e10))
    assert augmented.startswith(f"augmented Lagrangian: verified from ε = {first:.0e} N/m")
    assert "stopped at its cap of 100 updates" in augmented


def test_an_unloaded_scene_has_nothing_to_converge():
    """No load: no contact carries force, every ε gives the free answer: the summary says so
    (not 'converges up to ε = 1e+00 … error grows to 0.0e+00'), the JSON has no ε."""
    scene = contactqp.Scene(DEFAULT_SCENE.bars, DEFAULT_SCENE.supports, (), DEFAULT_SCENE.walls)
    unloaded = penalty_sweep(scene)
    assert unloaded.summary().startswith("no contact carries a force here")
    assert "converges up to" not in unloaded.summary()
    assert unloaded.to_dict()["converged_up_to"] is None


def test_compare_holds_every_inequality_run_against_the_exact_reference():
    """compare(): the inequality runs carry the exact reference (the two-spring closed form
    λ = (P − k₁g)·k₂/(k₁ + k₂) = 6000 N of examples/two_bars.toml), the equality runs none."""
    runs = compare(EXAMPLES_DIR / "two_bars.toml")
    inequality = [run for run in runs if run.contact == "inequality"]
    assert inequality and all(run.exact_force.tolist() == [6000.0] for run in inequality)
    assert all(run.exact_force is None for run in runs if run.contact == "equality")
    lagrange = next(run for run in inequality if run.label == "lagrange")
    # |λ − 6000| by Lagrange on two one-element bars: round-off of a 2 x 2 solve
    assert lagrange.exact_error == abs(lagrange.result.contact_force[0] - 6000.0) < 1e-9
    labels = [run.label for run in inequality]
    assert "semismooth_newton FB" in labels and len(set(labels)) == len(labels)


@pytest.mark.parametrize("study", [compare, penalty_sweep])
def test_a_study_of_a_scene_too_big_to_hold_is_refused_before_any_solve(study, monkeypatch):
    """At 10⁷ elements compare grew past 24 GB and was killed: beyond MAX_STUDY_ELEMENTS a
    study says so up front, with the size it takes."""
    from contactqp import studies
    from contactqp.studies import comparison, sweeps

    def never(*args, **kwargs):
        raise AssertionError("solved before the size was checked")

    for module in (comparison, sweeps):
        monkeypatch.setattr(module, "solve", never)
    monkeypatch.setattr(comparison, "exact_reference", never)
    scene = contactqp.default_scene(studies.MAX_STUDY_ELEMENTS + 2)
    with pytest.raises(contactqp.SceneError, match=r"^bar: the scene has 1000002 elements; "
                                                   r".* takes at most 1000000"):
        study(scene)


def test_a_sweep_tells_its_progress_after_each_solve():
    seen = []
    penalty_sweep(penalties=(1e6, 1e8), progress=lambda done, total: seen.append((done, total)))
    assert seen == [(1, 4), (2, 4), (3, 4), (4, 4)]
