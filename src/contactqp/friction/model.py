"""A model with friction: K, f, C, g, T on plain arrays, the prescribed dofs condensed out.

Glossary (the symbols of every module of :mod:`contactqp.friction`):

- n dofs, m contacts, d tangential directions per contact (1 in 2D, 2 in 3D).
- K (n x n) the stiffness, f (n) the load; min ½uᵀKu − fᵀu is the elastic energy to minimise.
- C (m x n), g (m): the normal rows, C u ≤ g (no penetration); the normal force λ_N ≥ 0 of
  row i acts on the dofs as −C_iᵀλ_N,i.
- T (d·m x n): the tangential rows, contact i owning rows d·i … d·i + d − 1. The slip of an
  increment is v = T(u − u_prev), u_prev the state it starts from; the friction force λ_T (m x d)
  acts on the dofs as −Tᵀλ_T. With this sign λ_T points along the slip, so the force it exerts,
  −λ_T, opposes it, as the normal force λ_N ≥ 0 pushes against C u.
- The flexibility of the rows, W = G K⁻¹ Gᵀ for G = [C; T] (k = m + d·m rows), and each row's
  stiffness 1/W_ii: the force that moves it by a unit length with nothing else held.

A contact whose normal is not modelled (a bar on a bed) has no row of C: pass ``C=None`` and
``contacts=m``. K must be positive definite on the free dofs: every rigid motion held by
prescribed dofs (the QP backends would take a body held by friction alone; the factorisation
every other method and the check share would not).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from contactqp.errors import ProblemError
from contactqp.friction._factor import Factor

SYMMETRY = 1e-10  # K − Kᵀ beyond this fraction of K's largest entry: K is not symmetric


@dataclass(frozen=True, eq=False)
class FrictionModel:
    """K, f, C, g, T with the prescribed dofs condensed out, and the solves methods share.

    Build it with :func:`friction_model`. The arrays below live on the free dofs.

    Attributes
    ----------
    n, contacts, d : int
        All dofs, the contacts m, the tangential rows per contact.
    free, prescribed : int arrays
        The free and the prescribed dofs.
    values : array
        The prescribed dofs' displacements (length).
    K : scipy.sparse.csc_array
        The free dofs' stiffness (force/length).
    load : array
        f − K_fp u_p on the free dofs: the load with the prescribed motion's pull (force).
    C : scipy.sparse.csr_array or None
        The normal rows on the free dofs.
    gap : array or None
        g − C_p u_p: each row's gap with the free dofs at rest (length).
    T : scipy.sparse.csr_array
        The tangential rows on the free dofs.
    tangential_shift : array
        T_p u_p: what the prescribed dofs add to T u (length).
    """

    n: int
    contacts: int
    d: int
    free: np.ndarray
    prescribed: np.ndarray
    values: np.ndarray
    K: sp.csc_array
    load: np.ndarray
    C: sp.csr_array | None
    gap: np.ndarray | None
    T: sp.csr_array
    tangential_shift: np.ndarray
    source: _Source = dataclasses.field(repr=False)

    @property
    def normal_rows(self) -> int:
        """The rows of C (m, or 0 for a bed)."""
        return 0 if self.C is None else self.contacts

    @cached_property
    def rows(self) -> sp.csr_array:
        """G = [C; T] on the free dofs (k x free)."""
        blocks = [self.T] if self.C is None else [self.C, self.T]
        return sp.csr_array(sp.vstack(blocks, format="csr"))

    @cached_property
    def factor(self) -> Factor:
        """K's factorisation with the dofs the rows read eliminated last (:mod:`._factor`)."""
        touched = np.unique(self.rows.indices)
        return Factor(self.K, touched)

    @cached_property
    def flexibility(self) -> np.ndarray:
        """W = G K⁻¹ Gᵀ (k x k, length/force)."""
        return self.factor.flexibility(self.rows)

    @cached_property
    def row_stiffness(self) -> np.ndarray:
        """1/W_ii per row: the force that moves row i by a unit length (force/length). Where K
        cannot be factorised (a body held by friction alone, for the QP backends), the upper
        bound Σ_j G_ij² K_jj stands in: it only sets the scale of the answer's states."""
        try:
            diagonal = np.diag(self.flexibility)
        except ProblemError:
            G = self.rows
            return np.asarray(G.multiply(G) @ self.K.diagonal()).ravel()
        return np.where(self.inert, 0.0, 1.0 / np.where(self.inert, 1.0, diagonal))

    @property
    def tangential_stiffness(self) -> np.ndarray:
        """Per contact one stiffness for its slip, the largest of its tangential rows' (a
        scalar, so that λ_T + k v keeps the direction of v in 3D) (force/length)."""
        rows = self.row_stiffness[self.normal_rows:].reshape(self.contacts, self.d)
        return rows.max(axis=1)

    @cached_property
    def inert(self) -> np.ndarray:
        """Rows that read no free dof (zero flexibility): a tangential row on a dof held by
        symmetry. Their force goes to the supports; the methods leave it at zero."""
        diagonal = np.diag(self.flexibility)
        return diagonal <= 1e-14 * diagonal.max(initial=0.0)

    @cached_property
    def load_scale(self) -> float:
        """The loads' part of the force scale F: the largest load on any dof and the largest
        reaction of the prescribed dofs with no contact force, R₀ = K_pf u₀ + K_pp u_p − f_p
        (force). A prescribed motion counts by the force it takes to impose it on the body
        left free, not by its pull on free dofs held at rest (K_fp u_p, which a rigid motion
        of the caps makes 10⁴ times the contact forces of the Cattaneo spheres). Where K
        cannot be factorised (a body held by friction alone) that pull stands in."""
        source = self.source
        loads = float(np.abs(source.f).max(initial=0.0))
        try:
            u0 = self.unloaded
        except ProblemError:
            return max(loads, float(np.abs(self.load).max(initial=0.0)))
        reactions = (source.K_fp.T @ u0 + source.K_pp @ self.values
                     - source.f[self.prescribed])
        return max(loads, float(np.abs(reactions).max(initial=0.0)))

    @cached_property
    def unloaded(self) -> np.ndarray:
        """u₀ = K⁻¹(f − K_fp u_p): the free dofs with no contact force (length)."""
        return self.factor.solve(self.load)

    def full(self, u_free: np.ndarray) -> np.ndarray:
        """The displacement of all n dofs, the prescribed ones at their values."""
        u = np.empty(self.n)
        u[self.free], u[self.prescribed] = u_free, self.values
        return u

    def previous(self, previous_u: np.ndarray | None) -> np.ndarray:
        """The state an increment starts from (all n dofs; zero when not given), validated."""
        if previous_u is None:
            return np.zeros(self.n)
        return _vector("previous_u", previous_u, self.n)

    def slip_origin(self, previous_u: np.ndarray | None) -> np.ndarray:
        """c with T_free u_free − c = T(u − u_prev): the slip's origin on the free dofs."""
        return self.source.T @ self.previous(previous_u) - self.tangential_shift

    def targets(self, previous_u: np.ndarray | None) -> np.ndarray:
        """h with G u_free − h = (C u − g, T(u − u_prev)): minus the gaps, then the slips."""
        origin = self.slip_origin(previous_u)
        return origin if self.C is None else np.concatenate([self.gap, origin])

    def reduced_rhs(self, previous_u: np.ndarray | None) -> np.ndarray:
        """b = G u₀ − h: what the rows read (minus the gaps, the slips) with no contact force."""
        return self.rows @ self.unloaded - self.targets(previous_u)

    def displacement(self, forces: np.ndarray) -> np.ndarray:
        """u_free = K⁻¹(f − Gᵀλ) for the contact forces λ = (λ_N, λ_T flat) (length)."""
        return self.factor.solve(self.load - self.rows.T @ forces)

    def with_loads(self, f: np.ndarray | None = None, values: np.ndarray | None = None,
                   g: np.ndarray | None = None) -> FrictionModel:
        """The same K, C, T (and factorisation) under another load, prescribed motion or gap:
        the next increment of a load path.

        Parameters
        ----------
        f : array, n, optional
            The load on all dofs (force); default: this model's.
        values : array, optional
            The prescribed dofs' displacements (length); default: this model's.
        g : array, m, optional
            The gaps (length); default: this model's.
        """
        source = self.source
        f = source.f if f is None else _vector("f", f, self.n)
        values = self.values if values is None else _vector("values", values,
                                                             self.prescribed.size)
        g = source.g if g is None else _vector("g", g, self.contacts)
        model = dataclasses.replace(
            self, values=values, load=f[self.free] - source.K_fp @ values,
            gap=None if self.C is None else g - source.C_p @ values,
            tangential_shift=source.T_p @ values, source=dataclasses.replace(source, f=f, g=g))
        for name in ("rows", "factor", "flexibility", "row_stiffness", "inert"):  # K, C, T unchanged
            if name in self.__dict__:
                model.__dict__[name] = self.__dict__[name]
        return model


