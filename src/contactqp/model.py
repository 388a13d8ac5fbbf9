"""Pure functions from a scene to the algebra: sparse K, P, constraint rows C and gaps g.

Supports are eliminated: the unknowns are the displacements of the free nodes only. The wall
constraints are written ``C D <= g`` (or ``= g``), one row per wall in scene order, with the
wall's side folded into the sign of the row: a "+" wall is u_i <= gap, a "-" wall is
-u_i <= gap. With the Lagrangian L = Π + λᵀ(C D − g), λ >= 0 is then the force with which
each wall pushes the bar, and the wall's force on the bar in +x is −Cᵀλ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from contactqp.scene import Bar, Scene


@dataclass(frozen=True, eq=False)
class Model:
    """The algebra of a scene: minimise ½ DᵀKD − DᵀP subject to C D (<= or =) g.

    Attributes
    ----------
    scene : the scene it was built from.
    free : node number of each unknown (the free nodes, in order).
    K : sparse stiffness of the free nodes (N/m), tridiagonal, CSR.
    P : loads on the free nodes (N).
    C : sparse constraint rows, one per wall (dimensionless, ±1 at the wall's node), CSR.
    g : the walls' gaps (m).
    """

    scene: Scene
    free: np.ndarray
    K: sp.csr_array
    P: np.ndarray
    C: sp.csr_array
    g: np.ndarray

    @property
    def n_free(self) -> int:
        return int(self.free.size)

    @property
    def n_walls(self) -> int:
        return int(self.g.size)

    def full_displacements(self, u_free: np.ndarray) -> np.ndarray:
        """Displacements of every node (m), zero at the supports."""
        u = np.zeros(self.scene.n_nodes)
        u[self.free] = u_free
        return u


def stiffness_matrix(bar: Bar) -> sp.csr_array:
    """Assembled stiffness of every node of a bar (N/m): tridiagonal, singular (no supports)."""
    k = bar.stiffness
    diagonal = np.concatenate((k, [0.0])) + np.concatenate(([0.0], k))
    return sp.csr_array(sp.diags_array([-k, diagonal, -k], offsets=[-1, 0, 1]))


def element_forces(bar: Bar, u: np.ndarray) -> np.ndarray:
    """Axial force of each element (N, tension positive) from the nodal displacements (m)."""
    return bar.stiffness * np.diff(u)


def internal_forces(bar: Bar, u: np.ndarray) -> np.ndarray:
    """K_full u without forming K: the force each node needs to hold the elements (N)."""
    n_e = element_forces(bar, u)
    f = np.zeros(bar.n_nodes)
    f[:-1] -= n_e
    f[1:] += n_e
    return f


def wall_rows(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """(node, sign) of each wall's constraint row sign·u_node <= gap, in scene order."""
    nodes = np.array([w.node for w in scene.walls], dtype=int)
    signs = np.array([w.sign for w in scene.walls], dtype=float)
    return nodes, signs


def wall_forces(scene: Scene, contact_force: np.ndarray) -> np.ndarray:
    """Force of the walls on each node in +x (N): −Cᵀλ in node numbering."""
    nodes, signs = wall_rows(scene)
    f = np.zeros(scene.n_nodes)
    np.add.at(f, nodes, -signs * np.asarray(contact_force, dtype=float))
    return f


def penetration(scene: Scene, u: np.ndarray) -> np.ndarray:
    """How far each node is past its wall (m), C u − g: positive = penetrated."""
    nodes, signs = wall_rows(scene)
    gaps = np.array([w.gap for w in scene.walls], dtype=float)
    return signs * u[nodes] - gaps


def build_model(scene: Scene) -> Model:
    """The model of a scene, O(n) in time and memory."""
    n = scene.n_nodes
    is_free = np.ones(n, dtype=bool)
    is_free[[s.node for s in scene.supports]] = False
    free = np.flatnonzero(is_free)
    column = np.full(n, -1)
    column[free] = np.arange(free.size)
    K = sp.csr_array(stiffness_matrix(scene.bar)[free][:, free])
    nodes, signs = wall_rows(scene)
    C = sp.csr_array((signs, (np.arange(nodes.size), column[nodes])), shape=(nodes.size, free.size))
    g = np.array([w.gap for w in scene.walls], dtype=float)
    return Model(scene, free, K, scene.nodal_loads()[free], C, g)
