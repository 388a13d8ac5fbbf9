"""A :class:`~contactqp.Problem` in files: one ``.npz`` bundle, or a folder of Matrix Market
files (``K.mtx``, ``f.mtx``, ``C.mtx``, ``g.mtx``, as FE codes export them, and ``extra.npz``
for the rest). A problem with friction adds its tangential rows (``T_data``, ``T_indices``,
``T_indptr``, ``T_shape`` in a bundle; ``T.mtx`` in a folder) and ``mu`` or ``slip_bound``
(in the bundle, or the folder's ``extra.npz``).

Files are read as a hostile user may send them: every read ends in a Problem or in one
:class:`~contactqp.errors.ProblemError` line naming the file and what is wrong with it.

- ``.npz``: opened as a zip archive (anything else is refused as not a bundle); each array's
  header is read first, and refused when it holds objects (no pickle is ever loaded), when
  its shape needs more bytes than its entry in the archive holds or than this machine's
  memory, or when it is not the kind of array the key needs; sparse index arrays are checked
  (:func:`contactqp._validate.compressed`) before any matrix is made of them.
- Matrix Market: the header (banner, comments, size line) is parsed here, so that a file
  whose first line is not a Matrix Market banner, whose field is complex or pattern, or
  whose size line claims more entries than the file can hold is refused before anything is
  allocated; empty matrices (0 rows or columns) are made here, not read; a symmetric file
  that lists both triangles (which would double every off-diagonal entry) is refused; the
  body is read by scipy (:func:`scipy.io.mmread`), which checks every index.

Writing refuses an empty path and a path that is not a ``.npz`` file or a folder.
"""

from __future__ import annotations

import os
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from contactqp import _validate
from contactqp.errors import ProblemError
from contactqp.problem import MAX_DOFS, Problem

MATRIX_MARKET = ("K.mtx", "f.mtx", "C.mtx", "g.mtx")
NPZ_MATRICES = ("K_data", "K_indices", "K_indptr", "C_data", "C_indices", "C_indptr",
                "C_shape", "f", "g")
NPZ_EXTRAS = ("prescribed", "prescribed_values", "kinds", "names", "coordinates", "units",
              "name")
NPZ_FRICTION = ("T_data", "T_indices", "T_indptr", "T_shape", "mu", "slip_bound")
ENTRY_BYTES = {"array": 2, "coordinate": 6}  # the fewest bytes an entry takes in the body


