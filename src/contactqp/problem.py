"""A user's own linear model with unilateral constraints: K, f, C, g, validated.

    minimise ½ uᵀK u − fᵀu   subject to   C u <= g (a row of kind "inequality"),
                                          C u  = g (a row of kind "equality"),
                                          u[prescribed] = prescribed_values.

K (n x n) is the stiffness, symmetric positive definite or semidefinite, f (n) the loads, C
(m x n) the contact rows and g (m) their gaps: C u <= g is non-penetration, and the contact
force λ >= 0 of a row acts on the structure as −Cᵀλ. A :class:`Problem` holds plain arrays
(K and C as CSR, the rest numpy) and checks them once, when it is made: every bad input is a
:class:`~contactqp.errors.ProblemError` of one line naming the field and the value.

A Problem owns its arrays. It copies what it is given (the caller's arrays are never
changed, not even sorted, and editing them afterwards changes nothing here) and keeps its
copies read-only. K is kept as its symmetric part ½(K + Kᵀ), the same K where the caller's is
symmetric. What is checked when it is made (:mod:`contactqp._validate` for the arrays):

- every array real and finite, each entry 0 or within 1e-30 to 1e30 in size (f, g and the
  prescribed values any size up to 1e30); sparse index arrays checked before use;
- K symmetric entry by entry: |K_ij − K_ji| <= :data:`SYMMETRY_RTOL` · √(K_ii K_jj), so that a
  soft block cannot hide an asymmetry behind a stiff one; K_ii >= 0 and K_ij² <= K_ii K_jj
  (every 2 x 2 block positive semidefinite), which refuses most indefinite K at once;
- C's rows: none zero, no constraint given twice, rows some u meets all at once
  (:mod:`contactqp.feasibility.rows`), none on prescribed dofs alone (a row may touch a
  prescribed dof: its support then carries the row's force too).

What needs a factorisation of K (a negative pivot: K indefinite; rigid modes that nothing
holds) is found when the model is built (:mod:`contactqp.model.sparse`). Files:
:mod:`contactqp.problem_files` (``.npz`` bundles and Matrix Market folders).

**Friction** (:mod:`contactqp.friction`, docs/friction.md). ``T`` (d·m x n) adds tangential
rows, d = 1 (2D) or 2 (3D) per contact, contact i owning rows d·i … d·i + d − 1; with it exactly
one of ``mu`` (Coulomb's coefficient per contact: the friction force may reach μᵢλ_N,i) or
``slip_bound`` (Tresca's bound per contact, force: it may reach sᵢ), each one value per contact
or one for all. A problem with no rows of C and a T is a contact without a normal row (a bar on
a bed, Tresca only): its contacts are then ``slip_bound``'s entries (d = rows of T / entries),
or T's rows for one value. Friction takes inequality rows only.
"""

from __future__ import annotations

import copy
import functools
import inspect
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp import _validate
from contactqp.errors import OptionError, ProblemError
from contactqp.feasibility.rows import row_conflict

KINDS = ("inequality", "equality")
SYMMETRY_RTOL = 1e-10  # |K_ij − K_ji| may be this much of √(K_ii K_jj) (round-off)
MINOR_RTOL = 1e-10  # K_ij² may exceed K_ii K_jj by this fraction (round-off of a rigid link)
MAX_DOFS = 10**8  # beyond this many unknowns (or rows) no factorisation fits in memory
SPARSE_MODEL = "_sparse_model"  # where contactqp.model.sparse keeps a Problem's model (per engine)
KEPT_MODELS = (SPARSE_MODEL, "_friction_")  # where a Problem keeps its models (names begin so)


