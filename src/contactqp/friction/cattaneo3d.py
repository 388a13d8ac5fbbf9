"""Cattaneo–Mindlin in 3D: two identical elastic spheres pressed, then pulled sideways.

Glossary: R the radius of both spheres, E and ν their material, G = E/(2(1 + ν)) the shear
modulus, P the normal load and Q the tangential one (force), μ the friction coefficient, a the
radius of the circle of contact, c the radius of the stick zone, δ the tangential compliance:
how far the spheres' distant points move against each other along Q (length).

**The closed forms** (Johnson, *Contact Mechanics*, §4.2 and §7.2). Pressed by P, two spheres
of radius R touch over a circle of radius a, a³ = 3PR*/(4E*) with 1/R* = 2/R and
1/E* = 2(1 − ν²)/E, that is a³ = 3PR(1 − ν²)/(4E) (the same a as one sphere on a rigid flat),
under Hertz's pressure p(r) = p₀√(1 − r²/a²), p₀ = 3P/(2πa²). Pulled afterwards by Q < μP,
they stick over r < c and slip in the annulus c < r < a, where (Cattaneo 1938, Mindlin 1949)

    c/a = (1 − Q/(μP))^(1/3),
    δ = (3μP/(16a)) · 2(2 − ν)/G · [1 − (1 − Q/(μP))^(2/3)],

and in the stick zone the friction traction is μp₀[√(1 − r²/a²) − (c/a)√(1 − r²/c²)] along Q,
so the reserve μp − |q| = μp₀(c/a)√(1 − r²/c²) there. For small Q, δ ≈ Q(2 − ν)/(4Ga),
Mindlin's compliance of a bonded circle. Mindlin's traction is along Q everywhere; the 3D
answer has a transverse part the closed form neglects (Johnson §7.2; measured on the finest
model: 3 % of the friction force summed over the contact, up to 13 % at one pair).

**Why two identical bodies, one the mirror of the other**: as in 2D
(:mod:`contactqp.friction.cattaneo`): only Dundurs' β = 0 decouples the normal and tangential
problems, which the closed forms assume; one sphere on a rigid flat has β ≈ 0.29 at ν = 0.3.
The lower sphere is the upper mirrored in the contact plane z = 0 (K₂ = S K₁ S, S flipping
the sign of the z dofs), and each node of the upper sphere's surface over the disk
x² + y² ≤ zone² is paired with its image: the normal row −u₁z + u₂z ≤ 2z (the gap of the two
surfaces) and the two tangential rows u₁x − u₂x, u₁y − u₂y (the relative slip). The Coulomb
solve sees the full coupled problem; the decoupling is observed (the normal force does not
change as Q is applied), not assumed.

**Why half of each sphere, not a quarter.** Q along x keeps the plane y = 0 a plane of
symmetry (u_y = 0 on it), so each body is the half y ≥ 0 of its lower hemisphere. The plane
x = 0 is one for the normal load (u_x = 0 on it) and an antisymmetry for the tangential one
(u_y = u_z = 0 on it): with both loads it is neither, so the quarter model of
:mod:`contactqp.fem.sphere` cannot carry them together. The half is that quarter
(:func:`~contactqp.fem.sphere_mesh.graded_quarter_hemisphere`) and its mirror image in x = 0,
so the mesh is symmetric about x = 0. Every force the model carries is half the whole pair's:
P = 2Σλ_N, Q = 2Σλ_T,x.

**The load.** The cut through each centre (z = ±R) is a rigid cap that moves as a whole:
(δ/2, 0, −Δ/2) for the upper and (−δ/2, 0, Δ/2) for the lower, Δ the approach and δ the
caps' relative sideways shift. Q is reached by moving the caps (a force on a cap would leave
its sideways position held by friction alone), after the approach, in increments
(``previous=``). P and Q are read from the answer; the closed forms are evaluated at those.

**What δ measures here.** The closed form's δ is the relative motion of two half-spaces'
distant points; the model's is that of the caps, at depth R. A sphere lacks the half-space's
material between the contact plane and its own surface, which curves away from the plane,
so it is more compliant than a half-space: the caps' shift exceeds the closed form's δ by a
share that grows as a/R (measured: docs/friction.md, "Cattaneo–Mindlin in 3D"). The
measure reports the caps' shift as it is; the closed forms hold as a/R → 0.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from contactqp.errors import ProblemError


@dataclass(frozen=True, eq=False)
class CattaneoSpheres:
    """Two mirrored half spheres as the arrays of a :class:`contactqp.Problem` (module
    docstring).

    Attributes
    ----------
    arrays : dict
        K, f, C, g, T and the prescribed dofs as :class:`contactqp.Problem` takes them (their
        values from :meth:`cap_values`).
    x, y, r : arrays, m
        Each pair's position on the contact plane and its distance from the centre of
        contact, rows by increasing r (length).
    tributary : array, m
        The area of contact plane each pair carries (length²): force / tributary = traction.
    zone_edge : bool array, m
        The pairs next to a surface node outside the zone: a contact that reaches one may
        extend past the pairs.
    radius, young, poisson : float
        R, E, ν.
    caps : int
        How many nodes each cap has.
    held : int
        How many dofs each body holds at u_y = 0 on the plane y = 0 (the caps' included).
    cap_dofs : int array, 2
        The upper and the lower cap's first x dof (all of a cap moves alike): where u is read.
    mesh : skfem.MeshTet
        The upper half sphere (the lower is its mirror image in z = 0).
    """

    arrays: dict = dataclasses.field(repr=False)
    x: np.ndarray
    y: np.ndarray
    r: np.ndarray
    tributary: np.ndarray
    zone_edge: np.ndarray
    radius: float
    young: float
    poisson: float
    caps: int
    held: int
    cap_dofs: np.ndarray
    mesh: object = dataclasses.field(repr=False)

    @property
    def dofs(self) -> int:
        """All dofs of both bodies."""
        return int(self.arrays["K"].shape[0])

    def problem(self, mu: float, approach: float, shift: float = 0.0):
        """The :class:`contactqp.Problem` of the pair under Coulomb's ``mu``, the caps moved
        by the approach Δ and the shift δ (length); the next increment is
        ``problem.with_values(prescribed_values=spheres.cap_values(approach, shift))``, which
        keeps K's factorisation."""
        from contactqp.problem import Problem

        return Problem(**self.arrays, mu=mu, prescribed_values=self.cap_values(approach, shift),
                       name=f"Cattaneo–Mindlin spheres, {self.dofs} dofs")

    def cap_values(self, approach: float, shift: float) -> np.ndarray:
        """The prescribed displacements: upper cap (δ/2, 0, −Δ/2), lower cap (−δ/2, 0, Δ/2),
        and u_y = 0 on the plane y = 0 (length)."""
        n = self.caps
        return np.concatenate([np.full(n, shift / 2), np.full(n, -approach / 2),
                               np.full(n, -shift / 2), np.full(n, approach / 2),
                               np.zeros(2 * self.held)])


def half_hemisphere(radius: float, zone: float, fine: float, growth: float):
    """The graded quarter hemisphere (:func:`contactqp.fem.sphere_mesh.graded_quarter_hemisphere`)
    and its mirror image in x = 0: the half y ≥ 0 of the lower hemisphere of a sphere of
    centre (0, 0, R), graded towards the disk x² + y² ≤ zone² of the flat z = 0."""
    import skfem

    from contactqp.fem.sphere_mesh import graded_quarter_hemisphere

    quarter = graded_quarter_hemisphere(radius, zone, fine, growth)
    x = quarter.p[0]
    mirrored = np.flatnonzero(x >= 1e-12 * radius)
    image = np.arange(x.size)
    image[mirrored] = x.size + np.arange(mirrored.size)
    points = np.hstack([quarter.p, quarter.p[:, mirrored] * np.array([[-1.0], [1.0], [1.0]])])
    # the image of a tetrahedron turns the other way: swap two corners to keep it positive
    tetrahedra = np.hstack([quarter.t, image[quarter.t][[1, 0, 2, 3]]])
    return skfem.MeshTet(np.ascontiguousarray(points), np.ascontiguousarray(tetrahedra))


def cattaneo_spheres(radius: float = 10.0, young: float = 210e3, poisson: float = 0.3,
                     zone: float = 0.4, fine: float = 0.03, growth: float = 0.3
                     ) -> CattaneoSpheres:
    """Two identical spheres, one the mirror of the other, halves y ≥ 0 (module docstring).

    Parameters
    ----------
    radius : float
        R (length).
    young, poisson : float
        E (stress) and ν.
    zone : float
        The radius of the disk of the contact plane where elements are ``fine`` and nodes are
        paired (length); wider than the contact.
    fine : float
        The longest edge allowed over that disk (length).
    growth : float
        How fast the elements grow away from it
        (:func:`~contactqp.fem.sphere_mesh.graded_quarter_hemisphere`).
    """
    from contactqp.fem.elasticity import solid_stiffness
    from contactqp.fem.sphere import contact_nodes, zone_edge
    from contactqp.fem.sphere_mesh import curved_faces, tributary_areas

    if not 0.0 < zone < radius or not 0.0 < fine < zone or not growth > 0.0:
        raise ProblemError(f"cattaneo_spheres: zone = {zone!r}, fine = {fine!r}, growth = "
                           f"{growth!r}; they need 0 < fine < zone < radius and growth > 0")
    mesh = half_hemisphere(radius, zone, fine, growth)
    K1, dofs = solid_stiffness(mesh, young, poisson)
    n1 = K1.shape[0]
    flip = sp.diags(np.where(np.isin(np.arange(n1), dofs[2]), -1.0, 1.0))
    K = sp.block_diag([K1, flip @ K1 @ flip], format="csr")
    x, y, z = mesh.p
    curved = curved_faces(mesh, radius)
    rows = contact_nodes(mesh, curved, zone)
    m = rows.size
    pairs = np.arange(m)
    C = _pair_rows([pairs], [dofs[2, rows]], -1.0, n1, m)
    T = _pair_rows([2 * pairs, 2 * pairs + 1], [dofs[0, rows], dofs[1, rows]], 1.0, n1, 2 * m)
    tol = 1e-12 * radius
    cut = np.flatnonzero(z > radius - tol)
    on_plane = np.union1d(np.flatnonzero(y < tol), cut)
    prescribed = np.concatenate([dofs[0, cut], dofs[2, cut], n1 + dofs[0, cut],
                                 n1 + dofs[2, cut], dofs[1, on_plane], n1 + dofs[1, on_plane]])
    arrays = {"K": K, "f": np.zeros(2 * n1), "C": C, "g": 2.0 * z[rows], "T": T,
              "prescribed": prescribed}
    return CattaneoSpheres(arrays, x[rows], y[rows], np.hypot(x[rows], y[rows]),
                           tributary_areas(mesh, curved)[rows], zone_edge(curved, rows),
                           float(radius), float(young), float(poisson), int(cut.size),
                           int(on_plane.size), np.array([dofs[0, cut[0]], n1 + dofs[0, cut[0]]]),
                           mesh)


def _pair_rows(row_numbers: list, columns: list, sign: float, n1: int, k: int) -> sp.csr_array:
    """Rows reading ``sign`` · (upper dof − lower dof): row_numbers[j] reads columns[j] of the
    upper body and the same of the lower (n1 dofs further)."""
    rows = np.concatenate([*row_numbers, *row_numbers])
    cols = np.concatenate([*columns, *(n1 + c for c in columns)])
    values = np.concatenate([np.full(sum(r.size for r in row_numbers), sign),
                             np.full(sum(r.size for r in row_numbers), -sign)])
    return sp.csr_array((values, (rows, cols)), shape=(k, 2 * n1))


# ------------------------------------------------------------------------- closed forms

def contact_radius(load: float, radius: float, young: float, poisson: float) -> float:
    """Hertz's a = (3PR(1 − ν²)/(4E))^(1/3) for two identical spheres (length)."""
    return (3.0 * load * radius * (1.0 - poisson**2) / (4.0 * young)) ** (1.0 / 3.0)


def stick_ratio(tangential: float, normal: float, mu: float) -> float:
    """Cattaneo and Mindlin's c/a = (1 − Q/(μP))^(1/3)."""
    return max(1.0 - tangential / (mu * normal), 0.0) ** (1.0 / 3.0)


def compliance(tangential: float, normal: float, mu: float, radius: float, young: float,
               poisson: float) -> float:
    """Mindlin's δ = (3μP/(16a)) · 2(2 − ν)/G · [1 − (1 − Q/(μP))^(2/3)], a Hertz's for P
    (length)."""
    a = contact_radius(normal, radius, young, poisson)
    shear = young / (2.0 * (1.0 + poisson))
    part = 1.0 - max(1.0 - tangential / (mu * normal), 0.0) ** (2.0 / 3.0)
    return 3.0 * mu * normal / (16.0 * a) * 2.0 * (2.0 - poisson) / shear * part


# ------------------------------------------------------------------------ the measure

@dataclass(frozen=True)
class CattaneoMeasure3D:
    """A computed answer against Cattaneo and Mindlin's (lengths, forces of the whole pair).

    Attributes
    ----------
    load, tangential : float
        P = 2Σλ_N, Q = 2Σλ_T,x.
    contact_radius, hertz_contact_radius : float
        a read from the pressure (where the line through the (r², p²) of the pushing pairs in
        the outer :data:`contactqp.fem.sphere.EDGE` of the contact reaches p = 0) and
        Hertz's for P.
    stick, stick_closed_form : float
        c read from the answer's states (the radius of the disk whose area is that of the
        sticking pairs', both halves) and (1 − Q/(μP))^(1/3) times Hertz's a.
    stick_band : tuple of float
        The farthest sticking pair's r and the nearest slipping pair's r.
    compliance, compliance_closed_form : float
        δ, the caps' relative shift along x, and Mindlin's for P and Q.
    """

    load: float
    tangential: float
    contact_radius: float
    hertz_contact_radius: float
    stick: float
    stick_closed_form: float
    stick_band: tuple[float, float]
    compliance: float
    compliance_closed_form: float

    @property
    def stick_ratio_error(self) -> float:
        """(c/a)/(c/a)_closed form − 1, both over Hertz's a."""
        return self.stick / self.stick_closed_form - 1.0

    @property
    def compliance_error(self) -> float:
        """δ/δ_closed form − 1."""
        return self.compliance / self.compliance_closed_form - 1.0

    @property
    def contact_radius_error(self) -> float:
        """a/a_Hertz − 1."""
        return self.contact_radius / self.hertz_contact_radius - 1.0


def measure(spheres: CattaneoSpheres, result, mu: float) -> CattaneoMeasure3D:
    """Read P, Q, a, c and δ from a Result of :func:`contactqp.solve` (or a
    :class:`~contactqp.friction.FrictionAnswer`) and compare them with the closed forms.

    Raises
    ------
    ProblemError
        The contact reaches a pair next to the surface outside the zone (widen the zone: the
        true contact may extend past the pairs).
    """
    from contactqp.fem.sphere import EDGE, squared_pressure_line

    normal = np.asarray(result.contact_force if hasattr(result, "contact_force")
                        else result.normal_force)
    friction = np.asarray(result.friction_force)
    state = np.asarray(result.state)
    load, tangential = 2.0 * float(normal.sum()), 2.0 * float(friction[:, 0].sum())
    elastic = (spheres.radius, spheres.young, spheres.poisson)
    a_hertz = contact_radius(load, *elastic)
    pushing = state != "open"
    if (pushing & spheres.zone_edge).any():
        raise ProblemError("cattaneo3d.measure: the contact reaches the zone's edge; widen the "
                           "zone")
    r, area = spheres.r, spheres.tributary
    outer = pushing & (r >= (1.0 - EDGE) * r[pushing].max())
    slope, intercept = squared_pressure_line(r[outer], normal[outer] / area[outer], area[outer])
    sticking = state == "stick"
    stick = math.sqrt(2.0 * float(area[sticking].sum()) / math.pi)
    slipping = state == "slip"
    band = (float(r[sticking].max(initial=0.0)), float(r[slipping].min(initial=math.inf)))
    u = np.asarray(result.u)
    shift = float(u[spheres.cap_dofs[0]] - u[spheres.cap_dofs[1]])
    return CattaneoMeasure3D(
        load, tangential, math.sqrt(-intercept / slope) if slope < 0.0 < intercept else math.nan,
        a_hertz, stick, stick_ratio(tangential, load, mu) * a_hertz, band, shift,
        compliance(tangential, load, mu, *elastic))


# ------------------------------------------------------------------------- the path

@dataclass(frozen=True, eq=False)
class ShearPath:
    """The pair pressed, then sheared in increments, each measured.

    Attributes
    ----------
    pressed : contactqp.Result
        The approach alone (no shift).
    sheared : tuple of contactqp.Result
        Each shear, an increment from the one before (``previous=``).
    measures : tuple of CattaneoMeasure3D
        Each shear's reading.
    shifts : tuple of float
        The caps' relative shift δ of each shear (length).
    mu : float
        μ.
    """

    pressed: object
    sheared: tuple
    measures: tuple
    shifts: tuple
    mu: float

    @property
    def ratios(self) -> np.ndarray:
        """Q/(μP) of each shear, as computed."""
        return np.array([m.tangential / (self.mu * m.load) for m in self.measures])


def shear_path(spheres: CattaneoSpheres, mu: float, approach: float, ratios, solve,
               method: str = "lagrange", **options) -> ShearPath:
    """Press the pair by the approach Δ, then shear it towards each Q/(μP) in ``ratios``
    (increasing), each shear an increment from the one before, by ``method`` of ``solve``
    (:func:`contactqp.solve`, passed in: this module lies below the pipeline and does not
    import it; Coulomb: ``"lagrange"``, ``"qp"``, ``"cone"``).

    Each shift is Mindlin's δ for the target Q/(μP) at the pressed P, times the ratio of the
    computed to Mindlin's δ of the shear before (one at the first): the targets are met to
    about the change of that ratio, and the closed forms are evaluated at the computed Q, P.
    """
    problem = spheres.problem(mu, approach)
    pressed = solve(problem, method, **options)
    load = measure(spheres, pressed, mu).load
    elastic = (spheres.radius, spheres.young, spheres.poisson)
    previous, scale = pressed, 1.0
    sheared, measures, shifts = [], [], []
    for ratio in ratios:
        shift = scale * compliance(ratio * mu * load, load, mu, *elastic)
        result = solve(problem.with_values(prescribed_values=spheres.cap_values(approach, shift)),
                       method, previous=previous, **options)
        reading = measure(spheres, result, mu)
        scale = reading.compliance / reading.compliance_closed_form
        sheared.append(result)
        measures.append(reading)
        shifts.append(shift)
        previous = result
    return ShearPath(pressed, tuple(sheared), tuple(measures), tuple(shifts), float(mu))
