"""Mesh convergence: the default scene's contact force against the continuous taper's, over
the number of elements, for each area rule."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from contactqp.builders import (
    DEFAULT_DIAMETERS,
    DEFAULT_GAP,
    DEFAULT_LENGTH,
    DEFAULT_LOAD,
    DEFAULT_MODULUS,
    default_scene,
)
from contactqp.solve import solve


def cone_compliance(a: float, b: float) -> float:
    """∫ₐᵇ dx / (E·A(x)) of the default scene's conical bar (m/N): 4(b − a)/(E·π·d(a)·d(b))."""
    d0, d1 = DEFAULT_DIAMETERS

    def diameter(x: float) -> float:
        return d0 + (d1 - d0) * x / DEFAULT_LENGTH

    return 4.0 * (b - a) / (DEFAULT_MODULUS * np.pi * diameter(a) * diameter(b))


def cone_contact_force() -> float:
    """The continuum contact force of the default scene (N): λ = (F·f(0, L/2) − g) / f(0, L)."""
    free_tip = DEFAULT_LOAD * cone_compliance(0.0, DEFAULT_LENGTH / 2)
    return (free_tip - DEFAULT_GAP) / cone_compliance(0.0, DEFAULT_LENGTH)


@dataclass(frozen=True)
class MeshConvergence:
    """Relative contact-force error of the default scene against the continuum, per mesh."""

    elements: np.ndarray
    errors: dict[str, np.ndarray]  # area rule -> |λ_h − λ| / λ
    exact_force: float


def mesh_convergence(elements: tuple[int, ...] = (2, 4, 8, 16, 32, 64, 128, 256, 512, 1024)
                     ) -> MeshConvergence:
    """Solve the default scene on finer and finer meshes with both area rules."""
    exact = cone_contact_force()
    errors = {
        rule: np.array([abs(solve(default_scene(n, rule)).contact_force[0] - exact) / exact
                        for n in elements])
        for rule in ("midpoint", "exact")
    }
    return MeshConvergence(np.array(elements), errors, exact)
