"""Nitsche's method for walls at a bar's end and contacts between bar ends: the contact force
taken from the stress of the element at the contact, no multiplier and no penalty alone.

At a bar's end with outward normal ν (+1 at its last node, −1 at its first) a wall on that
side is the boundary condition u_n = ν·u_end <= g. The end element's force gives the normal
stress σ_n(u) = N = k (u_right − u_left) (k = EA/h of that element; tension positive at
either end, as σ_nn does not turn with the normal),
and the Signorini conditions are σ_n = [P_γ(u)]₋, P_γ(u) = σ_n(u) − γ (u_n − g), for any
γ > 0 (Chouly and Hild; GetFEM's and dolfinx's contact demos). Nitsche's weak form adds to
K u = P, per wall,

    − (θ/γ) σ_n(u) σ_n(v) + (1/γ) [P_γ(u)]₋ (θ σ_n(v) − γ v_n),    γ = γ₀ · EA/h,

θ = 1 (symmetric; needs γ₀ large enough), 0, or −1 (skew-symmetric; stable for every γ₀). The
system is piecewise linear: it is solved as a semismooth Newton iteration on the set of walls
with P_γ < 0, each step one sparse solve, until the set repeats. On a scene with bars held
only by contact a set may leave a bar free to move as a whole (every row that holds it off):
its system is singular, and what a singular solve returns depends on the LAPACK build, so each
set is first completed by the rows that stop such a bar in the direction of its load
(:func:`~contactqp.methods._active_set.pinning`, as Lagrange's loop does) and no singular
system is ever solved. The contact force is
λ = −[P_γ(u)]₋ >= 0. Where the end node carries no load the answer is the exact discrete
Signorini answer for every γ₀ (consistency: the element's force is the contact force there);
a load at the end node (a distributed load's share) makes it differ by what γ₀ and θ decide,
which vanishes as γ₀ → ∞. A bar contact between the last node of one bar and the first node
of another is two boundaries in contact: σ_n is the mean of the two end elements' forces, γ
scaled by the mean of their stiffnesses, u_n = u_a − u_b. A wall at an interior node has no
boundary for Nitsche, nor a bar contact elsewhere: refused with the reason.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from contactqp import linalg
from contactqp.errors import OptionError, SolverError
from contactqp.methods._active_set import pinning
from contactqp.methods.base import Solution
from contactqp.model import Model

THETAS = (1.0, 0.0, -1.0)
DEFAULT_GAMMA0 = 100.0
MAX_ITERATIONS = 50


def boundary_rows(model: Model) -> tuple[sp.csr_array, np.ndarray]:
    """(S: per contact row, the gradient of its normal stress σ_n(u) over the free nodes;
    the stiffness k each row's γ is scaled by). A wall at a bar's end facing out: σ_n the end
    element's force, k its stiffness. A bar contact between the last node of one bar and the
    first node of the next (a facing b in +x, two boundaries in contact): σ_n the mean of the
    two end elements' forces, k the mean of their stiffnesses. Any other row is an
    OptionError that says why."""
    layout = model.layout
    rows, nodes, signs, gaps = layout.rows
    first, last = layout.bar_ends
    position = np.full(layout.n_nodes, -1)
    position[model.free] = np.arange(model.n_free)
    entries: list[tuple[int, int, float]] = []  # (row, free unknown, value of ∂σ_n/∂u)
    scale = np.zeros(gaps.size)
    n_walls = len(layout.scene.walls)
    order = np.argsort(rows, kind="stable")  # each row's entries together
    for row, mine in enumerate(np.split(order, np.flatnonzero(np.diff(rows[order])) + 1)):
        if row < n_walls:
            node, sign = int(nodes[mine[0]]), float(signs[mine[0]])
            faces_out = (node == last[node] and sign > 0) or (node == first[node] and sign < 0)
            if not faces_out:
                bar = int(layout.node_bar[node])
                where = f"bar {bar} node {node - int(layout.node_offsets[bar])}"
                reason = ("is at an interior node, which has no boundary"
                          if node not in (first[node], last[node]) else "faces into the bar")
                raise OptionError(f"method 'nitsche' imposes contact on a boundary of a bar: "
                                  f"wall[{row}] at {where} {reason} (use lagrange or another "
                                  "method)")
            ends = [(node, node - 1 if sign > 0 else node + 1, 1.0)]
        else:
            a = int(nodes[mine][signs[mine] > 0][0])
            b = int(nodes[mine][signs[mine] < 0][0])
            if not (a == last[a] and b == first[b]):
                raise OptionError(
                    f"method 'nitsche' imposes contact between bar ends: contact[{row - n_walls}] "
                    "must join the last node of one bar (a) to the first node of another (b) "
                    "(use lagrange or another method)")
            ends = [(a, a - 1, 0.5), (b, b + 1, 0.5)]
        for node, other, weight in ends:
            # σ_n is the end element's force N = k (u_right − u_left), tension positive,
            # whichever end of the bar (σ_nn does not turn with the normal)
            k = float(layout.link_stiffness[min(node, other)])
            along = weight * k * (1.0 if node > other else -1.0)
            entries += [(row, position[node], along), (row, position[other], -along)]
            scale[row] += weight * k
    kept = [(r, c, v) for r, c, v in entries if c >= 0]  # a supported node has no unknown
    r, c, v = (np.array(x) for x in zip(*kept))
    return sp.csr_array((v, (r, c)), shape=(gaps.size, model.n_free)), scale


def _advice(gamma0: float) -> str:
    """What to try when a system is singular: a small γ₀ leaves θ = 1 unstable, a large one
    swamps K in round-off (γ₀ = 1e300 overflowed, and "a larger γ₀" was no advice)."""
    if gamma0 > DEFAULT_GAMMA0:
        return (f"γ₀ = {gamma0:g} swamps the stiffness in round-off: a smaller γ₀ (the default "
                f"is {DEFAULT_GAMMA0:g})")
    return "a larger γ₀ or θ = −1 is stable"


def solve_nitsche(model: Model, contact: str, *, gamma0: float = DEFAULT_GAMMA0,
                  theta: float = 1.0, max_iterations: int = MAX_ITERATIONS) -> Solution:
    """Nitsche's method (module docstring) with γ = ``gamma0`` × EA/h and ``theta``."""
    if model.n_contacts == 0:
        return Solution(model.free_displacement, np.zeros(0), solver="nitsche")
    S, k = boundary_rows(model)  # σ_n(u) = S u per row
    gamma = gamma0 * k
    E = model.C  # the normal displacement u_n = C u (a wall: ν u_end; a contact: u_a − u_b)
    g = model.g
    pin = pinning(model)  # a set that leaves a bar free gets the rows that stop it
    active = np.ones(model.n_contacts, dtype=bool)  # start in contact: the first step tells
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
                              f"γ₀ = {gamma0:g} ({error}); {_advice(gamma0)}") from None
        trial = S @ u - gamma * (E @ u - g)  # P_γ(u)
        pushing = (np.ones(model.n_contacts, dtype=bool) if contact == "equality"
                   else trial < 0.0)
        force = np.where(pushing, -trial, 0.0)
        following = pin(pushing)
        if np.array_equal(pushing, active):
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


__all__ = ["DEFAULT_GAMMA0", "THETAS", "boundary_rows", "solve_nitsche"]