def memory_bytes() -> int:
    """This machine's memory (bytes; 2⁴⁰ where the system does not say)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 2**40


def save_problem(problem: Problem, path: str | os.PathLike) -> Path:
    """Write a problem to ``path``: one ``.npz`` bundle, or (a path without that suffix) a
    folder of Matrix Market files K.mtx, f.mtx, C.mtx, g.mtx (and T.mtx with friction) plus
    ``extra.npz`` for the rest (prescribed dofs, kinds, names, coordinates, units, name, mu,
    slip_bound).

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
        ``problem`` is not a Problem, ``path`` is empty or not a path, or the file or folder
        cannot be written (one line naming it and why).
    """
    if not isinstance(problem, Problem):
        raise ProblemError(f"save_problem writes a contactqp.Problem, got "
                           f"{type(problem).__name__}")
    target = _path("save_problem", path)
    try:
        return _write(problem, target)
    except OSError as error:
        raise ProblemError(f"cannot write problem {str(path)!r}: "
                           f"{error.strerror or error}") from None


def _path(what: str, path: Any) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise ProblemError(f"{what} needs a path (text or os.PathLike), got "
                           f"{type(path).__name__}")
    text = os.fspath(path)
    if not isinstance(text, str) or not text.strip():
        raise ProblemError(f"{what} needs a file or folder name, got {text!r}")
    return Path(text)


def _write(problem: Problem, path: Path) -> Path:
    """:func:`save_problem`'s writing."""
    extra = {"prescribed": problem.prescribed, "prescribed_values": problem.prescribed_values,
             "kinds": np.array(problem.kinds, dtype=str).reshape(-1),
             "names": np.array(problem.names, dtype=str).reshape(-1),
             "units": np.array(problem.units), "name": np.array(problem.name)}
    if problem.coordinates is not None:
        extra["coordinates"] = problem.coordinates
    for key in ("mu", "slip_bound"):
        if getattr(problem, key) is not None:
            extra[key] = getattr(problem, key)
    if path.suffix == ".npz":
        K, C, T = problem.K, problem.C, problem.T
        tangential = {} if T is None else {"T_data": T.data, "T_indices": T.indices,
                                           "T_indptr": T.indptr, "T_shape": np.array(T.shape)}
        np.savez_compressed(path, K_data=K.data, K_indices=K.indices, K_indptr=K.indptr,
                            C_data=C.data, C_indices=C.indices, C_indptr=C.indptr,
                            C_shape=np.array(C.shape), f=problem.f, g=problem.g, **extra,
                            **tangential)
        return path
    if path.exists() and not path.is_dir():
        raise ProblemError(f"cannot write problem {str(path)!r}: it is a file, not a folder "
                           "(a bundle's name ends in .npz)")
    import scipy.io  # only for Matrix Market files

    path.mkdir(parents=True, exist_ok=True)
    for file, value in zip(MATRIX_MARKET, (problem.K, problem.f, problem.C, problem.g)):
        # an empty vector goes as a coordinate file: scipy 1.16's writer of an empty dense
        # array never returns (its threads wait on each other; fixed in later releases)
        dense = not sp.issparse(value) and np.size(value) > 0
        scipy.io.mmwrite(path / file, np.asarray(value).reshape(-1, 1) if dense
                         else sp.coo_matrix(value if sp.issparse(value) else (0, 1)),
                         precision=17)
    if problem.T is not None:
        scipy.io.mmwrite(path / "T.mtx", sp.coo_matrix(problem.T), precision=17)
    elif (path / "T.mtx").exists():  # a folder written before, with friction: not this one's
        (path / "T.mtx").unlink()
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
        kinds, names, coordinates, units, name, T, mu, slip_bound).

    Returns
    -------
    Problem
        The problem, validated.

    Raises
    ------
    ProblemError
        A missing, unreadable or malformed file, or a problem that is not valid (one line
        naming the file or the field, and what is wrong).
    """
    path = _path("load_problem", path)
    if not path.exists():
        raise ProblemError(f"problem file {str(path)!r} does not exist")
    try:
        arrays = _read_folder(path) if path.is_dir() else _read_npz(path)
    except OSError as error:
        raise ProblemError(f"cannot read problem {str(path)!r}: "
                           f"{error.strerror or error}") from None
    return Problem(**{**arrays, **fields})


# ---------------------------------------------------------------------------- .npz bundles

def _read_npz(path: Path) -> dict[str, Any]:
    """The problem's fields from a bundle."""
    arrays = _npz_arrays(path)
    missing = [key for key in NPZ_MATRICES if key not in arrays]
    if missing:
        raise ProblemError(f"{path.name} is not a contactqp problem bundle: it lacks "
                           f"{', '.join(missing)} (save_problem writes them)")
    n, m = _length(path, arrays, "f"), _length(path, arrays, "g")
    shape = arrays["C_shape"]
    if shape.dtype.kind not in "iu" or shape.shape != (2,) or tuple(shape.tolist()) != (m, n):
        raise ProblemError(f"{path.name}: C_shape is {shape.tolist()!r}, but g and f make C "
                           f"{m}x{n}")
    matrices = {}
    for name, rows, cols in (("K", n, n), ("C", m, n)):
        r, c, v = _validate.compressed(f"{path.name}: {name}", arrays[f"{name}_indptr"],
                                       arrays[f"{name}_indices"], arrays[f"{name}_data"],
                                       rows, cols)
        matrices[name] = sp.coo_array((v, (r, c)), shape=(rows, cols))
    return {**matrices, "f": arrays["f"], "g": arrays["g"], **_extras(path, arrays),
            **_tangential(path, arrays, n)}