@dataclass(frozen=True, eq=False)
class Problem:
    """A linear model with contact rows (module docstring), checked when it is made.

    Parameters
    ----------
    K : sparse or dense array, n x n
        Stiffness, symmetric positive (semi)definite (kept as ½(K + Kᵀ)).
    f : array, n
        Loads (force units).
    C : sparse or dense array, m x n
        Contact rows: C u <= g is non-penetration.
    g : array, m
        Gaps (length units): positive open, negative a press fit.
    prescribed : int array, optional
        Degrees of freedom held at ``prescribed_values`` (default 0). A contact row may touch
        one (a punch whose motion is given); its support then carries the row's force.
    prescribed_values : array, optional
        Their displacements (length units).
    kinds : sequence of str, optional
        Per row "inequality" (the default) or "equality".
    names : sequence of str, optional
        Per row, for tables (default "row[i]"); each one line of text.
    coordinates : array, n x d, optional
        Where each dof sits, for charts.
    units : str
        A label for the answer, e.g. "N, mm".
    name : str
        The problem's name, for tables.
    T : sparse or dense array, d·m x n, optional
        Tangential rows (module docstring): T(u − u_prev) is each contact's slip (length).
    mu : float or array, m, optional
        Coulomb's friction coefficient per contact (at least 0); needs T.
    slip_bound : float or array, m, optional
        Tresca's slip bound per contact (force, at least 0); needs T.

    Raises
    ------
    ProblemError
        A field that is not valid (one line naming it and the value).
    """

    K: sp.csr_array
    f: np.ndarray
    C: sp.csr_array
    g: np.ndarray
    prescribed: np.ndarray = field(default=None)  # type: ignore[assignment]
    prescribed_values: np.ndarray = field(default=None)  # type: ignore[assignment]
    kinds: tuple[str, ...] = field(default=None)  # type: ignore[assignment]
    names: tuple[str, ...] = field(default=None)  # type: ignore[assignment]
    coordinates: np.ndarray | None = None
    units: str = ""
    name: str = ""
    T: sp.csr_array | None = None
    mu: np.ndarray | None = None
    slip_bound: np.ndarray | None = None

    def __post_init__(self) -> None:
        for key, value in validated(self).items():
            object.__setattr__(self, key, value)

    @property
    def n(self) -> int:
        """Number of degrees of freedom."""
        return int(self.f.size)

    @property
    def m(self) -> int:
        """Number of contact rows."""
        return int(self.g.size)

    @property
    def friction(self) -> str | None:
        """"coulomb" (``mu`` given), "tresca" (``slip_bound``) or None (no friction)."""
        return None if self.T is None else ("coulomb" if self.mu is not None else "tresca")

    @property
    def contacts(self) -> int:
        """The contacts friction acts on: m, or slip_bound's entries for a bed (no rows of C);
        0 without friction."""
        if self.T is None:
            return 0
        return self.m or int((self.slip_bound if self.mu is None else self.mu).size)

    @property
    def d(self) -> int:
        """Tangential rows per contact: 1 (2D) or 2 (3D); 0 without friction."""
        return self.T.shape[0] // self.contacts if self.T is not None else 0

    @property
    def unit_names(self) -> tuple[str, str]:
        """(force, length) from the label ``units`` = "force, length" ("" where not given), as a
        scene's :attr:`~contactqp.scene.Scene.unit_names`."""
        parts = [p.strip() for p in self.units.split(",")]
        return (parts[0], parts[1]) if len(parts) == 2 else ("", "")

    @cached_property
    def equality(self) -> np.ndarray:
        """Per row, True where it is an equality row (read-only; worked out once, since the
        active-set loops read it every step)."""
        return _validate.frozen(np.array([kind == "equality" for kind in self.kinds],
                                         dtype=bool))

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without the models it keeps (K's factorisation is not pickled; the next
        solve builds it again)."""
        return {k: v for k, v in self.__dict__.items() if not k.startswith(KEPT_MODELS)}

    def __repr__(self) -> str:
        friction = (f", {self.friction} friction on {self.contacts} contacts ({self.d + 1}D)"
                    if self.T is not None else "")
        return (f"<Problem {self.name or 'unnamed'}: {self.n} dofs, {self.m} contact rows, "
                f"{self.prescribed.size} prescribed{friction}>")

    def with_values(self, f: Any = None, g: Any = None,
                    prescribed_values: Any = None) -> Problem:
        """This problem with other loads, gaps or prescribed values (None: its own), each
        checked as when it is made; K, C and everything else shared (they are read-only), so
        that its model can share this one's factorisation
        (:meth:`contactqp.model.sparse.SparseModel.with_values`).

        Parameters
        ----------
        f, g, prescribed_values : array, optional
            The new loads (n), gaps (m) and prescribed values (one per prescribed dof).

        Returns
        -------
        Problem
            The problem with those values.

        Raises
        ------
        ProblemError
            A value that is not valid, or gaps that leave no u (one line naming them).
        """
        problem = detached(self)  # the model of these values is its own, every engine's
        # a friction model shares its factorisation with the next values' (K, C, T are kept)
        parent = self.__dict__.get("_friction_model", self.__dict__.get("_friction_parent"))
        if parent is not None:
            problem.__dict__["_friction_parent"] = parent
        changes = {"f": None if f is None else _validate.vector("f", f, self.n),
                   "g": None if g is None else _validate.vector("g", g, self.m),
                   "prescribed_values": None if prescribed_values is None else _validate.vector(
                       "prescribed_values", prescribed_values, self.prescribed.size)}
        for key, value in changes.items():
            if value is not None:
                object.__setattr__(problem, key, value)
        if g is not None:
            conflict = row_conflict(self.C, problem.g, self.equality, self.names)
            if conflict:
                raise ProblemError(conflict)
        return problem


def detached(problem: Problem) -> Problem:
    """``problem`` without the models it keeps (every engine's, friction's): a copy that shares
    its arrays, which are read-only. A model holds its problem's detached copy, so that the two
    do not hold each other: that cycle kept each solve's factorisations (420 MB at 3.3·10⁵
    dofs) until Python's cyclic collector ran."""
    return copy.copy(problem)  # which leaves them out, as pickle does (Problem.__getstate__)


