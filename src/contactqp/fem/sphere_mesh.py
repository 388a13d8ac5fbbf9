"""Tetrahedral meshes of the quarter of a sphere's lower hemisphere, graded towards a contact
disk of the flat, with the nodes of the curved faces kept on the sphere (linear tetrahedra,
scikit-fem's MeshTet).

The sphere of radius R touches the flat z = 0 at the origin: centre (0, 0, R); the quarter
with x ≥ 0 and y ≥ 0 below the cut z = R. The same shape as the 2D quarter disk
(:mod:`contactqp.fem.mesh`), one dimension up.
"""

from __future__ import annotations

import logging
import math
from contextlib import contextmanager

import numpy as np

from contactqp.fem._skfem import require_skfem

# the six edges of a tetrahedron and its four faces, as corners of t
EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
FACES = ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3))


def volumes(mesh) -> np.ndarray:
    """The signed volume of each tetrahedron, (p₁ − p₀) · ((p₂ − p₀) × (p₃ − p₀)) / 6
    (length³): positive when corners 1, 2, 3 turn anticlockwise seen from outside."""
    p, t = mesh.p, mesh.t
    d1, d2, d3 = (p[:, t[k]] - p[:, t[0]] for k in (1, 2, 3))
    return np.einsum("ij,ij->j", d1, np.cross(d2, d3, axis=0)) / 6.0


def element_sizes(mesh) -> np.ndarray:
    """The longest edge of each tetrahedron (length)."""
    p, t = mesh.p, mesh.t
    return np.max([np.linalg.norm(p[:, t[i]] - p[:, t[j]], axis=0) for i, j in EDGES], axis=0)


def boundary_faces(mesh) -> np.ndarray:
    """The faces of only one tetrahedron, 3 x k node numbers (scikit-fem's own facet tables
    take seconds per refinement at 10⁵ elements; a face found by its sorted corners, once)."""
    n = np.int64(mesh.p.shape[1])
    faces = np.sort(np.hstack([mesh.t[list(face)] for face in FACES]).astype(np.int64), axis=0)
    keys = (faces[0] * n + faces[1]) * n + faces[2]  # < n³ ≤ 8·10¹⁸ for MAX_NODES: fits int64
    _, first, counts = np.unique(keys, return_index=True, return_counts=True)
    return faces[:, first[counts == 1]]


def curved_faces(mesh, radius: float) -> np.ndarray:
    """The boundary faces on the sphere: every one not in a symmetry plane or the cut."""
    faces = boundary_faces(mesh)
    corners = mesh.p[:, faces]  # 3 coordinates x 3 corners x k faces
    tol = 1e-12 * radius
    flat = ((np.abs(corners[0]) < tol).all(axis=0) | (np.abs(corners[1]) < tol).all(axis=0)
            | (np.abs(corners[2] - radius) < tol).all(axis=0))
    return faces[:, ~flat]


def _oriented(mesh):
    """The mesh with corners 0 and 1 swapped where a tetrahedron's volume is negative, so that
    every volume is positive and a node moved through a face would show as a negative one."""
    t = mesh.t.copy()
    turned = volumes(mesh) < 0.0
    t[0, turned], t[1, turned] = mesh.t[1, turned], mesh.t[0, turned]
    return type(mesh)(mesh.p, t)


def _onto_sphere(mesh, radius: float):
    """The mesh, oriented, with the nodes of its curved faces moved out onto the sphere along
    the rays from the centre (0, 0, R), which keep a node in the planes x = 0, y = 0, z = R."""
    mesh = _oriented(mesh)
    nodes = np.unique(curved_faces(mesh, radius))
    points = mesh.p.copy()
    centre = np.array([[0.0], [0.0], [radius]])
    offset = points[:, nodes] - centre
    points[:, nodes] = centre + radius * offset / np.linalg.norm(offset, axis=0)
    return type(mesh)(points, mesh.t)


@contextmanager
def _quiet_skfem():
    """scikit-fem logs a warning at each refinement of more than 1000 elements (it copies the
    refined arrays to C order, which is harmless); without a handler it reaches stderr."""
    logger = logging.getLogger("skfem")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)


