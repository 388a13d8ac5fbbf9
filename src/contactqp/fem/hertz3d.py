"""Hertz's closed form for an elastic sphere pressed onto a rigid flat (point contact).

Glossary: R the sphere's radius, E Young's modulus, ν Poisson's ratio, E* = E/(1 − ν²) the
effective modulus of an elastic body on a rigid flat, P the load (force), a the radius of the
circle of contact, p₀ the peak pressure at its centre, δ the approach (how far the sphere's
distant points move towards the flat). Valid while a ≪ R (the half-space idealisation); see
Johnson, *Contact Mechanics*, §4.2:

    a = (3PR/(4E*))^(1/3),   p₀ = 3P/(2πa²),   δ = a²/R,   p(r) = p₀√(1 − r²/a²),

and, from those, P = (4/3) E* √R δ^(3/2).
"""

from __future__ import annotations

import math

import numpy as np

from contactqp.fem._arguments import at_least_zero, poisson_ratio, positive


def effective_modulus(young: float, poisson: float) -> float:
    """E* = E/(1 − ν²) for an elastic body on a rigid flat (stress units)."""
    young = positive("effective_modulus", "young", young)
    return young / (1.0 - poisson_ratio("effective_modulus", poisson) ** 2)


def sphere_contact_radius(load: float, radius: float, young: float, poisson: float) -> float:
    """The radius of the circle of contact a = (3PR/(4E*))^(1/3) (length units).

    Parameters
    ----------
    load : float
        P, the load pressing the sphere onto the flat (force).
    radius : float
        R, the sphere's radius (length).
    young, poisson : float
        E (stress) and ν of the sphere; the flat is rigid.
    """
    load = at_least_zero("sphere_contact_radius", "load", load)
    radius = positive("sphere_contact_radius", "radius", radius)
    return (3.0 * load * radius / (4.0 * effective_modulus(young, poisson))) ** (1.0 / 3.0)


def sphere_peak_pressure(load: float, radius: float, young: float, poisson: float) -> float:
    """The peak pressure p₀ = 3P/(2πa²) (stress units); arguments as for
    `sphere_contact_radius`."""
    a = sphere_contact_radius(load, radius, young, poisson)
    return 3.0 * load / (2.0 * math.pi * a**2) if a > 0.0 else 0.0  # no load, no p₀


def sphere_approach(load: float, radius: float, young: float, poisson: float) -> float:
    """The approach δ = a²/R (length units); arguments as for `sphere_contact_radius`."""
    return sphere_contact_radius(load, radius, young, poisson) ** 2 / radius


def sphere_load(approach: float, radius: float, young: float, poisson: float) -> float:
    """The load that gives the approach δ: P = (4/3) E* √R δ^(3/2) (force).

    Parameters
    ----------
    approach : float
        δ (length).
    radius, young, poisson : float
        As for `sphere_contact_radius`.
    """
    approach = at_least_zero("sphere_load", "approach", approach)
    radius = positive("sphere_load", "radius", radius)
    return 4.0 / 3.0 * effective_modulus(young, poisson) * math.sqrt(radius) * approach**1.5


def sphere_pressure(r: np.ndarray, contact_radius: float, peak: float) -> np.ndarray:
    """Hertz's pressure p₀√(1 − r²/a²) inside the circle r < a, zero outside it (stress
    units); ``r`` the distance from the centre of contact (length)."""
    contact_radius = positive("sphere_pressure", "contact_radius", contact_radius)
    peak = at_least_zero("sphere_pressure", "peak", peak)
    ratio = np.clip(np.abs(np.asarray(r, dtype=float)) / contact_radius, 0.0, 1.0)
    return peak * np.sqrt(1.0 - ratio**2)


__all__ = ["effective_modulus", "sphere_approach", "sphere_contact_radius", "sphere_load",
           "sphere_peak_pressure", "sphere_pressure"]
