"""Rank updates of a set's CHOLMOD factor: a set of rows held that differs from a factored one
by k rows costs k rank-one updates of the factor (CHOLMOD's ``cholmod_updown``), not a new
numeric factorisation.

cvxopt exposes CHOLMOD's analysis, numeric factorisation and solves (one column at a time),
not its Modify module. Its wheels ship the whole CHOLMOD library, and this module calls the
library cvxopt has loaded through ctypes (its wheels' copy beside it, else the one CHOLMOD
the process has loaded), with its own quiet ``cholmod_common`` and the interpreter lock held
through each call (``ctypes.PyDLL``: one Common, one thread at a time). A set's numeric
factor is taken over from cvxopt's (:meth:`Modified.taken_from`: ``cholmod_l_change_factor``
to a simplicial LDLᵀ in place, as updates need one; cvxopt's factor gets a copy of the
analysis back, made by ``cholmod_l_copy_factor`` before any numeric factorisation), then
moved by ``cholmod_l_updown`` with the rows that enter (update) and leave (downdate) as the
columns of a sparse matrix permuted as the factor is, and solved by ``cholmod_l_solve``.

Measured on the Hertz cylinder of the scaling benchmark (3.3·10⁵ dofs, CHOLMOD 3.0.6 of
cvxopt 1.3's wheel): a numeric factorisation 0.40 s; the change in place 0.11 s once; an
update 1 ms a row (3D sphere, 9·10⁴ dofs: 8 ms a row against 2.9 s); a solve with the
simplicial factor 0.067 s against the supernodal one's 0.048 s. A downdate of a row held by
R loses about log₁₀(R/K) digits of that dof's pivot (cancellation); the set solves refine
on the system's own residuals (:mod:`contactqp.model.augmented`), which keep the answer
exact while the factor is within a few digits.

:func:`library` is None wherever any of this is not found or not as expected (another
CHOLMOD build, 32-bit indices, a platform without the library file): the sets are then
factorised each (:mod:`contactqp.model.augmented`), as before.
"""

from __future__ import annotations

import ctypes
import os
import time
import weakref
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
import scipy.sparse as sp

COMMON_BYTES = 1 << 16  # room for cholmod_common (about 2.6 kB in CHOLMOD 3, more in 5)
CHOLMOD_REAL = 1
CHOLMOD_A = 0  # cholmod_solve's system: A x = b
VERSIONS = (3, 4, 5)  # CHOLMOD major versions whose structs this module writes


class _Dense(ctypes.Structure):
    _fields_ = [("nrow", ctypes.c_size_t), ("ncol", ctypes.c_size_t),
                ("nzmax", ctypes.c_size_t), ("d", ctypes.c_size_t), ("x", ctypes.c_void_p),
                ("z", ctypes.c_void_p), ("xtype", ctypes.c_int), ("dtype", ctypes.c_int)]


class _Sparse(ctypes.Structure):
    _fields_ = [("nrow", ctypes.c_size_t), ("ncol", ctypes.c_size_t),
                ("nzmax", ctypes.c_size_t), ("p", ctypes.c_void_p), ("i", ctypes.c_void_p),
                ("nz", ctypes.c_void_p), ("x", ctypes.c_void_p), ("z", ctypes.c_void_p),
                ("stype", ctypes.c_int), ("itype", ctypes.c_int), ("xtype", ctypes.c_int),
                ("dtype", ctypes.c_int), ("sorted", ctypes.c_int), ("packed", ctypes.c_int)]


_POINTER = ctypes.c_void_p
SIGNATURES = {  # CHOLMOD's long-integer functions this module calls: (result, arguments)
    "start": (ctypes.c_int, [_POINTER]),
    "updown": (ctypes.c_int, [ctypes.c_int, _POINTER, _POINTER, _POINTER]),
    "copy_factor": (_POINTER, [_POINTER, _POINTER]),
    "change_factor": (ctypes.c_int, [ctypes.c_int] * 5 + [_POINTER, _POINTER]),
    "solve": (ctypes.POINTER(_Dense), [ctypes.c_int, _POINTER, _POINTER, _POINTER]),
    "free_factor": (ctypes.c_int, [_POINTER, _POINTER]),
    "free_dense": (ctypes.c_int, [_POINTER, _POINTER]),
}


@dataclass(frozen=True, eq=False)
class Library:
    """CHOLMOD's long-integer functions this module calls (their signatures set once), and
    its Common."""

    dll: Any
    common: Any

    def function(self, name: str) -> Any:
        return getattr(self.dll, f"cholmod_l_{name}")


