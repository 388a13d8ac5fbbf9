"""The two friction laws: Tresca (a given slip bound per contact) and Coulomb (μ λ_N)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from contactqp.errors import ProblemError
from contactqp.friction.model import FrictionModel, nonnegative

TRESCA, COULOMB = "tresca", "coulomb"


@dataclass(frozen=True, eq=False)
class Law:
    """A friction law per contact.

    Attributes
    ----------
    kind : str
        ``"tresca"``: the friction force of contact i may reach the slip bound sᵢ (force),
        whatever its normal force (the law of a given friction, Tresca's; convex). ``"coulomb"``:
        it may reach μᵢ λ_N,i (dimensionless μᵢ; not convex).
    values : array, m
        sᵢ or μᵢ, at least zero; a zero is a frictionless contact.
    """

    kind: str
    values: np.ndarray

    def bound(self, normal_force: np.ndarray | None) -> np.ndarray:
        """The largest friction force each contact may carry (force)."""
        if self.kind == TRESCA:
            return self.values
        return self.values * np.maximum(normal_force, 0.0)

    @property
    def frictional(self) -> np.ndarray:
        """The contacts with friction at all (bound or coefficient above zero)."""
        return self.values > 0.0


def tresca(model: FrictionModel, slip_bound) -> Law:
    """Tresca's law with slip bounds s (force, one per contact or one for all)."""
    return Law(TRESCA, nonnegative("slip_bound", slip_bound, model.contacts))


def coulomb(model: FrictionModel, mu) -> Law:
    """Coulomb's law with coefficients μ (one per contact or one for all); needs normal rows."""
    if model.C is None:
        raise ProblemError("mu: Coulomb's law needs normal rows C (the bound is μ λ_N); with "
                           "C=None give slip_bound (Tresca)")
    return Law(COULOMB, nonnegative("mu", mu, model.contacts))
