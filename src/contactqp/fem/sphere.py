"""An elastic sphere pressed onto a rigid flat, for the Hertz comparison in 3D.

The sphere of radius R touches the flat z = 0 at the origin: centre (0, 0, R). The model is
the quarter of its lower hemisphere with x ≥ 0 and y ≥ 0
(:func:`~contactqp.fem.sphere_mesh.graded_quarter_hemisphere`, linear tetrahedra): the symmetry planes x = 0 and y = 0 slide in their planes (u_x = 0 on the
one, u_y = 0 on the other), the cut z = R through the centre is pushed down by the approach δ
(u_z = −δ, free to slide sideways, as under a frictionless rigid plate), and every node of the
sphere within the contact disk x² + y² ≤ zone² may not pass the flat: z + u_z ≥ 0, the row
−u_z ≤ z of C u ≤ g. The load on the whole sphere is P = 4 Σλ (the model is a quarter of it);
Hertz's a and p₀ follow from that P (:mod:`contactqp.fem.hertz3d`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from contactqp import _validate
from contactqp._validate import one_line
from contactqp.errors import ProblemError
from contactqp.fem._arguments import at_least_zero, nodes_within, poisson_ratio, positive
from contactqp.fem.cylinder import PUSHING
from contactqp.fem.elasticity import dof_coordinates, rows_above_flat, solid_stiffness
from contactqp.fem.hertz3d import sphere_contact_radius, sphere_peak_pressure
from contactqp.fem.sphere_mesh import (
    curved_faces,
    expected_nodes,
    graded_quarter_hemisphere,
    tributary_areas,
)
from contactqp.problem import Problem

NAME = "sphere_on_flat"


@dataclass(frozen=True, eq=False)
class SphereModel:
    """The sphere on the flat as a :class:`~contactqp.Problem`, and what reads its answer.

    Attributes
    ----------
    problem : contactqp.Problem
        K, f = 0, C, g, the prescribed symmetry and approach.
    mesh : skfem.MeshTet
        The quarter hemisphere (length units).
    x, y : arrays, m
        Each contact row's position on the flat (length); rows by increasing distance from
        the lowest point, row 0 the lowest point itself.
    r : array, m
        Each row's distance from the lowest point, √(x² + y²), increasing (length).
    tributary : array, m
        The area of flat each row carries (length²): force / tributary = pressure.
    zone_edge : bool array, m
        The rows next to a node of the sphere outside the zone: a contact that reaches one
        may extend past the rows.
    radius, young, poisson : float
        R, E, ν.
    """

    problem: Problem
    mesh: object
    x: np.ndarray
    y: np.ndarray
    r: np.ndarray
    tributary: np.ndarray
    zone_edge: np.ndarray
    radius: float
    young: float
    poisson: float


def zone_edge(faces: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Per row (``rows``: node numbers), whether an edge of ``faces`` joins it to a node that
    is not a row."""
    is_row = np.zeros(faces.max(initial=0) + 1, dtype=bool)
    is_row[rows] = True
    ends = np.hstack([faces[[0, 1]], faces[[1, 2]], faces[[2, 0]]])
    crossing = is_row[ends[0]] != is_row[ends[1]]
    outermost = np.zeros_like(is_row)
    outermost[ends[:, crossing][is_row[ends[:, crossing]]]] = True
    return outermost[rows]


