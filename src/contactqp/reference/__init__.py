"""Exact references for unilateral contact, independent of the methods: answers that tests and
benchmarks hold every method to. Two paths, one answer (:func:`reference` picks):

**Statics in extended precision** (:func:`statics_reference`), for one bar with walls only, at
any size (used up to 1e6 elements). No K, no C, no solver: fix the supported nodes and the
nodes of an active set A of walls (u = ±gap). The fixed nodes cut the bar into segments, and
each is solved by statics alone:

    equilibrium at a free node j:  N_j − N_(j−1) + P_j = 0          (N tension, element j = j→j+1)
    head (before the first fixed node):  N_e = −Σ_(j<=e) P_j
    tail (after the last fixed node):    N_e =  Σ_(j>e) P_j
    between fixed nodes a < b:           N_e = N_a − Σ_(a<j<=e) P_j, with N_a from compatibility
                                         Σ_(a<=e<b) N_e / k_e = u_b − u_a
    a fixed node's reaction:             R_j = N_(j−1) − N_j − P_j,  a wall's force λ = −sign·R_j

Every sum is a cumulative sum in ``numpy.longdouble`` (80-bit on x86-64, eps 1.1e-19; where the
platform has no extended type it is float64, and ``Reference.precision`` says so). The answer
is certified to ``CERTIFICATE`` of the load and displacement scales.

**Exact rational arithmetic** (:mod:`contactqp.reference.exact`), for every other scene.
"""

from __future__ import annotations

import numpy as np

from contactqp.errors import SceneError
from contactqp.model.chain.floating import unheld_bars
from contactqp.model.chain.numbering import layout_of
from contactqp.reference.exact import Reference, rational_reference
from contactqp.scene import Scene

CERTIFICATE = 1e-13  # relative: the arithmetic is ~1e-19, this leaves room for n up to 1e6


def reference(scene: Scene, max_steps: int | None = None,
              start: np.ndarray | None = None) -> Reference:
    """The exact unilateral contact solution of ``scene`` (module docstring): statics in
    extended precision for one bar with walls only, exact rational arithmetic otherwise.

    ``max_steps`` (default 2·rows + 10) bounds each active-set loop. ``start`` (statics path
    only): the rows active at the first step, e.g. those a method found pushing; the answer
    is certified by the same test whatever the start, so a start saves steps (a large contact
    patch takes the loop thousands) without making the reference depend on the method. Raises SceneError when
    no certified answer is reached within them (and, on the rational path, its fallbacks),
    and for a scene beyond the rational path's reach (more than ``MAX_EXACT_NODES`` nodes).
    """
    unheld = unheld_bars(scene)
    if unheld:
        raise SceneError(unheld)
    if len(scene.bars) == 1 and not scene.contacts and scene.supports:
        return statics_reference(scene, max_steps, start)
    return rational_reference(scene, max_steps)


# ---------------------------------------------------------------------------------------------
# Statics in extended precision: one bar with walls


def _solve(k: np.ndarray, P: np.ndarray, fixed: np.ndarray, values: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray]:
    """(u per node, N per element) of a chain with stiffness k and nodal loads P, nodes
    ``fixed`` (sorted, unique) held at ``values``; all in longdouble."""
    n_nodes = P.size
    c = 1.0 / k
    SP = np.cumsum(P)  # SP[j] = Σ_(i<=j) P_i
    elements = np.arange(n_nodes - 1)
    # the fixed node at or left of each element's first node (−1: head), and right of it
    left = np.searchsorted(fixed, elements, side="right") - 1
    N = np.empty(n_nodes - 1, dtype=P.dtype)
    head = left < 0
    tail = left == fixed.size - 1
    inner = ~head & ~tail
    N[head] = -SP[elements[head]]
    N[tail] = SP[-1] - SP[elements[tail]]
    if inner.any():
        a = fixed[left[inner]]
        S = SP[elements[inner]] - SP[a]  # Σ_(a<j<=e) P_j
        segment = left[inner]  # segments are runs of equal ``segment``, in element order
        starts = np.flatnonzero(np.r_[True, segment[1:] != segment[:-1]])
        ids = segment[starts]
        sum_c = np.add.reduceat(c[inner], starts)
        sum_cS = np.add.reduceat(c[inner] * S, starts)
        N_a = (values[ids + 1] - values[ids] + sum_cS) / sum_c
        N[inner] = np.repeat(N_a, np.diff(np.r_[starts, S.size])) - S
    # displacements: u_(e+1) − u_e = N_e c_e, anchored at the fixed node of each run
    D = np.zeros(n_nodes, dtype=P.dtype)
    np.cumsum(N * c, out=D[1:])
    anchor = np.searchsorted(fixed, np.arange(n_nodes), side="right") - 1
    anchor[anchor < 0] = 0  # the head hangs from the first fixed node
    u = values[anchor] + D - D[fixed[anchor]]
    u[fixed] = values
    return u, N


def statics_reference(scene: Scene, max_steps: int | None = None,
                      start: np.ndarray | None = None) -> Reference:
    """The solution of a one-bar scene with walls only, by statics in extended precision
    (module docstring); ``max_steps`` and ``start`` as for :func:`reference`."""
    if len(scene.bars) != 1 or scene.contacts:
        raise SceneError(f"scene {scene.name!r}: the statics reference solves one bar with walls "
                         f"only; it has {len(scene.bars)} bars and {len(scene.contacts)} bar "
                         "contacts (the rational reference takes them)")
    real = np.longdouble
    layout = layout_of(scene)
    k = layout.element_stiffness.astype(real)
    P = layout.nodal_loads.astype(real)
    supports = np.unique(layout.support_nodes)
    _, nodes, signs, gaps = layout.rows
    nodes, signs, gaps_real = nodes.astype(np.intp), signs.astype(real), gaps.astype(real)
    force_scale = max(float(np.abs(P).max(initial=0.0)), 1e-300)
    active = np.zeros(nodes.size, dtype=bool) if start is None else np.array(start, dtype=bool)
    max_steps = 2 * nodes.size + 10 if max_steps is None else max_steps
    for step in range(1, max_steps + 1):
        fixed = np.r_[supports, nodes[active]]
        order = np.argsort(fixed)
        values = np.r_[np.zeros(supports.size, dtype=real), signs[active] * gaps_real[active]]
        u, N = _solve(k, P, fixed[order], values[order])
        N_full = np.r_[real(0), N, real(0)]  # N_(−1) = N_n = 0
        reaction = N_full[nodes] - N_full[nodes + 1] - P[nodes]
        lam = np.where(active, -signs * reaction, real(0))
        penetration = signs * u[nodes] - gaps_real
        length_scale = max(float(np.abs(u).max()), float(np.abs(gaps).max(initial=0.0)),
                           force_scale / float(k.max()))
        pulling = active & (lam < -CERTIFICATE * force_scale)
        penetrated = ~active & (penetration > CERTIFICATE * length_scale)
        if not (pulling.any() or penetrated.any()):
            # certified: λ >= −CERTIFICATE·F is round-off of an exact λ >= 0
            return Reference(np.maximum(lam, 0.0).astype(float), u.astype(float), step,
                             float(np.finfo(real).eps))
        active = (active & ~pulling) | penetrated
    raise SceneError(f"scene {scene.name!r}: the reference's active set was not certified in "
                     f"{max_steps} steps")
