"""Cattaneo–Mindlin in 2D: two identical plane-strain cylinders pressed, then pulled sideways.

Glossary: R the radius, E and ν the material of both cylinders, P the normal load and Q the
tangential one per unit thickness (force/length), μ the friction coefficient, a the contact
half-width, p₀ the peak pressure, c the half-width of the stick zone, q(x) the friction
traction.

**The closed form** (Johnson, *Contact Mechanics*, §7.1). Pressed by P, the cylinders touch
over |x| < a under Hertz's p(x) = p₀√(1 − x²/a²), with a² = 4PR*/(πE*) for 1/R* = 2/R and
1/E* = 2(1 − ν²)/E, that is a = √(4PR(1 − ν²)/(πE)), and p₀ = 2P/(πa). Pulled afterwards by
Q < μP, they stick over |x| < c, c/a = √(1 − Q/(μP)), and slip beyond, under

    q(x) = μp₀[√(1 − x²/a²) − (c/a)√(1 − x²/c²)]   (|x| < c;  μp(x) for c < |x| < a).

**Why two identical bodies.** The closed form neglects the coupling between normal and
tangential tractions, which is exact only when Dundurs' β = 0: identical materials (or both
incompressible). An elastic body on a rigid flat has β = (1 − 2ν)/(2(1 − ν)) ≈ 0.29 at ν = 0.3:
its pressure pulls the surface inwards along a flat that does not follow, so friction acts under
normal load alone and Cattaneo's q does not hold. Setting ν = 0.5 on a rigid flat would make
β = 0 but lock linear triangles, so this model keeps two identical elastic bodies.

**Why one body and its mirror image suffice to think about, and why the model has both.**
Mirror the upper cylinder in the contact plane y = 0 to get the lower one. For the normal load
the pair is symmetric: u₂(x, −y) = (u₁ₓ, −u₁ᵧ), both surfaces move alike along x and no relative
slip arises, so friction is idle and each body sees a rigid frictionless flat. For the
tangential load the pair is antisymmetric: u₂(x, −y) = (−u₁ₓ, u₁ᵧ), the relative slip is 2u₁ₓ
and the relative normal displacement is zero, so the gap does not change. The two parts are
decoupled, which is β = 0: Coulomb's problem splits into frictionless Hertz, then Tresca with
bound μλ_N. A single body cannot carry both parts at once (its own surface motion mixes the
inward pull of the normal part with the slip of the tangential one, the rigid flat's error),
so the model assembles both bodies, the lower one's stiffness that of the upper mirrored
(K₂ = S K₁ S, S flipping the sign of the y dofs), and pairs each node of the upper arc with its
mirror image: the row −u₁ᵧ + u₂ᵧ ≤ 2y (the gap of two arcs) and the tangential row u₁ₓ − u₂ₓ
(the relative slip). The Coulomb solve then sees the full coupled problem; that its fixed point
settles in two iterations is the decoupling observed, not assumed.

**The bodies.** Each is the half of a cylinder's cross-section between its contact point and
its centre (a half disk: the graded quarter disk of :mod:`contactqp.fem.mesh` and its mirror
image in x = 0, so the mesh is symmetric about the contact's centre line). The cut through
each centre is a rigid cap that moves as a whole: (δ/2, −Δ/2) for the upper one and
(−δ/2, Δ/2) for the lower, Δ the approach, δ the sideways shift. Q is reached by moving the
caps (a displacement): a force on a cap would leave its sideways position held by friction
alone. P = Σλ_N and Q = Σλ_T are read from the answer; the closed form is evaluated at those.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from contactqp.errors import ProblemError
from contactqp.friction.answer import FrictionAnswer
from contactqp.friction.model import FrictionModel, friction_model


@dataclass(frozen=True, eq=False)
class CattaneoModel:
    """Two mirrored cylinders as a friction model (module docstring).

    Attributes
    ----------
    model : FrictionModel
        Both bodies' K, C, T; the caps prescribed (values from :meth:`cap_values`).
    x : array, m
        Each pair's position along the contact plane, increasing (length).
    tributary : array, m
        The length of contact plane each pair carries (length): force / tributary = traction.
    radius, young, poisson : float
        R, E, ν.
    caps : int, 4
        How many prescribed dofs each cap part has: (upper x, upper y, lower x, lower y).
    arrays : dict
        K, f, C, g, T and the prescribed dofs as :class:`contactqp.Problem` takes them (the
        caps' values from :meth:`cap_values`).
    """

    model: FrictionModel
    x: np.ndarray
    tributary: np.ndarray
    radius: float
    young: float
    poisson: float
    caps: tuple[int, int, int, int]
    arrays: dict = dataclasses.field(repr=False, default_factory=dict)

    def cap_values(self, approach: float, shift: float) -> np.ndarray:
        """The prescribed displacements: upper cap (δ/2, −Δ/2), lower cap (−δ/2, Δ/2)."""
        upper_x, upper_y, lower_x, lower_y = self.caps
        return np.concatenate([np.full(upper_x, shift / 2), np.full(upper_y, -approach / 2),
                               np.full(lower_x, -shift / 2), np.full(lower_y, approach / 2)])


def half_disk(radius: float, zone: float, fine: float, growth: float):
    """The graded quarter disk (:func:`contactqp.fem.mesh.graded_quarter_disk`) and its mirror
    image in x = 0: the lower half of a cylinder of centre (0, R), graded towards |x| ≤ zone."""
    import skfem

    from contactqp.fem.mesh import graded_quarter_disk

    quarter = graded_quarter_disk(radius, zone, fine, growth)
    x, y = quarter.p
    on_axis = x < 1e-12 * radius
    mirrored = np.flatnonzero(~on_axis)
    number = np.arange(x.size)
    image = number.copy()
    image[mirrored] = x.size + np.arange(mirrored.size)
    points = np.hstack([quarter.p, np.vstack([-x[mirrored], y[mirrored]])])
    # the image of a triangle turns the other way: swap two corners to keep it positive
    triangles = np.hstack([quarter.t, image[quarter.t][[0, 2, 1]]])
    return skfem.MeshTri(points, triangles)


def cattaneo_cylinders(radius: float = 10.0, young: float = 210e3, poisson: float = 0.3,
                       zone: float = 0.4, fine: float = 0.01, growth: float = 0.05
                       ) -> CattaneoModel:
    """Two identical plane-strain cylinders, one the mirror of the other (module docstring).

    Parameters
    ----------
    radius : float
        R (length).
    young, poisson : float
        E (stress) and ν.
    zone : float
        The half-width of the strip where elements are ``fine`` and nodes are paired (length);
        wider than the contact.
    fine : float
        The element size along that strip (length).
    growth : float
        How fast the elements grow away from it (:func:`~contactqp.fem.mesh.graded_quarter_disk`).
    """
    from contactqp.fem.elasticity import plane_strain_stiffness

    if not 0.0 < zone < radius or not 0.0 < fine < zone:
        raise ProblemError(f"cattaneo_cylinders: zone = {zone!r}, fine = {fine!r}; they need "
                           "0 < fine < zone < radius")
    mesh = half_disk(radius, zone, fine, growth)
    K1, dofs = plane_strain_stiffness(mesh, young, poisson)
    n1 = K1.shape[0]
    flip = sp.diags(np.where(np.isin(np.arange(n1), dofs[1]), -1.0, 1.0))
    K = sp.block_diag([K1, flip @ K1 @ flip], format="csr")
    x, y = mesh.p
    tol = 1e-9 * radius
    boundary = mesh.boundary_nodes()
    arc = boundary[(y[boundary] < radius - tol) & (np.abs(x[boundary]) <= zone * (1 + 1e-9))]
    arc = arc[np.argsort(x[arc])]
    m = arc.size
    pairs = np.arange(m)
    C = sp.csr_array((np.concatenate([-np.ones(m), np.ones(m)]),
                      (np.concatenate([pairs, pairs]),
                       np.concatenate([dofs[1, arc], n1 + dofs[1, arc]]))), shape=(m, 2 * n1))
    T = sp.csr_array((np.concatenate([np.ones(m), -np.ones(m)]),
                      (np.concatenate([pairs, pairs]),
                       np.concatenate([dofs[0, arc], n1 + dofs[0, arc]]))), shape=(m, 2 * n1))
    cut = np.flatnonzero(y > radius - tol)
    prescribed = np.concatenate([dofs[0, cut], dofs[1, cut], n1 + dofs[0, cut],
                                 n1 + dofs[1, cut]])
    model = friction_model(K, np.zeros(2 * n1), C, 2.0 * y[arc], T, prescribed=prescribed)
    midpoints = 0.5 * (x[arc][1:] + x[arc][:-1])
    tributary = np.diff(np.concatenate([x[arc][:1], midpoints, x[arc][-1:]]))
    arrays = {"K": K, "f": np.zeros(2 * n1), "C": C, "g": 2.0 * y[arc], "T": T,
              "prescribed": prescribed}
    return CattaneoModel(model, x[arc], tributary, float(radius), float(young), float(poisson),
                         (cut.size,) * 4, arrays)


def hertz_half_width(load: float, radius: float, young: float, poisson: float) -> float:
    """a = √(4PR(1 − ν²)/(πE)) for two identical cylinders (length)."""
    return math.sqrt(4.0 * load * radius * (1.0 - poisson**2) / (math.pi * young))


def stick_ratio(tangential: float, normal: float, mu: float) -> float:
    """Cattaneo's c/a = √(1 − Q/(μP)) in 2D."""
    return math.sqrt(max(1.0 - tangential / (mu * normal), 0.0))


def traction(x: np.ndarray, half_width: float, peak: float, mu: float,
             stick: float) -> np.ndarray:
    """Cattaneo's q(x) = μp₀[√(1 − x²/a²) − (c/a)√(1 − x²/c²)] (the second term for |x| < c)
    (stress)."""
    x = np.abs(np.asarray(x, dtype=float))
    outer = np.sqrt(np.clip(1.0 - (x / half_width) ** 2, 0.0, None))
    inner = np.sqrt(np.clip(1.0 - (x / stick) ** 2, 0.0, None)) if stick > 0 else 0.0 * x
    return mu * peak * (outer - stick / half_width * inner)


@dataclass(frozen=True)
class CattaneoMeasure:
    """A computed answer against Cattaneo's (lengths, forces per length).

    Attributes
    ----------
    load, tangential : float
        P = Σλ_N, Q = Σλ_T.
    half_width, hertz_half_width : float
        a read from the pressure (the edge of the pushing pairs, p² linear in x²) and
        Hertz's for P.
    stick, stick_closed_form : float
        c read from the stick zone's edge (mean of both sides) and √(1 − Q/(μP)) times
        Hertz's a.
    traction_error : float
        max |q − q_Cattaneo| over |x| ≤ 0.9c, over the closed form's peak.
    x, pressure, friction : arrays
        Each pair's position, pressure λ_N/tributary and traction λ_T/tributary.
    """

    load: float
    tangential: float
    half_width: float
    hertz_half_width: float
    stick: float
    stick_closed_form: float
    traction_error: float
    x: np.ndarray
    pressure: np.ndarray
    friction: np.ndarray

    @property
    def stick_ratio_error(self) -> float:
        """(c/a)/(c/a)_Cattaneo − 1, both over Hertz's a."""
        return self.stick / self.stick_closed_form - 1.0


def measure(cattaneo: CattaneoModel, answer: FrictionAnswer, mu: float) -> CattaneoMeasure:
    """Read P, Q, a, c and q(x) from an answer and compare them with the closed forms."""
    x = cattaneo.x
    pressure = answer.normal_force / cattaneo.tributary
    friction = answer.friction_force[:, 0] / cattaneo.tributary
    load, tangential = float(answer.normal_force.sum()), float(answer.friction_force.sum())
    a_hertz = hertz_half_width(load, cattaneo.radius, cattaneo.young, cattaneo.poisson)
    peak = 2.0 * load / (math.pi * a_hertz)
    ratio = stick_ratio(tangential, load, mu)
    # the edges: Hertz's p² and the stick zone's (μp − |q|)² are linear in x² (exact for the
    # closed forms), extrapolated from the last two pushing / sticking pairs on each side
    pushing = pressure > 1e-6 * pressure.max()
    half_width = np.mean([_edge(x, pressure, pushing, side) for side in (-1, 1)])
    reserve = np.clip(mu * pressure - np.abs(friction), 0.0, None)
    stick = np.mean([_edge(x, reserve, answer.stick & pushing, side) for side in (-1, 1)])
    inside = np.abs(x) <= 0.9 * ratio * a_hertz
    closed = traction(x, a_hertz, peak, mu, ratio * a_hertz)
    error = float(np.abs(friction - closed)[inside].max(initial=0.0)) / float(
        traction(np.linspace(0, a_hertz, 2001), a_hertz, peak, mu, ratio * a_hertz).max())
    return CattaneoMeasure(load, tangential, float(half_width), a_hertz, float(stick),
                           ratio * a_hertz, error, x, pressure, friction)


def _edge(x: np.ndarray, value: np.ndarray, inside: np.ndarray, side: int) -> float:
    """Where a quantity that ends like √(c² − x²) reaches zero, on one side of x = 0: the line
    through the last two pairs of the run of ``inside`` pairs from the centre, in (x², value²)."""
    centre = int(np.argmin(np.abs(x)))
    step = 1 if side > 0 else -1
    last = centre
    while 0 <= last + step < x.size and inside[last + step]:
        last += step
    if last == centre or not inside[centre]:
        return 0.0
    x0, x1 = x[last - step] ** 2, x[last] ** 2
    v0, v1 = value[last - step] ** 2, value[last] ** 2
    if v0 <= v1:
        return float(abs(x[last]))
    return float(np.sqrt(x1 + v1 * (x1 - x0) / (v0 - v1)))