def _called(init: Any) -> Any:
    """The dataclass's __init__, with its call checked first: an unknown field or a missing one
    is a ProblemError of one line naming it, not a TypeError."""
    signature = inspect.signature(init)

    @functools.wraps(init)
    def checked(self: Problem, *args: Any, **kwargs: Any) -> None:
        try:
            signature.bind(self, *args, **kwargs)
        except TypeError as error:
            fields = ", ".join(name for name in signature.parameters if name != "self")
            raise ProblemError(f"Problem: {error} (its fields: {fields})".replace(
                "__init__() ", "")) from None
        init(self, *args, **kwargs)
    checked.__module__, checked.__qualname__ = __name__, "Problem.__init__"  # for the docs
    return checked


Problem.__init__ = _called(Problem.__init__)  # type: ignore[method-assign]


def symmetric_part(K: sp.csr_array) -> sp.csr_array:
    """½(K + Kᵀ), read-only, after checking K entry by entry (module docstring): a
    ProblemError naming the first entry that is not symmetric, a negative diagonal, or a
    2 x 2 block that is not positive semidefinite."""
    diagonal = K.diagonal()
    negative = np.flatnonzero(diagonal < 0.0)
    if negative.size:
        i = int(negative[0])
        raise ProblemError(f"K must be positive semidefinite, but K[{i}, {i}] = "
                           f"{float(diagonal[i])!r} < 0")
    root = np.sqrt(diagonal)
    difference = (K - K.T).tocoo()
    allowed = SYMMETRY_RTOL * root[difference.row] * root[difference.col]
    excess = np.abs(difference.data) / np.where(allowed > 0.0, allowed, np.nan)
    excess[allowed == 0.0] = np.inf
    if difference.nnz and np.nanmax(excess) > 1.0:
        k = int(np.nanargmax(excess))
        i, j = int(difference.row[k]), int(difference.col[k])
        raise ProblemError(
            f"K must be symmetric: K[{i}, {j}] = {float(K[i, j])!r} but K[{j}, {i}] = "
            f"{float(K[j, i])!r} (they may differ by {SYMMETRY_RTOL:.0e} of "
            f"√(K[{i}, {i}]·K[{j}, {j}]) = {float(root[i] * root[j]):.3g})")
    S = sp.csr_array((K + K.T) * 0.5)
    S.sum_duplicates()
    S.eliminate_zeros()
    coo = S.tocoo()
    off = coo.row != coo.col
    i, j, value = coo.row[off], coo.col[off], coo.data[off]
    beyond = value**2 > diagonal[i] * diagonal[j] * (1.0 + MINOR_RTOL)
    if beyond.any():
        k = int(np.flatnonzero(beyond)[0])
        a, b = int(i[k]), int(j[k])
        raise ProblemError(
            f"K must be positive semidefinite, but K[{a}, {b}]² = {float(value[k]) ** 2:.6g} "
            f"exceeds K[{a}, {a}]·K[{b}, {b}] = {float(diagonal[a] * diagonal[b]):.6g}: a u on "
            f"dofs {a} and {b} alone has negative energy")
    for array in (S.data, S.indices, S.indptr):
        _validate.frozen(array)
    return S