def _tangential(path: Path, arrays: dict[str, np.ndarray], n: int) -> dict[str, Any]:
    """A bundle's T, checked as K and C are (its shape n columns), or nothing."""
    keys = NPZ_FRICTION[:4]
    present = [key for key in keys if key in arrays]
    if not present:
        return {}
    if len(present) < len(keys):
        missing = [key for key in keys if key not in arrays]
        raise ProblemError(f"{path.name}: has {present[0]} but lacks {', '.join(missing)} "
                           "(a problem's tangential rows T need all four)")
    shape = arrays["T_shape"]
    if shape.dtype.kind not in "iu" or shape.shape != (2,) or shape[1] != n or not (
            0 <= shape[0] <= MAX_DOFS):
        raise ProblemError(f"{path.name}: T_shape is {shape.tolist()!r}, but f makes T "
                           f"(rows) x {n}")
    rows = int(shape[0])
    r, c, v = _validate.compressed(f"{path.name}: T", arrays["T_indptr"], arrays["T_indices"],
                                   arrays["T_data"], rows, n)
    return {"T": sp.coo_array((v, (r, c)), shape=(rows, n))}


def _length(path: Path, arrays: dict[str, np.ndarray], key: str) -> int:
    value = arrays[key]
    if value.ndim != 1:
        raise ProblemError(f"{path.name}: {key} must be one-dimensional, got shape "
                           f"{value.shape}")
    return int(value.size)


def _npz_arrays(path: Path) -> dict[str, np.ndarray]:
    """Every array of a bundle, each checked before it is read (module docstring)."""
    try:
        archive = zipfile.ZipFile(path)
    except zipfile.BadZipFile:
        raise ProblemError(f"cannot read problem {str(path)!r}: it is not an .npz bundle "
                           "(not a zip archive)") from None
    arrays: dict[str, np.ndarray] = {}
    with archive:
        for info in archive.infolist():
            key = info.filename[:-4] if info.filename.endswith(".npy") else None
            if key not in NPZ_MATRICES + NPZ_EXTRAS + NPZ_FRICTION:
                continue  # not one of a problem's arrays: never read
            arrays[key] = _member(path, archive, info, key)
    return arrays


def _member(path: Path, archive: zipfile.ZipFile, info: zipfile.ZipInfo, key: str
            ) -> np.ndarray:
    """One array of a bundle: its header read and checked first (module docstring)."""
    where = f"{path.name}: {key}"
    try:
        with archive.open(info) as stream:
            version = np.lib.format.read_magic(stream)
            reader = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                      else np.lib.format.read_array_header_2_0)
            shape, fortran, dtype = reader(stream)
            if dtype.hasobject:
                raise ProblemError(f"{where} holds Python objects (dtype {dtype}); a problem "
                                   "bundle holds numbers and text only (no pickles are read)")
            if dtype.kind not in "iufUb" or dtype.fields is not None:
                raise ProblemError(f"{where} has dtype {dtype}, not numbers or text")
            count = int(np.prod(shape, dtype=np.int64)) if shape else 1
            needed = count * dtype.itemsize
            if needed > memory_bytes():
                raise ProblemError(f"{where} claims shape {shape} ({needed / 2**30:.3g} GiB), "
                                   f"more than this machine's memory")
            if needed > info.file_size:
                raise ProblemError(f"{where} claims shape {shape} ({needed} bytes) but its "
                                   f"entry holds {info.file_size} bytes (truncated or forged)")
            data = stream.read(needed)
            if len(data) != needed:
                raise ProblemError(f"{where} is truncated: {len(data)} of {needed} bytes")
    except ProblemError:
        raise
    except (ValueError, SyntaxError, EOFError, zipfile.BadZipFile, zipfile.LargeZipFile, OSError,
            NotImplementedError, RuntimeError, zlib.error) as error:
        raise ProblemError(f"{where} cannot be read: {_reason(error)}") from None
    array = np.frombuffer(data, dtype=dtype, count=count)
    return array.reshape(shape, order="F" if fortran else "C").copy()


