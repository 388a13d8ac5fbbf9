"""A long elastic cylinder pressed onto a rigid flat (plane strain), for the Hertz comparison.

The model is the quarter of the cylinder's cross-section below its centre and right of its
axis of symmetry (:func:`~contactqp.fem.mesh.graded_quarter_disk`): the symmetry line x = 0
slides vertically (u_x = 0), the cut y = R through the centre is pushed down by the approach δ
(u_y = −δ, free to slide sideways, as under a frictionless rigid plate), and every node of the
arc within the contact strip 0 ≤ x ≤ zone may not pass the flat: y + u_y ≥ 0, the row
−u_y ≤ y of C u ≤ g. The load per unit thickness of the whole cylinder is P = 2 Σλ (the
model is half of it); Hertz's a and p₀ follow from that P (:mod:`contactqp.fem.hertz`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from contactqp import _validate
from contactqp._validate import one_line
from contactqp.errors import ProblemError
from contactqp.fem._arguments import at_least_zero, nodes_within, poisson_ratio, positive
from contactqp.fem.elasticity import (
    dof_coordinates,
    plane_strain_stiffness,
    rows_above_flat,
    tributary_lengths,
)
from contactqp.fem.hertz import hertz_half_width, hertz_peak_pressure
from contactqp.fem.mesh import graded_quarter_disk
from contactqp.problem import Problem

# a row pushes when its force exceeds this fraction of the largest one: above the noise a QP
# solver leaves on open rows at its default accuracy (1e-8 relative and less), far below the
# last pushing row's share (about √(h/a) of the peak, h the row spacing)
PUSHING = 1e-6
NAME = "cylinder_on_flat"


@dataclass(frozen=True, eq=False)
class CylinderModel:
    """The cylinder on the flat as a :class:`~contactqp.Problem`, and what reads its answer.

    Attributes
    ----------
    problem : contactqp.Problem
        K, f = 0, C, g, the prescribed symmetry and approach.
    mesh : skfem.MeshTri
        The quarter disk (length units).
    x : array, m
        Each contact row's position along the flat, increasing; row 0 is the lowest point.
    tributary : array, m
        The length of flat each row carries (length): force / tributary = pressure.
    radius, young, poisson : float
        R, E, ν.
    """

    problem: Problem
    mesh: object
    x: np.ndarray
    tributary: np.ndarray
    radius: float
    young: float
    poisson: float


def _arc_nodes(mesh, radius: float) -> np.ndarray:
    """The nodes on the arc (the lowest point included, the cut's corner not), by x."""
    boundary = mesh.boundary_nodes()
    x, y = mesh.p[:, boundary]
    tol = 1e-12 * radius
    arc = boundary[(y < radius - tol) & ((x > tol) | (y < tol))]
    return arc[np.argsort(mesh.p[0, arc])]


def cylinder_on_flat(radius: float = 10.0, young: float = 210e3, poisson: float = 0.3,
                     approach: float = 0.01, zone: float | None = None,
                     fine: float | None = None, growth: float = 0.05,
                     units: str = "N, mm") -> CylinderModel:
    """A plane-strain cylinder pushed onto a rigid flat by ``approach`` (module docstring).

    Parameters
    ----------
    radius : float
        R (length).
    young, poisson : float
        E (stress = force/length²) and ν.
    approach : float
        δ, how far the cut through the centre is pushed down (length). At δ = 10⁻³ R the
        contact half-width is about 0.02 R, small enough for Hertz's half-space.
    zone : float, optional
        The strip of the flat where rows are placed and elements are ``fine`` (length);
        default 0.05 R. It must be wider than the contact (:func:`measure` says when not).
    fine : float, optional
        The element size along that strip (length); default zone / 40.
    growth : float
        How fast the elements grow away from the strip (:func:`graded_quarter_disk`).
    units : str
        The label of the answer's units.
    """
    radius, young = positive(NAME, "radius", radius), positive(NAME, "young", young)
    poisson, approach = poisson_ratio(NAME, poisson), positive(NAME, "approach", approach)
    zone = 0.05 * radius if zone is None else positive(NAME, "zone", zone)
    fine = zone / 40.0 if fine is None else positive(NAME, "fine", fine)
    growth = positive(NAME, "growth", growth)
    units = one_line(f"{NAME}: units", units)
    if zone > radius:
        raise ProblemError(f"{NAME}: zone = {zone!r} is wider than the radius {radius!r}")
    # zone/fine elements along the strip in layers that thicken at the rate growth, then the
    # rings around it out to R (measured: within a factor of 2 above the meshes made)
    nodes_within(NAME, 4.0 * (zone / fine) / growth
                 + 2.0 * math.pi / growth**2 * math.log(max(radius * growth / fine, 2.0)),
                 f"fine = {fine!r} (zone {zone!r}, growth {growth!r})")
    mesh = graded_quarter_disk(radius, zone, fine, growth)
    K, dofs = plane_strain_stiffness(mesh, young, poisson)
    x, y = mesh.p
    tol = 1e-12 * radius
    symmetry, cut = np.flatnonzero(x < tol), np.flatnonzero(y > radius - tol)
    arc = _arc_nodes(mesh, radius)
    rows = arc[x[arc] <= zone * (1.0 + 1e-9)]
    C = rows_above_flat(dofs, rows)
    problem = Problem(
        K, np.zeros(K.shape[0]), C, y[rows],
        prescribed=np.concatenate([dofs[0, symmetry], dofs[1, cut]]),
        prescribed_values=np.concatenate([np.zeros(symmetry.size), np.full(cut.size, -approach)]),
        names=[f"x={xi:.4g}" for xi in x[rows]], coordinates=dof_coordinates(mesh, dofs),
        units=units, name=f"cylinder on a flat, {K.shape[0]} dofs")
    tributary = tributary_lengths(x[arc])[: rows.size]
    return CylinderModel(problem, mesh, x[rows], tributary, radius, young, poisson)


@dataclass(frozen=True)
class HertzComparison:
    """A computed contact against Hertz's for the same load (lengths, forces per length).

    Attributes
    ----------
    load : float
        P = 2 Σλ, the load per unit thickness of the whole cylinder.
    half_width, peak_pressure : float
        The computed a (the edge of the run of pushing rows from x = 0, interpolated) and p₀
        (the lowest row's pressure).
    hertz_half_width, hertz_peak_pressure : float
        Hertz's a and p₀ for that load.
    x, pressure : arrays, m
        Each row's position and its lumped pressure λ / tributary length.
    """

    load: float
    half_width: float
    peak_pressure: float
    hertz_half_width: float
    hertz_peak_pressure: float
    x: np.ndarray
    pressure: np.ndarray

    @property
    def half_width_error(self) -> float:
        """a / a_Hertz − 1."""
        return self.half_width / self.hertz_half_width - 1.0

    @property
    def peak_pressure_error(self) -> float:
        """p₀ / p₀_Hertz − 1."""
        return self.peak_pressure / self.hertz_peak_pressure - 1.0


def edge_of_contact(x: np.ndarray, pressure: np.ndarray, last: int) -> float:
    """Where the pressure falls to zero, beyond the last pushing row (length).

    Hertz's pressure squared is linear in x², p² = p₀²(1 − x²/a²), so the line through the
    last two pushing rows in (x², p²) meets zero at x = a; on any smooth pressure that ends
    as a square root it interpolates the edge to second order in the row spacing.
    """
    x0, x1 = x[last - 1], x[last]
    p0, p1 = pressure[last - 1], pressure[last]
    return float(np.sqrt(x1**2 + p1**2 * (x1**2 - x0**2) / (p0**2 - p1**2)))


def measure(model: CylinderModel, contact_force: np.ndarray,
            resolution: float = 0.0) -> HertzComparison:
    """Read a and p₀ from the contact forces and compare them with Hertz's.

    Parameters
    ----------
    model : CylinderModel
        The model the forces answer.
    contact_force : array, m
        One force per row (force per length).
    resolution : float
        Forces at or below this are read as zero (force per length): for an inexact method,
        the Result's ``force_error_bound``, so that what it leaves on open rows does not
        widen the contact. Forces below 1e-6 of the largest are always read as zero.

    Raises
    ------
    ProblemError
        ``contact_force`` is not one finite number per row, or ``resolution`` is negative;
        the contact spans fewer than two rows (refine), or reaches the zone's last row (widen
        the zone: the true contact may extend past it). A ValueError, as before.
    """
    force = _validate.vector("contact_force", contact_force, model.x.size)
    resolution = at_least_zero("measure", "resolution", resolution)
    # the strip in contact is the run of pushing rows from the lowest point
    open_rows = np.flatnonzero(force <= max(PUSHING * force.max(), resolution))
    last = int(open_rows[0]) - 1 if open_rows.size else force.size - 1
    if last < 1:
        raise ProblemError(f"measure: contact_force pushes on {last + 1} row(s) from the "
                           "lowest point, too few to read a and p0 (largest force "
                           f"{float(force.max(initial=0.0)):.3g}); refine the mesh (fine), or "
                           "give the contact forces of a solve that loads the cylinder")
    if last == force.size - 1:
        raise ProblemError(f"measure: the contact reaches the zone's last row at x = "
                           f"{model.x[last]:.4g}; widen the zone")
    pressure = force / model.tributary
    load = 2.0 * float(force.sum())
    elastic = (model.radius, model.young, model.poisson)
    return HertzComparison(
        load, edge_of_contact(model.x, pressure, last), float(pressure[0]),
        hertz_half_width(load, *elastic), hertz_peak_pressure(load, *elastic),
        model.x, pressure)