def _prescribed(problem: Problem, n: int, C: sp.csr_array) -> tuple[np.ndarray, np.ndarray]:
    dofs = (_validate.frozen(np.zeros(0, dtype=np.intp)) if problem.prescribed is None
            else _validate.index_vector("prescribed", problem.prescribed, n))
    values = (_validate.frozen(np.zeros(dofs.size)) if problem.prescribed_values is None
              else _validate.vector("prescribed_values", problem.prescribed_values, dofs.size))
    if dofs.size and C.shape[0]:
        held = np.zeros(n, dtype=bool)
        held[dofs] = True
        free_entries = np.bincount(C.tocoo().row[~held[C.indices]], minlength=C.shape[0])
        only = np.flatnonzero(free_entries == 0)
        if only.size:
            raise ProblemError(f"contact row {int(only[0])} touches prescribed dofs only: it "
                               "constrains no free dof (drop it, or free a dof it touches)")
    return dofs, values


def _labels(field_name: str, values: Any, m: int, default: Any) -> tuple[str, ...]:
    if values is None:
        return tuple(default(i) for i in range(m))
    if isinstance(values, str) or not hasattr(values, "__iter__"):
        values = (values,)
    values = tuple(values)
    if len(values) != m:
        raise ProblemError(f"{field_name} must be {m} strings, one per row of C; got "
                           f"{len(values)}: {values!r}"[:200])
    labels = tuple(_validate.one_line(f"{field_name}[{i}]", v) for i, v in enumerate(values))
    if field_name == "kinds":
        bad = [v for v in labels if v not in KINDS]
        if bad:
            raise ProblemError(f"kinds must be one of {', '.join(KINDS)} per row; got {bad[0]!r}")
    return tuple(str(v) for v in labels)


def validated(problem: Problem) -> dict[str, Any]:
    """The problem's fields in the form it keeps (module docstring), or a ProblemError
    naming the first bad one."""
    f = _validate.vector("f", problem.f)
    g = _validate.vector("g", problem.g)
    n = f.size
    if n > MAX_DOFS or g.size > MAX_DOFS:
        raise ProblemError(f"{n} dofs and {g.size} rows: at most {MAX_DOFS} of each fit")
    K = symmetric_part(_validate.matrix("K", problem.K, (n, n)))
    C = _validate.matrix("C", problem.C, (g.size, n))
    kinds = _labels("kinds", problem.kinds, g.size, lambda i: "inequality")
    names = _labels("names", problem.names, g.size, lambda i: f"row[{i}]")
    conflict = row_conflict(C, g, np.array([k == "equality" for k in kinds], dtype=bool), names)
    if conflict:
        raise ProblemError(conflict)
    dofs, values = _prescribed(problem, n, C)
    coordinates = problem.coordinates
    if coordinates is not None:
        coordinates = _validate.numbers("coordinates", coordinates)
        if coordinates.ndim != 2 or coordinates.shape[0] != n:
            raise ProblemError(f"coordinates must be n x d with n = {n}, got shape "
                               f"{coordinates.shape}")
        _validate.finite_in_range("coordinates", coordinates.reshape(-1), True)
        coordinates = _validate.frozen(coordinates)
    for key in ("units", "name"):
        _validate.one_line(key, getattr(problem, key))
    return {"K": K, "f": f, "C": C, "g": g, "prescribed": dofs, "prescribed_values": values,
            "kinds": kinds, "names": names, "coordinates": coordinates,
            **friction_fields(problem, n, g.size, kinds)}


