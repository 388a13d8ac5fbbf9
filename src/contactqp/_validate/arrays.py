"""A user's arrays (:mod:`contactqp._validate`): each function returns the library's own
read-only copy, or raises in one line naming the field and the value."""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp._validate.scalars import (
    MAGNITUDE,
    flag,
    in_range,
    is_number,
    number,
    one_of,
    positive_number,
    positive_numbers,
    positive_values,
    shown,
    text,
    value_array,
    whole_number,
)
from contactqp.errors import ContactqpError, ProblemError

TINY = 1e-90  # a load, a gap or a coordinate may be this small (or 0): any smaller is noise,
# and below 1e-308 arithmetic loses digits (subnormal numbers: a load and gaps of 5e-324 cycled)
MAX_ENTRIES = 2 * 10**9  # stored entries of a matrix beyond which none of its factors fits
SHOWN = 60  # characters of a value a message quotes at most


def _quoted(value: Any) -> str:
    text = shown(value)
    return text if len(text) <= SHOWN else text[: SHOWN - 3] + "..."


def frozen(array: np.ndarray) -> np.ndarray:
    """``array`` made read-only (it must be the library's own copy)."""
    array.flags.writeable = False
    return array


def numbers(name: str, value: Any, error: type[ContactqpError] = ProblemError) -> np.ndarray:
    """``value`` as a new float64 array (any shape), every entry a real number (module
    docstring); finiteness and size are left to the caller."""
    if isinstance(value, (str, bytes)):
        raise error(f"{name} must be an array of numbers, got text {_quoted(value)}")
    if sp.issparse(value):
        raise error(f"{name} must be a dense array of numbers, got a sparse "
                    f"{type(value).__name__}")
    if isinstance(value, np.ma.MaskedArray) and np.ma.getmaskarray(value).any():
        # a masked entry has no value to solve with; its data underneath is not the user's
        where = np.argwhere(np.ma.getmaskarray(value))[0]
        raise error(f"{name} has masked entries ({name}[{', '.join(map(str, where))}] first): "
                    f"give every value, e.g. {name}.filled(0.0)")
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError, OverflowError) as reason:
        raise error(f"{name} must be an array of numbers; got {_quoted(value)} "
                    f"({str(reason).splitlines()[0]})") from None
    kind = raw.dtype.kind
    if kind in "iuf":
        return np.array(raw, dtype=float, copy=True)
    if kind == "c":
        raise error(f"{name} has complex values (dtype {raw.dtype}): contactqp models are "
                    f"real; pass {name}.real if the imaginary parts are round-off")
    if kind == "b":
        raise error(f"{name} has boolean values (dtype bool): give numbers")
    if kind == "O":
        flat = raw.reshape(-1)
        for i, item in enumerate(flat.tolist()):
            if not is_number(item):
                where = np.unravel_index(i, raw.shape) if raw.ndim > 1 else (i,)
                raise error(f"{name}[{', '.join(map(str, where))}] must be a number, got "
                            f"{_quoted(item)}")
        return np.array([float(item) for item in flat.tolist()], dtype=float).reshape(raw.shape)
    raise error(f"{name} must be an array of numbers, got dtype {raw.dtype} "
                f"({'text' if kind in 'US' else 'not numbers'})")


def finite_in_range(name: str, values: np.ndarray, tiny: bool,
                    error: type[ContactqpError] = ProblemError,
                    where: np.ndarray | None = None) -> None:
    """Every entry finite, and 0 or within MAGNITUDE's range (``tiny``: any small size will
    do, as for a gap or a load). ``where``: each entry's (row, column), for the message."""
    if not values.size:
        return
    size = np.abs(values)
    bad = ~np.isfinite(values) | (size > MAGNITUDE)
    smallest = TINY if tiny else 1.0 / MAGNITUDE
    bad |= (size < smallest) & (values != 0.0)
    if not bad.any():
        return
    i = int(np.flatnonzero(bad)[0])
    at = (f"[{int(where[0][i])}, {int(where[1][i])}]" if where is not None
          else f"[{i}]" if values.ndim == 1 else str(np.unravel_index(i, values.shape)))
    value = float(values.reshape(-1)[i]) if where is None else float(values[i])
    if not np.isfinite(value):
        raise error(f"{name}{at} must be finite, got {value!r} ({int(bad.sum())} such entries)")
    sizes = f"0 or {smallest:.0e} to {MAGNITUDE:.0e}"
    raise error(f"{name}{at} = {value!r} is outside the range contactqp computes in ({sizes} "
                "in size; choose other units)")


def vector(name: str, value: Any, size: int | None = None, *, tiny: bool = True,
           error: type[ContactqpError] = ProblemError) -> np.ndarray:
    """``value`` as a read-only float64 vector (of ``size`` entries where given)."""
    array = numbers(name, value, error)
    if array.ndim != 1 or (size is not None and array.size != size):
        want = f"({size},)" if size is not None else "one-dimensional"
        raise error(f"{name} must have shape {want}, got {array.shape}")
    finite_in_range(name, array, tiny, error)
    return frozen(array)


