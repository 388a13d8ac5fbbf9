"""Hertz's closed form for a long cylinder pressed onto a rigid flat (plane strain).

Glossary: R the cylinder's radius, E Young's modulus, ν Poisson's ratio, E* = E/(1 − ν²) the
plane-strain modulus, P the load per unit thickness (force per length), a the half-width of the
contact strip, p₀ the peak pressure. Valid while a ≪ R (the half-space idealisation).
"""

from __future__ import annotations

import math

import numpy as np

from contactqp.fem._arguments import at_least_zero, poisson_ratio, positive


def plane_strain_modulus(young: float, poisson: float) -> float:
    """E* = E/(1 − ν²) for an elastic cylinder on a rigid flat (stress units)."""
    young = positive("plane_strain_modulus", "young", young)
    return young / (1.0 - poisson_ratio("plane_strain_modulus", poisson) ** 2)


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
    load = at_least_zero("hertz_half_width", "load", load)
    radius = positive("hertz_half_width", "radius", radius)
    return math.sqrt(4.0 * load * radius / (math.pi * plane_strain_modulus(young, poisson)))


def hertz_peak_pressure(load: float, radius: float, young: float, poisson: float) -> float:
    """The peak pressure p₀ = 2P/(πa) (stress units); arguments as for `hertz_half_width`."""
    half_width = hertz_half_width(load, radius, young, poisson)
    return 2.0 * load / (math.pi * half_width) if half_width > 0.0 else 0.0  # no load, no p₀


def hertz_pressure(x: np.ndarray, half_width: float, peak: float) -> np.ndarray:
    """Hertz's elliptical pressure p₀√(1 − (x/a)²) inside the strip −a < x < a, zero outside
    it (stress units)."""
    half_width = positive("hertz_pressure", "half_width", half_width)
    peak = at_least_zero("hertz_pressure", "peak", peak)
    ratio = np.clip(np.abs(np.asarray(x, dtype=float)) / half_width, 0.0, 1.0)
    return peak * np.sqrt(1.0 - ratio**2)
