"""The model of a scene: minimise ½ uᵀKu − uᵀP subject to C u (<= or =) g, over the free nodes.

K is the stiffness matrix of the chain (:class:`~contactqp.model.chain.layout_names.Layout`) with the
supports taken out: tridiagonal, zero coupling between bars, kept in LAPACK's symmetric band
storage and solved in O(n): by statics when every bar is held by one support, else by one
banded Cholesky factorisation. With the Lagrangian L = Π + λᵀ(C u − g), λ >= 0 is the force
with which each wall (or the other bar) pushes, and the contacts' force on the nodes is −Cᵀλ.

The condensed chain is in condense.py; what methods read off a model besides its solves with
K (the strain formulation's rows, the stiffness the walls see, forces without circulation) is
in reading.py.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from contactqp import linalg
from contactqp.errors import SceneError, SolverError
from contactqp.model.base import (
    ContactModel,
    ScaleTerms,
    balanced_by_contact,
    first_step_forces,
)
from contactqp.model.chain.layout_names import (
    Layout,
    contact_forces_on_nodes,
    largest,
    penetration,
)
from contactqp.model.chain.numbering import layout_of
from contactqp.scene import Scene, row_names
from contactqp.scene.scene import SCENE_MODEL


@dataclass(frozen=True, eq=False)
class Model(ContactModel):
    """The algebra of a scene (module docstring).

    Attributes
    ----------
    layout : the numbering and arrays of the scene (``layout.scene`` the scene itself).
    free : global node number of each unknown (the free nodes, in order).
    band : K in LAPACK symmetric lower band storage (2 x n_free: diagonal, sub-diagonal).
    P : loads on the free nodes.
    C : sparse contact rows over the free nodes, one per wall (±1) then one per bar contact
        (+1 at node a, −1 at node b), CSR.
    g : the contacts' gaps.
    """

    layout: Layout
    free: np.ndarray
    band: np.ndarray
    P: np.ndarray
    C: sp.csr_array
    g: np.ndarray

    @property
    def scene(self) -> Scene:
        return self.layout.scene

    def with_layout(self, layout: Layout) -> Model:
        """This model for a scene that differs only in its load values and gaps (``layout``
        from :meth:`Layout.with_values`): the numbering, K and C shared, P and g anew."""
        model = Model(layout, self.free, self.band, free_loads(layout), self.C, layout.rows.gap)
        # what K and the supports decide, worked out here once for every model made from this
        # one (a prepared scene's solves), and K itself if made; never P or g
        kept = ["floating", "determinate", "stiffest", "K", "row_stiffness", "row_roots",
                "_entries", "_one_entry_per_row", "_contact_columns", "_free_run"]
        if self.determinate is not None:
            kept.append("compliance_to_support")
        for name in kept:
            model.__dict__[name] = getattr(self, name)
        return model

    @cached_property
    def K(self) -> sp.csr_array:
        """K as a sparse CSR matrix (made from the band when first asked for)."""
        band = self.band
        return sp.csr_array(sp.diags_array([band[1, :-1], band[0], band[1, :-1]],
                                           offsets=[-1, 0, 1]))

    def solve_K(self, rhs: np.ndarray) -> np.ndarray:
        """K⁻¹ rhs (every column of ``rhs``): by statics where every bar is held by one
        support (:func:`determinate_chain_solve`, exact to round-off), else one banded
        Cholesky factorisation (LAPACK pbsv). SolverError when K is not positive definite,
        and when a bar has no support (:attr:`floating`): K is singular there."""
        if self.floating:
            raise SolverError(
                f"bar[{self.floating[0]}] has no support, so K is singular and has no inverse; "
                f"the methods that need K⁻¹ cannot solve this scene ({FLOATING_METHODS} can)")
        if self.determinate is not None:
            rhs = np.asarray(rhs, dtype=float)
            out = np.empty(rhs.shape)
            for block, support in self.determinate:  # one block of free nodes per bar
                out[block] = determinate_chain_solve(self.compliance_to_support[block], support,
                                                     rhs[block])
            return out
        try:
            return linalg.solve_spd_band(self.band, rhs)
        except np.linalg.LinAlgError as error:
            raise SolverError(f"K is not positive definite ({error})") from None

    @cached_property
    def stiffest(self) -> float:
        """K's largest diagonal entry (N/m; 1 without unknowns): the hull's displacement floor."""
        return float(self.band[0].max()) if self.band.size else 1.0

    @cached_property
    def floating(self) -> tuple[int, ...]:
        """The bars with no support (:attr:`Layout.floating_bars`)."""
        return tuple(self.layout.floating_bars.tolist())

    @property
    def held(self) -> Model:
        """This model, or where bars have no support (:attr:`floating`) the model with each
        such bar tied to zero at its node 0 by a spring as stiff as the whole bar (its
        elements in series), so that K is positive definite. For scales only (U, the
        stiffness the walls see, a solver's scaling): never for an answer."""
        return self._tied if self.floating else self  # never kept as itself: no cycle

    @cached_property
    def _tied(self) -> Model:
        """:attr:`held` where bars float (made once)."""
        band = self.band.copy()
        layout = self.layout
        column = np.searchsorted(self.free, layout.node_offsets[list(self.floating)])
        band[0, column] += [1.0 / float(self.scene.bars[b].compliance[-1])
                            for b in self.floating]
        model = Model(layout, self.free, band, self.P, self.C, self.g)
        model.__dict__["floating"] = ()
        model.__dict__["determinate"] = None  # the springs are not supports
        return model

    @cached_property
    def determinate(self) -> tuple[tuple[slice, int], ...] | None:
        """When every bar is held by exactly one support (statically determinate): per bar,
        the slice of its free nodes and the support's position in that slice. Else None."""
        scene = self.scene
        if len(scene.supports) != len(scene.bars) or self.layout.floating_bars.size:
            return None
        first = np.searchsorted(self.free, self.layout.node_offsets)
        return tuple((slice(int(first[b]), int(first[b + 1])), support)
                     for b, support in sorted((s.bar, s.node) for s in scene.supports))

    def energy_of(self, push: np.ndarray) -> float:
        """pushᵀ K⁻¹ push; where every bar is held by one support and few nodes are pushed,
        from the Green's function G_ij = min(φ_i, φ_j) of the nodes pushed (same bar, same
        side of its support; :func:`determinate_chain_solve`) with no pass over the chain."""
        loaded = np.flatnonzero(push)
        if self.determinate is None or loaded.size > GREEN_ROWS:
            return super().energy_of(push)
        if loaded.size == 1:  # one node pushed (one wall passed): φ_j f_j²
            j = int(loaded[0])
            return float(self.compliance_to_support[j] * push[j] ** 2)
        side = np.empty(loaded.size, dtype=np.intp)  # one number per bar and side of support
        for b, (block, support) in enumerate(self.determinate):
            inside = (loaded >= block.start) & (loaded < block.stop)
            side[inside] = 2 * b + (loaded[inside] - block.start >= support)
        phi, force = self.compliance_to_support[loaded], push[loaded]
        green = np.where(side[:, None] == side[None, :], np.minimum(phi[:, None], phi[None, :]),
                         0.0)
        return float(force @ green @ force)

    @cached_property
    def compliance_to_support(self) -> np.ndarray:
        """φ per free node when every bar is held by one support: Σ 1/k_e over the elements
        between the node and its bar's support, the displacement a unit force there causes."""
        parts = []
        for b, s in sorted((s.bar, s.node) for s in self.scene.supports):  # one per bar
            from_0 = self.scene.bars[b].compliance
            parts.append(from_0[1:] if s == 0 else np.abs(np.delete(from_0, s) - from_0[s]))
        return np.concatenate(parts)

    @property
    def n_free(self) -> int:
        return int(self.free.size)

    @property
    def n_contacts(self) -> int:
        """Contact rows: one per wall, then one per bar contact."""
        return int(self.g.size)

    @cached_property
    def free_displacement(self) -> np.ndarray:
        """K⁻¹P: the displacement the loads cause with no contact at all."""
        return self.solve_K(self.P)

    @cached_property
    def free_displacement_of_nodes(self) -> np.ndarray:
        """K⁻¹P at every node (0 at the supports), once per model: the hull starts from it
        and the check's natural map reads the free gaps from it (read-only)."""
        u = self.full_displacements(self.free_displacement)
        u.flags.writeable = False
        return u

    def solve_K_and_loads(self, rhs: np.ndarray) -> np.ndarray:
        """K⁻¹ rhs (columns), with K⁻¹P (:attr:`free_displacement`) from the same
        factorisation when it is not known yet."""
        if "free_displacement" in self.__dict__:
            return self.solve_K(rhs)
        rhs = np.asarray(rhs, dtype=float)
        solved = self.solve_K(np.column_stack((rhs, self.P)))
        self.__dict__["free_displacement"] = solved[:, -1]
        return solved[:, :-1] if rhs.ndim == 2 else solved[:, 0]

    # --- the protocol (contactqp.model.base)
    @property
    def equality(self) -> np.ndarray:
        """No row of a scene is an equality of its own (``contact="equality"`` holds them all)."""
        return np.zeros(self.n_contacts, dtype=bool)

    @cached_property
    def row_names(self) -> tuple[str, ...]:
        return tuple(row_names(self.scene))

    @property
    def units(self) -> tuple[str, str]:
        return self.scene.unit_names

    @property
    def singular(self) -> bool:
        """Whether a bar has no support (K singular: contact alone holds it)."""
        return bool(self.floating)

    def largest_imbalance(self, u_free: np.ndarray, contact_force: np.ndarray,
                          links: np.ndarray | None = None) -> float:
        """‖K u − P + Cᵀλ‖∞ over the free nodes (:meth:`imbalance`). ``links``: the
        element forces on the links between nodes (:func:`link_forces`), where the caller has
        them: then (K u)_j = N_(j−1) − N_j, one subtraction. Worked out in blocks of
        IMBALANCE_BLOCK nodes: no array of n, whose first touch costs its page faults (an
        8 MB temporary took ~3 ms at 10⁶ nodes on this project's machines)."""
        band, P, n = self.band, self.P, u_free.size
        columns, inverse = self._contact_columns
        rows, _, values = self._entries
        force = contact_force if self._one_entry_per_row else contact_force[rows]
        push = np.bincount(inverse, values * force, minlength=columns.size)
        every = columns.size == n  # every free node touched: columns is 0 … n − 1
        if links is not None and n <= IMBALANCE_BLOCK and (self._free_run is None
                                                           or n <= SHORT_CHAIN):
            # free nodes apart (supports inside the chain: a batch's cases), or few, one
            # block: the same subtraction N_(j−1) − N_j, read at the free nodes (the links 0
            # past the ends)
            ends = np.concatenate(([0.0], links, [0.0]))
            r = np.subtract(ends[:-1], ends[1:]).take(self.free)  # one gather, no free + 1
            r -= P
            if every:
                r += push
            else:
                r[columns] += push
            return float(np.abs(r, out=r).max(initial=0.0))
        edges = np.searchsorted(columns, np.arange(0, n + IMBALANCE_BLOCK, IMBALANCE_BLOCK))
        run = self._free_run if links is not None else None
        offset = run.start if run is not None else 0
        top = 0.0
        for k, start in enumerate(range(0, n, IMBALANCE_BLOCK)):
            stop = min(start + IMBALANCE_BLOCK, n)
            first, last = start + offset, stop + offset  # global nodes: r = N_(j−1) − N_j
            if run is not None and first >= 1 and last <= links.size:
                r = np.subtract(links[first - 1:last - 1], links[first:last])
            elif run is not None:  # the chain's first or last node: a link missing
                r = np.zeros(stop - start)
                low = max(first, 1)  # N_(j−1) exists
                r[low - first:] += links[low - 1:last - 1]
                high = min(last, links.size)  # N_j exists
                r[:high - first] -= links[first:high]
            else:
                r = band[0, start:stop] * u_free[start:stop]
                low = max(start, 1)  # r_j += k_(j−1,j) u_(j−1)
                r[low - start:] += band[1, low - 1:stop - 1] * u_free[low - 1:stop - 1]
                high = min(stop, n - 1)  # r_j += k_(j,j+1) u_(j+1)
                r[:high - start] += band[1, start:high] * u_free[start + 1:high + 1]
            r -= P[start:stop]
            a, b = edges[k], edges[k + 1]
            if every:
                r += push[a:b]
            else:
                r[columns[a:b] - start] += push[a:b]
            top = max(top, float(np.abs(r, out=r).max(initial=0.0)))
        return top

    @cached_property
    def _contact_columns(self) -> tuple[np.ndarray, np.ndarray]:
        """The free nodes C touches (sorted, each once), and per entry of C its place there
        (marked and counted, O(n): a sort of 10⁵ walls' columns took 10 ms)."""
        columns = self._entries[1]
        touched = np.zeros(self.n_free, dtype=bool)
        touched[columns] = True
        place = np.cumsum(touched) - 1
        return np.flatnonzero(touched), place[columns]

    @cached_property
    def row_stiffness(self) -> np.ndarray:
        """s̄_i = c_iᵀK c_i / (c_iᵀc_i)² per row (:func:`contactqp.model.base.row_stiffness`),
        from K's band: a row holds one node (a wall) or two (a bar contact), so c_iᵀK c_i is
        Σ c² K_jj plus, for two neighbouring nodes, 2 c_a c_b K_ab (no sparse product: it took
        26 ms of a first solve against 10⁵ walls)."""
        rows, columns, values = self._entries
        if rows.size and np.bincount(rows).max() > 2:
            return super().row_stiffness
        m, band = self.n_contacts, self.band
        squared = np.bincount(rows, values * values, minlength=m)
        energy = np.bincount(rows, values * values * band[0, columns], minlength=m)
        pair = np.flatnonzero(rows[1:] == rows[:-1])  # entries pair and pair + 1: one row
        apart = columns[pair + 1] - columns[pair]
        pair, low = pair[np.abs(apart) == 1], np.minimum(columns[pair], columns[pair + 1])
        low = low[np.abs(apart) == 1]
        energy += np.bincount(rows[pair], 2.0 * values[pair] * values[pair + 1] * band[1, low],
                              minlength=m)
        with np.errstate(divide="ignore", invalid="ignore"):
            s = energy / squared**2
        s.flags.writeable = False
        return s

    def reactions_of(self, u: np.ndarray, contact_force: np.ndarray) -> np.ndarray:
        """Each support's force (+x) for displacements ``u`` of every node (statics)."""
        return support_balance(self.layout, *support_links(self.layout, u), contact_force)

    def support_change(self, du: np.ndarray) -> np.ndarray:
        """The supports' forces of a move ``du`` of the free nodes (statics, no load)."""
        left, right = support_links(self.layout, self.full_displacements(du))
        return left - right

    def seen_stiffness(self, rows: np.ndarray) -> np.ndarray:
        """1 / the compliance each row sees with the supports held
        (:attr:`Layout.row_compliance`: statics along the chain; 0 on a floating bar)."""
        compliance = self.layout.row_compliance[rows]
        with np.errstate(divide="ignore"):
            return np.where(np.isfinite(compliance), 1.0 / compliance, 0.0)

    def pseudo_solve(self, rhs: np.ndarray) -> np.ndarray:
        """K⁺ rhs: K⁻¹ rhs, or where bars float (:attr:`floating`) the least-norm solution of
        K u = rhs less each floating bar's resultant spread evenly over its nodes (its part
        that only contact can carry): solved on :attr:`held` (whose tie springs then carry
        nothing) and each floating bar's mean displacement taken out."""
        if not self.floating:
            return self.solve_K(rhs)
        groups = self._floating_groups
        rhs = np.asarray(rhs, dtype=float)
        balanced = rhs - np.bincount(groups, rhs, minlength=len(self.floating) + 1)[
            groups] / self._floating_sizes[groups]
        balanced[groups == len(self.floating)] = rhs[groups == len(self.floating)]
        u = self.held.solve_K(balanced)
        means = np.bincount(groups, u, minlength=len(self.floating) + 1) / self._floating_sizes
        shift = means[groups]
        shift[groups == len(self.floating)] = 0.0
        return u - shift

    @cached_property
    def _floating_groups(self) -> np.ndarray:
        """Per free node, the index of its floating bar among :attr:`floating` (their count
        for a node of a supported bar)."""
        groups = np.full(self.n_free, len(self.floating), dtype=np.intp)
        bars = self.layout.bar_of(self.free)
        for k, bar in enumerate(self.floating):
            groups[bars == bar] = k
        return groups

    @cached_property
    def _free_modes(self) -> np.ndarray:
        """The modes K leaves free, columns: each floating bar's translation (1 on its nodes)."""
        count = len(self.floating)
        modes = np.zeros((self.n_free, count))
        groups = self._floating_groups if count else np.zeros(0, dtype=np.intp)
        rows = np.flatnonzero(groups < count)
        modes[rows, groups[rows]] = 1.0
        return modes

    @cached_property
    def _floating_sizes(self) -> np.ndarray:
        sizes = np.bincount(self._floating_groups, minlength=len(self.floating) + 1)
        return np.maximum(sizes, 1).astype(float)

    def scale_terms(self) -> ScaleTerms:
        """The scales' terms (:mod:`contactqp.model.base`), by statics on the chain."""
        layout = self.layout
        if self.floating:
            u0 = self.full_displacements(
                self.pseudo_solve(balanced_by_contact(self.P, self._free_modes, self.C)))
        else:  # K⁻¹P, which the methods read too: solved once per model
            u0 = self.free_displacement_of_nodes
        passed = np.maximum(penetration(layout, u0), 0.0)  # rows of ±1: a length as it is
        contact = first_step_forces(passed, self.row_stiffness, self.C_transpose_times,
                                    self.energy_of)
        unbalanced = (np.abs(np.bincount(self._floating_groups, self.P)[: len(self.floating)])
                      if self.floating else np.zeros(0))
        if self.determinate is not None:  # each bar's one support carries the bar's loads
            reactions = layout.bar_loads
        else:
            reactions = self.reactions_of(u0, np.zeros(self.n_contacts))
        return ScaleTerms(
            loads=largest(layout.nodal_loads), reactions=largest(reactions),
            contact=largest(contact), unbalanced=largest(unbalanced), free=largest(u0),
            passed=largest(passed), widest=float(np.maximum.reduce(self.g, initial=0.0)),
            size=float(layout.longest_bar), softest=float(np.minimum.reduce(
                self.band[0], initial=np.inf)) if self.band.size else 0.0)

    def full_displacements(self, u_free: np.ndarray) -> np.ndarray:
        """Displacements of every node, zero at the supports."""
        u_free = np.asarray(u_free, dtype=float)
        if u_free.shape == self.free.shape:  # placed (np.insert: 10x slower on a batch)
            u = np.zeros(self.layout.n_nodes)
            u[self.free] = u_free
            return u
        # another length (a method's bad answer): the check says so, naming it
        supports = np.sort(self.layout.support_nodes)
        return np.insert(u_free, supports - np.arange(supports.size), 0.0)


def build_model(scene: Scene | Layout) -> Model:
    """The model of a scene, O(n) in time and memory: K comes straight from the element
    stiffnesses in band form (the chain with its supports taken out).

    Parameters
    ----------
    scene : Scene or Layout
        The scene, or its layout (the numbering, when it is already made).

    Returns
    -------
    Model
        K in band storage, the loads P, the contact rows C and gaps g, and the solves with K.

    Raises
    ------
    SceneError
        Anything but a Scene or a Layout; a scene whose loads leave a bar held by contact
        alone unheld.
    """
    if not isinstance(scene, (Scene, Layout)):
        raise SceneError(f"scene must be a contactqp.Scene or its Layout, got {scene!r}")
    layout = scene if isinstance(scene, Layout) else layout_of(scene)
    if layout.scene.beds:  # every chain path builds its model here: none ignores the bed
        raise SceneError("the scene has a frictional bed: contactqp.solve takes it (with "
                         "friction, as a problem: problem_from_scene); the chain model and "
                         "what reads it (prepare, load_path, compare, check) do not")
    n = layout.n_nodes
    supports = np.sort(layout.support_nodes)
    free = np.delete(np.arange(n), supports)
    k = layout.link_stiffness  # 0 between bars: no element joins them
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
    rows = layout.rows
    keep = ~layout.support_mask[rows.node]  # a bar contact's supported end contributes nothing
    column = np.full(n, -1, dtype=np.intp)  # each free node's number among the free ones
    column[free] = np.arange(free.size)
    # CSR straight from the entries, put in row order (walls come so; then every bar
    # contact's node a, then every node b)
    entries = np.flatnonzero(keep)
    if layout.scene.contacts:
        entries = entries[np.argsort(rows.row[entries], kind="stable")]
    indptr = np.concatenate(([0], np.cumsum(np.bincount(rows.row[entries],
                                                          minlength=rows.gap.size))))
    C = sp.csr_array((rows.coefficient[entries], column[rows.node[entries]], indptr),
                     shape=(rows.gap.size, free.size))
    P = free_loads(layout)
    return Model(layout, free, band, P, C, rows.gap)


def scene_model(scene: Scene) -> Model:
    """The model of ``scene``, built once and kept with the scene's layout: a Scene does not
    change, so every later solve, preparation or load path of the same scene object reuses
    the model and what it has worked out since (K's solves and factor, K⁻¹P, the scales F
    and U, the free gaps; :class:`Model`'s cached properties), and computes none of it
    twice. The model is kept in the scene (:data:`contactqp.scene.scene.KEPT`), not in its
    layout, which the model holds: no cycle keeps either past its last user. Its arrays are
    read-only, so that no caller can change what the next one reads.
    A scene with other values (:meth:`Scene.with_values`) has a layout of its own, and so a
    model of its own."""
    model = scene.__dict__.get(_KEPT_MODEL)
    if model is None:
        model = build_model(layout_of(scene))
        for array in (model.free, model.band, model.P):
            array.flags.writeable = False
        scene.__dict__[_KEPT_MODEL] = model
    return model


# where scene_model keeps a scene's model: in the scene, not its layout, which the model holds
_KEPT_MODEL = SCENE_MODEL


def free_loads(layout: Layout) -> np.ndarray:
    """P: the nodal loads on the free nodes (the supports taken out), in order."""
    return np.delete(layout.nodal_loads, layout.support_nodes)


FLOATING_METHODS = "lagrange, penalty, augmented, qp and nitsche"  # the methods that solve bars with no support

GREEN_ROWS = 16  # right-hand sides with at most this many loaded rows use the Green's function
SHORT_CHAIN = 1024  # free nodes up to which the imbalance gathers them even as one run
IMBALANCE_BLOCK = 131072  # nodes per block of Model.largest_imbalance (1 MB: 4096-10⁶ measured, this fastest)


def determinate_chain_solve(compliance: np.ndarray, support: int, rhs: np.ndarray) -> np.ndarray:
    """K⁻¹ rhs for a chain held at node ``support`` alone; ``compliance`` is φ per free node
    (:attr:`Model.compliance_to_support`); rhs rows are the free nodes in order (forces, N).

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
    loaded = np.flatnonzero((columns != 0.0).any(axis=0))  # rows any right-hand side loads
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
        step = np.diff(compliance[support:], prepend=0.0)  # 1/k_e past the support
        out = np.empty(columns.shape)
        right = columns[:, support:]
        force = np.cumsum(right[:, ::-1], axis=1)[:, ::-1]
        np.cumsum(force * step, axis=1, out=out[:, support:])
        if support > 0:
            step = -np.diff(compliance[:support], append=0.0)
            elongation = np.cumsum(columns[:, :support], axis=1) * step
            out[:, :support] = np.cumsum(elongation[:, ::-1], axis=1)[:, ::-1]
    return out[0] if rhs.ndim == 1 else out.T


__all__ = ["Model", "build_model", "determinate_chain_solve", "scene_model", "support_balance",
           "support_links", "support_reactions"]


def support_links(layout: Layout, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(left, right): the force of the link on each side of each support for displacements
    ``u`` of every node, k (u[j + 1] − u[j]) as :func:`element_forces` makes it, on those links
    alone (0 between bars and past either end: :attr:`Layout.support_sides`)."""
    sides = []
    for link, k in layout.support_sides:
        force = np.zeros(link.size)
        where = link >= 0
        j = link[where]
        force[where] = k * (u[j + 1] - u[j])
        sides.append(force)
    return sides[0], sides[1]


def support_reactions(layout: Layout, forces: np.ndarray, contact_force: np.ndarray
                      ) -> np.ndarray:
    """The force (+x) each support applies: what equilibrium of its node leaves over from
    the elements on either side (``forces`` per link, 0 between bars), the loads and the
    contacts there."""
    nodes = layout.support_nodes
    right = np.where(nodes < forces.size, forces[np.minimum(nodes, forces.size - 1)], 0.0)
    left = np.where(nodes > 0, forces[np.maximum(nodes - 1, 0)], 0.0)
    return support_balance(layout, left, right, contact_force)


def support_balance(layout: Layout, left: np.ndarray, right: np.ndarray,
                    contact_force: np.ndarray) -> np.ndarray:
    """Each support's force from the forces of the links on its ``left`` and ``right``
    (:func:`support_links`), less the loads and the contacts at its node."""
    outside = layout.nodal_loads[layout.support_nodes]
    if layout.scene.contacts:  # a bar contact may end at a support; walls may not
        outside = outside + contact_forces_on_nodes(layout, contact_force)[layout.support_nodes]
    return left - right - outside
