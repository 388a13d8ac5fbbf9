"""A model condensed onto its contact nodes: the small problem a method solves when the bar is
long and the contacts few, and how every displacement comes back from it.

Static condensation of a chain onto some of its nodes is again a chain: the elements between
two kept nodes (or a kept node and a support) act in series, stiffness 1 / Σ L/(EA), and a
stretch beyond the last kept node towards a free end carries nothing. So the condensed
stiffness S⁻¹ (S = B K⁻¹ Bᵀ the flexibility between the contact nodes, B selecting them) is
tridiagonal, built in O(n) from sums of compliances, and never formed as a dense matrix: any
number of contact nodes, every method and QP solver sees a banded problem.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from contactqp import linalg
from contactqp.errors import SolverError
from contactqp.model.chain.layout_names import Layout, node_set, spread
from contactqp.model.chain.model import Model


@dataclass(frozen=True, eq=False)
class Condensed:
    """The problem in the contact nodes only: one unknown per node that carries a contact, its
    tridiagonal stiffness S⁻¹ (``band``: LAPACK lower band storage, diagonal then
    sub-diagonal), its load S⁻¹ w₀ (w₀ the nodes' free displacements), the same contact rows
    and gaps. A method solves it like a Model; then every displacement follows from the
    contact forces by statics (:meth:`displacements`).
    """

    full: Model
    nodes: np.ndarray  # the contact nodes, as unknowns of ``full``
    floating = ()  # condensing solves with K: every bar has a support (Model.floating)
    flexibility_in_blocks = False  # as a Model (contactqp.model.base)
    band: np.ndarray
    P: np.ndarray
    C: sp.csr_array
    u0: np.ndarray  # K⁻¹P over the full model's unknowns
    load_factor: float = 1.0  # the loads are ``full``'s times this (a step of a load path)

    @property
    def layout(self) -> Layout:
        return self.full.layout

    @property
    def g(self) -> np.ndarray:
        return self.full.g

    @cached_property
    def K(self) -> sp.csr_array:
        """S⁻¹ as a sparse tridiagonal matrix (diagonal alone for fewer than two nodes)."""
        band = self.band
        if band.shape[1] < 2:  # no neighbours: scipy refuses the off-diagonals' offsets
            return sp.csr_array(sp.diags_array(band[0], shape=(band.shape[1],) * 2))
        return sp.csr_array(sp.diags_array([band[1, :-1], band[0], band[1, :-1]],
                                           offsets=[-1, 0, 1]))

    @property
    def n_free(self) -> int:
        return int(self.nodes.size)

    @property
    def n_contacts(self) -> int:
        return int(self.g.size)

    def solve_K(self, rhs: np.ndarray) -> np.ndarray:
        """S rhs: the condensed chain solved (banded Cholesky, LAPACK pbsv)."""
        rhs = np.asarray(rhs, dtype=float)
        if self.nodes.size == 0:
            return rhs.copy()
        try:
            return linalg.solve_spd_band(self.band, rhs)
        except np.linalg.LinAlgError as error:
            raise SolverError(f"condensed formulation: the condensed stiffness is not "
                              f"positive definite ({error})") from None

    solve_K_and_loads = solve_K

    @property
    def free_displacement(self) -> np.ndarray:
        """w₀: the contact nodes' displacement under the loads with no contact."""
        return self.u0[self.nodes]

    @property
    def displacement_scale(self) -> float:
        """U: the full model's (the same problem, in fewer unknowns)."""
        return self.full.displacement_scale

    def displacements(self, contact_force: np.ndarray) -> np.ndarray:
        """Free-node displacements of the full model under contact forces λ: u = K⁻¹P −
        K⁻¹Cᵀλ, the second term by statics: S Cᵀλ at the contact nodes (one banded solve),
        spread along the chain (:func:`contactqp.model.chain.layout_names.spread`: forces at the contact
        nodes alone move the rest linearly in the compliance)."""
        push = self.C.T @ np.asarray(contact_force, dtype=float)
        moved = self.solve_K(push)
        layout, full = self.layout, self.full
        kept = full.free[self.nodes]
        anchors = node_set(layout.n_nodes, layout.support_nodes, kept)
        values = np.zeros(anchors.size)  # 0 at the supports
        values[np.searchsorted(anchors, kept)] = moved
        # u0 − the spread at the free nodes, in the one new array the free nodes need
        u = spread(layout, anchors, values)[full.free]
        return np.subtract(self.u0, u, out=u)

    def scaled(self, factor: float) -> Condensed:
        """The same problem with every load times ``factor`` (a step of a load path: the
        condensed chain is reused)."""
        return Condensed(self.full, self.nodes, self.band, factor * self.P, self.C,
                         factor * self.u0, factor * self.load_factor)


def condensed_model(model: Model) -> Condensed:
    """:func:`condense` of ``model``, made once and kept on it (a scene keeps its model, so a
    scene solved again in the condensed formulation is condensed once)."""
    kept = model.__dict__.get("condensed")
    if kept is None:
        kept = model.__dict__["condensed"] = condense(model)
    return kept


def condense(model: Model) -> Condensed:
    """Condense a model onto its contact nodes (module docstring): one solve for K⁻¹P (by
    statics where every bar has one support) and O(n) sums for the condensed chain."""
    layout = model.layout
    nodes = np.flatnonzero(np.bincount(model.C.indices, minlength=model.n_free))
    u0 = model.free_displacement
    kept = model.free[nodes]  # global numbers, increasing
    anchors = node_set(layout.n_nodes, layout.support_nodes, kept)
    # the compliance between neighbouring anchors, element by element (inf across bars)
    between = np.add.reduceat(layout.link_compliance, anchors)[:-1] if anchors.size else (
        np.zeros(0))
    with np.errstate(divide="ignore"):
        series = 1.0 / between  # 0 across a junction
    is_kept = np.zeros(layout.n_nodes, dtype=bool)
    is_kept[kept] = True
    position = np.flatnonzero(is_kept[anchors])  # where each kept node sits among anchors
    to_left = np.where(position > 0, series[np.maximum(position - 1, 0)], 0.0)
    to_right = np.where(position < anchors.size - 1,
                        series[np.minimum(position, max(series.size - 1, 0))]
                        if series.size else 0.0, 0.0)
    band = np.zeros((2, nodes.size))
    band[0] = to_left + to_right
    # a kept node and the next anchor, also kept: the series spring between them couples them
    adjacent = np.append(position[1:] == position[:-1] + 1, False)
    band[1] = np.where(adjacent, -to_right, 0.0)
    column = np.full(model.n_free, -1)
    column[nodes] = np.arange(nodes.size)
    C = model.C.tocoo()
    reduced_C = sp.csr_array((C.data, (C.row, column[C.col])), shape=(model.n_contacts, nodes.size))
    w0 = u0[nodes]
    load = band[0] * w0
    load[:-1] += band[1, :-1] * w0[1:]
    load[1:] += band[1, :-1] * w0[:-1]
    return Condensed(model, nodes, band, load, reduced_C, u0)


__all__ = ["Condensed", "condense", "condensed_model"]
