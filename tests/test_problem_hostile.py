"""Hostile input to a user's own model: contactqp.Problem, its files, the command line, the
methods' options and contactqp.fem (issue 37's audit, each reproducer a test).

Every case ends in a right answer or one line naming the field and the value: never a
traceback, a crash of the interpreter, a silent wrong answer or a changed input. Cases that
crashed the interpreter before run in a fresh one (a crash would take pytest with it). The
expected answers come from :func:`closed_forms.exact_problem_answer` (exact rational
arithmetic over every set of rows in contact), never from the library.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp

import contactqp
from closed_forms import exact_problem_answer
from contactqp.errors import ContactqpError, OptionError, ProblemError, SolverError

# a chain of three unit springs from the ground, its tip against a wall 0.5 away
K3 = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
F3 = np.array([0.0, 0.0, 1.0])
C3 = np.array([[0.0, 0.0, 1.0]])
G3 = np.array([0.5])
METHODS = ("lagrange", "penalty", "augmented", "qp", "lemke", "pgs", "semismooth_newton")


def one_line(error: BaseException, *words: str) -> str:
    text = str(error)
    assert "\n" not in text, text
    for word in words:
        assert word in text, (word, text)
    return text


def isolated(code: str, cwd: Path) -> list[str]:
    """Run ``code`` in a fresh interpreter (a crash fails this test, not the run); its lines
    of standard output. It must exit 0."""
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=cwd, check=False,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    return done.stdout.splitlines()


# ----------------------------------------------------------- malformed sparse structure

CORRUPTIONS = {  # name -> (array, index, value): what the audit wrote into a valid CSR
    "indices out of range": ("indices", 3, 10**6),
    "negative index": ("indices", 0, -1),
    "indptr past the entries": ("indptr", 2, 100),
    "indptr decreasing": ("indptr", 2, 0),
}
MESSAGES = {"indices out of range": "indices[3] = 1000000 is outside 0..2",
            "negative index": "indices[0] = -1 is outside 0..2",
            "indptr past the entries": "indptr decreases",
            "indptr decreasing": "indptr decreases"}


def test_malformed_csr_given_directly_or_in_a_bundle_is_one_line(tmp_path):
    """The audit's crashes: a CSR whose index arrays point out of range crashed the
    interpreter in Problem(...), in load_problem and in `contactqp solve p.npz`."""
    code = f"""
        import json, subprocess, sys
        import numpy as np, scipy.sparse as sp
        import contactqp
        K = sp.csr_array(np.array({K3.tolist()}))
        out = {{}}
        for name, (array, index, value) in {CORRUPTIONS!r}.items():
            for field in ("K", "C"):
                bad = sp.csr_array(K) if field == "K" else sp.csr_array(
                    np.array([[0, 1.0, 0], [0, 0, 1.0], [1.0, 0, 0], [0, 0, 2.0]]))
                arrays = {{"data": bad.data.copy(), "indices": bad.indices.copy(),
                          "indptr": bad.indptr.copy()}}
                arrays[array][index] = value
                bad.data, bad.indices, bad.indptr = (arrays["data"], arrays["indices"],
                                                     arrays["indptr"])
                args = {{"K": K, "f": [0, 0, 1.0], "C": [[0, 0, 1.0]], "g": [0.5]}}
                if field == "C":
                    args["C"], args["g"] = bad, [9.0, 8.0, 7.0, 6.0]
                else:
                    args["K"] = bad
                try:
                    contactqp.Problem(**args)
                    out[name + " " + field] = "accepted"
                except contactqp.ProblemError as error:
                    out[name + " " + field] = str(error)
                # the same arrays in a bundle, under the keys save_problem writes
                good = contactqp.Problem(K, [0, 0, 1.0], [[0, 0, 1.0]], [0.5])
                saved = dict(K_data=good.K.data, K_indices=good.K.indices,
                             K_indptr=good.K.indptr, C_data=good.C.data,
                             C_indices=good.C.indices, C_indptr=good.C.indptr,
                             C_shape=np.array(good.C.shape), f=good.f, g=good.g)
                if field == "K":
                    saved.update(K_data=arrays["data"], K_indices=arrays["indices"],
                                 K_indptr=arrays["indptr"])
                if field == "C":
                    continue  # the bundles below corrupt K
                np.savez("bad.npz", **saved)
                try:
                    contactqp.load_problem("bad.npz")
                    out[name + " " + field + " npz"] = "accepted"
                except contactqp.ProblemError as error:
                    out[name + " " + field + " npz"] = str(error)
                cli = subprocess.run([sys.executable, "-m", "contactqp", "solve", "bad.npz"],
                                     capture_output=True, text=True)
                out[name + " " + field + " cli"] = f"{{cli.returncode}} {{cli.stderr.strip()}}"
        print(json.dumps(out))
    """
    seen = json.loads(isolated(code, tmp_path)[-1])
    for name, message in MESSAGES.items():
        assert message in seen[f"{name} K"] and "K is a malformed CSR" in seen[f"{name} K"]
        assert "C is a malformed CSR" in seen[f"{name} C"]
        assert message in seen[f"{name} K npz"] and "bad.npz: K" in seen[f"{name} K npz"]
        status, text = seen[f"{name} K cli"].split(" ", 1)
        assert status == "2" and message in text and "\n" not in text  # bad input, not a bug
    for text in seen.values():
        assert "accepted" not in text and "\n" not in text


@pytest.mark.parametrize("layout", ["csc", "coo", "bsr"])
def test_other_sparse_formats_are_checked_before_use(layout):
    matrix = getattr(sp, f"{layout}_array")(K3)
    if layout == "coo":
        matrix.coords = (matrix.coords[0].copy(), matrix.coords[1].copy())
        matrix.coords[1][0] = 7
        expected = "column index 7"
    else:
        matrix.indices = matrix.indices.copy()
        matrix.indices[0] = 50
        expected = "is outside"
    with pytest.raises(ProblemError) as raised:
        contactqp.Problem(matrix, F3, C3, G3)
    one_line(raised.value, "K is a malformed", expected)


def test_the_callers_arrays_are_never_changed_and_later_edits_change_nothing():
    """Problem() sorted the caller's CSR in place and summed its duplicates; a Problem kept
    the caller's f, g, prescribed values and K.data, so editing them afterwards changed it
    (and slipped a non-symmetric K past validation)."""
    K = sp.csr_array((np.array([-1.0, 1.0, 1.0, -1.0, 2.0, -1.0, -1.0, 1.0]),
                      np.array([1, 0, 0, 0, 1, 2, 1, 2]),  # row 0 unsorted, a duplicate
                      np.array([0, 3, 6, 8])), shape=(3, 3))
    assert np.array_equal(K.toarray(), K3)
    C = sp.csr_array(C3)
    f, g, values = F3.copy(), G3.copy(), np.array([0.0])
    arrays = [K.data, K.indices, K.indptr, C.data, C.indices, C.indptr, f, g, values]
    before = [a.copy() for a in arrays]
    problem = contactqp.Problem(K, f, C, g, prescribed=[0], prescribed_values=values)
    for a, b in zip(arrays, before):
        assert a.dtype == b.dtype and np.array_equal(a, b)
    answer = contactqp.solve(problem)
    K.data[:] = 99.0
    C.data[:] = 5.0
    f[:], g[:], values[:] = 7.0, -3.0, 0.25
    again = contactqp.solve(problem)
    assert np.array_equal(answer.u, again.u) and answer.verified and again.verified
    for array in (problem.K.data, problem.f, problem.g, problem.prescribed_values):
        with pytest.raises(ValueError):
            array[0] = 1.0  # read-only: the Problem's own copies


def test_read_only_input_is_accepted():
    K = sp.csr_array(K3)
    for array in (K.data, K.indices, K.indptr):
        array.flags.writeable = False
    f = F3.copy()
    f.flags.writeable = False
    result = contactqp.solve(contactqp.Problem(K, f, C3, G3))
    u, _ = exact_problem_answer(K3, F3, C3, G3)
    assert result.verified and np.allclose(result.u, u, atol=1e-14)


# ------------------------------------------------------------- types and magnitudes

@pytest.mark.parametrize(("field", "value", "words"), [
    ("f", np.array([0, 0, 1 + 0j]), ("f has complex values",)),
    ("K", K3.astype(complex), ("K has complex values",)),
    ("K", sp.csr_array(K3.astype(complex)), ("K.data has complex values",)),
    ("C", np.array([[0, 0, 1j]]), ("C has complex values",)),
    ("g", np.array([0.5 + 0j]), ("g has complex values",)),
    ("f", np.array([0, None, 1.0], dtype=object), ("f[1] must be a number, got None",)),
    ("K", np.array([[2, -1, 0], [-1, None, -1], [0, -1, 1]], dtype=object),
     ("K[1, 1] must be a number, got None",)),
    ("f", np.array(["0", "0", "1"]), ("f must be an array of numbers", "text")),
    ("f", "loads", ("f must be an array of numbers",)),
    ("g", np.array([True]), ("g has boolean values",)),
    ("f", [0, 0, float("nan")], ("f[2] must be finite, got nan",)),
    ("K", np.where(K3 == 2.0, np.inf, K3), ("K[0, 0] must be finite, got inf",)),
    ("f", [0, 0, 1e308], ("f[2] = 1e+308 is outside the range",)),
    ("C", [[0, 0, 1e-200]], ("C[0, 2] = 1e-200 is outside the range",)),
    ("C", [[0, 0, 1e200]], ("C[0, 2] = 1e+200 is outside the range",)),
    ("K", K3 * 1e155, ("is outside the range",)),
    ("prescribed", [True, False, False], ("a boolean mask", "np.flatnonzero")),
    ("prescribed", [0.0], ("prescribed must be a list of dof indices",)),
    ("names", ["tip\nwall"], ("names[0] must be one line of text",)),
    ("name", "two\nlines", ("name must be one line of text",)),
    ("coordinates", np.array([[0.0], [1.0], [np.nan]]), ("coordinates[2] must be finite",)),
])
def test_values_that_are_not_real_finite_numbers_in_range_are_one_line(field, value, words):
    args = {"K": K3, "f": F3, "C": C3, "g": G3, field: value}
    with pytest.raises(ProblemError) as raised:
        contactqp.Problem(**args)
    one_line(raised.value, *words)


def test_integers_and_single_precision_are_converted_exactly():
    problem = contactqp.Problem(K3.astype(np.int64), F3.astype(np.float32),
                                C3.astype(np.int8), G3.astype(np.float32))
    assert problem.K.dtype == problem.f.dtype == np.float64
    assert np.array_equal(problem.K.toarray(), K3) and problem.g[0] == 0.5


# ----------------------------------------------------------------- K's definiteness

@pytest.mark.parametrize(("K", "words"), [
    ([[1.0, 2.0], [2.0, 1.0]], ("positive semidefinite", "K[0, 1]² = 4")),
    ([[0.0, 1.0], [1.0, 0.0]], ("positive semidefinite",)),
    # springs 1, −0.4, 1, 1 from the ground: every 2 x 2 block passes, K does not
    ([[0.6, 0.4, 0.0, 0.0], [0.4, 0.6, -1.0, 0.0], [0.0, -1.0, 2.0, -1.0],
      [0.0, 0.0, -1.0, 1.0]], ("positive semidefinite", "negative")),
])
def test_an_indefinite_K_is_refused_with_its_evidence_by_every_method(K, words):
    """The audit's worst silent wrong answer: an indefinite K (an energy unbounded below) was
    verified by lagrange, penalty, lemke and the command line."""
    K = np.asarray(K)
    n = K.shape[0]
    assert np.linalg.eigvalsh(K).min() < 0.0
    f, C = np.eye(n)[0], np.eye(1, n, n - 1)
    for method in METHODS:
        with pytest.raises(ProblemError) as raised:
            contactqp.solve(contactqp.Problem(K, f, C, [0.5]), method)
        one_line(raised.value, *words)


def test_a_soft_block_cannot_hide_an_asymmetry_behind_a_stiff_one():
    """5 % asymmetry in a soft block beside a stiff one passed a test relative to the largest
    entry, and the answer was verified 1.2e-2·U off."""
    K = np.array([[1e6, -1e6, 0, 0], [-1e6, 2e6, 0, 0], [0, 0, 2.0, -1.0], [0, 0, -1.05, 1.0]])
    with pytest.raises(ProblemError) as raised:
        contactqp.Problem(K, [0, 0, 0, 1.0], [[0, 0, 0, 1.0]], [0.5])
    one_line(raised.value, "K must be symmetric", "K[2, 3]", "K[3, 2]")


@pytest.mark.parametrize("method", ["lagrange", "qp"])
def test_a_singular_K_that_contact_holds_is_solved(method):
    """Problem([[0.]], [1.], [[1.]], [1.]) raised "Factor is exactly singular"; its answer is
    u = 1, λ = 1."""
    result = contactqp.solve(contactqp.Problem([[0.0]], [1.0], [[1.0]], [1.0]), method)
    assert result.verified, result.message
    assert result.u[0] == pytest.approx(1.0, abs=1e-9)
    assert result.contact_force[0] == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("method", ["penalty", "augmented"])
def test_the_penalty_methods_hold_a_K_held_by_contact_alone_as_lagrange_does(method):
    """A free spring pushed by 1 onto a row u₀ <= 0.5: the row takes the whole load (λ = 1)
    and the spring moves rigidly to it, u = (0.5, 0.5) by hand; the sparse penalty and
    augmented Lagrangian once refused it as singular (each set is now pinned so that it holds
    the free mode, as Lagrange's is)."""
    result = contactqp.solve(contactqp.Problem([[1.0, -1.0], [-1.0, 1.0]], [1.0, 0.0],
                                               [[1.0, 0.0]], [0.5]), method)
    assert result.verified, result.message
    np.testing.assert_allclose(result.u, [0.5, 0.5], atol=1e-5 * result.displacement_scale)
    assert result.contact_force[0] == pytest.approx(1.0, abs=1e-5 * result.force_scale)


@pytest.mark.parametrize("method", ["lemke", "pgs", "semismooth_newton"])
def test_methods_that_need_K_inverse_refuse_a_K_held_by_contact_alone_in_one_line(method):
    with pytest.raises(SolverError) as raised:
        contactqp.solve(contactqp.Problem([[1.0, -1.0], [-1.0, 1.0]], [1.0, 0.0],
                                          [[1.0, 0.0]], [0.5]), method)
    one_line(raised.value, "singular")


def test_a_singular_K_nothing_holds_is_one_line_naming_the_mode():
    K = sp.block_diag((K3, np.array([[1.0, -1.0], [-1.0, 1.0]]))).tocsr()
    with pytest.raises(ProblemError) as raised:
        contactqp.solve(contactqp.Problem(K, np.zeros(5), np.eye(1, 5, 2), [0.5]))
    one_line(raised.value, "nothing holds the model", "dof 3", "dof 4")


@pytest.mark.parametrize("contrast", [1e10, 1e12, 1e14])
def test_stiffness_contrasts_that_are_positive_definite_are_solved(contrast):
    """A positive definite K with a stiffness contrast of 1e12 was refused as "nothing holds
    the model along a mode": the test for a zero pivot was relative to the stiffest entry. A
    stiff spring from the ground, a soft one on it, a stiff block beside a soft one."""
    c = contrast
    K = np.array([[c + 1.0, -1.0, 0, 0], [-1.0, 1.0, 0, 0], [0, 0, c, -c], [0, 0, -c, 2 * c]])
    K = sp.block_diag((K, [[1.0 / c]])).toarray()
    f = np.array([0.0, 1.0, 0.0, c, 1.0 / c])
    C = np.array([[0, 1.0, 0, 0, 0], [0, 0, 0, 0, 1.0]])
    g = np.array([0.5, 2.0])
    u, lam = exact_problem_answer(K, f, C, g)
    result = contactqp.solve(contactqp.Problem(K, f, C, g))
    assert result.verified, result.message
    assert np.allclose(result.u, u, rtol=1e-9, atol=1e-12)
    assert np.allclose(result.contact_force, lam, rtol=1e-9, atol=1e-12)


# ------------------------------------------------------- right answers that were flagged

@pytest.mark.parametrize("method", METHODS)
def test_a_row_with_a_looser_parallel_copy_is_solved_by_every_method(method):
    """c·u <= 0.5 and 2c·u <= 1.5: lagrange and semismooth Newton ended 0.125 past the wall
    (both rows held: W_AA singular, its least-norm solution meets neither)."""
    C, g = np.array([[0, 0, 1.0], [0, 0, 2.0]]), np.array([0.5, 1.5])
    u, lam = exact_problem_answer(K3, F3, C, g)
    result = contactqp.solve(contactqp.Problem(K3, F3, C, g), method)
    assert result.verified, result.message
    assert np.abs(result.u - u).max() <= 1e-5 * result.displacement_scale
    assert np.abs(result.contact_force - lam).max() <= 1e-5 * result.force_scale


# ------------------------------------------------------------------------- files

def _problem() -> contactqp.Problem:
    return contactqp.Problem(K3, F3, C3, G3, prescribed=[0], names=["tip"])


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _npz_with(tmp_path: Path, **changes) -> Path:
    problem = _problem()
    arrays = {"K_data": problem.K.data, "K_indices": problem.K.indices,
              "K_indptr": problem.K.indptr, "C_data": problem.C.data,
              "C_indices": problem.C.indices, "C_indptr": problem.C.indptr,
              "C_shape": np.array(problem.C.shape), "f": problem.f, "g": problem.g}
    arrays.update(changes)
    arrays = {k: v for k, v in arrays.items() if v is not None}
    np.savez(tmp_path / "p.npz", **arrays)
    return tmp_path / "p.npz"


def _forged_header(tmp_path: Path) -> Path:
    """A bundle whose f claims 10¹¹ entries (800 GB) in a few bytes."""
    path = _npz_with(tmp_path)
    header = np.lib.format.header_data_from_array_1_0(np.zeros(3))
    header["shape"] = (10**11,)
    with zipfile.ZipFile(path, "a") as archive, archive.open("f.npy", "w",
                                                             force_zip64=True) as stream:
        np.lib.format.write_array_header_1_0(stream, header)
        stream.write(np.zeros(3).tobytes())
    return path


NPZ_CASES = [
    ("empty", lambda p: _write(p / "p.npz", b""), "not an .npz bundle"),
    ("text", lambda p: _write(p / "p.npz", b"K = [[1]]\n"), "not an .npz bundle"),
    ("npy renamed", lambda p: (np.save(p / "x.npy", np.ones(3)), (p / "x.npy").rename(
        p / "p.npz"))[1] and p / "p.npz", "not an .npz bundle"),
    ("truncated", lambda p: _write(p / "p.npz", _npz_with(p).read_bytes()[:300]),
     "not an .npz bundle"),
    ("corrupt", lambda p: _write(p / "p.npz", _npz_with(p).read_bytes()[:200] + b"\0" * 50
                                 + _npz_with(p).read_bytes()[250:]), "p.npz"),
    ("pickled", lambda p: _npz_with(p, f=np.array([0, None, 1.0], dtype=object)),
     "holds Python objects"),
    ("missing key", lambda p: _npz_with(p, K_data=None), "lacks K_data"),
    ("wrong C_shape", lambda p: _npz_with(p, C_shape=np.array([5, 5])), "C_shape"),
    ("800 GB", _forged_header, "claims shape (100000000000,)"),
    ("text where numbers", lambda p: _npz_with(p, g=np.array(["0.5"])), "g"),
]


@pytest.mark.filterwarnings("ignore:Duplicate name")  # the forged header's second f.npy
@pytest.mark.parametrize(("name", "make", "words"), NPZ_CASES, ids=[c[0] for c in NPZ_CASES])
def test_a_bad_bundle_is_one_line_naming_the_file(tmp_path, name, make, words):
    path = make(tmp_path)
    with pytest.raises(ProblemError) as raised:
        contactqp.load_problem(path)
    one_line(raised.value, words)
    assert "pickle" not in str(raised.value).lower() or name == "pickled"


def _folder(tmp_path: Path, **texts: str) -> Path:
    problem = _problem()
    scipy.io.mmwrite(tmp_path / "K.mtx", sp.coo_matrix(problem.K))
    scipy.io.mmwrite(tmp_path / "C.mtx", sp.coo_matrix(problem.C))
    scipy.io.mmwrite(tmp_path / "f.mtx", problem.f.reshape(-1, 1))
    scipy.io.mmwrite(tmp_path / "g.mtx", problem.g.reshape(-1, 1))
    for name, text in texts.items():
        (tmp_path / f"{name}.mtx").write_text(text)
    return tmp_path


BANNER = "%%MatrixMarket matrix coordinate real"
MTX_CASES = [
    ("not matrix market", {"K": "1 2 3\n"}, ("K.mtx is not a Matrix Market file",)),
    ("complex", {"K": "%%MatrixMarket matrix coordinate complex general\n3 3 1\n1 1 1 0\n"},
     ("K.mtx holds complex values",)),
    ("pattern", {"C": "%%MatrixMarket matrix coordinate pattern general\n1 3 1\n1 3\n"},
     ("C.mtx holds no values",)),
    ("both triangles", {"K": f"{BANNER} symmetric\n3 3 6\n1 1 2\n2 1 -1\n1 2 -1\n2 2 2\n"
                        "3 2 -1\n3 3 1\n"}, ("K.mtx is declared symmetric", "both sides")),
    ("forged size", {"K": f"{BANNER} general\n3 3 100000000000\n1 1 2\n"},
     ("K.mtx claims 100000000000 entries",)),
    ("truncated", {"K": f"{BANNER} general\n3 3 7\n1 1 2\n"}, ("K.mtx claims 7 entries",)),
    ("index out of range", {"K": f"{BANNER} general\n3 3 1\n9 9 2\n"}, ("K.mtx cannot be read",)),
    ("no size line", {"g": "%%MatrixMarket matrix array real general\n% only a comment\n"},
     ("g.mtx has no size line",)),
    ("too many rows", {"f": "%%MatrixMarket matrix array real general\n4 1\n0\n0\n1\n2\n"},
     ("f.mtx has 4 entries but K.mtx is 3x3",)),
]


@pytest.mark.parametrize(("name", "texts", "words"), MTX_CASES, ids=[c[0] for c in MTX_CASES])
def test_a_bad_matrix_market_file_is_one_line_naming_the_file(tmp_path, name, texts, words):
    with pytest.raises(ProblemError) as raised:
        contactqp.load_problem(_folder(tmp_path, **texts))
    one_line(raised.value, *words)


def test_vectors_in_coordinate_format_are_read(tmp_path):
    """Valid coordinate-format f.mtx and g.mtx were refused."""
    folder = _folder(tmp_path, f="%%MatrixMarket matrix coordinate real general\n3 1 1\n3 1 1\n",
                     g="%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 0.5\n")
    problem = contactqp.load_problem(folder, prescribed=[0])
    assert problem.f.tolist() == [0.0, 0.0, 1.0] and problem.g.tolist() == [0.5]


@pytest.mark.skipif(os.geteuid() == 0 if hasattr(os, "geteuid") else True,
                    reason="root reads a file whatever its mode")
def test_an_unreadable_file_is_one_line(tmp_path):
    folder = _folder(tmp_path)
    (folder / "K.mtx").chmod(0)
    with pytest.raises(ProblemError) as raised:
        contactqp.load_problem(folder)
    one_line(raised.value, "K.mtx")


@pytest.mark.parametrize("n, m", [(0, 0), (1, 0), (3, 1)])
@pytest.mark.parametrize("name", ["p.npz", "folder"])
def test_every_valid_problem_makes_the_round_trip(tmp_path, n, m, name):
    """The round trip of a problem with no rows through a folder crashed the interpreter
    (SIGFPE in the Matrix Market reader), as did n = 0."""
    K = K3[:n, :n] if n < 3 else K3
    C = np.eye(m, n, n - 1) if m else np.zeros((0, n))
    problem = contactqp.Problem(K, np.ones(n), C, np.full(m, 0.5))
    back = contactqp.load_problem(contactqp.save_problem(problem, tmp_path / name))
    assert (back.n, back.m) == (n, m)
    assert np.array_equal(back.K.toarray(), problem.K.toarray())
    assert np.array_equal(back.f, problem.f) and np.array_equal(back.g, problem.g)
    result = contactqp.solve(back)
    assert result.verified and result.u.shape == (n,)


@pytest.mark.parametrize(("call", "words"), [
    (lambda: contactqp.save_problem(_problem(), ""), ("needs a file or folder name",)),
    (lambda: contactqp.save_problem("hello", "x.npz"), ("writes a contactqp.Problem", "str")),
    (lambda: contactqp.load_problem(None), ("load_problem needs a path", "NoneType")),
    (lambda: contactqp.save_problem(_problem(), "/proc/no/such/place.npz"),
     ("cannot write problem",)),
])
def test_bad_paths_and_objects_are_one_line(call, words):
    with pytest.raises(ProblemError) as raised:
        call()
    one_line(raised.value, *words)


def test_saving_to_an_empty_path_writes_nothing_here(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ProblemError):
        contactqp.save_problem(_problem(), "")
    assert list(tmp_path.iterdir()) == []


# -------------------------------------------------------------------- runs that end

@pytest.mark.parametrize(("method", "options", "words"), [
    ("pgs", {"tolerance": 1e-30, "max_iterations": 10**9}, ("at most 1000000",)),
    ("semismooth_newton", {"max_iterations": 10**9}, ("at most 10000",)),
    ("augmented", {"max_iterations": 10**9}, ("at most 10000",)),
    ("lemke", {"max_iterations": 10**9}, ("at most 1000000",)),
    ("lagrange", {"max_iterations": 10**9}, ("at most 10000",)),
    ("pgs", {"max_iterations": -1}, ("max_iterations must be a whole number >= 1",)),
    ("pgs", {"tolerance": float("nan")}, ("tolerance",)),
    ("semismooth_newton", {"tolerance": "small"}, ("tolerance",)),
])
def test_requests_that_would_run_unbounded_are_refused(method, options, words):
    with pytest.raises(OptionError) as raised:
        contactqp.solve(_problem(), method, **options)
    one_line(raised.value, *words)


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"fine": 0}, ("cylinder_on_flat: fine must be > 0",)),
    ({"fine": -1}, ("cylinder_on_flat: fine must be > 0",)),
    ({"fine": 1e-7}, ("more than the 2e+06",)),
    ({"growth": 0}, ("growth must be > 0",)),
    ({"poisson": 0.5}, ("poisson must be in [0, 0.5)",)),
    ({"young": "210e3"}, ("young must be a number",)),
    ({"radius": 0}, ("radius must be > 0",)),
    ({"zone": -1.0}, ("zone must be > 0",)),
    ({"units": "N\nmm"}, ("units must be one line",)),
])
def test_fem_builders_check_their_arguments_before_meshing(kwargs, words):
    pytest.importorskip("skfem")
    from contactqp.fem import cylinder_on_flat

    with pytest.raises(ProblemError) as raised:
        cylinder_on_flat(**kwargs)
    one_line(raised.value, *words)


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"elements": 0}, ("elements must be a whole number >= 1",)),
    ({"elements": 8.5}, ("elements must be a whole number >= 1",)),
    ({"elements": 10**5}, ("more than the 2e+06",)),
    ({"poisson": 0.5}, ("poisson",)),
    ({"waves": 0}, ("waves",)),
])
def test_the_block_checks_its_arguments(kwargs, words):
    pytest.importorskip("skfem")
    from contactqp.fem import block_on_wavy_foundation

    with pytest.raises(ProblemError) as raised:
        block_on_wavy_foundation(**kwargs)
    one_line(raised.value, *words)