FRICTION_LAWS = {"mu": "Coulomb's friction coefficient", "slip_bound": "Tresca's slip bound"}


def friction_fields(problem: Problem, n: int, m: int, kinds: tuple[str, ...]) -> dict[str, Any]:
    """T, mu and slip_bound in the form a Problem keeps them (module docstring), or a
    ProblemError naming the first bad one."""
    given = [key for key in FRICTION_LAWS if getattr(problem, key) is not None]
    if problem.T is None:
        if given:
            raise ProblemError(f"{given[0]} is given without T: friction needs the tangential "
                               "rows T (d·m x n) it acts along")
        return {"T": None, "mu": None, "slip_bound": None}
    if not given:
        raise ProblemError("T is given without mu (Coulomb) or slip_bound (Tresca): give "
                           "the friction law per contact")
    if len(given) == 2:
        raise ProblemError("mu and slip_bound are both given: a contact follows Coulomb (mu) "
                           "or Tresca (slip_bound); give one")
    key = given[0]
    if "equality" in kinds:
        raise ProblemError(f"kinds: row {kinds.index('equality')} is an equality row; friction "
                           "takes inequality contact rows only")
    T = _validate.matrix("T", problem.T, (None, n))
    law = _validate.numbers(key, getattr(problem, key))
    if law.ndim > 1:
        raise ProblemError(f"{key} must be one value per contact or one for all, got shape "
                           f"{law.shape}")
    if m == 0 and key == "mu":
        raise ProblemError("mu needs normal rows C (Coulomb's bound is μ·λ_N); a contact "
                           "without one (a bed) takes slip_bound")
    contacts = m or (law.size if law.ndim == 1 else T.shape[0])
    if contacts == 0 or T.shape[0] not in (contacts, 2 * contacts):
        raise ProblemError(f"T has {T.shape[0]} rows for {contacts} contacts: it needs d·m "
                           "rows, d = 1 (2D) or 2 (3D) per contact, contact i owning rows "
                           "d·i … d·i + d − 1")
    if law.ndim == 0:
        law = np.full(contacts, float(law))
    if law.size != contacts:
        raise ProblemError(f"{key} has {law.size} entries for {contacts} contacts: give one per "
                           "contact or one for all")
    _validate.finite_in_range(key, law, True)
    negative = np.flatnonzero(law < 0.0)
    if negative.size:
        i = int(negative[0])
        raise ProblemError(f"{key}[{i}] = {float(law[i])!r} is negative: "
                           f"{FRICTION_LAWS[key]} is at least 0 (0: no friction)")
    values = {"mu": None, "slip_bound": None, key: _validate.frozen(law)}
    return {"T": T, **values}


def frictionless(problem: Any, what: str) -> Any:
    """``problem`` where ``what`` can take it: anything but a Problem with friction or a
    scene with a frictional bed, which only :func:`contactqp.solve` and its friction methods
    solve and check (one line saying so, never a frictionless answer in its place)."""
    if isinstance(problem, Problem) and problem.T is not None:
        raise OptionError(f"{what} takes no friction: the problem has {problem.friction} "
                          f"friction (T); {FRICTION_SOLVE}")
    if getattr(problem, "beds", ()):  # a Scene (which this layer does not import)
        raise OptionError(f"{what} takes no friction: the scene has a frictional bed; "
                          f"{FRICTION_SOLVE}")
    return problem


FRICTION_SOLVE = ("solve it with contactqp.solve (methods lagrange, qp, cone, relaxed, "
                  "semismooth_newton, penalty, augmented), whose Result checks it")


__all__ = ["FRICTION_LAWS", "KINDS", "MAX_DOFS", "SPARSE_MODEL", "SYMMETRY_RTOL", "Problem",
           "detached", "friction_fields", "frictionless", "symmetric_part", "validated"]
