"""The QP of a scene, scaled so that every solver sees numbers of order one.

In the scaled unknowns x = u / U (U a displacement scale):

    minimise    ½ xᵀ K̂ x + q̂ᵀ x          K̂ = K / k,  q̂ = −P / F,  k = F / U
    subject to  C x <= ĝ   (inequality)   ĝ = g / U
                C x  = ĝ   (equality)

It is Π = ½ uᵀKu − uᵀP divided by F·U, so the multiplier μ of each row is the contact force in
units of F: λ = F·μ. The convention is the model's: L = Π + λᵀ(C u − g), λ >= 0 the force with
which a wall pushes the bar. With ``scale=False``, U = 1 and F = 1 (the QP in the scene's own
units).

Scaling (:func:`scales`): k is the stiffness the loaded and walled nodes see together,
1 / ‖K⁻¹e‖∞ with e = 1 at those nodes; U = max(‖K⁻¹P‖∞, largest −gap), the displacement the
loads cause without walls or the largest initial penetration; F = k·U. Then q̂, ĝ and the
expected multipliers are O(1), and k depends only on where loads and walls are, so a new load
or gap changes q̂ and ĝ alone (the cvxpy backend re-solves without re-canonicalising).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from contactqp._validate import flag
from contactqp.errors import OptionError
from contactqp.model import Condensed, ContactModel, Model, build_model, elongation_rows
from contactqp.scene import Scene


@dataclass(frozen=True, eq=False)
class QPProblem:
    """The QP of a scene in scaled units: minimise ½ xᵀKx + qᵀx subject to C x <= g
    (``contact="inequality"``) or C x = g (``"equality"``).

    Attributes
    ----------
    K : scaled stiffness K_SI / stiffness_scale (dimensionless), sparse symmetric, CSC.
    q : scaled linear term −P_SI / force_scale (dimensionless).
    C : constraint rows, one per wall (dimensionless, ±1), CSC.
    g : scaled right-hand sides gap / displacement_scale (dimensionless).
    contact : "inequality" or "equality".
    displacement_scale : U: the displacements are u = U·x.
    force_scale : F (N): the contact forces are λ = F·μ, μ the multipliers of the scaled QP
        with the convention L = ½ xᵀKx + qᵀx + μᵀ(C x − g).
    ties : the strain formulation's tie rows T x = 0 (B u − e = 0: each element's elongation
        e tied to the displacements u), or None. Then x = [u; e], K = diag(0, k_e / k) and
        the multipliers of the tie rows are the element forces in units of F.
    """

    K: sp.csc_array
    q: np.ndarray
    C: sp.csc_array
    g: np.ndarray
    contact: str
    displacement_scale: float = 1.0
    force_scale: float = 1.0
    ties: sp.csc_array | None = None

    @property
    def n_ties(self) -> int:
        """Number of tie rows (0 unless the strain formulation)."""
        return 0 if self.ties is None else int(self.ties.shape[0])

    @property
    def n_displacements(self) -> int:
        """Number of displacement unknowns: the first entries of x."""
        return self.n - self.n_ties

    def rows(self) -> sp.csc_array:
        """Every constraint row, the tie rows (= 0) first, then the contact rows (C x <= g or
        = g): what solvers that take one row matrix are given."""
        if self.ties is None:
            return self.C
        return sp.csc_array(sp.vstack((self.ties, self.C), format="csc"))

    def rows_rhs(self) -> np.ndarray:
        """The right-hand sides of :meth:`rows`: zero for the ties, then g."""
        return np.concatenate((np.zeros(self.n_ties), self.g))

    @cached_property
    def K_upper(self) -> sp.csc_array:
        """The upper triangle of K (CSC), as OSQP and Clarabel take it (by masking the index
        arrays: scipy's triu costs more than a small solve)."""
        K, n = self.K, self.n
        columns = np.repeat(np.arange(n), np.diff(K.indptr))
        keep = K.indices <= columns
        indptr = np.concatenate(([0], np.cumsum(np.bincount(columns[keep], minlength=n))))
        return sp.csc_array((K.data[keep], K.indices[keep], indptr), shape=K.shape)

    @property
    def stiffness_scale(self) -> float:
        """k = F / U (N/m): K_SI = k·K."""
        return self.force_scale / self.displacement_scale

    @property
    def n(self) -> int:
        """Number of unknowns (free nodes)."""
        return int(self.q.size)

    def to_si(self, x: np.ndarray, multipliers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(free-node displacements in m, contact forces in N) from the scaled solution x and
        the multipliers μ of the rows (convention above: μ >= 0 when a wall pushes)."""
        x = np.asarray(x, dtype=float).reshape(-1)[: self.n_displacements]
        mu = np.asarray(multipliers, dtype=float).reshape(-1)
        return self.displacement_scale * x, self.force_scale * mu

    def from_si(self, u_free: np.ndarray, contact_force: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The inverse of :meth:`to_si`: (x, μ) from displacements (m) and forces (N)."""
        u = np.asarray(u_free, dtype=float).reshape(-1)
        lam = np.asarray(contact_force, dtype=float).reshape(-1)
        return u / self.displacement_scale, lam / self.force_scale


def scales(model: Model | Condensed) -> tuple[float, float]:
    """(U, F): the displacement and force scales of a model's QP (module docstring), in the
    scene's units.

    k = 1 / ‖K⁻¹e‖∞, e = 1 at every loaded or walled free node: the stiffness of the bar as
    the loads and walls see it, from the scene's structure alone. U is the model's
    displacement scale (:attr:`contactqp.model.Model.displacement_scale`: ‖K⁻¹P‖∞, the free
    displacement, or the deepest press fit) rounded to a power of two of metres; F = k·U.
    Contact forces are then O(F): a wall with an open gap can only take what the loads bring.
    Open gaps are not a scale: a far wall's gap would shrink the loads below the solver's
    tolerance (measured: Clarabel "Solved" with 81 N on a 1 N load pulling away from a
    zero-gap wall, U set by a second wall 0.19 mm away). Without loads or walls k falls back
    to the largest diagonal of K.
    """
    e = np.zeros(model.n_free)
    e[np.flatnonzero(model.P)] = 1.0
    e[model.C.indices] = 1.0
    if e.any():
        held = model.held if isinstance(model, Model) else model  # a bar with no support: K + springs
        k = 1.0 / float(np.abs(held.solve_K_and_loads(e)).max())
    else:
        k = float(model.K.diagonal().max())
    # U rounded to a power of two (of metres, so that a solver sees the same numbers whatever
    # the scene's units): then the scaled K does not change with the loads until U crosses a
    # power of two (a cvxpy re-solve along a load path finds its cached problem)
    U, metre = model.displacement_scale, model.layout.scene.unit.metre
    U = math.ldexp(1.0, round(math.log2(U * metre))) / metre if math.isfinite(U) else U
    return U, k * U


def qp_from_model(model: ContactModel, contact: str = "inequality", scale: bool = True,
                  formulation: str = "full") -> QPProblem:
    """The QP data of a model (see :class:`QPProblem`), scaled by :func:`scales` or in SI;
    ``formulation`` "full" (x = u, Hessian K) or "strain" (x = [u; e], Hessian diag(0, k_e),
    tie rows B u − e = 0). A model with no chain (a user's problem) is scaled by its own F
    and U (:func:`_general_qp`)."""
    if model.layout is None:
        return _general_qp(model, contact, scale)
    U, F = scales(model) if scale else (1.0, 1.0)
    if formulation == "strain":
        return _strain_qp(model, contact, U, F)
    if formulation != "full":
        raise OptionError(f"QP formulation must be 'full' or 'strain'; got {formulation!r}")
    k = F / U
    K = _csc_from_band(model.band / k) if isinstance(model, Model) else sp.csc_array(model.K / k)
    return QPProblem(
        K=K, q=-model.P / F, C=sp.csc_array(model.C), g=model.g / U, contact=contact,
        displacement_scale=U, force_scale=F,
    )


def _general_qp(model: ContactModel, contact: str, scale: bool = True) -> QPProblem:
    """The QP of a model with no chain, scaled by its F and U (x = u / U, multipliers λ / F)
    as a scene's QP is; mixed inequality and equality rows are refused (the backends take one
    kind of row)."""
    equality = model.equality
    if equality.any() and not equality.all() and contact != "equality":
        raise OptionError("qp: the QP backends take rows of one kind, and this problem mixes "
                          "inequality and equality rows (use lagrange, penalty or augmented)")
    kind = "equality" if contact == "equality" or equality.all() else "inequality"
    U, F = (model.displacement_scale, model.force_scale) if scale else (1.0, 1.0)
    return QPProblem(K=sp.csc_array(model.K / (F / U)), q=-model.P / F,
                     C=sp.csc_array(model.C), g=model.g / U, contact=kind,
                     displacement_scale=U, force_scale=F)


def _strain_qp(model: Model, contact: str, U: float, F: float) -> QPProblem:
    """The strain formulation: unknowns x = [u; e] (both in units of U), energy
    ½ Σ k_e e² (k_e = EA/L of each element), tie rows B u − e = 0 (:func:`elongation_rows`).
    The Hessian is diagonal; the bar's ill-conditioning (cond K ~ n²) moves into the rows."""
    if not isinstance(model, Model):
        raise OptionError("formulation='strain' needs the full model, not a condensed one")
    B = elongation_rows(model)
    k = model.layout.element_stiffness / (F / U)
    n, m = model.n_free, k.size
    identity = sp.eye_array(m, format="csc")
    return QPProblem(
        K=sp.csc_array(sp.diags_array(np.concatenate((np.zeros(n), k))).tocsc()),
        q=np.concatenate((-model.P / F, np.zeros(m))),
        C=sp.csc_array(sp.hstack((model.C, sp.csr_array((model.n_contacts, m))), format="csc")),
        g=model.g / U, contact=contact, displacement_scale=U, force_scale=F,
        ties=sp.csc_array(sp.hstack((B, -identity), format="csc")),
    )


def _csc_from_band(band: np.ndarray) -> sp.csc_array:
    """The symmetric tridiagonal matrix of a lower band (diagonal; sub-diagonal) as CSC,
    built from its index arrays (no sparse conversions: the QP method's main fixed cost)."""
    n = band.shape[1]
    diagonal, sub = band[0], band[1, :-1]
    rows = np.stack((np.arange(n) - 1, np.arange(n), np.arange(n) + 1), axis=1)
    data = np.stack((np.concatenate(([0.0], sub)), diagonal, np.concatenate((sub, [0.0]))), axis=1)
    keep = (rows >= 0) & (rows < n)
    counts = keep.sum(axis=1)
    indptr = np.concatenate(([0], np.cumsum(counts)))
    return sp.csc_array((data[keep], rows[keep], indptr), shape=(n, n))


def qp_problem(scene: Scene, contact: str = "inequality", scale: bool = True,
               formulation: str = "full") -> QPProblem:
    """The QP of a scene, ready for any solver: minimise ½ xᵀKx + qᵀx s.t. C x <= g (or = g).

    With ``scale=True`` (the default, as for ``solve(method="qp")``) the data are
    non-dimensional; :meth:`QPProblem.to_si` maps a solution and its multipliers back to metres
    and newtons. With ``scale=False`` they are in SI units (K in N/m, q in N, g in m). A
    solver's own equilibration may be better off on the scaled data (see :data:`~contactqp.methods.qp.settings.PRESCALED`).
    ``formulation="strain"`` gives the QP in displacements and element elongations
    (:func:`_strain_qp`).

    Parameters
    ----------
    scene : Scene
        The scene.
    contact : str
        ``"inequality"`` (C x <= g, the default) or ``"equality"`` (C x = g).
    scale : bool
        Scale the data to order one (default True).
    formulation : str
        ``"full"`` (default) or ``"strain"``.

    Returns
    -------
    QPProblem
        The QP data (sparse K, q, C, g) and the scales that map it back.

    Raises
    ------
    OptionError
        An unknown contact kind or formulation.
    """
    if contact not in ("inequality", "equality"):
        raise OptionError(f"contact must be one of inequality, equality; got {contact!r}")
    flag("scale", scale, OptionError)
    return qp_from_model(build_model(scene), contact, scale, formulation)


__all__ = ["QPProblem", "qp_from_model", "qp_problem", "scales"]
