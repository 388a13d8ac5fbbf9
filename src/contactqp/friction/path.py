"""A load path with history: increments, each one's slip measured from the last one's u.

Friction is path-dependent. Under proportional loading with Q/P < μ Mindlin and Deresiewicz
find no slip at all; Cattaneo's partial slip appears only when P comes first and Q after. A
quasi-static answer is therefore a sequence: each increment solves the friction law on the
slip T(u − u_prev) from the state the previous one reached.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from contactqp.errors import ProblemError
from contactqp.friction.answer import FrictionAnswer
from contactqp.friction.coulomb import solve_coulomb
from contactqp.friction.model import FrictionModel
from contactqp.friction.tresca import solve_tresca


@dataclass(frozen=True, eq=False)
class Increment:
    """One step of a load path: its model (the load at its end), its start, its answer."""

    model: FrictionModel
    previous_u: np.ndarray
    answer: FrictionAnswer


def load_path(model: FrictionModel, steps: Iterable[dict], *, slip_bound=None, mu=None,
              method: str | None = None, options: dict | None = None,
              start_u: np.ndarray | None = None) -> list[Increment]:
    """Solve a sequence of increments, each from the state the last one reached.

    Parameters
    ----------
    model : FrictionModel
        K, C, T and the first load (the factorisation is made once and shared).
    steps : iterable of dict
        Per increment the load at its end: keys ``f`` (n), ``values`` (prescribed
        displacements), ``g`` (gaps), any of them (:meth:`FrictionModel.with_loads`).
    slip_bound, mu : float or array
        Exactly one: Tresca's bounds or Coulomb's coefficients.
    method : str, optional
        Default ``"active_set"`` (Tresca) or ``"fixed_point"`` (Coulomb).
    options : dict, optional
        The method's options for every increment.
    start_u : array, n, optional
        The state before the first increment (default zero).

    Returns
    -------
    list of Increment
    """
    if (slip_bound is None) == (mu is None):
        raise ProblemError("give exactly one of slip_bound (Tresca) and mu (Coulomb)")
    previous = model.previous(start_u)
    increments = []
    for step in steps:
        current = model.with_loads(**step)
        if mu is None:
            answer = solve_tresca(current, slip_bound, previous_u=previous,
                                  method=method or "active_set", options=options)
        else:
            answer = solve_coulomb(current, mu, previous_u=previous,
                                   method=method or "fixed_point", options=options)
        increments.append(Increment(current, previous, answer))
        previous = answer.u
    return increments