def sphere_on_flat(radius: float = 10.0, young: float = 210e3, poisson: float = 0.3,
                   approach: float = 0.01, zone: float | None = None,
                   fine: float | None = None, growth: float = 0.3,
                   units: str = "N, mm") -> SphereModel:
    """An elastic sphere pushed onto a rigid flat by ``approach`` (module docstring).

    Parameters
    ----------
    radius : float
        R (length).
    young, poisson : float
        E (stress = force/length²) and ν.
    approach : float
        δ, how far the cut through the centre is pushed down (length). At δ = 10⁻³ R the
        contact radius is about 0.032 R, small enough for Hertz's half-space.
    zone : float, optional
        The radius of the disk of the flat where rows are placed and elements are ``fine``
        (length); default 0.05 R. It must be wider than the contact (:func:`measure_sphere` says
        when not).
    fine : float, optional
        The element size over that disk (length); default zone / 10, which with the default
        zone, growth and approach makes 1.3·10⁴ dofs and reads a and p₀ within 1.5 % of
        Hertz's.
    growth : float
        How fast the elements grow away from the disk
        (:func:`~contactqp.fem.sphere_mesh.graded_quarter_hemisphere`); to refine, divide it by what ``fine`` is divided by.
    units : str
        The label of the answer's units.

    Raises
    ------
    ProblemError
        An argument that is not valid, or a mesh past :data:`~contactqp.fem._arguments.
        MAX_NODES` nodes (one line naming it).
    """
    radius, young = positive(NAME, "radius", radius), positive(NAME, "young", young)
    poisson, approach = poisson_ratio(NAME, poisson), positive(NAME, "approach", approach)
    zone = 0.05 * radius if zone is None else positive(NAME, "zone", zone)
    fine = zone / 10.0 if fine is None else positive(NAME, "fine", fine)
    growth = positive(NAME, "growth", growth)
    units = one_line(f"{NAME}: units", units)
    if zone > radius:
        raise ProblemError(f"{NAME}: zone = {zone!r} is wider than the radius {radius!r}")
    nodes_within(NAME, expected_nodes(radius, zone, fine, growth),
                 f"fine = {fine!r} (zone {zone!r}, growth {growth!r})")
    mesh = graded_quarter_hemisphere(radius, zone, fine, growth)
    K, dofs = solid_stiffness(mesh, young, poisson)
    x, y, z = mesh.p
    tol = 1e-12 * radius
    curved = curved_faces(mesh, radius)
    rows = contact_nodes(mesh, curved, zone)
    symmetry_x, symmetry_y = np.flatnonzero(x < tol), np.flatnonzero(y < tol)
    cut = np.flatnonzero(z > radius - tol)
    problem = Problem(
        K, np.zeros(K.shape[0]), rows_above_flat(dofs, rows), z[rows],
        prescribed=np.concatenate([dofs[0, symmetry_x], dofs[1, symmetry_y], dofs[2, cut]]),
        prescribed_values=np.concatenate([np.zeros(symmetry_x.size + symmetry_y.size),
                                          np.full(cut.size, -approach)]),
        names=[f"x={xi:.4g} y={yi:.4g}" for xi, yi in zip(x[rows], y[rows])],
        coordinates=dof_coordinates(mesh, dofs), units=units, name=f"sphere on a flat, {K.shape[0]} dofs")
    return SphereModel(problem, mesh, x[rows], y[rows], np.hypot(x[rows], y[rows]),
                       tributary_areas(mesh, curved)[rows], zone_edge(curved, rows), radius,
                       young, poisson)


def contact_nodes(mesh, curved: np.ndarray, zone: float) -> np.ndarray:
    """The nodes of the ``curved`` faces over the disk x² + y² ≤ zone², by their distance
    from the lowest point (then by x), the lowest point first."""
    x, y = mesh.p[:2]
    surface = np.unique(curved)
    nodes = surface[np.hypot(x[surface], y[surface]) <= zone * (1.0 + 1e-9)]
    return nodes[np.lexsort((x[nodes], np.hypot(x[nodes], y[nodes])))]


@dataclass(frozen=True)
class HertzComparison3D:
    """A computed contact against Hertz's for the same load (lengths, forces).

    Attributes
    ----------
    load : float
        P = 4 Σλ, the load on the whole sphere.
    contact_radius, peak_pressure : float
        The computed a and p₀, each from a line through the (r², p²) of pushing rows (see
        :func:`measure_sphere`): a where the line of the outer :data:`EDGE` of the contact reaches
        p = 0, p₀ where the line of its inner :data:`CENTRE` reaches r = 0.
    centre_pressure : float
        The lowest row's lumped pressure, λ / tributary area (the pressure read at one node:
        see :func:`measure_sphere` for why it is not p₀).
    hertz_contact_radius, hertz_peak_pressure : float
        Hertz's a and p₀ for that load.
    r, pressure : arrays, m
        Each row's distance from the lowest point and its lumped pressure λ / tributary area.
    """

    load: float
    contact_radius: float
    peak_pressure: float
    centre_pressure: float
    hertz_contact_radius: float
    hertz_peak_pressure: float
    r: np.ndarray
    pressure: np.ndarray

    @property
    def contact_radius_error(self) -> float:
        """a / a_Hertz − 1."""
        return self.contact_radius / self.hertz_contact_radius - 1.0

    @property
    def peak_pressure_error(self) -> float:
        """p₀ / p₀_Hertz − 1."""
        return self.peak_pressure / self.hertz_peak_pressure - 1.0

    @property
    def centre_pressure_error(self) -> float:
        """The lowest row's pressure / p₀_Hertz − 1."""
        return self.centre_pressure / self.hertz_peak_pressure - 1.0


