"""Pure functions from a scene to the algebra: sparse K, P, constraint rows C and gaps g.

The nodes of every bar are numbered in one sequence (:meth:`Scene.global_node`), so K is one
tridiagonal band whose coupling is zero between bars. Supports are eliminated: the unknowns
are the displacements of the free nodes only. The contact constraints are written ``C D <= g``
(or ``= g``), one row per wall in scene order, then one per bar contact, with the wall's side
folded into the sign of the row: a "+" wall is u_i <= gap, a "-" wall is -u_i <= gap, a bar
contact u_a − u_b <= gap. With the Lagrangian L = Π + λᵀ(C D − g), λ >= 0 is then the force
with which each wall (or the other bar) pushes, and the contacts' force on the nodes in +x is
−Cᵀλ.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from contactqp import linalg
from contactqp.errors import OptionError, SolverError
from contactqp.scene import Bar, Scene

CONTACT_KINDS = ("inequality", "equality")  # the wall rows as C D <= g, or as C D = g
CONDENSE_LIMIT = 2000  # contact nodes: the condensed flexibility is a dense square of this size


def contact_kind(contact: str) -> str:
    """``contact`` if it is one of :data:`CONTACT_KINDS`, else an OptionError naming it."""
    if contact not in CONTACT_KINDS:
        raise OptionError(f"contact must be one of {', '.join(CONTACT_KINDS)}; got {contact!r}")
    return contact


@dataclass(frozen=True, eq=False)
class Model:
    """The algebra of a scene: minimise ½ DᵀKD − DᵀP subject to C D (<= or =) g.

    Attributes
    ----------
    scene : the scene it was built from.
    free : node number of each unknown (the free nodes, in order).
    P : loads on the free nodes (N).
    C : sparse constraint rows, one per wall (±1 at the wall's node) then one per bar contact
        (+1 at node a, −1 at node b), dimensionless, CSR.
    g : the contacts' gaps (m).
    stiffness : K, the stiffness of the free nodes (N/m): for a chain its LAPACK symmetric
        lower band storage (2 x n_free: diagonal, sub-diagonal), else a sparse matrix.
    K : K as a sparse CSR matrix (made from the band when first asked for).
    """

    scene: Scene
    free: np.ndarray
    stiffness: np.ndarray | sp.sparray
    P: np.ndarray
    C: sp.csr_array
    g: np.ndarray

    @property
    def K_band(self) -> np.ndarray | None:
        """K in band storage, or None when K is not a chain (a condensed model)."""
        return self.stiffness if isinstance(self.stiffness, np.ndarray) else None

    def solve_K(self, rhs: np.ndarray) -> np.ndarray:
        """K⁻¹ rhs (every column of ``rhs``). A chain held by one support is statically
        determinate: :func:`determinate_chain_solve` (statics, exact to round-off). Another
        chain: one banded Cholesky factorisation (LAPACK pbsv). Otherwise a sparse solve.
        SolverError when K is not positive definite."""
        if self.K_band is None:
            return linalg.solve(self.K, rhs, spd=True)
        if self.determinate is not None:
            rhs = np.asarray(rhs, dtype=float)
            out = np.empty(rhs.shape)
            for block, support in self.determinate:  # one block of free nodes per bar
                out[block] = determinate_chain_solve(self.compliance[block], support, rhs[block])
            return out
        try:
            return linalg.solve_spd_band(self.K_band, rhs)
        except np.linalg.LinAlgError as error:
            raise SolverError(f"K is not positive definite ({error})") from None

    @cached_property
    def determinate(self) -> tuple[tuple[slice, int], ...] | None:
        """When every bar is held by exactly one support (statically determinate): per bar,
        the slice of its free nodes and the support's position in that slice. Else None."""
        scene = self.scene
        if self.K_band is None or len(scene.supports) != len(scene.bars):
            return None
        blocks = []
        first = np.searchsorted(self.free, scene.node_offsets)
        for b, support in sorted((s.bar, s.node) for s in scene.supports):
            blocks.append((slice(int(first[b]), int(first[b + 1])), support))
        return tuple(blocks)

    @cached_property
    def compliance(self) -> np.ndarray:
        """φ (m/N) per free node when every bar is held by one support: Σ 1/k_e over the
        elements between the node and its bar's support, the displacement a unit force there
        causes."""
        parts = []
        for b, s in sorted((s.bar, s.node) for s in self.scene.supports):  # one per bar
            from_0 = self.scene.bars[b].compliance_from_node_0
            parts.append(from_0[1:] if s == 0 else np.abs(np.delete(from_0, s) - from_0[s]))
        return np.concatenate(parts) if len(parts) > 1 else parts[0]

    @cached_property
    def K(self) -> sp.csr_array:
        band = self.K_band
        if band is None:
            return sp.csr_array(self.stiffness)
        return sp.csr_array(sp.diags_array([band[1, :-1], band[0], band[1, :-1]], offsets=[-1, 0, 1]))

    @property
    def n_free(self) -> int:
        return int(self.free.size)

    @cached_property
    def free_displacement(self) -> np.ndarray:
        """K⁻¹P (free nodes): the displacement the loads cause with no contact at all."""
        return self.solve_K(self.P)

    def solve_K_and_loads(self, rhs: np.ndarray) -> np.ndarray:
        """K⁻¹ rhs (columns), with K⁻¹P (:attr:`free_displacement`) from the same
        factorisation when it is not known yet."""
        if "free_displacement" in self.__dict__:
            return self.solve_K(rhs)
        rhs = np.asarray(rhs, dtype=float)
        solved = self.solve_K(np.column_stack((rhs, self.P)))
        self.__dict__["free_displacement"] = solved[:, -1]
        return solved[:, :-1] if rhs.ndim == 2 else solved[:, 0]

    @cached_property
    def force_scale(self) -> float:
        """F: the scene's force scale, from the loads and the prescribed gaps alone (never from
        an answer): the largest force the loads put through any cut of a bar
        (:func:`load_force_scale`), and for a wall that starts past its node (gap < 0) the
        force that pushes the node back, |gap| × the stiffness it sees with the supports held.
        In a scene that nothing loads (the answer is u = 0, λ = 0) it is the softest
        element's stiffness times :attr:`displacement_scale`."""
        walls = self.g[: len(self.scene.walls)]
        press = np.flatnonzero(walls < 0.0)
        pushed_back = 0.0
        if press.size:
            nodes = self.scene.contact_rows[1][press]
            stiffness = seen_stiffness(self.scene, np.zeros(0, dtype=np.intp), nodes)
            pushed_back = float(np.max(-walls[press] * stiffness))
        scale = max(load_force_scale(self.scene), pushed_back)
        if scale > 0.0:
            return scale
        return float(self.scene.stiffness.min()) * self.displacement_scale

    @cached_property
    def displacement_scale(self) -> float:
        """U: the scene's displacement scale, from the loads and the prescribed gaps alone:
        the largest displacement the loads cause with no contact, ‖K⁻¹P‖∞, or the deepest
        press fit (largest −gap), whichever is larger. In a scene that nothing loads, the
        widest gap, or with none the longest bar."""
        scale = max(_largest(self.free_displacement), float(np.max(-self.g, initial=0.0)))
        if scale > 0.0:
            return scale
        widest = _largest(self.g)
        return widest if widest > 0.0 else max(float(b.lengths.sum()) for b in self.scene.bars)

    @property
    def n_contacts(self) -> int:
        """Contact rows: one per wall, then one per bar contact."""
        return int(self.g.size)

    def full_displacements(self, u_free: np.ndarray) -> np.ndarray:
        """Displacements of every node (m), zero at the supports."""
        supports = np.sort(self.scene.support_nodes)
        # np.insert puts each zero before the free node that follows the support
        return np.insert(np.asarray(u_free, dtype=float),
                         [node - i for i, node in enumerate(supports)], 0.0)


GREEN_ROWS = 16  # right-hand sides with at most this many loaded rows use the Green's function


def determinate_chain_solve(compliance: np.ndarray, support: int, rhs: np.ndarray) -> np.ndarray:
    """K⁻¹ rhs for a chain held at node ``support`` alone; ``compliance`` is φ per free node
    (:attr:`Model.compliance`); rhs rows are the free nodes in order (forces, N).

    Statically determinate: a unit force at node j stretches only the elements between the
    support and j, so K⁻¹ is the Green's function G_ij = min(φ_i, φ_j) for i, j on the same
    side of the support, 0 across it. With a few loaded rows (point loads, unit forces at the
    walls) each costs one pass; otherwise element forces by a cumulative sum of the loads
    beyond each element, elongations N/k = N·Δφ, displacements by a cumulative sum. Neither
    assembles K, whose rounded diagonal k_(e-1) + k_e costs 3e-8 of the contact force on a
    10⁶-element bar through a Cholesky solve (measured); these sums lose ~n·ε.
    """
    rhs = np.asarray(rhs, dtype=float)
    columns = np.ascontiguousarray(np.atleast_2d(rhs.T))  # one row per right-hand side
    loaded = np.unique(np.concatenate([np.flatnonzero(column) for column in columns]))
    if loaded.size <= GREEN_ROWS:
        out = np.zeros(columns.shape)
        for row in loaded:
            green = np.minimum(compliance, compliance[row])
            if support > 0:  # nothing crosses the support
                if row < support:
                    green[support:] = 0.0
                else:
                    green[:support] = 0.0
            out += columns[:, row : row + 1] * green
    else:
        flexibility = np.diff(compliance[support:], prepend=0.0)  # 1/k_e past the support
        out = np.empty(columns.shape)
        right = columns[:, support:]
        force = np.cumsum(right[:, ::-1], axis=1)[:, ::-1]
        np.cumsum(force * flexibility, axis=1, out=out[:, support:])
        if support > 0:
            flexibility = -np.diff(compliance[:support], append=0.0)
            elongation = np.cumsum(columns[:, :support], axis=1) * flexibility
            out[:, :support] = np.cumsum(elongation[:, ::-1], axis=1)[:, ::-1]
    return out[0] if rhs.ndim == 1 else out.T


def element_forces(scene: Scene | Bar, u: np.ndarray) -> np.ndarray:
    """Axial force of each element (N, tension positive) from the nodal displacements (m),
    bar after bar (:attr:`Scene.stiffness`)."""
    if isinstance(scene, Bar):
        return scene.stiffness * np.diff(u)
    stretch = np.diff(u)
    if scene.junctions.size:
        stretch = np.delete(stretch, scene.junctions)
    return scene.stiffness * stretch


def slot_forces(scene: Scene, forces: np.ndarray) -> np.ndarray:
    """Element forces placed between global nodes j and j + 1, 0 at a junction between bars."""
    if not scene.junctions.size:
        return forces
    return np.insert(forces, scene.junctions - np.arange(scene.junctions.size), 0.0)


def _largest(values: np.ndarray) -> float:
    """∞-norm (0 for no values; inf when any value is not finite)."""
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return 0.0
    largest = max(float(values.max()), -float(values.min()))
    return largest if np.isfinite(largest) else np.inf


def load_force_scale(scene: Scene) -> float:
    """The largest force the scene's loads put through any cut of a bar (N): over every bar
    and every node, the resultant of the loads (point and distributed) on either side, and
    every nodal load itself. A distributed load counts whole, not per node."""
    loads = scene.nodal_loads()
    offsets = scene.node_offsets
    sizes = np.diff(offsets)
    left = np.cumsum(loads)
    left -= np.repeat(np.r_[0.0, left[offsets[1:-1] - 1]], sizes)  # from each bar's node 0
    right = np.repeat(left[offsets[1:] - 1], sizes) - left
    return max(_largest(left), _largest(right), _largest(loads))


def seen_stiffness(scene: Scene, held: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """The stiffness (N/m) each of ``nodes`` (global) sees with the supports and the nodes
    ``held`` fixed: 1/c_left + 1/c_right, c the compliance Σ L/(EA) to the nearest fixed node
    on that side in the same bar (no term when there is none; a node does not hold itself)."""
    offsets = scene.node_offsets
    phi = scene.compliance
    fixed = np.unique(np.concatenate((scene.support_nodes, np.asarray(held, dtype=np.intp))))
    fixed_bar = np.searchsorted(offsets, fixed, side="right") - 1
    node_bar = np.searchsorted(offsets, nodes, side="right") - 1
    stiffness = np.zeros(nodes.size)
    for neighbour, sign in ((np.searchsorted(fixed, nodes, side="left") - 1, 1.0),
                            (np.searchsorted(fixed, nodes, side="right"), -1.0)):
        near = (neighbour >= 0) & (neighbour < fixed.size)
        near[near] &= fixed_bar[neighbour[near]] == node_bar[near]
        compliance = sign * (phi[nodes[near]] - phi[fixed[neighbour[near]]])
        stiffness[near] += 1.0 / compliance
    return stiffness


def contact_matrix(scene: Scene) -> sp.csr_array:
    """C in global node numbering (contact rows x nodes)."""
    rows, nodes, values, gaps = scene.contact_rows
    return sp.csr_array((values, (rows, nodes)), shape=(gaps.size, scene.n_nodes))


def wall_forces(scene: Scene, contact_force: np.ndarray) -> np.ndarray:
    """Force of the walls and bar contacts on each node in +x (N): −Cᵀλ in node numbering."""
    rows, nodes, values, _ = scene.contact_rows
    f = np.zeros(scene.n_nodes)
    np.add.at(f, nodes, -values * np.asarray(contact_force, dtype=float)[rows])
    return f


def penetration(scene: Scene, u: np.ndarray) -> np.ndarray:
    """How far each contact is closed past its gap (m), C u − g: positive = penetrated."""
    rows, nodes, values, gaps = scene.contact_rows
    closed = np.zeros(gaps.size)
    np.add.at(closed, rows, values * u[nodes])
    return closed - gaps


def build_model(scene: Scene) -> Model:
    """The model of a scene, O(n) in time and memory: K comes straight from the element
    stiffnesses in band form (a chain with its supports taken out)."""
    n = scene.n_nodes
    supports = np.sort(scene.support_nodes)
    free = np.delete(np.arange(n), supports)
    k = scene.slot_stiffness  # 0 between bars: no element joins them
    band = np.zeros((2, free.size))
    # node j's diagonal is k_(j-1) + k_j; its sub-diagonal entry couples it to node j + 1
    # through element j, unless node j + 1 is a support (then the entry is dropped)
    diagonal = np.zeros(n)
    diagonal[:-1] = k
    diagonal[1:] += k
    band[0] = np.delete(diagonal, supports)
    sub = np.zeros(n)
    sub[:-1] = -k
    sub[supports[supports > 0] - 1] = 0.0
    band[1] = np.delete(sub, supports)
    rows, nodes, values, g = scene.contact_rows
    keep = ~np.isin(nodes, supports)  # a bar contact's supported end contributes nothing
    columns = nodes[keep] - np.searchsorted(supports, nodes[keep])  # free-node numbers
    C = sp.csr_array((values[keep], (rows[keep], columns)), shape=(g.size, free.size))
    P = np.delete(scene.nodal_loads(), supports)
    return Model(scene, free, band, P, C, g)


def elongation_rows(model: Model) -> sp.csr_array:
    """B (elements x free nodes): B·u_free is the elongation of every element (m), with the
    supports' zero displacements taken out. The strain formulation's tie rows are B u − e = 0.
    Needs a chain model (one built by :func:`build_model`)."""
    if model.K_band is None:
        raise OptionError("formulation='strain' needs a chain model (one built by build_model)")
    scene = model.scene
    n_elements = scene.n_elements
    column = np.full(scene.n_nodes, -1)
    column[model.free] = np.arange(model.n_free)
    element = np.arange(n_elements)
    first = np.delete(np.arange(scene.n_nodes - 1), scene.junctions)  # element e's first node
    rows = np.concatenate((element, element))
    nodes = np.concatenate((first, first + 1))
    signs = np.concatenate((-np.ones(n_elements), np.ones(n_elements)))
    keep = column[nodes] >= 0
    return sp.csr_array((signs[keep], (rows[keep], column[nodes][keep])),
                        shape=(n_elements, model.n_free))


def without_circulation(model: Model, contact_force: np.ndarray) -> np.ndarray:
    """Contact forces (N) with the part taken out that rows holding a node at one position
    both ways would carry round and round: walls on both sides of a node whose gaps sum to 0
    (a clamped node), and the one-way loops of walls and bar contacts whose gaps add up
    (:attr:`Scene.tight_cycles`). Such a common part moves nothing, so the rows alone leave
    it open; the exact answer has none (contactqp.result)."""
    lam = np.array(contact_force, dtype=float)
    C = model.C
    single = np.flatnonzero(np.diff(C.indptr) == 1)
    if single.size:
        column, sign = C.indices[C.indptr[single]], C.data[C.indptr[single]]
        plus = np.full(C.shape[1], -1)
        minus = np.full(C.shape[1], -1)
        plus[column[sign > 0]] = single[sign > 0]
        minus[column[sign < 0]] = single[sign < 0]
        both = (plus >= 0) & (minus >= 0)
        p, m = plus[both], minus[both]
        clamped = model.g[p] + model.g[m] == 0.0
        p, m = p[clamped], m[clamped]
        common = np.maximum(np.minimum(lam[p], lam[m]), 0.0)
        lam[p] -= common
        lam[m] -= common
    for cycle in model.scene.tight_cycles:
        rows = list(cycle)
        lam[rows] -= max(float(lam[rows].min()), 0.0)
    return lam


EXACT_WALL_STIFFNESS_LIMIT = 64  # wall nodes up to which wall_stiffness solves for S exactly


def wall_stiffness(model: Model) -> float | None:
    """The stiffest way the walled nodes can be moved together (N/m): the largest eigenvalue of
    S⁻¹, S = B K⁻¹ Bᵀ the flexibility between the walled nodes (B selects them). One wall:
    1/(K⁻¹)ᵢᵢ, the stiffness it sees (mesh-independent). Two walls on nodes joined by a stiff
    element: that element's stretching mode. Above :data:`EXACT_WALL_STIFFNESS_LIMIT` walled
    nodes, the bound λmax(S⁻¹) <= λmax(K_BB) <= largest row sum of |K_BB| (S⁻¹ is K_BB less a
    positive semidefinite term; Gershgorin). None without walls."""
    nodes = np.unique(model.C.indices)
    if nodes.size == 0:
        return None
    if nodes.size > EXACT_WALL_STIFFNESS_LIMIT:
        K_BB = model.K[nodes][:, nodes]
        return float(np.abs(K_BB).sum(axis=1).max())
    selector = np.zeros((model.n_free, nodes.size))
    selector[nodes, np.arange(nodes.size)] = 1.0
    flexibility = model.solve_K(selector)[nodes]
    smallest = float(sla.eigvalsh(0.5 * (flexibility + flexibility.T), check_finite=False)[0])
    return 1.0 / smallest if smallest > 0.0 else float(np.abs(model.K.diagonal()[nodes]).max())


@dataclass(frozen=True, eq=False)
class Condensed:
    """A model condensed onto its contact nodes, and how to get every displacement back.

    ``model`` has one unknown per node that carries a wall: its stiffness is S⁻¹, S = B K⁻¹ Bᵀ
    the flexibility between those nodes (B selects them), its load S⁻¹ w₀ with w₀ = B K⁻¹ P
    their free displacements, and the same wall rows and gaps. Any method solves it; then
    u = K⁻¹P − K⁻¹Cᵀλ, from the same factorisation (``u0`` and ``X`` = K⁻¹Bᵀ).
    """

    model: Model
    u0: np.ndarray
    X: np.ndarray

    def displacements(self, contact_force: np.ndarray) -> np.ndarray:
        """Free-node displacements of the full model (m) under contact forces λ (N)."""
        return self.u0 - self.X @ (self.model.C.T @ np.asarray(contact_force, dtype=float))


def condense(model: Model) -> Condensed:
    """Condense a chain model onto its contact nodes with one banded Cholesky factorisation
    of K (LAPACK pbsv) and one solve per contact node plus one for the loads."""
    if model.K_band is None:
        raise OptionError("formulation='condensed' needs a chain model (one built by build_model)")
    nodes = np.unique(model.C.indices)
    if nodes.size > CONDENSE_LIMIT:
        raise OptionError(
            f"formulation='condensed': {nodes.size} contact nodes give a dense "
            f"{nodes.size}x{nodes.size} flexibility (limit {CONDENSE_LIMIT}); use 'full'"
        )
    rhs = np.zeros((model.n_free, nodes.size + 1), order="F")  # columns contiguous
    rhs[:, 0] = model.P
    rhs[nodes, np.arange(1, nodes.size + 1)] = 1.0
    solved = model.solve_K(rhs)
    model.__dict__.setdefault("free_displacement", solved[:, 0])  # K⁻¹P, for the check
    flexibility = solved[nodes, 1:]
    try:
        stiffness = sla.inv(flexibility, check_finite=False) if nodes.size else flexibility
    except np.linalg.LinAlgError as error:
        raise SolverError(f"condensed formulation: the flexibility is singular ({error})") from None
    stiffness = 0.5 * (stiffness + stiffness.T)
    u0, X = solved[:, 0], solved[:, 1:]
    column = np.full(model.n_free, -1)
    column[nodes] = np.arange(nodes.size)
    C = model.C.tocoo()
    reduced = Model(
        model.scene, model.free[nodes], sp.csr_array(stiffness), stiffness @ u0[nodes],
        sp.csr_array((C.data, (C.row, column[C.col])), shape=(model.n_contacts, nodes.size)),
        model.g,
    )
    return Condensed(reduced, u0, X)