@dataclass(frozen=True, eq=False)
class _Source:
    """What the condensed arrays came from: the user's f and g, T on all dofs, and the blocks
    on the prescribed dofs that a new load or prescribed motion passes through."""

    f: np.ndarray
    g: np.ndarray | None
    T: sp.csr_array
    K_fp: sp.csr_array
    C_p: sp.csr_array | None
    T_p: sp.csr_array
    K_pp: sp.csr_array


def friction_model(K, f, C, g, T, *, prescribed=None, values=None,
                   contacts: int | None = None) -> FrictionModel:
    """Validate a model with friction and condense its prescribed dofs out.

    Parameters
    ----------
    K : sparse or dense array, n x n
        The stiffness (force/length), symmetric, positive definite once the prescribed dofs
        are held.
    f : array, n
        The load (force).
    C : sparse or dense array, m x n, or None
        The normal rows (C u ≤ g); None for contacts without a normal (a bed).
    g : array, m, or None
        The gaps (length); None with C.
    T : sparse or dense array, d·m x n
        The tangential rows, d = 1 (2D) or 2 (3D) per contact, contact i owning rows
        d·i … d·i + d − 1.
    prescribed : int array, optional
        Dofs held at ``values``.
    values : array, optional
        Their displacements (length); default zero.
    contacts : int, optional
        m when C is None.

    Returns
    -------
    FrictionModel

    Raises
    ------
    ProblemError
        An array of the wrong shape, not finite, K not symmetric, or T's rows not d per
        contact; one line naming the field and the value.
    """
    K = _square(K)
    n = K.shape[0]
    f = _vector("f", f, n)
    if C is None:
        if g is not None:
            raise ProblemError("g: given without C; pass both or neither")
        if contacts is None or int(contacts) < 1:
            raise ProblemError(f"contacts: {contacts!r}; with C=None give the number of contacts")
        m = int(contacts)
    else:
        C = _matrix("C", C, None, n)
        m = C.shape[0]
        if m == 0:
            raise ProblemError("C: no rows; a model with friction needs at least one contact")
        g = _vector("g", g, m)
    T = _matrix("T", T, None, n)
    if T.shape[0] not in (m, 2 * m):
        raise ProblemError(f"T: {T.shape[0]} rows for {m} contacts; give 1 (2D) or 2 (3D) rows "
                           "per contact")
    held, values = _prescribed(prescribed, values, n)
    free = np.setdiff1d(np.arange(n), held)
    if free.size == 0:
        raise ProblemError("prescribed: every dof is prescribed; nothing is left to solve")
    K_ff = sp.csc_array(K[free][:, free])
    K_fp = sp.csr_array(K[free][:, held])
    C_p = None if C is None else sp.csr_array(C[:, held])
    T_p = sp.csr_array(T[:, held])
    return FrictionModel(
        n=n, contacts=m, d=T.shape[0] // m, free=free, prescribed=held, values=values,
        K=K_ff, load=f[free] - K_fp @ values,
        C=None if C is None else sp.csr_array(C[:, free]),
        gap=None if C is None else g - C_p @ values,
        T=sp.csr_array(T[:, free]), tangential_shift=T_p @ values,
        source=_Source(f, g, T, K_fp, C_p, T_p, sp.csr_array(K[held][:, held])))


