"""Studies (contactqp.studies): the penalty sweep shows the augmented method beating the penalty;
the Nitsche sweep shows how γ₀ and θ decide Nitsche's answer where the end node is loaded.
"""

from __future__ import annotations

import numpy as np
import pytest

from closed_forms import (
    cone_like_f,
)
from contactqp.studies import nitsche_sweep, penalty_sweep


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
