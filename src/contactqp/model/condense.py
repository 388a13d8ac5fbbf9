"""A model condensed onto its contact nodes: the small problem a method solves when the bar is
long and the contacts few, and how every displacement comes back from it."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from contactqp.errors import OptionError, SolverError
from contactqp.model.chain import Model, displacement_scale
from contactqp.model.layout import Layout

CONDENSE_LIMIT = 2000  # contact nodes: the condensed flexibility is a dense square of this size


@dataclass(frozen=True, eq=False)
class Condensed:
    """The problem in the contact nodes only: one unknown per node that carries a contact, its
    stiffness S⁻¹ (S = B K⁻¹ Bᵀ the flexibility between those nodes, B selecting them), its
    load S⁻¹ w₀ (w₀ = B K⁻¹ P their free displacements), the same contact rows and gaps. A
    method solves it like a Model; then u = K⁻¹P − K⁻¹Cᵀλ (:meth:`displacements`), from the
    same factorisation of K (``u0`` = K⁻¹P and ``X`` = K⁻¹Bᵀ).
    """

    full: Model
    nodes: np.ndarray  # the contact nodes, as unknowns of ``full``
    S_inverse: np.ndarray
    P: np.ndarray
    C: sp.csr_array
    u0: np.ndarray
    X: np.ndarray

    @property
    def layout(self) -> Layout:
        return self.full.layout

    @property
    def g(self) -> np.ndarray:
        return self.full.g

    @cached_property
    def K(self) -> sp.csr_array:
        return sp.csr_array(self.S_inverse)

    @property
    def n_free(self) -> int:
        return int(self.nodes.size)

    @property
    def n_contacts(self) -> int:
        return int(self.g.size)

    def solve_K(self, rhs: np.ndarray) -> np.ndarray:
        """S rhs: the condensed stiffness inverted by its flexibility."""
        flexibility = self.X[self.nodes]
        return flexibility @ np.asarray(rhs, dtype=float)

    solve_K_and_loads = solve_K

    @property
    def free_displacement(self) -> np.ndarray:
        """w₀: the contact nodes' displacement under the loads with no contact."""
        return self.u0[self.nodes]

    @cached_property
    def displacement_scale(self) -> float:
        """U of the condensed problem: its free displacement or its deepest press fit."""
        return displacement_scale(self.free_displacement, self.g, self.layout.scene)

    def displacements(self, contact_force: np.ndarray) -> np.ndarray:
        """Free-node displacements of the full model under contact forces λ."""
        return self.u0 - self.X @ (self.C.T @ np.asarray(contact_force, dtype=float))

    def scaled(self, factor: float) -> Condensed:
        """The same problem with every load times ``factor`` (a step of a load path: the
        factorisation of K is reused)."""
        return Condensed(self.full, self.nodes, self.S_inverse, factor * self.P, self.C,
                         factor * self.u0, self.X)


def condense(model: Model) -> Condensed:
    """Condense a model onto its contact nodes with one factorisation of K and one solve per
    contact node plus one for the loads."""
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
    reduced_C = sp.csr_array((C.data, (C.row, column[C.col])), shape=(model.n_contacts, nodes.size))
    return Condensed(model, nodes, stiffness, stiffness @ u0[nodes], reduced_C, u0, X)


__all__ = ["CONDENSE_LIMIT", "Condensed", "condense"]
