"""A user's own linear model with unilateral constraints: K, f, C, g, validated.

    minimise ½ uᵀK u − fᵀu   subject to   C u <= g (a row of kind "inequality"),
                                          C u  = g (a row of kind "equality"),
                                          u[prescribed] = prescribed_values.

K (n x n) is the stiffness, symmetric positive definite or semidefinite, f (n) the loads, C
(m x n) the contact rows and g (m) their gaps: C u <= g is non-penetration, and the contact
force λ >= 0 of a row acts on the structure as −Cᵀλ. A :class:`Problem` holds plain arrays
(K and C as CSR, the rest numpy) and checks them once, when it is made: every bad input is a
:class:`~contactqp.errors.ProblemError` of one line naming the field and the value. What
needs a factorisation of K (rigid modes that nothing holds) is found when the model is built
(:mod:`contactqp.model.sparse`).

Files: :func:`save_problem` and :func:`load_problem` for one ``.npz`` bundle, or a folder of
Matrix Market files (``K.mtx``, ``f.mtx``, ``C.mtx``, ``g.mtx``, as FE codes export them).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp.errors import ProblemError
from contactqp.problem_feasibility import row_conflict

KINDS = ("inequality", "equality")
SYMMETRY_RTOL = 1e-10  # K may differ from Kᵀ by this much of its largest entry (round-off)
MAX_DOFS = 10**8  # beyond this many unknowns (or rows) no factorisation fits in memory
MAX_ENTRIES = 2 * 10**9  # ... nor this many stored entries of K or C
MATRIX_MARKET = ("K.mtx", "f.mtx", "C.mtx", "g.mtx")


@dataclass(frozen=True, eq=False)
class Problem:
    """A linear model with contact rows (module docstring), checked when it is made.

    Parameters
    ----------
    K : sparse or dense array, n x n
        Stiffness, symmetric (to :data:`SYMMETRY_RTOL`) positive (semi)definite.
    f : array, n
        Loads (force units).
    C : sparse or dense array, m x n
        Contact rows: C u <= g is non-penetration.
    g : array, m
        Gaps (length units): positive open, negative a press fit.
    prescribed : int array, optional
        Degrees of freedom held at ``prescribed_values`` (default 0); no contact row may
        touch one.
    prescribed_values : array, optional
        Their displacements (length units).
    kinds : sequence of str, optional
        Per row "inequality" (the default) or "equality".
    names : sequence of str, optional
        Per row, for tables (default "row[i]").
    coordinates : array, n x d, optional
        Where each dof sits, for charts.
    units : str
        A label for the answer, e.g. "N, mm".
    name : str
        The problem's name, for tables.
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

    @cached_property
    def equality(self) -> np.ndarray:
        """Per row, True where it is an equality row (read-only; worked out once, since the
        active-set loops read it every step)."""
        rows = np.array([kind == "equality" for kind in self.kinds], dtype=bool)
        rows.flags.writeable = False
        return rows

    def __repr__(self) -> str:
        return (f"<Problem {self.name or 'unnamed'}: {self.n} dofs, {self.m} contact rows, "
                f"{self.prescribed.size} prescribed>")


def _dense_vector(field_name: str, value: Any, size: int | None) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise ProblemError(f"{field_name} must be an array of numbers; got {error}") from None
    if array.ndim != 1 or (size is not None and array.size != size):
        want = f"({size},)" if size is not None else "one-dimensional"
        raise ProblemError(f"{field_name} must have shape {want}, got {array.shape}")
    _finite(field_name, array)
    return array


def _finite(field_name: str, values: np.ndarray, rows: np.ndarray | None = None) -> None:
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        where = bad[0] if rows is None else rows[bad[0]]
        raise ProblemError(f"{field_name} must be finite, got {float(values[bad[0]])!r} at entry "
                           f"{where} ({bad.size} such entries)")


def _sparse(field_name: str, value: Any, shape: tuple[int | None, int]) -> sp.csr_array:
    """A matrix as CSR float64 with its duplicates summed, checked for shape and values."""
    try:
        matrix = sp.csr_array(value, dtype=float)
    except MemoryError:
        raise ProblemError(f"{field_name} is too large to hold in memory") from None
    except (TypeError, ValueError) as error:
        raise ProblemError(f"{field_name} must be a matrix of numbers; got {error}") from None
    if matrix.ndim != 2 or any(want is not None and got != want
                               for got, want in zip(matrix.shape, shape)):
        want = "x".join("m" if s is None else str(s) for s in shape)
        raise ProblemError(f"{field_name} must be {want} (f has n = {shape[1]} entries), got "
                           f"shape {matrix.shape}")
    if matrix.nnz > MAX_ENTRIES:
        raise ProblemError(f"{field_name} has {matrix.nnz} stored entries, more than "
                           f"{MAX_ENTRIES} (no factorisation of it fits in memory)")
    matrix.sum_duplicates()
    _finite(field_name, matrix.data)
    matrix.eliminate_zeros()
    return matrix