def _reason(error: BaseException) -> str:
    """One line of why an array could not be read, without Python's internals (numpy's header
    parser names AST nodes by their address)."""
    text = str(error).splitlines()[0] if str(error) else type(error).__name__
    if " object at 0x" in text or "malformed node" in text:
        return "its header is not a numpy array header"
    return text


def _extras(path: Path, data: dict[str, np.ndarray]) -> dict[str, Any]:
    """The fields beside K, f, C, g, in the form Problem takes (text as text)."""
    out: dict[str, Any] = {}
    for key in ("prescribed", "prescribed_values", "coordinates", "mu", "slip_bound"):
        if key in data:
            out[key] = data[key]
    for key in ("kinds", "names"):
        if key in data:
            out[key] = tuple(str(v) for v in _text(path, key, data[key]).reshape(-1))
    for key in ("units", "name"):
        if key in data:
            value = _text(path, key, data[key])
            if value.shape != ():
                raise ProblemError(f"{path.name}: {key} must be one text, got shape "
                                   f"{value.shape}")
            out[key] = str(value)
    return out


def _text(path: Path, key: str, value: np.ndarray) -> np.ndarray:
    if value.dtype.kind != "U":
        raise ProblemError(f"{path.name}: {key} must be text, got dtype {value.dtype}")
    return value


# ------------------------------------------------------------------ Matrix Market folders

def _read_folder(path: Path) -> dict[str, Any]:
    missing = [file for file in MATRIX_MARKET if not (path / file).is_file()]
    if missing:
        raise ProblemError(f"problem folder {str(path)!r} lacks {', '.join(missing)} (it needs "
                           f"{', '.join(MATRIX_MARKET)})")
    K, f, C, g = (_read_matrix_market(path / file) for file in MATRIX_MARKET)
    f, g = _column(path / "f.mtx", f), _column(path / "g.mtx", g)
    _sizes_agree(K.shape, f.size, C.shape, g.size)
    arrays = {"K": K, "f": f, "C": C, "g": g}
    if (path / "T.mtx").is_file():
        T = _read_matrix_market(path / "T.mtx")
        if T.shape[1] != K.shape[0]:
            raise ProblemError(f"T.mtx has {T.shape[1]} columns but K.mtx is "
                               f"{K.shape[0]}x{K.shape[1]}")
        arrays["T"] = T
    extra = path / "extra.npz"
    if extra.exists():
        arrays.update(_extras(extra, _npz_arrays(extra)))
    return arrays


def _sizes_agree(K: tuple[int, ...], n: int, C: tuple[int, ...], m: int) -> None:
    """A ProblemError naming the two files whose sizes disagree: K.mtx n x n, f.mtx n
    entries, C.mtx m x n, g.mtx m entries."""
    if K[0] != K[1]:
        raise ProblemError(f"K.mtx is {K[0]}x{K[1]}: a stiffness is square")
    if n != K[0]:
        raise ProblemError(f"f.mtx has {n} entries but K.mtx is {K[0]}x{K[1]}")
    if C[1] != K[0]:
        raise ProblemError(f"C.mtx has {C[1]} columns but K.mtx is {K[0]}x{K[1]}")
    if m != C[0]:
        raise ProblemError(f"g.mtx has {m} entries but C.mtx has {C[0]} rows")


def _column(path: Path, value: Any) -> np.ndarray:
    """A vector file (n x 1 or 1 x n, array or coordinate format) as a 1-D array."""
    shape = value.shape
    if len(shape) != 2 or min(shape) > 1 and shape[0] * shape[1] != 0:
        raise ProblemError(f"{path.name} must hold one column (n x 1), got {shape[0]}x{shape[1]}")
    dense = value.toarray() if sp.issparse(value) else np.asarray(value)
    return dense.reshape(-1)