def problem_friction_model(problem) -> FrictionModel:
    """The friction model of a :class:`contactqp.Problem` with friction, built once and kept
    with it; a problem made by ``with_values`` from one whose model was built shares its
    factorisation (:meth:`FrictionModel.with_loads`)."""
    kept = problem.__dict__.get("_friction_model")
    if kept is not None:
        return kept
    parent = problem.__dict__.get("_friction_parent")
    if parent is not None:
        model = parent.with_loads(f=problem.f, values=problem.prescribed_values,
                                  g=problem.g if problem.m else None)
    else:
        normal = {"C": problem.C, "g": problem.g} if problem.m else {
            "C": None, "g": None, "contacts": problem.contacts}
        model = friction_model(problem.K, problem.f, T=problem.T,
                               prescribed=problem.prescribed,
                               values=problem.prescribed_values, **normal)
    problem.__dict__["_friction_model"] = model
    return model


def _square(K) -> sp.csr_array:
    """K as a symmetric sparse square array, or a one-line refusal."""
    try:
        K = sp.csr_array(K, dtype=float)
    except (TypeError, ValueError) as error:
        raise ProblemError(f"K: not a matrix of numbers ({error})") from None
    if K.ndim != 2 or K.shape[0] != K.shape[1] or K.shape[0] == 0:
        raise ProblemError(f"K: shape {K.shape}; it must be square, n x n with n ≥ 1")
    if not np.all(np.isfinite(K.data)):
        raise ProblemError("K: has entries that are not finite")
    largest = float(np.abs(K.data).max(initial=0.0))
    asymmetry = float(np.abs((K - K.T).data).max(initial=0.0))
    if asymmetry > SYMMETRY * largest:
        raise ProblemError(f"K: not symmetric (|K − Kᵀ| up to {asymmetry:.3g} against entries "
                           f"up to {largest:.3g})")
    return K


