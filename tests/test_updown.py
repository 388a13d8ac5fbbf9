"""Sets reached by rank updates of a factor (contactqp.model.updown, used by
contactqp.model.augmented): a set of rows held that differs from a factored one by k rows is
k rank-one updates of that factor (CHOLMOD's cholmod_updown, called in the library cvxopt
ships), not a new numeric factorisation.

Every expected number comes from elsewhere: the dense matrix solved by LAPACK, and the same
solve with the updates switched off (each set factorised, as before they existed); the
random problems against exact rational arithmetic by this route are in
tests/test_sparse_scale.py (test_random_problems_exact_by_either_route, route "updates").

Glossary: K stiffness, C rows, ρ a row's weight, M = K + Cᵀ diag(ρ) C on the rows held.
"""

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp
from contactqp.model import updown
from contactqp.model.factor import Cholmod
from test_sparse_scale import always_update, random_rows, spring_chain

pytest.importorskip("cvxopt")
if updown.library() is None:  # pragma: no cover - a cvxopt without its CHOLMOD library file
    pytest.skip("CHOLMOD's library is not found beside cvxopt", allow_module_level=True)


def factored(K: sp.csr_array, C: np.ndarray, rows: np.ndarray, rho: np.ndarray) -> Cholmod:
    """CHOLMOD's factor of K + C_rowsᵀ diag(ρ_rows) C_rows on the pattern of K + CᵀC."""
    n = K.shape[0]
    pattern = sp.csc_matrix(abs(K) + abs(sp.csr_array(C)).T @ abs(sp.csr_array(C)))
    engine = Cholmod.of_pattern(pattern)
    M = sp.csr_array(K + C[rows].T @ np.diag(rho[rows]) @ C[rows])
    engine.factor("M", np.asarray(M.toarray()[engine.rows, engine.columns]).reshape(-1))
    assert engine.n == n and engine.spare is not None
    return engine


@pytest.mark.parametrize("seed", range(5))
def test_updates_and_downdates_equal_the_dense_inverse(seed):
    """A factor of one set taken over and moved to another (rows entering and leaving,
    weights spread over 10⁴) solves like LAPACK's inverse of the other set's matrix; the
    engine factors again on its own analysis afterwards."""
    rng = np.random.default_rng(seed)
    n, m = 40, 16
    K = spring_chain(n, rng)
    C = random_rows(m, n, 3, (-1.0, 1.0, 2.0), rng)
    rho = rng.uniform(1.0, 1e4, m)
    first, second = np.sort(rng.choice(m, 9, replace=False)), np.sort(rng.choice(m, 7,
                                                                                 replace=False))
    engine = factored(K, C, first, rho)
    moved = updown.Modified.taken_from(engine.symbolic, n, engine.spare)
    entering, leaving = np.setdiff1d(second, first), np.setdiff1d(first, second)
    Cs = sp.csr_array(C)
    assert moved.update(Cs[entering], rho[entering], add=True)
    assert moved.update(Cs[leaving], rho[leaving], add=False)
    b = rng.standard_normal((n, 3))
    M = K.toarray() + C[second].T @ np.diag(rho[second]) @ C[second]
    expected = np.linalg.solve(M, b)
    assert np.abs(moved.solve(b) - expected).max() <= 1e-9 * np.abs(expected).max()
    assert np.abs(moved.solve(b[:, 0]) - expected[:, 0]).max() <= 1e-9 * np.abs(expected).max()
    engine.factor("K", np.asarray(K.toarray()[engine.rows, engine.columns]).reshape(-1))
    again = np.linalg.solve(K.toarray(), b)
    assert np.abs(engine.solve(b) - again).max() <= 1e-10 * np.abs(again).max()


def hertz() -> contactqp.Problem:
    """The Hertz cylinder at 6.4·10⁴ dofs pushed by 1 nm, whose sets change over a few rows at
    the contact's edge (18, 10, 5 rows released)."""
    from contactqp.fem import cylinder_on_flat

    return cylinder_on_flat(zone=0.5, fine=0.5 / 20000, growth=0.4, approach=1e-6).problem


def afresh(built: contactqp.Problem) -> contactqp.Problem:
    return contactqp.Problem(built.K, built.f, built.C, built.g, prescribed=built.prescribed,
                             prescribed_values=built.prescribed_values)


def test_hertz_through_updates_equals_each_set_factorised(monkeypatch, capfd):
    """The cylinder with every set reached by updates, and with the updates switched off
    (each set factorised): the same rows in contact and forces within the two bounds; the
    updates spend fewer numeric factorisations of a set, and print nothing."""
    built = hertz()
    with monkeypatch.context() as patch:
        always_update(patch)
        by_updates = contactqp.solve(afresh(built), "lagrange")
    with monkeypatch.context() as patch:
        patch.setattr(updown, "library", lambda: None)
        factorised = contactqp.solve(afresh(built), "lagrange")
    assert by_updates.verified and factorised.verified
    assert np.array_equal(by_updates.contact_force > 0, factorised.contact_force > 0)
    assert np.abs(by_updates.contact_force - factorised.contact_force).max() <= (
        by_updates.force_error_bound + factorised.force_error_bound)
    assert by_updates.info["set_updates"] >= 1
    assert by_updates.info["set_factorisations"] < factorised.info["set_factorisations"]
    assert factorised.info["set_updates"] == 0
    assert capfd.readouterr() == ("", "")