# The parts of the contact, as fractions of its radius, whose rows place its edge (the outer
# 30 %) and its peak (the inner half): wide enough to hold a few rings of rows, since the
# lumped pressure alternates between neighbouring nodes of unequal tributary areas (measured:
# the two kinds 5 % of p₀ apart at h = a/13, 14 % at a/3), narrow enough to be the edge's and
# the centre's own.
EDGE = 0.3
CENTRE = 0.5


def squared_pressure_line(r: np.ndarray, pressure: np.ndarray,
                          area: np.ndarray) -> tuple[float, float]:
    """(slope, intercept) of the line p² = intercept + slope · r² through rows at distances
    ``r`` with pressures ``pressure``, least squares weighted by their tributary ``area``
    (so that a row's weight is the part of the flat its pressure stands for).

    Near the centre of a smooth pressure symmetric about it, and near an edge where it falls
    as a square root, p² is linear in r² to first order; Hertz's, p₀²(1 − r²/a²), is
    linear throughout.
    """
    slope, intercept = np.polyfit(r**2, pressure**2, 1, w=np.sqrt(area))
    return float(slope), float(intercept)


def measure_sphere(model: SphereModel, contact_force: np.ndarray,
                   resolution: float = 0.0) -> HertzComparison3D:
    """Read a and p₀ from the contact forces and compare them with Hertz's (the sphere's
    counterpart of the cylinder's :func:`~contactqp.fem.measure`).

    A row's lumped pressure is its force over its tributary area; on these meshes it
    alternates by a few % between neighbouring nodes (their tributary areas differ by up to
    2 : 1), so one row is a poor reading and a and p₀ are read from many: a is where the
    line of :func:`squared_pressure_line` through the pushing rows in the outer :data:`EDGE`
    of the contact (by the farthest pushing row) reaches p = 0, p₀ where the line through
    those in its inner :data:`CENTRE` reaches r = 0.

    Parameters
    ----------
    model : SphereModel
        The model the forces answer.
    contact_force : array, m
        One force per row (force).
    resolution : float
        Forces at or below this are read as zero (force): for an inexact method, the
        Result's ``force_error_bound``, so that what it leaves on open rows does not widen
        the contact. Forces below 1e-6 of the largest are always read as zero.

    Raises
    ------
    ProblemError
        ``contact_force`` is not one finite number per row, or ``resolution`` is negative;
        the lowest point does not push, too few rows push to read a or p₀ (refine), or the
        contact reaches a row next to the sphere outside the zone (widen the zone: the true
        contact may extend past it). A ValueError, as the cylinder's.
    """
    force = _validate.vector("contact_force", contact_force, model.r.size)
    resolution = at_least_zero("measure_sphere", "resolution", resolution)
    pushing = force > max(PUSHING * force.max(initial=0.0), resolution)
    if not pushing[0]:
        raise ProblemError("measure_sphere: the lowest point does not push; push further (approach)")
    if (pushing & model.zone_edge).any():
        far = model.r[pushing & model.zone_edge].min()
        raise ProblemError(f"measure_sphere: the contact reaches the zone's edge at r = {far:.4g}; widen the zone")
    pressure = force / model.tributary
    farthest = model.r[pushing].max()
    lines = []
    for part in (model.r >= (1.0 - EDGE) * farthest, model.r <= CENTRE * farthest):
        rows = pushing & part
        line = (squared_pressure_line(model.r[rows], pressure[rows], model.tributary[rows])
                if np.unique(model.r[rows]).size >= 3 else (0.0, 0.0))
        if not line[0] < 0.0 < line[1]:  # too few rows, or a pressure not falling outwards
            raise ProblemError(f"measure_sphere: {np.count_nonzero(pushing)} rows push, too few to "
                             "read a and p₀; refine the mesh (fine)")
        lines.append(line)
    (edge_slope, edge_intercept), (_, centre_intercept) = lines
    load = 4.0 * float(force.sum())
    elastic = (model.radius, model.young, model.poisson)
    return HertzComparison3D(
        load, math.sqrt(-edge_intercept / edge_slope), math.sqrt(centre_intercept),
        float(pressure[0]), sphere_contact_radius(load, *elastic),
        sphere_peak_pressure(load, *elastic), model.r, pressure)
