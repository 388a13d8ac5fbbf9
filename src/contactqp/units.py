"""Unit systems: a scene's numbers are in one consistent system, and so is every answer."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Units:
    """A consistent unit system (force = stress × area, stiffness = force / length): the
    names of its units, and the size of its length and stress units in SI (m, Pa). Every
    number of a scene is in its units, and so is every answer: the algebra needs no
    conversion.

    Parameters
    ----------
    name : str
        The system's name (``"SI"``, ``"mm-N-MPa"``).
    length : str
        The name of its length unit.
    area : str
        The name of its area unit.
    force : str
        The name of its force unit.
    stress : str
        The name of its stress unit.
    metre : float
        The size of its length unit in metres.
    pascal : float
        The size of its stress unit in pascals.
    """

    name: str
    length: str
    area: str
    force: str
    stress: str
    metre: float  # one length unit, in m
    pascal: float  # one stress unit, in Pa

    @property
    def stiffness(self) -> str:
        """The unit of a stiffness (and of a distributed load): force per length."""
        return f"{self.force}/{self.length}"


UNIT_SYSTEMS = {
    "SI": Units("SI", "m", "m²", "N", "Pa", 1.0, 1.0),
    "mm-N-MPa": Units("mm-N-MPa", "mm", "mm²", "N", "MPa", 1e-3, 1e6),
}


__all__ = ["UNIT_SYSTEMS", "Units"]
