"""The model protocol: what every model offers the methods and the check, whichever front end
made it (a bar scene's chain, :mod:`contactqp.model.chain.model`, or a user's K, f, C, g,
:mod:`contactqp.model.sparse`).

A model is the problem in its free dofs (the prescribed ones condensed out):

    minimise ½ uᵀK u − uᵀP   subject to   C u <= g (inequality rows),  C u = g (equality rows),

with the answer's contact forces λ (one per row, positive when the row pushes: it acts as
−Cᵀλ). It offers

- its algebra: ``n_free``, ``n_contacts``, ``K`` (sparse, free x free), ``P``, ``C`` (CSR),
  ``g``, ``equality`` (per row), ``row_names``, ``floating`` (modes K leaves free); the
  products the check reads on every answer, each a model may work out its own fast way:
  ``C_times`` (C u), ``C_transpose_times`` (Cᵀλ), ``largest_imbalance`` (‖K u − P + Cᵀλ‖∞:
  a chain in blocks from its band or its element forces), ``free_part`` (u at the free dofs,
  a view where they are one run);
- its solves: ``solve_K`` (K⁻¹), ``free_displacement`` (K⁻¹P), ``set_solve`` (the exact
  answer with a set of rows held on their gaps, and its corrections); where
  ``flexibility_in_blocks`` is True, ``flexibility(rows)`` forms W = C K⁻¹ Cᵀ of the rows a
  block of columns at a time, keeping no K⁻¹Cᵀ (a user's model with CHOLMOD's factor);
- what it is in the user's words: ``full_displacements`` (every dof), ``reactions`` (the
  force of each support or prescribed dof), ``units`` (force, length);
- the scales the check measures against, by one rule (:func:`force_scale`,
  :func:`displacement_scale`, :func:`row_stiffness`), from terms each model works out its own
  fast way (:meth:`ContactModel.scale_terms`).

Methods pick their fast paths by what a model can do (``model.layout`` is a chain's
numbering, None elsewhere), never by its type.

The scales (never from an answer; u₀ the answer with no contact force; on a K that leaves modes
X free, u₀ = K⁺(P − Cᵀμ), the loads with what they put on X taken up by the rows that touch X
(:func:`balanced_by_contact`); p = C u₀ − g where u₀ passes a row (an equality row:
|C u₀ − g|)):

    F = max(‖f‖∞, ‖R₀‖∞, ‖λ₀‖∞, ‖Xᵀf‖∞)   the largest load; the largest support reaction of
        u₀ (the force a prescribed motion makes, as the body carries it: never K_ID u_D, which
        a fine mesh inflates a thousandfold); the contact forces of one step towards closing
        u₀'s penetrations, λ₀ = μ S p, S = diag(s̄), μ = pᵀSp / (Sp)ᵀW(Sp) (W = C K⁻¹ Cᵀ: one
        solve; for one row λ₀ = p / W_ii, the force that pushes it back); and the loads the
        free modes X of K leave to contact (each mode scaled to a largest entry of 1);
        where all are 0 (nothing loads the model), U times the smallest stiffness of a dof;
    U = max(‖u₀‖∞, ‖p / |c|‖∞)   the largest displacement with no contact (prescribed motions
        included) and how far u₀ passes a row; where both are 0, the widest gap, else the
        model's size (a chain's longest bar; a problem's coordinates' extent, or 1);
    s̄_i = c_iᵀ K c_i / (c_iᵀ c_i)²   per row: at least the stiffness 1/W_ii the row sees
        (Cauchy–Schwarz), with no solve (:attr:`~ContactModel.row_stiffness`); the residuals
        read the stiffness itself, 1/W_ii, where s̄ says a row matters
        (:meth:`~ContactModel.seen_stiffness`).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp.model import saddle


@dataclass(frozen=True)
class ScaleTerms:
    """What the scales are made of (module docstring), each model's own numbers.

    Attributes
    ----------
    loads : ‖f‖∞ over every dof (force).
    reactions : ‖R₀‖∞, the largest support reaction with no contact force (force).
    contact : ‖λ₀‖∞ (force).
    unbalanced : ‖Xᵀf‖∞ over the free modes (force; 0 where K leaves none).
    free : ‖u₀‖∞ (length).
    passed : ‖p / |c|‖∞ (length).
    widest : the widest gap, ‖g⁺ / |c|‖∞ (length).
    size : the model's own length where nothing else gives one.
    softest : the smallest stiffness of a free dof (force per length).
    """

    loads: float
    reactions: float
    contact: float
    unbalanced: float
    free: float
    passed: float
    widest: float
    size: float
    softest: float


ROUND_OFF_LENGTH = 1e-12  # of the largest force over the softest stiffness: round-off of u₀


def displacement_scale(terms: ScaleTerms) -> Any:
    """U by its rule (module docstring); ‖u₀‖∞ and how far it passes a row count where they
    are more than the round-off of u₀, ROUND_OFF_LENGTH of the largest force term over the
    softest stiffness (a floating body's balanced loads leave u₀ = 1e-38 m on one front end,
    0 on the other). Terms may be arrays (one entry per case of a batch): U is then one."""
    if _plain(terms):  # one case: the same rule in Python floats, without numpy's set-up
        force = max(terms.loads, terms.reactions, terms.contact, terms.unbalanced)
        noise = ROUND_OFF_LENGTH * force / terms.softest if terms.softest > 0.0 else 0.0
        scale = max(terms.free, terms.passed)
        fallback = (terms.widest if terms.widest > 0.0 else
                    terms.size if terms.size > 0.0 else 1.0)
        return float(scale if scale > noise else fallback)
    force = _largest_force(terms)
    with np.errstate(divide="ignore", invalid="ignore"):
        noise = _positive_or(terms.softest, lambda: ROUND_OFF_LENGTH * force / terms.softest,
                             0.0)
    scale = np.maximum(terms.free, terms.passed)
    fallback = _positive_or(terms.widest, lambda: terms.widest,
                            _positive_or(terms.size, lambda: terms.size, 1.0))
    return _scalar(np.where(scale > noise, scale, fallback))


def force_scale(terms: ScaleTerms, U: Any) -> Any:
    """F by its rule (module docstring); terms and U may be arrays, as for U."""
    if _plain(terms) and isinstance(U, float):
        scale = max(terms.loads, terms.reactions, terms.contact, terms.unbalanced)
        return float(scale if scale > 0.0 else terms.softest * U if terms.softest > 0.0
                     else 1.0)
    scale = _largest_force(terms)
    fallback = _positive_or(terms.softest, lambda: np.multiply(terms.softest, U), 1.0)
    return _scalar(np.where(scale > 0.0, scale, fallback))


def _positive_or(term: Any, then: Any, otherwise: Any) -> Any:
    """then() where ``term`` > 0, else ``otherwise``: elementwise for an array term, by
    Python for a number (numpy's where on numbers takes microseconds)."""
    if isinstance(term, float):
        return then() if term > 0.0 else otherwise
    return np.where(np.greater(term, 0.0), then(), otherwise)


def _largest_force(terms: ScaleTerms) -> Any:
    """The largest of the force terms, each a number or an array (one entry per case)."""
    return np.maximum(np.maximum(terms.loads, terms.reactions),
                      np.maximum(terms.contact, terms.unbalanced))


def _plain(terms: ScaleTerms) -> bool:
    """Whether every term is one number, none of them NaN (the batch's are arrays)."""
    values = tuple(vars(terms).values())  # not dataclasses.astuple: it deep-copies arrays
    return all(isinstance(v, float) for v in values) and not any(map(math.isnan, values))


def _scalar(value: np.ndarray) -> Any:
    return float(value) if np.ndim(value) == 0 else value


# the default penalties, each this many times a row's s̄ (:func:`row_stiffness`): the penalty
# method's (contactqp.methods.penalty, contactqp.friction.penalty) and the augmented
# Lagrangian's (contactqp.methods.augmented, contactqp.friction.penalty)
PENALTY_PER_STIFFNESS = 1e6
AUGMENTED_PER_STIFFNESS = 100.0


def row_stiffness(K: sp.sparray, C: sp.csr_array) -> np.ndarray:
    """Per row, c_iᵀ K c_i / (c_iᵀ c_i)² (module docstring), read-only."""
    if C.shape[0] and np.all(np.diff(C.indptr) == 1):  # one dof per row (walls, a flat)
        squared = C.data * C.data
        energy = squared * K.diagonal()[C.indices]  # c² K_jj, as a chain reads its rows
    else:
        squared = np.asarray(C.multiply(C).sum(axis=1)).reshape(-1)
        energy = np.asarray((C @ K).multiply(C).sum(axis=1)).reshape(-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = energy / squared**2
    s.flags.writeable = False
    return s


def first_step_forces(p: np.ndarray, s: np.ndarray, transpose_times: Any,
                      energy_of: Any) -> np.ndarray:
    """λ₀ = μ S p, μ = pᵀSp / (Sp)ᵀW(Sp), W = C K⁻¹ Cᵀ (one solve): the forces of one
    steepest-descent step, weighted by the rows' stiffness, towards closing the penetrations
    p (module docstring). Zeros where p is."""
    weighted = np.where(p > 0.0, s * p, 0.0)
    if not weighted.any():
        return np.zeros(p.size)
    push = transpose_times(weighted)  # Cᵀ(S p)
    flex = energy_of(push)  # pushᵀ K⁺ push
    if not flex > 0.0:
        return np.zeros(p.size)
    return (float(p @ weighted) / flex) * weighted


def balanced_by_contact(P: np.ndarray, modes: np.ndarray, C: sp.csr_array) -> np.ndarray:
    """P with what it leaves on the free ``modes`` X (columns) taken up by the contact rows
    that touch them: P − Cᵀμ, μ = C X a with (C X)ᵀ(C X) a = XᵀP, so that Xᵀ(P − Cᵀμ) = 0 (the
    resultant a floating body's loads put on its contacts, spread over them as they touch the
    mode; independent of the basis X). P as it is where K leaves no mode free, or where the
    rows do not touch the modes (then only contact can say where the load goes)."""
    if modes.size == 0:
        return P
    touched = C @ modes
    gram = touched.T @ touched
    try:
        a = np.linalg.solve(gram, modes.T @ P)
    except np.linalg.LinAlgError:
        a = np.linalg.lstsq(gram, modes.T @ P, rcond=None)[0]
    return P - C.T @ (touched @ a)


def normalised_modes(modes: np.ndarray) -> np.ndarray:
    """The free modes (columns, any basis of their span) in reduced row-echelon form, each
    scaled to a largest entry of 1: a basis that does not depend on the one given (the
    translations of two floating bars come back as each bar's own)."""
    if modes.size == 0:
        return modes
    import scipy.linalg

    _, _, pivots = scipy.linalg.qr(modes.T, pivoting=True, mode="economic")
    chosen = np.sort(pivots[: modes.shape[1]])
    echelon = modes @ np.linalg.solve(modes[chosen], np.eye(modes.shape[1]))
    return echelon / np.abs(echelon).max(axis=0)


def natural_map(forces: np.ndarray, gaps: np.ndarray, free: np.ndarray,
                roots: np.ndarray | None = None) -> float | np.ndarray:
    """The natural-map residual of the contact LCP (Siconos's measure, not part of
    ``verified``): ‖min(z, w)‖∞ / ‖q‖∞ (min(z, w) = z − (z − w)₊), z the contact forces, w the
    gaps they leave and q the gaps with no contact force. With ``roots`` r (√ of the compliance
    each row sees) each row is scaled as the LCP scaled to a unit diagonal is, z = λ·r, w/r,
    q/r, so that the number is the same in every unit system. Over the last axis (one value
    per case for cases x rows)."""
    return natural_top(forces, gaps, roots) / natural_size(free, roots)


def natural_top(forces: np.ndarray, gaps: np.ndarray, roots: np.ndarray | None,
                own_gaps: bool = False) -> np.ndarray:
    """‖min(z, w)‖∞ of :func:`natural_map`, each row scaled by ``roots`` (if given);
    ``own_gaps``: ``gaps`` is the caller's scratch, scaled in place."""
    scaled = roots is not None
    if scaled:  # λ = D z and D w, D = diag(W)^-½ = 1/roots
        forces, gaps = forces * roots, np.divide(gaps, roots, out=gaps if own_gaps else None)
    with np.errstate(invalid="ignore"):  # in the scaled forces' array when there is one
        top = np.minimum(forces, gaps, out=forces if scaled else None)
        return np.fmax.reduce(np.abs(top, out=top), axis=-1, initial=0.0)  # NaN rows: none


def natural_size(free: np.ndarray, roots: np.ndarray | None) -> np.ndarray:
    """‖q‖∞ of :func:`natural_map` (1 where it is 0), each row scaled by ``roots``."""
    if roots is not None:
        free = free / roots
    with np.errstate(invalid="ignore"):
        size = np.fmax.reduce(np.abs(free), axis=-1, initial=0.0)
    return np.where(size > 0.0, size, 1.0)


class ContactModel(ABC):
    """The protocol (module docstring). Subclasses are frozen dataclasses holding ``K``,
    ``P``, ``C``, ``g`` and ``layout`` (a chain's numbering, with which the bar quantities
    come: element forces, stresses; None for any other model); the scales are worked out
    here, once, from their terms."""

    K: sp.sparray  # the stiffness over the free dofs
    free: np.ndarray  # the free dofs' numbers among all the model's dofs, ascending
    P: np.ndarray
    C: sp.csr_array
    g: np.ndarray
    # whether flexibility(rows) forms W a block of solved columns at a time, holding no
    # K⁻¹Cᵀ of every row (module docstring)
    flexibility_in_blocks = False

    # --- the algebra
    @property
    def n_free(self) -> int:
        return int(self.P.size)

    @property
    def n_contacts(self) -> int:
        return int(self.g.size)

    @property
    @abstractmethod
    def equality(self) -> np.ndarray:
        """Per row, True where the row is an equality (held on its gap whatever the contact
        kind asked for)."""

    @property
    @abstractmethod
    def row_names(self) -> tuple[str, ...]:
        """Each row's name, for messages and tables."""

    @property
    @abstractmethod
    def units(self) -> tuple[str, str]:
        """(force, length) unit labels ("" where the user gave none)."""

    @property
    @abstractmethod
    def singular(self) -> bool:
        """Whether K leaves modes free (a K held by contact rows alone)."""

    def imbalance(self, u_free: np.ndarray, contact_force: np.ndarray) -> np.ndarray:
        """K u − P + Cᵀλ over the free dofs: what an answer leaves out of balance."""
        out = self.K @ u_free - self.P
        out += self.C_transpose_times(contact_force)
        return out

    def largest_imbalance(self, u_free: np.ndarray, contact_force: np.ndarray) -> float:
        """‖K u − P + Cᵀλ‖∞ over the free dofs (:meth:`imbalance`): the check's
        equilibrium residual, before its scale."""
        return float(np.abs(self.imbalance(u_free, contact_force)).max(initial=0.0))

    def C_times(self, u_free: np.ndarray) -> np.ndarray:
        """C u: how far each row's points move toward its gap (a bincount over C's entries,
        with none of a sparse product's set-up: the check reads it on every answer)."""
        rows, columns, values = self._entries
        if self._one_entry_per_row:  # each row reads one dof (walls, a flat): no sum
            moved = u_free[columns]
            moved *= values
            return moved
        return np.bincount(rows, values * u_free[columns], minlength=self.n_contacts)

    def C_transpose_times(self, contact_force: np.ndarray) -> np.ndarray:
        """Cᵀλ: the force the contact rows put on the free dofs (as :meth:`C_times`)."""
        rows, columns, values = self._entries
        return np.bincount(columns, values * contact_force[rows], minlength=self.n_free)

    @cached_property
    def _entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """C's entries as (row, column, value) arrays, once per model: copies, since scipy
        sorts a CSR matrix's indices in place when an operation needs them sorted."""
        C = self.C
        return (np.repeat(np.arange(C.shape[0]), np.diff(C.indptr)), C.indices.copy(),
                np.array(C.data, dtype=float))

    @cached_property
    def _one_entry_per_row(self) -> bool:
        """Whether C has exactly one entry in each row, in row order."""
        return bool(np.array_equal(self.C.indptr, np.arange(self.C.shape[0] + 1)))

    @cached_property
    def free_gaps(self) -> np.ndarray:
        """g − C K⁻¹P: the gap each row keeps with no contact force (the natural map's q)."""
        return self.g - self.C_times(self.free_displacement)

    @cached_property
    def free_gap_size(self) -> float:
        """‖q‖∞ of the natural map, each row scaled by :attr:`row_roots`, once per model."""
        return float(natural_size(self.free_gaps, self.row_roots))

    @cached_property
    def row_roots(self) -> np.ndarray:
        """1/√s̄ per row (the natural map's scaling; inf where s̄ is 0)."""
        with np.errstate(divide="ignore"):
            return 1.0 / np.sqrt(self.row_stiffness)

    def free_part(self, u: np.ndarray) -> np.ndarray:
        """u at the free dofs (``u[free]``, in order): a view where they are one run of
        consecutive dofs (a chain held at one end), so that a check of 10⁶ nodes copies none."""
        run = self._free_run
        return u[run] if run is not None else u[self.free]

    @cached_property
    def _free_run(self) -> slice | None:
        free = self.free
        if free.size and int(free[-1]) - int(free[0]) + 1 == free.size:
            return slice(int(free[0]), int(free[-1]) + 1)
        return slice(0, 0) if not free.size else None

    # --- the solves
    def energy_of(self, push: np.ndarray) -> float:
        """pushᵀ K⁺ push for a force ``push`` on the free dofs (one solve; a model may know a
        cheaper way)."""
        return float(push @ self.pseudo_solve(push))

    @abstractmethod
    def solve_K(self, rhs: np.ndarray) -> np.ndarray:
        """K⁻¹ rhs (a SolverError where K leaves a mode free)."""

    @cached_property
    def free_displacement(self) -> np.ndarray:
        """K⁻¹P: the free dofs' displacement with no contact force."""
        return self.solve_K(self.P)

    # --- the set solve: the exact answer with some rows held on their gaps
    def set_solve(self, rows: np.ndarray, force: np.ndarray, gap: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
        """(u, λ_rows) with K u + C_rowsᵀ λ_rows = force and C_rows u = gap: by default the
        saddle-point system by sparse LU (:func:`contactqp.model.saddle.set_solve`), which
        is O(n) on a chain."""
        u, lam, redundant = saddle.set_solve(self.K, self.C[rows], force, gap)
        self.__dict__["_redundant"] = (np.asarray(rows).tobytes(), redundant)
        return u, lam

    def redundant(self, rows: np.ndarray) -> bool:
        """Whether ``rows`` repeat each other's constraint (their forces are not unique, only
        Cᵀλ is)."""
        kept = self.__dict__.get("_redundant")
        key = np.asarray(rows).tobytes()
        if kept is None or kept[0] != key:
            self.set_solve(rows, np.zeros(self.n_free), np.zeros(len(rows)))
        return bool(self.__dict__["_redundant"][1])

    def on_set(self, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(u, λ per row) with the rows in ``active`` held on their gaps and the others
        carrying nothing."""
        rows = np.flatnonzero(active)
        lam = np.zeros(self.n_contacts)
        u, lam[rows] = self.set_solve(rows, self.P, self.g[rows])
        return u, lam

    @abstractmethod
    def support_change(self, du: np.ndarray) -> np.ndarray:
        """How the supports' forces change when the free dofs move by ``du`` (loads and
        prescribed motions unchanged)."""

    # --- the user's words
    @abstractmethod
    def full_displacements(self, u_free: np.ndarray) -> np.ndarray:
        """Every dof's displacement (the prescribed ones at their values)."""

    @abstractmethod
    def reactions_of(self, u: np.ndarray, contact_force: np.ndarray) -> np.ndarray:
        """The force each support (prescribed dof) applies, for displacements ``u`` of
        every dof and the contact forces."""

    # --- the scales
    @abstractmethod
    def scale_terms(self) -> ScaleTerms:
        """The terms of the scales (:class:`ScaleTerms`), worked out once."""

    @cached_property
    def displacement_scale(self) -> float:
        """U (module docstring)."""
        return float(displacement_scale(self._terms))

    @cached_property
    def force_scale(self) -> float:
        """F (module docstring)."""
        return float(force_scale(self._terms, self.displacement_scale))

    @cached_property
    def _terms(self) -> ScaleTerms:
        return self.scale_terms()

    @cached_property
    def row_stiffness(self) -> np.ndarray:
        """s̄_i = c_iᵀK c_i / (c_iᵀc_i)² per row: at least the stiffness the row sees (module
        docstring), with no solve."""
        return row_stiffness(self.K, self.C)

    @abstractmethod
    def seen_stiffness(self, rows: np.ndarray) -> np.ndarray:
        """1 / (c_i K⁻¹ c_iᵀ) of each of ``rows``: the stiffness the row sees with the supports
        held (and no other row); 0 where the row moves a mode K leaves free (nothing but
        contact holds it there)."""


__all__ = ["AUGMENTED_PER_STIFFNESS", "PENALTY_PER_STIFFNESS", "ContactModel", "ScaleTerms",
           "balanced_by_contact", "displacement_scale", "first_step_forces", "force_scale",
           "natural_map", "natural_size", "natural_top", "normalised_modes", "row_stiffness"]
