"""Friction: Tresca as a QP (2D) or a cone program (3D), Coulomb by a fixed point and by cone
programs, the duals read as friction forces, and a check with an error bound.

Plain arrays in (K, f, C, g, T, per contact a slip bound or a friction coefficient, the
prescribed dofs), one :class:`FrictionAnswer` out; :mod:`.model` has the glossary and the
sign conventions.
"""

from contactqp.friction.answer import FrictionAnswer
from contactqp.friction.check import (
    FrictionCheck,
    FrictionResiduals,
    check_coulomb,
    check_tresca,
    friction_residuals,
)
from contactqp.friction.coulomb import solve_coulomb
from contactqp.friction.model import FrictionModel, friction_model
from contactqp.friction.tresca import solve_tresca

__all__ = [
    "FrictionAnswer", "FrictionCheck", "FrictionModel", "FrictionResiduals", "check_coulomb",
    "check_tresca", "friction_model", "friction_residuals", "solve_coulomb", "solve_tresca",
]