def _matrix(name: str, matrix, rows: int | None, n: int) -> sp.csr_array:
    """A sparse array of ``n`` columns with finite entries, or a one-line refusal."""
    try:
        matrix = sp.csr_array(np.atleast_2d(matrix) if not sp.issparse(matrix) else matrix,
                              dtype=float)
    except (TypeError, ValueError) as error:
        raise ProblemError(f"{name}: not a matrix of numbers ({error})") from None
    if matrix.shape[1] != n or (rows is not None and matrix.shape[0] != rows):
        raise ProblemError(f"{name}: shape {matrix.shape}; it needs {n} columns, one per dof")
    if not np.all(np.isfinite(matrix.data)):
        raise ProblemError(f"{name}: has entries that are not finite")
    return matrix


def _vector(name: str, vector, size: int) -> np.ndarray:
    """A finite float vector of ``size`` entries (a scalar is repeated), or a refusal."""
    try:
        out = np.array(vector, dtype=float)
    except (TypeError, ValueError) as error:
        raise ProblemError(f"{name}: not numbers ({error})") from None
    if out.ndim == 0:
        out = np.full(size, float(out))
    if out.shape != (size,):
        raise ProblemError(f"{name}: shape {out.shape}; it needs {size} entries")
    if not np.all(np.isfinite(out)):
        raise ProblemError(f"{name}: has entries that are not finite")
    return out


def nonnegative(name: str, vector, size: int) -> np.ndarray:
    """A per-contact bound or coefficient: finite, at least zero."""
    out = _vector(name, vector, size)
    if out.min(initial=0.0) < 0.0:
        raise ProblemError(f"{name}: {out.min():.6g} is negative; it must be at least zero")
    return out


def _prescribed(prescribed, values, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The prescribed dofs (distinct, in range) and their values."""
    if prescribed is None:
        if values is not None:
            raise ProblemError("values: given without prescribed dofs")
        return np.zeros(0, dtype=int), np.zeros(0)
    held = np.asarray(prescribed)
    if held.ndim != 1 or (held.size and not np.issubdtype(held.dtype, np.integer)):
        raise ProblemError(f"prescribed: {held.dtype} array of shape {held.shape}; it must "
                           "list dof numbers")
    held = held.astype(int)
    if held.size and (held.min() < 0 or held.max() >= n):
        raise ProblemError(f"prescribed: dof numbers from {held.min()} to {held.max()}; they "
                           f"must lie in 0 … {n - 1}")
    if np.unique(held).size != held.size:
        raise ProblemError("prescribed: lists a dof twice")
    values = np.zeros(held.size) if values is None else _vector("values", values, held.size)
    return held, values