def quarter_hemisphere(radius: float, refinements: int = 2):
    """A uniform tetrahedral mesh of the quarter of the lower hemisphere, nodes on the sphere.

    The first mesh is three tetrahedra around the centre (0, 0, R): the corners are the lowest
    point (0, 0, 0), the rim points (R, 0, R) and (0, R, R), and the point of the sphere on the
    ray (1, 1, −1) between them. Each uniform refinement is followed by moving the new nodes of
    the curved faces out onto the sphere.

    Parameters
    ----------
    radius : float
        R (length).
    refinements : int
        Uniform refinements (each splits a tetrahedron in 8).

    Returns
    -------
    skfem.MeshTet
    """
    skfem = require_skfem()
    between = radius * np.array([1.0, 1.0, -1.0]) / math.sqrt(3.0) + [0.0, 0.0, radius]
    points = np.array([[0.0, 0.0, radius], [0.0, 0.0, 0.0], [radius, 0.0, radius],
                       [0.0, radius, radius], between]).T
    mesh = skfem.MeshTet(np.ascontiguousarray(points),
                         np.array([[0, 0, 0], [1, 2, 3], [2, 3, 1], [4, 4, 4]]))
    with _quiet_skfem():
        for _ in range(refinements):
            mesh = _onto_sphere(mesh.refined(), radius)
    return _oriented(mesh)


def distance_to_disk(points: np.ndarray, zone: float) -> np.ndarray:
    """The distance of each point from the disk x² + y² ≤ zone² of the flat z = 0 (length)."""
    x, y, z = points
    return np.hypot(np.clip(np.hypot(x, y) - zone, 0.0, None), z)


def graded_quarter_hemisphere(radius: float, zone: float, fine: float, growth: float = 0.3):
    """A quarter hemisphere refined towards the contact disk until every element is small
    enough.

    Elements are bisected at their longest edge (scikit-fem's adaptive refinement of
    tetrahedra, which keeps their shape within bounds) until each is no longer than
    ``fine + growth · d``, d the distance of its centroid from the disk x² + y² ≤ zone² of the
    flat; every node a refinement puts on a chord of the sphere is moved out onto it.

    Parameters
    ----------
    radius : float
        R (length).
    zone : float
        The radius of the disk of the flat, around the lowest point, over which elements are
        ``fine`` (length); take it larger than the contact radius.
    fine : float
        The longest edge allowed at that disk (length).
    growth : float
        How fast the allowed size grows with the distance from the disk (dimensionless).
        Far from the disk the nodes grow as 1/growth³, so it is larger than in 2D; under the
        contact, at the depth of the largest shear stress (about half the contact radius a),
        elements are about fine + growth · a/2 across, which limits the accuracy as much as
        ``fine`` does: refine both together (docs/hertz.md).

    Returns
    -------
    skfem.MeshTet
        Every tetrahedron positively oriented (:func:`volumes` > 0).
    """
    mesh = quarter_hemisphere(radius, refinements=2)
    with _quiet_skfem():
        while True:
            centroids = mesh.p[:, mesh.t].mean(axis=1)
            allowed = fine + growth * distance_to_disk(centroids, zone)
            coarse = np.flatnonzero(element_sizes(mesh) > allowed)
            if coarse.size == 0:
                return mesh
            mesh = _onto_sphere(mesh.refined(coarse), radius)


def tributary_areas(mesh, faces: np.ndarray) -> np.ndarray:
    """The area of the flat each node carries: a third of the area, projected on z = 0, of
    each of ``faces`` it is a corner of (length², one per node of the mesh). A node's contact
    force divided by it is the lumped (nodal) pressure of linear elements; a node on a
    symmetry plane carries only the part of its surroundings inside the model."""
    corners = mesh.p[:2, faces]  # x, y of 3 corners x k faces
    d1, d2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    area = 0.5 * np.abs(d1[0] * d2[1] - d1[1] * d2[0])
    return np.bincount(faces.reshape(-1), np.tile(area / 3.0, 3), minlength=mesh.p.shape[1])


SPACING = 0.1  # volume per node over the cube of the longest edge allowed (measured)


def expected_nodes(radius: float, zone: float, fine: float, growth: float) -> float:
    """About how many nodes :func:`graded_quarter_hemisphere` makes: a node per SPACING·s³
    of volume, s = fine + growth · d the size allowed at the distance d from the contact
    disk (radius ρ = zone), over the quarter of the shells around it in z ≥ 0 (the disk's
    top, a quarter torus, a hemisphere: πρ² + π²ρd + 2πd²). Measured: 0.7 to 1.15 times
    the meshes made, from 750 to 3·10⁴ nodes."""
    d = np.geomspace(fine * 1e-3, radius, 400)
    shell = 0.25 * math.pi * (zone**2 + math.pi * zone * d + 2.0 * d**2)
    density = shell / (SPACING * (fine + growth * d) ** 3)
    return float(np.sum(0.5 * (density[1:] + density[:-1]) * np.diff(d)))
