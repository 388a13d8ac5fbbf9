"""Hertz's closed form for a long cylinder pressed onto a rigid flat (plane strain).

Glossary: R the cylinder's radius, E Young's modulus, ν Poisson's ratio, E* = E/(1 − ν²) the
plane-strain modulus, P the load per unit thickness (force per length), a the half-width of the
contact strip, p₀ the peak pressure. Valid while a ≪ R (the half-space idealisation).
"""

from __future__ import annotations

import math

import numpy as np


def plane_strain_modulus(young: float, poisson: float) -> float:
    """E* = E/(1 − ν²) for an elastic cylinder on a rigid flat (stress units)."""
    return young / (1.0 - poisson**2)


def hertz_half_width(load: float, radius: float, young: float, poisson: float) -> float:
    """The contact half-width a = √(4PR/(πE*)) (length units).

    Parameters
    ----------
    load : float
        P, the load per unit thickness (force/length).
    radius : float
        R, the cylinder's radius (length).
    young, poisson : float
        E (stress) and ν of the cylinder; the flat is rigid.
    """
    return math.sqrt(4.0 * load * radius / (math.pi * plane_strain_modulus(young, poisson)))


def hertz_peak_pressure(load: float, radius: float, young: float, poisson: float) -> float:
    """The peak pressure p₀ = 2P/(πa) (stress units); arguments as for `hertz_half_width`."""
    return 2.0 * load / (math.pi * hertz_half_width(load, radius, young, poisson))


def hertz_pressure(x: np.ndarray, half_width: float, peak: float) -> np.ndarray:
    """Hertz's elliptical pressure p₀√(1 − (x/a)²) inside the strip −a < x < a, zero outside
    it (stress units)."""
    ratio = np.clip(np.abs(np.asarray(x, dtype=float)) / half_width, 0.0, 1.0)
    return peak * np.sqrt(1.0 - ratio**2)
