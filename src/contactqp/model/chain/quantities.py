"""What the methods read off a model besides its solves with K: the strain formulation's tie
rows B (:func:`elongation_rows`), the stiffness the walls see, which sets the penalty's ε
(:func:`wall_stiffness`), and contact forces with the part taken out that loops of rows would
carry round (:func:`without_circulation`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from contactqp import linalg
from contactqp.model.chain.condensed import Condensed
from contactqp.model.chain.model import Model


def elongation_rows(model: Model) -> sp.csr_array:
    """B (elements x free nodes): B·u_free is the elongation of every element (m), with the
    supports' zero displacements taken out. The strain formulation's tie rows are B u − e = 0.
    """
    layout = model.layout
    n_elements = layout.n_elements
    column = np.full(layout.n_nodes, -1)
    column[model.free] = np.arange(model.n_free)
    element = np.arange(n_elements)
    first = np.delete(np.arange(layout.n_nodes - 1), layout.junctions)  # element e's first node
    rows = np.concatenate((element, element))
    nodes = np.concatenate((first, first + 1))
    signs = np.concatenate((-np.ones(n_elements), np.ones(n_elements)))
    keep = column[nodes] >= 0
    return sp.csr_array((signs[keep], (rows[keep], column[nodes][keep])),
                        shape=(n_elements, model.n_free))


def without_circulation(model: Model | Condensed, contact_force: np.ndarray) -> np.ndarray:
    """Contact forces (N) with the part taken out that rows holding a node at one position
    both ways would carry round and round: walls on both sides of a node whose gaps sum to 0
    (a clamped node), and the one-way loops of walls and bar contacts whose gaps add up
    (:attr:`Layout.tight_cycles`). Such a common part moves nothing, so the rows alone leave
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
    for cycle in model.layout.tight_cycles:
        rows = list(cycle)
        lam[rows] -= max(float(lam[rows].min()), 0.0)
    return lam


EXACT_WALL_STIFFNESS_LIMIT = 64  # wall nodes up to which wall_stiffness solves for S exactly


def wall_stiffness(model: Model | Condensed) -> float | None:
    """The stiffest way the walled nodes can be moved together (N/m): the largest eigenvalue of
    S⁻¹, S = B K⁻¹ Bᵀ the flexibility between the walled nodes (B selects them). One wall:
    1/(K⁻¹)ᵢᵢ, the stiffness it sees (mesh-independent). Two walls on nodes joined by a stiff
    element: that element's stretching mode. Above :data:`EXACT_WALL_STIFFNESS_LIMIT` walled
    nodes, the bound λmax(S⁻¹) <= λmax(K_BB) <= largest row sum of |K_BB| (S⁻¹ is K_BB less a
    positive semidefinite term; Gershgorin). None without walls."""
    nodes = np.unique(model.C.indices)
    if nodes.size == 0:
        return None
    model = model.held if isinstance(model, Model) else model
    if nodes.size > EXACT_WALL_STIFFNESS_LIMIT:
        K_BB = model.K[nodes][:, nodes]
        return float(np.abs(K_BB).sum(axis=1).max())
    selector = np.zeros((model.n_free, nodes.size))
    selector[nodes, np.arange(nodes.size)] = 1.0
    S = model.solve_K(selector)[nodes]
    smallest = float(linalg.symmetric_eigenvalues(0.5 * (S + S.T))[0])
    return 1.0 / smallest if smallest > 0.0 else float(np.abs(model.K.diagonal()[nodes]).max())


__all__ = ["elongation_rows", "wall_stiffness", "without_circulation"]