def _loaded_cholmod() -> list[str]:
    """Paths of the CHOLMOD library cvxopt uses: its wheels' vendored copy beside it (Linux's
    cvxopt.libs, macOS's .dylibs), else the one CHOLMOD this process has loaded (Linux's
    memory map; none where several are, as another package's may be another build)."""
    try:
        import cvxopt
    except ImportError:
        return []
    root = os.path.dirname(cvxopt.__file__)
    vendored = []
    for folder in (os.path.join(root, os.pardir, "cvxopt.libs"), os.path.join(root, ".dylibs")):
        if os.path.isdir(folder):
            vendored += sorted(os.path.join(folder, name) for name in os.listdir(folder)
                               if name.startswith("libcholmod"))
    if vendored:
        return vendored
    loaded = set()
    try:
        with open("/proc/self/maps") as maps:
            for line in maps:
                fields = line.split()
                if len(fields) >= 6 and os.path.basename(fields[-1]).startswith("libcholmod"):
                    loaded.add(os.path.realpath(fields[-1]))
    except OSError:
        return []
    return sorted(loaded) if len(loaded) == 1 else []


@lru_cache(maxsize=1)
def library() -> Library | None:
    """The CHOLMOD library cvxopt uses, ready to call, or None (module docstring)."""
    try:
        import cvxopt.cholmod  # noqa: F401 - loads the library this module looks for
    except ImportError:
        return None
    if ctypes.sizeof(ctypes.c_void_p) != 8:
        return None
    for path in _loaded_cholmod():
        try:
            dll = ctypes.PyDLL(path)  # holds the GIL through each call: one Common, threads
            version = (ctypes.c_int * 3)()
            dll.cholmod_l_version.argtypes = [ctypes.c_void_p]
            dll.cholmod_l_version(version)
            if version[0] not in VERSIONS:
                continue
            for name, (result, arguments) in SIGNATURES.items():
                call = getattr(dll, f"cholmod_l_{name}")
                call.restype, call.argtypes = result, arguments
        except (OSError, AttributeError):
            continue
        common = ctypes.create_string_buffer(COMMON_BYTES)
        found = Library(dll, common)
        if not found.function("start")(common):
            continue
        if not _quiet(common):
            continue
        return found
    return None


def factor_address(symbolic: Any) -> int | None:
    """The address of the cholmod_factor inside cvxopt's factor (a capsule named "CHOLMOD
    FACTOR ..."), or None."""
    capsule = ctypes.py_object(symbolic)
    name_of = ctypes.pythonapi.PyCapsule_GetName
    name_of.restype, name_of.argtypes = ctypes.c_char_p, [ctypes.py_object]
    pointer_of = ctypes.pythonapi.PyCapsule_GetPointer
    pointer_of.restype = ctypes.c_void_p
    pointer_of.argtypes = [ctypes.py_object, ctypes.c_char_p]
    name = name_of(capsule.value)
    if not (name or b"").startswith(b"CHOLMOD FACTOR"):
        return None
    return pointer_of(capsule.value, name) or None


def _quiet(common: Any) -> bool:
    """Set the Common's print level to 0 (CHOLMOD prints its warnings and errors from C
    otherwise, and the library prints nothing unless asked), where the Common's first fields
    read as cholmod_start leaves them (maxrank 8, supernodal CHOLMOD_AUTO, print 3, precise
    FALSE): their layout, the same in CHOLMOD 3 to 5, is then the one assumed. False
    otherwise (no updates: nothing is written into a layout not known)."""
    maxrank = ctypes.c_size_t.from_buffer(common, COMMON_MAXRANK).value
    supernodal = ctypes.c_int.from_buffer(common, COMMON_SUPERNODAL).value
    level = ctypes.c_int.from_buffer(common, COMMON_PRINT)
    precise = ctypes.c_int.from_buffer(common, COMMON_PRINT + 4).value
    if (maxrank, supernodal, level.value, precise) != (8, 1, 3, 0):
        return False
    level.value = 0
    return True


COMMON_MAXRANK, COMMON_SUPERNODAL, COMMON_PRINT = 32, 48, 144  # byte offsets in cholmod_common


def _factor_pointer(symbolic: Any) -> int | None:
    """:func:`factor_address` where the factor has 64-bit indices (itype 2, the functions
    this module calls), else None."""
    address = factor_address(symbolic)
    if not address or ctypes.c_int.from_address(address + 22 * 8 + 4 * 4).value != 2:
        return None
    return address