def index_vector(name: str, value: Any, n: int,
                 error: type[ContactqpError] = ProblemError) -> np.ndarray:
    """``value`` as read-only, distinct indices into 0..n−1 (integers only: a boolean mask
    is refused, since reading it as 0 and 1 would be wrong)."""
    if isinstance(value, (str, bytes)):
        raise error(f"{name} must be a list of dof indices (integers), got {_quoted(value)}")
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError):
        raise error(f"{name} must be a list of dof indices (integers), got "
                    f"{_quoted(value)}") from None
    if raw.dtype.kind == "b":
        raise error(f"{name} must be dof indices, got a boolean mask (give "
                    f"np.flatnonzero(mask))")
    if raw.ndim != 1 or (raw.size and raw.dtype.kind not in "iu"):
        raise error(f"{name} must be a list of dof indices (integers), got {_quoted(value)}")
    outside = np.flatnonzero((raw < 0) | (raw >= n)) if raw.size else raw
    if outside.size:
        raise error(f"{name} dof {int(raw[outside[0]])} is outside 0..{n - 1}")
    dofs = np.array(raw, dtype=np.intp, copy=True)
    unique, counts = np.unique(dofs, return_counts=True)
    if np.any(counts > 1):
        raise error(f"{name} dof {int(unique[counts > 1][0])} is listed twice")
    return frozen(dofs)


def _count(name: str, array: Any, what: str, error: type[ContactqpError]) -> np.ndarray:
    """A sparse matrix's index array as int64 after checking that it is one (1-D integers)."""
    raw = np.asarray(array)
    if raw.ndim != 1 or (raw.size and raw.dtype.kind not in "iu"):
        raise error(f"{name} is a malformed sparse matrix: its {what} must be a 1-D array of "
                    f"integers, got dtype {raw.dtype} and shape {raw.shape}")
    return raw.astype(np.int64, copy=False)


