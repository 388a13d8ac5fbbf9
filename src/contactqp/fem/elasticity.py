"""Linear elasticity assembled by scikit-fem with linear elements: plane strain on triangles
(P1), and the solid on tetrahedra; the rows that keep a body's nodes above a rigid flat."""

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
    return _linear_elastic(mesh, "ElementTriP1", young, poisson)


def solid_stiffness(mesh, young: float, poisson: float) -> tuple[sp.csr_array, np.ndarray]:
    """The stiffness of an isotropic elastic solid on a tetrahedral mesh (P1), and its dofs.

    Parameters
    ----------
    mesh : skfem.MeshTet
        The body (length units).
    young, poisson : float
        E (stress units) and ν.

    Returns
    -------
    K : scipy.sparse.csr_array, n x n
        Symmetric positive semidefinite (its null space: the six rigid motions).
    dofs : int array, 3 x nodes
        ``dofs[k, i]`` numbers node i's displacement along axis k (x, y, z).
    """
    # the strains of linear elements are constant: one quadrature point integrates K exactly,
    # and assembles it ten times faster than scikit-fem's default rule of four
    return _linear_elastic(mesh, "ElementTetP1", young, poisson, intorder=0)


def _linear_elastic(mesh, element: str, young: float, poisson: float,
                    **basis_options) -> tuple[sp.csr_array, np.ndarray]:
    """K of isotropic linear elasticity with scikit-fem's vector ``element`` and its dofs."""
    skfem = require_skfem()
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    basis = skfem.Basis(mesh, skfem.ElementVector(getattr(skfem, element)()), **basis_options)
    K = skfem.asm(linear_elasticity(*lame_parameters(young, poisson)), basis)
    return sp.csr_array(K), np.asarray(basis.nodal_dofs)



def dof_coordinates(mesh, dofs: np.ndarray) -> np.ndarray:
    """Where each dof sits (n x dimension, length units): its node's position."""
    coordinates = np.empty((dofs.size, mesh.p.shape[0]))
    for axis_dofs in dofs:
        coordinates[axis_dofs] = mesh.p.T
    return coordinates


def rows_above_flat(dofs: np.ndarray, nodes: np.ndarray) -> sp.csr_array:
    """C of the rows −u_z ≤ g, one per node (a node may not move down by more than its gap;
    down is along the last axis: y in 2D, z in 3D).

    Parameters
    ----------
    dofs : int array, dimension x nodes
        The dof numbering of :func:`plane_strain_stiffness` or :func:`solid_stiffness`.
    nodes : int array, m
        The nodes, in the order of the rows.
    """
    return sp.csr_array((-np.ones(nodes.size), (np.arange(nodes.size), dofs[-1, nodes])),
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