@dataclass(eq=False)
class Modified:
    """A simplicial LDLᵀ factor of a set's matrix that rank updates move from set to set:
    ``holds`` the key of the set whose matrix it factors, ``rows`` and ``rho`` that set's
    rows and weights. ``row_seconds``, ``column_seconds``: an update's time a row and a
    solve's a column, measured."""

    address: int
    n: int
    perm_inverse: np.ndarray = field(repr=False)
    holds: Any = None
    rows: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.intp))
    rho: np.ndarray = field(default_factory=lambda: np.zeros(0))
    row_seconds: float | None = None
    column_seconds: float | None = None  # a column of the last solve, timed

    @classmethod
    def taken_from(cls, symbolic: Any, n: int, spare: int) -> Modified | None:
        """The numeric factor in cvxopt's ``symbolic``, changed in place to a simplicial LDLᵀ
        and taken over; cvxopt's factor gets a copy of ``spare`` (the analysis, kept
        symbolic: :func:`spare_analysis`) in its place, so its next numeric factorisation
        is supernodal again with no new analysis. None where the library, the factor or the
        change is not as this module expects (cvxopt's factor then holds the analysis alone,
        or is left as it was)."""
        found = library()
        address = None if found is None else _factor_pointer(symbolic)
        if address is None:
            return None
        fresh = _copy(spare)
        if not fresh:
            return None
        if not found.function("change_factor")(CHOLMOD_REAL, 0, 0, 1, 1, address,
                                                found.common):
            release(fresh)
            return None
        set_pointer = ctypes.pythonapi.PyCapsule_SetPointer
        set_pointer.restype = ctypes.c_int
        set_pointer.argtypes = [ctypes.py_object, ctypes.c_void_p]
        set_pointer(symbolic, fresh)  # cvxopt frees it with the capsule
        made = cls(address, n, np.zeros(0, dtype=np.int64))
        weakref.finalize(made, release, address)
        perm = ctypes.c_void_p.from_address(address + 2 * 8).value
        if not perm or ctypes.c_size_t.from_address(address).value != n:
            return None
        order = np.ctypeslib.as_array(ctypes.cast(perm, ctypes.POINTER(ctypes.c_int64)),
                                      shape=(n,))
        inverse = np.empty(n, dtype=np.int64)
        inverse[order] = np.arange(n)
        made.perm_inverse = inverse
        return made

    def update(self, C_rows: sp.csr_array, weight: np.ndarray, add: bool) -> bool:
        """M ± C_rowsᵀ diag(weight) C_rows (weight > 0): whether CHOLMOD did it."""
        if not C_rows.shape[0]:
            return True
        start = time.perf_counter()
        columns = sp.csc_array(sp.csr_array(C_rows).T)
        columns.sum_duplicates()
        scaled = np.repeat(np.sqrt(weight), np.diff(columns.indptr)) * columns.data
        permuted = sp.csc_array((scaled, self.perm_inverse[columns.indices], columns.indptr),
                                shape=columns.shape)
        permuted.sort_indices()
        pointers = permuted.indptr.astype(np.int64)
        indices = permuted.indices.astype(np.int64)
        values = np.ascontiguousarray(permuted.data, dtype=float)
        matrix = _Sparse(self.n, permuted.shape[1], values.size, pointers.ctypes.data,
                         indices.ctypes.data, None, values.ctypes.data, None, 0, 2,
                         CHOLMOD_REAL, 0, 1, 1)
        found = library()
        done = found.function("updown")(int(add), ctypes.addressof(matrix), self.address,
                                        found.common)
        self.row_seconds = (time.perf_counter() - start) / C_rows.shape[0]
        return bool(done)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """The held matrix's inverse times ``rhs`` (one column or several, one call)."""
        start = time.perf_counter()
        rhs = np.asarray(rhs, dtype=float)
        block = np.asfortranarray(rhs.reshape(self.n, -1))
        found = library()
        dense = _Dense(self.n, block.shape[1], block.size, self.n, block.ctypes.data, None,
                       CHOLMOD_REAL, 0)
        answer = found.function("solve")(CHOLMOD_A, self.address, ctypes.addressof(dense),
                                         found.common)
        if not answer:
            from contactqp.errors import SolverError

            raise SolverError("CHOLMOD's solve with the updated factor failed")
        x = np.ctypeslib.as_array(ctypes.cast(answer.contents.x, ctypes.POINTER(ctypes.c_double)),
                                  shape=(block.shape[1], self.n)).T.copy()
        found.function("free_dense")(ctypes.byref(answer), found.common)
        self.column_seconds = (time.perf_counter() - start) / block.shape[1]
        return x.reshape(rhs.shape)


def spare_analysis(symbolic: Any) -> int | None:
    """A copy of the analysis in cvxopt's ``symbolic`` (before any numeric factorisation:
    the ordering and the supernodes, no values; :func:`release` frees it); None where the
    library or the factor is not as expected."""
    address = _factor_pointer(symbolic) if library() is not None else None
    return _copy(address) if address else None


def _copy(address: int) -> int | None:
    found = library()
    return found.function("copy_factor")(address, found.common) or None


def release(address: int) -> None:
    """Free a factor this module made (a copy of the analysis, a factor taken over)."""
    found = library()
    if found is not None:
        found.function("free_factor")(ctypes.byref(ctypes.c_void_p(address)), found.common)


__all__ = ["Modified", "factor_address", "library", "release", "spare_analysis"]
