"""The arguments of contactqp.fem's model builders, checked before any mesh is made: each bad
one is a :class:`~contactqp.errors.ProblemError` of one line naming the builder, the argument
and the value, and a mesh size that would refine past :data:`MAX_NODES` is refused before it
runs (a size of 0 would refine for ever)."""

from __future__ import annotations

from typing import Any

from contactqp._validate import number, whole_number
from contactqp.errors import ProblemError

MAX_NODES = 2_000_000  # a mesh larger than this (4·10⁶ dofs in 2D) is refused: minutes to build


def positive(builder: str, name: str, value: Any) -> float:
    """``value`` as a positive finite number within range."""
    return number(f"{builder}: {name}", value, minimum=0.0, strict=True, error=ProblemError)


def at_least_zero(builder: str, name: str, value: Any) -> float:
    """``value`` as a finite number >= 0 within range."""
    return number(f"{builder}: {name}", value, minimum=0.0, tiny=True, error=ProblemError)


def poisson_ratio(builder: str, value: Any) -> float:
    """ν in [0, 0.5): at 0.5 the plane-strain body is incompressible and its K not defined
    (the Lamé λ is infinite); below 0 is allowed by thermodynamics but not by these models."""
    nu = number(f"{builder}: poisson", value, tiny=True, error=ProblemError)
    if not 0.0 <= nu < 0.5:
        raise ProblemError(f"{builder}: poisson must be in [0, 0.5) (at 0.5 the material is "
                           f"incompressible and displacement elements lock), got {value!r}")
    return nu


def count(builder: str, name: str, value: Any, minimum: int = 1) -> int:
    """``value`` as a whole number >= ``minimum``."""
    return whole_number(f"{builder}: {name}", value, minimum, error=ProblemError)


def nodes_within(builder: str, expected: float, what: str) -> None:
    """Refuse a mesh expected to have more than MAX_NODES nodes (``what``: the arguments
    that make it so)."""
    if expected > MAX_NODES:
        raise ProblemError(f"{builder}: {what} makes a mesh of about {expected:.2g} nodes, more "
                           f"than the {MAX_NODES:.0e} these builders make (minutes to build; "
                           "assemble larger models with scikit-fem directly)")


__all__ = ["MAX_NODES", "at_least_zero", "count", "nodes_within", "poisson_ratio", "positive"]
