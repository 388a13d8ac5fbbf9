"""Plane-strain linear elasticity on a triangle mesh, assembled by scikit-fem (P1 elements)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from contactqp.fem._skfem import require_skfem


def plane_strain_stiffness(mesh, young: float, poisson: float) -> tuple[sp.csr_array, np.ndarray]:
    """The stiffness of a plane-strain body per unit thickness, and its dof numbering.

    Parameters
    ----------
    mesh : skfem.MeshTri
        The body (length units).
    young, poisson : float
        E (stress units) and ν.

    Returns
    -------
    K : scipy.sparse.csr_array, n x n
        Symmetric positive semidefinite (its null space: the rigid motions).
    dofs : int array, 2 x nodes
        ``dofs[0, i]`` numbers node i's horizontal displacement, ``dofs[1, i]`` its vertical.
    """
    skfem = require_skfem()
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    basis = skfem.Basis(mesh, skfem.ElementVector(skfem.ElementTriP1()))
    K = skfem.asm(linear_elasticity(*lame_parameters(young, poisson)), basis)
    return sp.csr_array(K), np.asarray(basis.nodal_dofs)


def dof_coordinates(mesh, dofs: np.ndarray) -> np.ndarray:
    """Where each dof sits (n x 2, length units): its node's position."""
    coordinates = np.empty((dofs.size, 2))
    coordinates[dofs[0]] = mesh.p.T
    coordinates[dofs[1]] = mesh.p.T
    return coordinates


def rows_above_flat(dofs: np.ndarray, nodes: np.ndarray) -> sp.csr_array:
    """C of the rows −u_y ≤ g, one per node (a node may not move down by more than its gap).

    Parameters
    ----------
    dofs : int array, 2 x nodes
        The dof numbering of :func:`plane_strain_stiffness`.
    nodes : int array, m
        The nodes, in the order of the rows.
    """
    return sp.csr_array((-np.ones(nodes.size), (np.arange(nodes.size), dofs[1, nodes])),
                        shape=(nodes.size, dofs.size))


def tributary_lengths(x: np.ndarray) -> np.ndarray:
    """The length of surface each of a row of boundary nodes carries (half to each neighbour).

    A node's contact force divided by it is the lumped (nodal) pressure of P1 elements. The
    first node, at x = 0 on a symmetry line, carries only its half towards the second.

    Parameters
    ----------
    x : array
        The nodes' positions along the flat, increasing (length).
    """
    midpoints = 0.5 * (x[1:] + x[:-1])
    return np.diff(np.concatenate([x[:1], midpoints, x[-1:]]))