def test_an_updated_factor_that_does_not_resolve_its_set_is_factorised_again(monkeypatch):
    """An updated factor whose solves are off by a tenth (as a downdate's cancellation could
    leave it) does not resolve the set: the set is factorised, no update is tried again, and
    the answer is the one of the updates switched off, within the two bounds."""
    built = hertz()
    always_update(monkeypatch)
    solve = updown.Modified.solve
    monkeypatch.setattr(updown.Modified, "solve", lambda self, rhs: 0.9 * solve(self, rhs))
    problem = afresh(built)
    spoiled = contactqp.solve(problem, "lagrange")
    monkeypatch.setattr(updown, "library", lambda: None)
    factorised = contactqp.solve(afresh(built), "lagrange")
    assert spoiled.verified and factorised.verified
    assert contactqp.model.sparse.problem_model(problem).cache.updates_refused
    assert np.abs(spoiled.contact_force - factorised.contact_force).max() <= (
        spoiled.force_error_bound + factorised.force_error_bound)


def test_no_library_no_updates(monkeypatch):
    """Where no CHOLMOD library file is found (another platform's cvxopt), library() is None
    and the solve factorises each set."""
    with monkeypatch.context() as patch:
        patch.setattr(updown, "_loaded_cholmod", list)
        updown.library.cache_clear()
        try:
            assert updown.library() is None
        finally:
            updown.library.cache_clear()
    assert updown.library() is not None


def test_a_refused_update_prints_nothing_and_says_so(capfd):
    """An update CHOLMOD refuses (the rows' matrix of the wrong size) is False, and nothing is
    printed (the library's Common is set quiet, not the process's file descriptors: those are
    shared by threads)."""
    rng = np.random.default_rng(7)
    K = spring_chain(20, rng)
    C = random_rows(6, 20, 2, (1.0, -1.0), rng)
    engine = factored(K, C, np.arange(3), np.ones(6))
    moved = updown.Modified.taken_from(engine.symbolic, 20, engine.spare)
    moved.n = 21  # the rows' matrix then has 21 rows for a factor of 20
    moved.perm_inverse = np.arange(21)
    assert moved.update(sp.csr_array(np.ones((1, 21))), np.ones(1), add=True) is False
    assert capfd.readouterr() == ("", "")


THREADED = """
import sys, threading
import numpy as np
import scipy.sparse as sp
import pytest
import contactqp
sys.path.insert(0, TESTS)
from test_sparse_scale import always_update
always_update(pytest.MonkeyPatch())  # every set after the first by updates, whatever they cost

def chain(n, seed):
    rng = np.random.default_rng(seed)
    k = rng.uniform(1.0, 10.0, n - 1)
    D = sp.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n))
    K = sp.csr_array(D.T @ sp.diags(k) @ D + 0.01 * sp.identity(n))
    m = n // 3
    C = sp.csr_array((np.ones(m), (np.arange(m), rng.choice(n, m, replace=False))),
                     shape=(m, n))
    return contactqp.Problem(K, 5.0 * rng.normal(size=n), C, rng.uniform(-0.1, 0.3, m))

results = {0: [], 1: []}
def work(thread):
    for _ in range(3):
        for i, n in enumerate(int(200 * 1.15**i) for i in range(SIZES)):
            found = contactqp.solve(chain(n, 100 * i + thread), "lagrange")
            results[thread].append((found.verified, found.info["set_updates"]))
threads = [threading.Thread(target=work, args=(s,)) for s in (0, 1)]
for t in threads:
    t.start()
for t in threads:
    t.join()
done = results[0] + results[1]
print(f"solved {len(done)} verified {sum(v for v, _ in done)} "
      f"updated {sum(u > 0 for _, u in done)}")
"""


def test_two_threads_solving_through_updates_at_once(tmp_path):
    """Two threads solving at once, most of their sets by updates: every answer verified, the
    process alive, and its stdout still its own afterwards. The library is called with the
    interpreter lock held (ctypes.PyDLL): with ctypes.CDLL, which lets it go, the two threads
    shared one Common's workspace, and this test failed in 4 of 6 runs (the child killed by
    a segmentation fault; the script is the review's reproducer, 90 solves a thread). In a
    child process, so that a crash fails this test, not the run."""
    import subprocess
    import sys
    from pathlib import Path

    sizes, solves = 30, 2 * 3 * 30
    script = tmp_path / "threaded.py"
    script.write_text(THREADED.replace("SIZES", str(sizes)).replace(
        "TESTS", repr(str(Path(__file__).parent))))
    done = subprocess.run([sys.executable, str(script)], check=False, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    words = done.stdout.split()
    assert words[:2] == ["solved", str(solves)] and words[3] == str(solves)
    assert int(words[5]) >= solves // 2  # most through updates: they ran side by side