def matrix_market_header(path: Path) -> tuple[str, str, str, tuple[int, ...], int]:
    """(format, field, symmetry, size, body start) of a Matrix Market file: its banner
    ``%%MatrixMarket matrix <format> <field> <symmetry>``, comments, then the size line
    (rows cols [entries]). A ProblemError naming the file where it is not one."""
    with open(path, "rb") as stream:
        banner = stream.readline(4096)
        words = banner.decode("latin-1").split()
        if len(words) != 5 or words[0].lower() != "%%matrixmarket" or (
                words[1].lower() != "matrix"):
            begins = banner[:40].decode("latin-1", "replace").strip()
            raise ProblemError(f"{path.name} is not a Matrix Market file: its first line must "
                               f"be '%%MatrixMarket matrix <format> <field> <symmetry>', it is "
                               f"{begins!r}")
        layout, kind, symmetry = (w.lower() for w in words[2:])
        line = banner
        while True:
            line = stream.readline(4096)
            if not line:
                raise ProblemError(f"{path.name} has no size line after its banner")
            if line.strip() and not line.lstrip().startswith(b"%"):
                break
        start = stream.tell()
    try:
        size = tuple(int(word) for word in line.split())
    except ValueError:
        raise ProblemError(f"{path.name}: its size line must be whole numbers, got "
                           f"{line[:60].decode('latin-1', 'replace').strip()!r}") from None
    expected = {"coordinate": 3, "array": 2}.get(layout)
    if expected is None:
        raise ProblemError(f"{path.name}: format {layout!r} is neither coordinate nor array")
    if len(size) != expected or min(size) < 0:
        raise ProblemError(f"{path.name}: a {layout} file's size line holds {expected} "
                           f"numbers >= 0, got {line[:60].decode('latin-1').strip()!r}")
    return layout, kind, symmetry, size, start


def _read_matrix_market(path: Path) -> Any:
    """One Matrix Market file, checked (module docstring): a sparse matrix or a 2-D array."""
    layout, kind, symmetry, size, start = matrix_market_header(path)
    name = path.name
    if kind not in ("real", "integer", "double"):
        why = ("complex values: contactqp models are real" if kind == "complex" else
               "no values (pattern)" if kind == "pattern" else f"field {kind!r}")
        raise ProblemError(f"{name} holds {why}")
    if symmetry not in ("general", "symmetric"):
        raise ProblemError(f"{name} is {symmetry}: contactqp reads general and symmetric files")
    rows, cols = size[0], size[1]
    if rows > MAX_DOFS or cols > MAX_DOFS:
        raise ProblemError(f"{name} claims {rows}x{cols}: at most {MAX_DOFS} rows and columns "
                           "fit")
    entries = (size[2] if layout == "coordinate" else rows * (rows + 1) // 2
               if symmetry == "symmetric" else rows * cols)  # array: one triangle if symmetric
    body = path.stat().st_size - start
    if entries * ENTRY_BYTES[layout] > body:
        raise ProblemError(f"{name} claims {entries} entries but holds {body} bytes after its "
                           "header (truncated or forged)")
    if rows == 0 or cols == 0 or entries == 0:  # made here: scipy's reader fails on them
        return sp.coo_array((rows, cols)) if layout == "coordinate" else np.zeros((rows, cols))
    import scipy.io  # only for Matrix Market files

    try:
        value = scipy.io.mmread(path)
    except (ValueError, OverflowError, MemoryError) as error:
        raise ProblemError(f"{name} cannot be read: {str(error).splitlines()[0]}") from None
    if symmetry == "symmetric" and sp.issparse(value):
        coo = sp.coo_array(value)
        off = coo.row != coo.col
        key = coo.row[off].astype(np.int64) * cols + coo.col[off]
        if np.unique(key).size != key.size:
            raise ProblemError(f"{name} is declared symmetric but lists entries on both sides "
                               "of the diagonal (a symmetric file lists one triangle; the "
                               "other is implied)")
    return value


__all__ = ["MATRIX_MARKET", "load_problem", "matrix_market_header", "memory_bytes",
           "save_problem"]
