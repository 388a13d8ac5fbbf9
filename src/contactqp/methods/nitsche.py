"""Nitsche's method for walls at a bar's end: the contact force taken from the stress of the
element at the contact, no multiplier and no penalty alone.

At a bar's end with outward normal ν (+1 at its last node, −1 at its first) a wall on that
side is the boundary condition u_n = ν·u_end <= g. The end element's force gives the normal
stress σ_n(u) = k (u_end − u_inner) (k = EA/h of that element; tension positive along ν),
and the Signorini conditions are σ_n = [P_γ(u)]₋, P_γ(u) = σ_n(u) − γ (u_n − g), for any
γ > 0 (Chouly and Hild; GetFEM's and dolfinx's contact demos). Nitsche's weak form adds to
K u = P, per wall,

    − (θ/γ) σ_n(u) σ_n(v) + (1/γ) [P_γ(u)]₋ (θ σ_n(v) − γ v_n),    γ = γ₀ · EA/h,

θ = 1 (symmetric; needs γ₀ large enough), 0, or −1 (skew-symmetric; stable for every γ₀). The
system is piecewise linear: it is solved as a semismooth Newton iteration on the set of walls
with P_γ < 0, each step one sparse solve, until the set repeats. The contact force is
λ = −[P_γ(u)]₋ >= 0. Where the end node carries no load the answer is the exact discrete
Signorini answer for every γ₀ (consistency: the element's force is the contact force there);
a load at the end node (a distributed load's share) makes it differ by what γ₀ and θ decide,
which vanishes as γ₀ → ∞. A wall at an interior node has no boundary for Nitsche: refused.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from contactqp import linalg
from contactqp.errors import OptionError, SolverError
from contactqp.model import Model
from contactqp.result import Solution

THETAS = (1.0, 0.0, -1.0)
DEFAULT_GAMMA0 = 100.0
MAX_ITERATIONS = 50


def end_rows(model: Model) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per contact row: (the free unknown of the wall's node, of the end element's other node
    or −1 where that is a support, ν, k of the end element); an OptionError for a row that is
    not a wall at a bar's end facing out."""
    layout = model.layout
    rows, nodes, signs, _ = layout.rows
    n_walls = len(layout.scene.walls)
    if model.n_contacts > n_walls:
        raise OptionError("method 'nitsche' imposes walls at a bar's end; bar contacts are not "
                          "built for it (use lagrange or another method)")
    first, last = layout.bar_ends
    position = np.full(layout.n_nodes, -1)
    position[model.free] = np.arange(model.n_free)
    end, inner, normal, stiffness = [], [], [], []
    for row, node, sign in zip(rows.tolist(), nodes.tolist(), signs.tolist()):
        at_last, at_first = node == last[node], node == first[node]
        if not (at_last and sign > 0) and not (at_first and sign < 0):
            bar = int(layout.node_bar[node])
            where = f"bar {bar} node {node - int(layout.node_offsets[bar])}"
            raise OptionError(
                f"method 'nitsche' imposes contact on a boundary of a bar: wall[{row}] at {where} "
                + ("is at an interior node, which has no boundary" if not (at_last or at_first)
                   else "faces into the bar") + " (use lagrange or another method)")
        other = node - 1 if at_last and sign > 0 else node + 1
        end.append(position[node])
        inner.append(position[other])
        normal.append(1.0 if sign > 0 else -1.0)
        stiffness.append(float(layout.link_stiffness[min(node, other)]))
    return np.array(end), np.array(inner), np.array(normal), np.array(stiffness)


def solve_nitsche(model: Model, contact: str, *, gamma0: float = DEFAULT_GAMMA0,
                  theta: float = 1.0, max_iterations: int = MAX_ITERATIONS) -> Solution:
    """Nitsche's method (module docstring) with γ = ``gamma0`` × EA/h and ``theta``."""
    if model.n_contacts == 0:
        return Solution(model.free_displacement, np.zeros(0), solver="nitsche")
    end, inner, normal, k = end_rows(model)
    gamma = gamma0 * k
    # σ_n(u) = s·u, s = k (e_end − e_inner); u_n = ẽ·u, ẽ = ν e_end (one row each)
    S = _rows(model.n_free, k, end, -k, inner)
    E = _rows(model.n_free, normal, end)
    g = model.g
    active = np.ones(end.size, dtype=bool)  # start in contact: the first step then tells
    seen: set[bytes] = set()
    for iteration in range(1, max_iterations + 1):
        # per row, active: −θ s ẽᵀ − ẽ sᵀ + γ ẽ ẽᵀ, right-hand side −g (θ s − γ ẽ);
        # inactive: −(θ/γ) s sᵀ
        on, off = active, ~active
        matrix = model.K.copy()
        rhs = model.P.copy()
        if on.any():
            So, Eo = S[on], E[on]
            matrix = (matrix - theta * (So.T @ Eo) - Eo.T @ So
                      + Eo.T @ sp.diags_array(gamma[on]) @ Eo)
            rhs = rhs - So.T @ (theta * g[on]) + Eo.T @ (gamma[on] * g[on])
        if off.any():
            Sf = S[off]
            matrix = matrix - Sf.T @ sp.diags_array(theta / gamma[off]) @ Sf
        try:
            u = linalg.solve(matrix, rhs)
        except SolverError as error:
            raise SolverError(f"nitsche: the system is singular with θ = {theta:g} and "
                              f"γ₀ = {gamma0:g} ({error}); a larger γ₀ or θ = −1 is stable"
                              ) from None
        trial = S @ u - gamma * (E @ u - g)  # P_γ(u)
        following = np.ones(end.size, dtype=bool) if contact == "equality" else trial < 0.0
        force = np.where(following, -trial, 0.0)
        if np.array_equal(following, active):
            return Solution(u, force, solver="nitsche", iterations=iteration,
                            status="solved", info={"gamma0": gamma0, "theta": theta})
        key = following.tobytes()
        if key in seen:
            return Solution(u, force, solver="nitsche", iterations=iteration,
                            status="the contact set cycles", claimed_success=False,
                            info={"gamma0": gamma0, "theta": theta})
        seen.add(key)
        active = following
    return Solution(u, force, solver="nitsche", iterations=max_iterations,
                    status=f"no stable contact set in {max_iterations} steps",
                    claimed_success=False, info={"gamma0": gamma0, "theta": theta})


def _rows(n: int, values_a: np.ndarray, columns_a: np.ndarray,
          values_b: np.ndarray | None = None, columns_b: np.ndarray | None = None
          ) -> sp.csr_array:
    """Sparse rows (one per wall) with ``values_a`` at ``columns_a`` (and ``values_b`` at
    ``columns_b``, skipped where the column is −1: a support)."""
    count = columns_a.size
    row, col, val = [np.arange(count)], [columns_a], [values_a]
    if values_b is not None:
        keep = columns_b >= 0
        row.append(np.arange(count)[keep])
        col.append(columns_b[keep])
        val.append(values_b[keep])
    return sp.csr_array((np.concatenate(val), (np.concatenate(row), np.concatenate(col))),
                        shape=(count, n))


__all__ = ["DEFAULT_GAMMA0", "THETAS", "end_rows", "solve_nitsche"]
