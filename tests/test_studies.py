"""Studies (contactqp.studies): the penalty sweep shows the augmented method beating the penalty.
"""

from __future__ import annotations

import pytest

from closed_forms import (
    cone_like_f,
)
from contactqp.studies import penalty_sweep


def test_penalty_sweep_shows_augmentation_beating_the_penalty():
    sweep = penalty_sweep()
    middle = list(sweep.penalties).index(1e10)
    # with ε f ≈ 75 the penalty is ~1 % off; the augmented updates remove the error
    assert sweep.force_error[middle] == pytest.approx(1 / (1 + 1e10 * cone_like_f()), rel=1e-3)
    assert sweep.augmented_error[middle] < 1e-10
    assert sweep.augmented_iterations[middle] > 1