def _symmetric(K: sp.csr_array) -> None:
    """K symmetric to SYMMETRY_RTOL of its largest entry, and no negative diagonal."""
    largest = float(np.abs(K.data).max(initial=0.0))
    difference = abs(K - K.T)
    worst = float(difference.max()) if difference.nnz else 0.0
    if worst > SYMMETRY_RTOL * largest:
        i, j = (int(a[0]) for a in np.nonzero(difference == worst))
        raise ProblemError(f"K must be symmetric: K[{i}, {j}] = {float(K[i, j])!r} but K[{j}, {i}] = "
                           f"{float(K[j, i])!r} (differ by {worst:.3g}, more than {SYMMETRY_RTOL:.0e} "
                           f"of the largest entry {largest:.3g})")
    diagonal = K.diagonal()
    negative = np.flatnonzero(diagonal < 0.0)
    if negative.size:
        i = int(negative[0])
        raise ProblemError(f"K must be positive semidefinite, but K[{i}, {i}] = "
                           f"{float(diagonal[i])!r} < 0")


def _prescribed(problem: Problem, n: int, C: sp.csr_array) -> tuple[np.ndarray, np.ndarray]:
    dofs = np.zeros(0, dtype=np.intp) if problem.prescribed is None else np.asarray(
        problem.prescribed)
    if dofs.ndim != 1 or (dofs.size and not np.issubdtype(dofs.dtype, np.integer)):
        raise ProblemError(f"prescribed must be a list of dof indices (integers), got "
                           f"{problem.prescribed!r}"[:200])
    dofs = dofs.astype(np.intp)
    outside = dofs[(dofs < 0) | (dofs >= n)]
    if outside.size:
        raise ProblemError(f"prescribed dof {outside[0]} is outside 0..{n - 1}")
    unique, counts = np.unique(dofs, return_counts=True)
    if np.any(counts > 1):
        raise ProblemError(f"prescribed dof {unique[counts > 1][0]} is listed twice")
    values = (np.zeros(dofs.size) if problem.prescribed_values is None
              else _dense_vector("prescribed_values", problem.prescribed_values, dofs.size))
    touched = C[:, dofs].tocoo() if dofs.size else None
    if touched is not None and touched.nnz:
        row, dof = int(touched.row[0]), int(dofs[touched.col[0]])
        raise ProblemError(f"prescribed dof {dof} is inside contact row {row}: a contact row "
                           "may only involve free dofs (move its part into g)")
    return dofs, values


def _labels(field_name: str, values: Any, m: int, default: Any) -> tuple[str, ...]:
    if values is None:
        return tuple(default(i) for i in range(m))
    values = tuple(values) if not isinstance(values, str) else (values,)
    if len(values) != m or not all(isinstance(v, str) for v in values):
        raise ProblemError(f"{field_name} must be {m} strings, one per row of C; got "
                           f"{values!r}"[:200])
    if field_name == "kinds":
        bad = [v for v in values if v not in KINDS]
        if bad:
            raise ProblemError(f"kinds must be one of {', '.join(KINDS)} per row; got {bad[0]!r}")
    return values


def validated(problem: Problem) -> dict[str, Any]:
    """The problem's fields in the form it keeps, or a ProblemError naming the first bad one."""
    f = _dense_vector("f", problem.f, None)
    n = f.size
    g = _dense_vector("g", problem.g, None)
    if n > MAX_DOFS or g.size > MAX_DOFS:
        raise ProblemError(f"{n} dofs and {g.size} rows: at most {MAX_DOFS} of each fit")
    K = _sparse("K", problem.K, (n, n))
    _symmetric(K)
    C = _sparse("C", problem.C, (g.size, n))
    kinds = _labels("kinds", problem.kinds, g.size, lambda i: "inequality")
    names = _labels("names", problem.names, g.size, lambda i: f"row[{i}]")
    conflict = row_conflict(C, g, np.array([k == "equality" for k in kinds], dtype=bool), names)
    if conflict:
        raise ProblemError(conflict)
    dofs, values = _prescribed(problem, n, C)
    coordinates = problem.coordinates
    if coordinates is not None:
        coordinates = np.asarray(coordinates, dtype=float)
        if coordinates.ndim != 2 or coordinates.shape[0] != n:
            raise ProblemError(f"coordinates must be n x d with n = {n}, got shape "
                               f"{coordinates.shape}")
        _finite("coordinates", coordinates.reshape(-1))
    for key in ("units", "name"):
        if not isinstance(getattr(problem, key), str):
            raise ProblemError(f"{key} must be text, got {getattr(problem, key)!r}")
    return {"K": K, "f": f, "C": C, "g": g, "prescribed": dofs, "prescribed_values": values,
            "kinds": kinds, "names": names, "coordinates": coordinates}


