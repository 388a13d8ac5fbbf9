"""A bar on a frictional bed, pulled at one end: the 1D closed form of partial slip.

Glossary: a bar of axial stiffness EA (force) and length L lies on a bed that resists sliding
up to τ per unit length (force/length). A force F < τL pulls its end x = 0 along the bar. The
bed holds it back over the slip zone 0 ≤ x < x_s = F/τ, where the friction is at its limit:
the axial force falls linearly, N = F − τx, and the bar stretches by
|u| = τ(x_s − x)²/(2EA); beyond x_s nothing moves.

The model: N linear elements of length h = L/N (K tridiagonal, EA/h), the nodes' displacements
along the bar, F on node 0 (f₀ = −F: the pull, x pointing away from the loaded end). Each node
but the last is a contact without a normal row (C=None) and one tangential row reading its
displacement; its Tresca bound is τ times its tributary length (h/2 at node 0, h inside). The
far end is held, u(L) = 0: the bar sticks there anyway (F < τL), and holding it makes K
positive definite, as the exact route needs (the QP backends also take the floating bar).

Where the nodes fall at x_s the answer is exact at the nodes: the lumped friction forces
make the axial force exact at every element's midpoint, N is linear, so the midpoint rule
integrates the stretch exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from contactqp.errors import ProblemError
from contactqp.friction.answer import FrictionAnswer
from contactqp.friction.model import FrictionModel, friction_model


@dataclass(frozen=True, eq=False)
class FrictionalBed:
    """The bar on the bed as a friction model.

    Attributes
    ----------
    model : FrictionModel
    slip_bound : array
        τ times each node's tributary length (force).
    x : array
        The nodes' positions from the loaded end (length).
    force, tau, axial_stiffness, length : float
        F, τ, EA, L.
    """

    model: FrictionModel
    slip_bound: np.ndarray
    x: np.ndarray
    force: float
    tau: float
    axial_stiffness: float
    length: float


def frictional_bed(length: float = 1.0, axial_stiffness: float = 1.0, elements: int = 10,
                   tau: float = 1.0, force: float = 0.5, floating: bool = False
                   ) -> FrictionalBed:
    """The bar on the bed (module docstring).

    Parameters
    ----------
    length, axial_stiffness, tau, force : float
        L (length), EA (force), τ (force/length), F < τL (force).
    elements : int
        N.
    floating : bool
        Leave the far end free (held by friction alone: K is then singular, for the QP
        backends only).
    """
    for name, value in (("length", length), ("axial_stiffness", axial_stiffness),
                        ("tau", tau), ("force", force)):
        if not np.isfinite(value) or value <= 0.0:
            raise ProblemError(f"frictional_bed: {name} = {value!r}; it must be positive")
    if int(elements) < 1:
        raise ProblemError(f"frictional_bed: elements = {elements!r}; at least 1")
    if force >= tau * length:
        raise ProblemError(f"frictional_bed: force = {force!r} ≥ τL = {tau * length!r}: the "
                           "whole bar slides")
    N = int(elements)
    h = length / N
    x = np.linspace(0.0, length, N + 1)
    k = axial_stiffness / h
    main = np.full(N + 1, 2.0 * k)
    main[[0, -1]] = k
    K = sp.diags([main, np.full(N, -k), np.full(N, -k)], [0, -1, 1], format="csr")
    f = np.zeros(N + 1)
    f[0] = -force
    contacts = N + 1 if floating else N
    T = sp.eye(contacts, N + 1, format="csr")
    tributary = np.full(N + 1, h)
    tributary[[0, -1]] = h / 2.0
    held = {} if floating else {"prescribed": [N], "values": [0.0]}
    model = friction_model(K, f, None, None, T, contacts=contacts, **held)
    return FrictionalBed(model, tau * tributary[:contacts], x, float(force), float(tau),
                         float(axial_stiffness), float(length))


def bed_displacement(x: np.ndarray, force: float, tau: float, axial_stiffness: float
                     ) -> np.ndarray:
    """The closed form u(x) = −τ(x_s − x)²/(2EA) for x < x_s = F/τ, zero beyond (length)."""
    x_s = force / tau
    return -tau * np.clip(x_s - np.asarray(x, dtype=float), 0.0, None) ** 2 / (
        2.0 * axial_stiffness)


def slip_length(bed: FrictionalBed, answer: FrictionAnswer) -> float:
    """x_s read from the pull-out, the loaded end's displacement: |u(0)| = τx_s²/(2EA) (length).

    The discrete answer is the closed form's parabola lowered by τ(x_s − x_k)²/(2EA), x_k the
    first node that sticks (|x_k − x_s| < h: the midpoint rule integrates the exact axial
    force; module docstring), so this x_s is exact where a node falls at x_s and within
    h²/(2x_s) elsewhere, and |u − u_exact| ≤ τh²/(2EA) at every node.
    """
    return float(np.sqrt(2.0 * bed.axial_stiffness * abs(answer.u[0]) / bed.tau))


def slip_zone_edge(bed: FrictionalBed, answer: FrictionAnswer) -> float:
    """x_s read from the shape of the slip zone: √|u| is linear in x there (the closed form),
    so the line through the last two slipping nodes meets zero at x_s (length). Exact where
    the discrete answer is; elsewhere within about h/2 (the lowered parabola's √ bends near
    its end)."""
    slipping = np.flatnonzero(~answer.stick)
    if slipping.size < 2:
        raise ValueError(f"slip zone: {slipping.size} node slips; refine (elements)")
    j0, j1 = slipping[-2], slipping[-1]
    r0, r1 = np.sqrt(np.abs(answer.u[[j0, j1]]))
    return float(bed.x[j1] + r1 * (bed.x[j1] - bed.x[j0]) / (r0 - r1))
