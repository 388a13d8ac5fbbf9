"""What every QP backend hands back to :mod:`contactqp.methods.qp`, and its failed form."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class QPOutcome:
    """A backend's answer before the dual sign and the scales are applied: the scaled solution
    x, the backend's own dual of every row of ``QPProblem.rows()`` (tie rows, then contact rows), its status text, whether that status claims
    success, its iteration count and timings (s) in ``info``."""

    x: np.ndarray
    dual: np.ndarray
    status: str
    claimed_success: bool
    iterations: int = 0
    info: dict[str, Any] = field(default_factory=dict)


def failed_outcome(n: int, m: int, status: str, **info: Any) -> QPOutcome:
    """NaN solution and multipliers: the solver raised or found nothing (the check flags it)."""
    return QPOutcome(np.full(n, np.nan), np.full(m, np.nan), status, False, 0, dict(info))


def vector_or_nan(values: Any, size: int) -> np.ndarray:
    """``values`` as a float vector of ``size``, or NaNs when the solver gave none."""
    if values is None:
        return np.full(size, np.nan)
    array = np.asarray(values, dtype=float).reshape(-1)
    return array if array.size == size else np.full(size, np.nan)