def save_problem(problem: Problem, path: str | os.PathLike) -> Path:
    """Write a problem to ``path``: one ``.npz`` bundle, or (a path without that suffix) a
    folder of Matrix Market files K.mtx, f.mtx, C.mtx, g.mtx plus ``extra.npz`` for the
    rest (prescribed dofs, kinds, names, coordinates, units, name).

    Parameters
    ----------
    problem : Problem
        The problem to write.
    path : str or os.PathLike
        ``something.npz``, or a folder (made if missing).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ProblemError
        The file or folder cannot be written (one line naming it and why).
    """
    try:
        return _write(problem, Path(path))
    except OSError as error:
        raise ProblemError(f"cannot write problem {str(path)!r}: {error}") from None


def _write(problem: Problem, path: Path) -> Path:
    """:func:`save_problem`'s writing."""
    extra = {"prescribed": problem.prescribed, "prescribed_values": problem.prescribed_values,
             "kinds": np.array(problem.kinds, dtype=str), "names": np.array(problem.names, dtype=str),
             "units": np.array(problem.units), "name": np.array(problem.name)}
    if problem.coordinates is not None:
        extra["coordinates"] = problem.coordinates
    if path.suffix == ".npz":
        K, C = problem.K, problem.C
        np.savez_compressed(path, K_data=K.data, K_indices=K.indices, K_indptr=K.indptr,
                            C_data=C.data, C_indices=C.indices, C_indptr=C.indptr,
                            C_shape=np.array(C.shape), f=problem.f, g=problem.g, **extra)
        return path
    import scipy.io  # only for Matrix Market files

    path.mkdir(parents=True, exist_ok=True)
    for file, value in zip(MATRIX_MARKET, (problem.K, problem.f, problem.C, problem.g)):
        scipy.io.mmwrite(path / file, sp.coo_matrix(value) if sp.issparse(value)
                         else np.asarray(value).reshape(-1, 1), precision=17)
    np.savez_compressed(path / "extra.npz", **extra)
    return path


def load_problem(path: str | os.PathLike, **fields: Any) -> Problem:
    """Read a problem written by :func:`save_problem`: an ``.npz`` bundle, or a folder with
    K.mtx, f.mtx, C.mtx and g.mtx (Matrix Market, as FE codes export them; ``extra.npz``
    beside them optional).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.npz`` file or the folder.
    **fields
        Given to :class:`Problem` over what the files say (prescribed, prescribed_values,
        kinds, names, coordinates, units, name).

    Returns
    -------
    Problem
        The problem, validated.

    Raises
    ------
    ProblemError
        A missing or unreadable file, or a problem that is not valid (one line naming the
        field and the value).
    """
    path = Path(path)
    if not path.exists():
        raise ProblemError(f"problem file {str(path)!r} does not exist")
    try:
        if path.is_dir():
            arrays = _read_folder(path)
        else:
            with np.load(path, allow_pickle=False) as data:
                arrays = _from_npz(dict(data))
    except ProblemError:
        raise
    except (OSError, ValueError, KeyError) as error:
        raise ProblemError(f"cannot read problem {str(path)!r}: {error}") from None
    return Problem(**{**arrays, **fields})


def _extras(data: dict[str, np.ndarray]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key in ("prescribed", "prescribed_values", "coordinates"):
        if key in data:
            out[key] = data[key]
    for key in ("kinds", "names"):
        if key in data:
            out[key] = tuple(str(v) for v in data[key])
    for key in ("units", "name"):
        if key in data:
            out[key] = str(data[key])
    return out


def _from_npz(data: dict[str, np.ndarray]) -> dict[str, Any]:
    n, shape = data["f"].size, tuple(int(s) for s in data["C_shape"])
    K = sp.csr_array((data["K_data"], data["K_indices"], data["K_indptr"]), shape=(n, n))
    C = sp.csr_array((data["C_data"], data["C_indices"], data["C_indptr"]), shape=shape)
    return {"K": K, "f": data["f"], "C": C, "g": data["g"], **_extras(data)}


def _read_folder(path: Path) -> dict[str, Any]:
    missing = [file for file in MATRIX_MARKET if not (path / file).exists()]
    if missing:
        raise ProblemError(f"problem folder {str(path)!r} lacks {', '.join(missing)} (it needs "
                           f"{', '.join(MATRIX_MARKET)})")
    import scipy.io  # only for Matrix Market files

    K, f, C, g = (scipy.io.mmread(path / file) for file in MATRIX_MARKET)
    arrays = {"K": K, "f": np.asarray(f).reshape(-1), "C": C, "g": np.asarray(g).reshape(-1)}
    extra = path / "extra.npz"
    if extra.exists():
        with np.load(extra, allow_pickle=False) as data:
            arrays.update(_extras(dict(data)))
    return arrays


__all__ = ["KINDS", "MAX_DOFS", "SYMMETRY_RTOL", "Problem", "load_problem", "save_problem"]