# ------------------------------------------------------------------ command line

def test_json_with_verbose_is_json_alone(tmp_path):
    """--verbose --json printed the solver's banner into the JSON."""
    path = contactqp.save_problem(_problem(), tmp_path / "p.npz")
    done = subprocess.run([sys.executable, "-m", "contactqp", "solve", str(path), "--method",
                           "qp", "--backend", "osqp", "--verbose", "--json"],
                          check=False, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["verified"] is True
    assert "OSQP" in done.stderr  # the banner went where progress goes


def test_no_solver_prints_anything_unless_asked(capfd):
    for backend in ("clarabel", "osqp", "cvxpy"):
        contactqp.solve(_problem(), "qp", backend=backend)
    contactqp.solve(_problem(), "pgs")
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_errors_are_contactqp_errors():
    assert issubclass(ProblemError, ContactqpError)


# --------------------------------------------------- what the audit found after the first fix

def test_an_unknown_or_missing_field_is_one_line():
    with pytest.raises(ProblemError) as raised:
        contactqp.Problem(K3, F3, C3, G3, stiffness=3.0)
    one_line(raised.value, "unexpected keyword argument 'stiffness'", "its fields: K, f, C, g")
    with pytest.raises(ProblemError) as raised:
        contactqp.Problem(K=K3, f=F3)
    one_line(raised.value, "missing a required argument: 'C'")


def test_index_and_value_arrays_of_different_lengths_are_malformed():
    K = sp.csr_array(K3)
    K.data = np.concatenate((K.data, [5.0]))  # one value more than indices: scipy reads past
    with pytest.raises(ProblemError) as raised:
        contactqp.Problem(K, F3, C3, G3)
    one_line(raised.value, "K is a malformed CSR matrix", "same length")


def test_numbers_below_what_arithmetic_carries_are_refused():
    with pytest.raises(ProblemError) as raised:
        contactqp.Problem(K3, F3 * 5e-324, C3, G3 * 5e-324)
    one_line(raised.value, "f[2] = 5e-324 is outside the range", "1e-90")


@pytest.mark.parametrize("method", ["lagrange", "qp"])
def test_equality_contact_on_rows_no_u_meets_names_them(method):
    C, g = np.array([[0, 0, 1.0], [0, 0, -1.0]]), np.array([0.5, -0.2])  # 0.2 <= u <= 0.5
    problem = contactqp.Problem(K3, F3, C, g)
    assert contactqp.solve(problem, method).verified  # unilateral: fine
    with pytest.raises(ProblemError) as raised:
        contactqp.solve(problem, method, contact="equality")  # u = 0.5 and u = 0.2
    one_line(raised.value, "rows 0 (row[0]) and 1 (row[1])", "leave no u")


def test_a_body_its_loads_pull_off_its_rows_or_leave_unpressed_is_one_line():
    spring = np.array([[1.0, -1.0], [-1.0, 1.0]])  # two dofs, nothing but a row holds them
    for f, g, words in (([-1.0, 0.0], [0.5], "away from every contact row"),
                        ([0.0, 0.0], [0.5], "its position there is not determined")):
        for method in ("lagrange", "qp"):
            with pytest.raises(ProblemError) as raised:
                contactqp.solve(contactqp.Problem(spring, f, [[1.0, 0.0]], g), method)
            one_line(raised.value, words)
    pressed = contactqp.solve(contactqp.Problem(spring, [1.0, 0.0], [[1.0, 0.0]], [0.5]))
    assert pressed.verified and pressed.u == pytest.approx([0.5, 0.5])


def test_a_symmetric_matrix_market_file_in_array_format_is_read(tmp_path):
    folder = _folder(tmp_path, K="%%MatrixMarket matrix array real symmetric\n3 3\n2\n-1\n0\n"
                     "2\n-1\n1\n")  # the lower triangle, column by column
    problem = contactqp.load_problem(folder, prescribed=[0])
    assert np.array_equal(problem.K.toarray(), K3)


def test_a_corrupt_or_garbled_bundle_is_one_line_without_internals(tmp_path):
    path = _npz_with(tmp_path)
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as archive:
        offset = archive.getinfo("f.npy").header_offset + 60  # inside f's compressed data
    data[offset: offset + 8] = b"\xff" * 8
    np.savez_compressed(tmp_path / "z.npz", **dict(np.load(path)))  # compressed, to corrupt
    zipped = bytearray((tmp_path / "z.npz").read_bytes())
    with zipfile.ZipFile(tmp_path / "z.npz") as archive:
        offset = archive.getinfo("g.npy").header_offset + 40
    zipped[offset: offset + 16] = b"\x00\xff" * 8
    (tmp_path / "z.npz").write_bytes(bytes(zipped))
    with pytest.raises(ProblemError) as raised:
        contactqp.load_problem(tmp_path / "z.npz")
    text = one_line(raised.value, "z.npz")
    assert "0x" not in text and "<ast" not in text



@pytest.mark.parametrize("field", ["K", "f", "C", "g"])
def test_a_masked_entry_is_refused_and_an_unmasked_masked_array_read(field):
    """A masked entry has no value to solve with (the data under the mask is not the user's);
    a masked array with nothing masked is its values."""
    arrays = {"K": np.array([[2.0, -1.0], [-1.0, 2.0]]), "f": np.array([1.0, 0.0]),
              "C": np.array([[1.0, 0.0]]), "g": np.array([0.25])}
    masked = dict(arrays)
    mask = np.zeros(arrays[field].shape, dtype=bool)
    mask.flat[-1] = True
    masked[field] = np.ma.masked_array(arrays[field], mask)
    with pytest.raises(contactqp.ProblemError, match=rf"^{field} has masked entries"):
        contactqp.Problem(masked["K"], masked["f"], masked["C"], masked["g"])
    plain = dict(arrays)
    plain[field] = np.ma.masked_array(arrays[field], np.zeros_like(mask))
    got = contactqp.Problem(plain["K"], plain["f"], plain["C"], plain["g"])
    want = contactqp.Problem(arrays["K"], arrays["f"], arrays["C"], arrays["g"])
    np.testing.assert_array_equal(contactqp.solve(got).u, contactqp.solve(want).u)


@pytest.mark.parametrize("method", ["lagrange", "penalty", "augmented", "qp", "lemke", "pgs",
                                    "semismooth_newton"])
def test_a_problem_with_no_contact_rows_is_k_inverse_f_by_every_method(method):
    """No rows: the answer is K⁻¹f (here [1, 2] by hand), verified; the sparse penalty's row
    products once failed on an empty C."""
    K = np.array([[2.0, -1.0], [-1.0, 1.0]])
    problem = contactqp.Problem(K, [0.0, 1.0], np.zeros((0, 2)), [])
    result = contactqp.solve(problem, method)
    assert result.verified and result.contact_force.size == 0
    np.testing.assert_allclose(result.u, [1.0, 2.0], rtol=1e-12)


@pytest.mark.parametrize(("backend", "solver"), [("clarabel", None), ("osqp", None)])
def test_a_force_carried_round_a_zero_gap_loop_is_judged_on_what_the_rows_put_on_the_dofs(
        backend, solver):
    """Rows u₀ − u₁ ≤ 0, u₁ − u₂ ≤ 0, u₂ − u₀ ≤ 0 add up to 0·u ≤ 0: any force carried round
    the loop moves nothing, so the exact answer fixes only Cᵀλ. Here f = (1, 0, −1) is taken
    by the loop whole (u = 0, Cᵀλ = f, by hand); Clarabel carries 1.23 more round it, which
    the check once flagged (the reference's set had dropped the row its least-norm forces
    pulled on)."""
    K = np.eye(3) + np.array([[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    C = np.array([[1.0, -1.0, 0.0], [0.0, 1.0, -1.0], [-1.0, 0.0, 1.0]])
    f = np.array([1.0, 0.0, -1.0])
    problem = contactqp.Problem(K, f, C, np.zeros(3))
    options = {"backend": backend} if solver is None else {"backend": backend, "solver": solver}
    result = contactqp.solve(problem, "qp", **options)
    assert result.verified, result.message
    F, U = result.force_scale, result.displacement_scale
    assert np.abs(result.u).max() <= contactqp.GUARANTEE[1] * U
    assert np.abs(C.T @ result.contact_force - f).max() <= contactqp.GUARANTEE[0] * F
    assert result.contact_force.min() >= -contactqp.GUARANTEE[0] * F