def compressed(name: str, indptr: Any, indices: Any, data: Any, major: int, minor: int,
               error: type[ContactqpError] = ProblemError, layout: str = "CSR"
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(major index, minor index, value) of each stored entry of a compressed sparse matrix
    (CSR: major = rows), after checking every index array in numpy: ``indptr`` of
    major + 1 entries from 0, never decreasing, up to the entries stored; every index in
    0..minor−1. Refused in one line otherwise."""
    indptr = _count(name, indptr, "indptr", error)
    indices = _count(name, indices, "indices", error)
    where = f"{name} is a malformed {layout} matrix"
    if indptr.size != major + 1:
        raise error(f"{where}: indptr has {indptr.size} entries, not {major + 1} (one more "
                    f"than its {major} {'rows' if layout == 'CSR' else 'columns'})")
    if indptr[0] != 0:
        raise error(f"{where}: indptr[0] = {int(indptr[0])}, not 0")
    drops = np.flatnonzero(np.diff(indptr) < 0)
    if drops.size:
        k = int(drops[0])
        raise error(f"{where}: indptr decreases at entry {k + 1} ({int(indptr[k])} then "
                    f"{int(indptr[k + 1])})")
    stored = int(indptr[-1])
    if stored > MAX_ENTRIES:
        raise error(f"{name} has {stored} stored entries, more than {MAX_ENTRIES} (no "
                    "factorisation of it fits in memory)")
    values = numbers(f"{name}.data", data, error).reshape(-1)
    if indices.size != values.size or indices.size < stored:
        raise error(f"{where}: indptr[-1] = {stored} but indices has {indices.size} and data "
                    f"{values.size} entries (they must have the same length, at least "
                    f"indptr[-1])")
    indices = indices[:stored]
    outside = np.flatnonzero((indices < 0) | (indices >= minor))
    if outside.size:
        k = int(outside[0])
        raise error(f"{where}: indices[{k}] = {int(indices[k])} is outside 0..{minor - 1}")
    majors = np.repeat(np.arange(major, dtype=np.int64), np.diff(indptr))
    return majors, indices, values[:stored]


def _triplets(name: str, value: Any, shape: tuple[int, int], error: type[ContactqpError]
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, columns, values) of every stored entry of a scipy sparse matrix, its index
    arrays checked before scipy converts anything."""
    layout = value.format
    n_rows, n_cols = shape
    if layout == "csr":
        return compressed(name, value.indptr, value.indices, value.data, n_rows, n_cols, error)
    if layout == "csc":
        cols, rows, data = compressed(name, value.indptr, value.indices, value.data, n_cols,
                                      n_rows, error, "CSC")
        return rows, cols, data
    if layout == "bsr":
        R, Cb = value.blocksize
        blocks = np.asarray(value.data)
        if R <= 0 or Cb <= 0 or n_rows % R or n_cols % Cb or blocks.ndim != 3:
            raise error(f"{name} is a malformed BSR matrix (blocks {R}x{Cb}, shape {shape})")
        compressed(name, value.indptr, value.indices, blocks.reshape(blocks.shape[0], -1)[:, 0]
                   if blocks.size else np.zeros(0), n_rows // R, n_cols // Cb, error, "BSR")
        if blocks.shape[1:] != (R, Cb) or blocks.shape[0] < int(np.asarray(value.indptr)[-1]):
            raise error(f"{name} is a malformed BSR matrix: data has shape {blocks.shape}")
        value = value.tocoo()  # safe now: every block index was checked
    elif layout != "coo":
        value = value.tocoo()  # dia, lil, dok: converted in numpy and Python; checked below
    coords = getattr(value, "coords", None)
    rows, cols = (coords if coords is not None and len(coords) == 2
                  else (value.row, value.col))
    rows = _count(name, rows, "row indices", error)
    cols = _count(name, cols, "column indices", error)
    data = numbers(f"{name}.data", value.data, error).reshape(-1)
    if not rows.size == cols.size == data.size:
        raise error(f"{name} is a malformed COO matrix: {rows.size} row indices, {cols.size} "
                    f"column indices and {data.size} values")
    for indices, limit, what in ((rows, n_rows, "row"), (cols, n_cols, "column")):
        outside = np.flatnonzero((indices < 0) | (indices >= limit))
        if outside.size:
            k = int(outside[0])
            raise error(f"{name} is a malformed COO matrix: {what} index {int(indices[k])} "
                        f"(entry {k}) is outside 0..{limit - 1}")
    return rows, cols, data


def _shape_of(name: str, value: Any, error: type[ContactqpError]) -> tuple[int, int]:
    try:
        shape = tuple(int(s) for s in value.shape)
    except (TypeError, ValueError, AttributeError):
        raise error(f"{name} is a malformed sparse matrix (shape {value.shape!r})") from None
    if len(shape) != 2 or min(shape) < 0:
        raise error(f"{name} must be a 2-D matrix, got shape {shape}")
    return shape  # type: ignore[return-value]


def matrix(name: str, value: Any, shape: tuple[int | None, int],
           error: type[ContactqpError] = ProblemError) -> sp.csr_array:
    """``value`` (any scipy sparse format, a dense array or nested lists) as the library's own
    CSR float64 matrix in canonical form, read-only, of ``shape`` (None: any number of rows).
    Every entry finite, and 0 or within MAGNITUDE's range."""
    if sp.issparse(value):
        got = _shape_of(name, value, error)
    else:
        dense = numbers(name, value, error)
        got = dense.shape
    if len(got) != 2 or any(want is not None and have != want for have, want in zip(got, shape)):
        want = "x".join("m" if s is None else str(s) for s in shape)
        raise error(f"{name} must be {want} (f has n = {shape[1]} entries), got shape {got}")
    if sp.issparse(value):
        rows, cols, data = _triplets(name, value, got, error)
    else:
        rows, cols = np.nonzero(dense)
        data = dense[rows, cols]
    if data.size > MAX_ENTRIES:
        raise error(f"{name} has {data.size} stored entries, more than {MAX_ENTRIES} (no "
                    "factorisation of it fits in memory)")
    finite_in_range(name, data, False, error, (rows, cols))
    with np.errstate(over="ignore", invalid="ignore"):
        canonical = sp.coo_array((data, (rows, cols)), shape=got).tocsr()
        canonical.sum_duplicates()  # sorted indices, duplicates summed (tocsr may not sort)
    coo = canonical.tocoo()
    finite_in_range(f"{name} (duplicates summed)", canonical.data, True, error,
                    (coo.row, coo.col))
    canonical.eliminate_zeros()
    for array in (canonical.data, canonical.indices, canonical.indptr):
        frozen(array)
    return canonical


def one_line(name: str, value: Any, error: type[ContactqpError] = ProblemError) -> str:
    """``value`` if it is text on one line (a line break would split every message that
    names it)."""
    if not isinstance(value, str):
        raise error(f"{name} must be text, got {_quoted(value)}")
    if any(ch in value for ch in "\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029") or any(
            ord(ch) < 32 and ch != "\t" for ch in value):
        raise error(f"{name} must be one line of text, got {_quoted(value)}")
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        raise error(f"{name} must be text UTF-8 can hold, got {value!r}") from None
    return value


__all__ = ["MAGNITUDE", "MAX_ENTRIES", "compressed", "finite_in_range", "flag", "frozen", "in_range", "index_vector", "is_number", "matrix", "number", "numbers", "one_line", "one_of", "positive_number", "positive_numbers", "positive_values", "shown", "text", "value_array", "vector", "whole_number"]
