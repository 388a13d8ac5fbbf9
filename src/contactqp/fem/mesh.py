"""Triangle meshes graded towards a contact zone, with curved boundary nodes kept on the circle.

The quarter disk of a cylinder of radius R whose lowest point touches the flat y = 0 at the
origin: centre (0, R), the symmetry line x = 0, the cut y = R, and the arc between (0, 0) and
(R, R). Elements are refined (scikit-fem's red-green-blue refinement, which keeps their shape)
until each is no larger than ``fine + growth · d``, d its distance from the strip of the flat
where contact can occur; every
node a refinement puts on a chord of the arc is moved out onto the circle, so the discrete
boundary is the cylinder's, not the coarse polygon's.
"""

from __future__ import annotations

import numpy as np

from contactqp.fem._skfem import require_skfem


def _project_arc(mesh, boundary: np.ndarray, radius: float):
    """The mesh with its boundary nodes off the straight edges moved onto the circle."""
    points = mesh.p.copy()
    x, y = points[:, boundary]
    tol = 1e-12 * radius
    curved = boundary[(x > tol) & (y < radius - tol)]
    centre = np.array([[0.0], [radius]])
    offset = points[:, curved] - centre
    points[:, curved] = centre + radius * offset / np.linalg.norm(offset, axis=0)
    return type(mesh)(points, mesh.t)


def quarter_disk(radius: float, refinements: int = 3):
    """A uniform triangle mesh of the quarter disk, boundary nodes on the circle.

    Parameters
    ----------
    radius : float
        R (length).
    refinements : int
        Uniform refinements of the first triangle (centre, (R, R), (0, 0)).

    Returns
    -------
    skfem.MeshTri
    """
    skfem = require_skfem()
    points = np.array([[0.0, radius, 0.0], [radius, radius, 0.0]])
    mesh = skfem.MeshTri(points, np.array([[0], [1], [2]]))
    for _ in range(refinements):
        mesh = mesh.refined()
        mesh = _project_arc(mesh, mesh.boundary_nodes(), radius)
    return mesh


def element_sizes(mesh) -> np.ndarray:
    """The longest edge of each triangle (length)."""
    corners = mesh.p[:, mesh.t]
    edges = corners - np.roll(corners, 1, axis=1)
    return np.linalg.norm(edges, axis=0).max(axis=0)


def distance_to_zone(points: np.ndarray, zone: float) -> np.ndarray:
    """The distance of each point from the strip 0 ≤ x ≤ zone of the flat y = 0 (length)."""
    x, y = points
    return np.hypot(np.clip(x - zone, 0.0, None), y)


def graded_quarter_disk(radius: float, zone: float, fine: float, growth: float = 0.05):
    """A quarter disk refined towards the contact zone until every element is small enough.

    Parameters
    ----------
    radius : float
        R (length).
    zone : float
        The half-width of the strip of the flat, from the lowest point, along which elements
        are ``fine`` (length); take it larger than the contact half-width.
    fine : float
        The longest edge allowed along that strip (length).
    growth : float
        How fast the allowed size grows with the distance from the strip (dimensionless): at
        0.05 an element 20 h deep is 2 h across, so the stresses under the contact are
        resolved about as finely as the pressure on it.

    Returns
    -------
    skfem.MeshTri
    """
    mesh = quarter_disk(radius, refinements=3)
    while True:
        centroids = mesh.p[:, mesh.t].mean(axis=1)
        allowed = fine + growth * distance_to_zone(centroids, zone)
        coarse = np.flatnonzero(element_sizes(mesh) > allowed)
        if coarse.size == 0:
            return mesh
        mesh = mesh.refined(coarse)
        mesh = _project_arc(mesh, mesh.boundary_nodes(), radius)
