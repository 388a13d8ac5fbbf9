"""The sparse model's exact method at the cost of a few factorisations
(contactqp.model.augmented, contactqp.model.factor): each set of rows held is one numeric
factorisation of K + C_AᵀRC_A on a pattern analysed once, λ by Uzawa's iteration on the
saddle-point system's own residuals.

Every expected number comes from elsewhere: the dense saddle-point system solved by LAPACK,
a diagonal K in closed form, exact rational arithmetic (tests/test_problem_solve.py's
exact_answer), and the SuperLU route (the Schur complement W_AA) on the same problem.

Glossary: K stiffness, f loads, C rows, g gaps, A the rows held, λ their forces (positive
when they push), u the displacements, R = diag ρ the rows' augmented stiffness.
"""

import warnings

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp
from contactqp.errors import ProblemError
from contactqp.model import factor as factor_module
from contactqp.model.augmented import augmented_set
from contactqp.model.factor import CholmodK
from contactqp.model.sparse import build_sparse_model
from test_problem_solve import Infeasible, exact_answer, random_problem

pytest.importorskip("cvxopt")


def spring_chain(n: int, rng: np.random.Generator) -> sp.csr_array:
    """A grounded chain of springs with stiffnesses in [1, 10) (SPD, tridiagonal)."""
    k = rng.uniform(1.0, 10.0, n + 1)
    main = k[:-1] + k[1:]
    return sp.csr_array(sp.diags([-k[1:-1], main, -k[1:-1]], [-1, 0, 1]))


def random_rows(m: int, n: int, most: int, values: tuple[float, ...],
                rng: np.random.Generator) -> np.ndarray:
    """m dense rows over n dofs, each on 1 to ``most`` dofs with entries from ``values``."""
    C = np.zeros((m, n))
    for i in range(m):
        dofs = rng.choice(n, int(rng.integers(1, most + 1)), replace=False)
        C[i, dofs] = rng.choice(values, dofs.size)
    return C


@pytest.mark.parametrize("seed", range(6))
def test_set_solve_equals_the_dense_saddle_point_system(seed):
    """Rows of 1-4 dofs each (CᵀC adds entries off K's pattern): the augmented set solve
    gives the saddle-point system's answer, solved densely by LAPACK, to round-off (1e-10 of
    the largest force and displacement: the dense solve's own round-off on a condition number
    of about 10⁴)."""
    rng = np.random.default_rng(seed)
    n, m = 40, 12
    K = spring_chain(n, rng)
    C = random_rows(m, n, 4, (-2.0, -1.0, 1.0, 2.0), rng)
    f = rng.uniform(-1.0, 1.0, n)
    for _ in range(100):  # gaps that some u meets: Problem refuses the others (its own tests)
        g = rng.uniform(-0.1, 0.1, m)
        try:
            problem = contactqp.Problem(K, f, sp.csr_array(C), g)
        except ProblemError:
            continue
        break
    model = build_sparse_model(problem)
    assert isinstance(model.factor, CholmodK)
    rows = np.sort(rng.choice(m, 6, replace=False))
    if np.linalg.matrix_rank(C[rows]) < rows.size:
        pytest.skip("dependent rows: the Schur complement's least-norm solve applies")
    u, lam = augmented_set(model, rows).solve(model, model.P, model.g[rows])
    saddle = np.block([[K.toarray(), C[rows].T], [C[rows], np.zeros((rows.size, rows.size))]])
    exact = np.linalg.solve(saddle, np.concatenate((f, g[rows])))
    assert np.abs(u - exact[:n]).max() <= 1e-10 * np.abs(exact[:n]).max()
    assert np.abs(lam - exact[n:]).max() <= 1e-10 * np.abs(exact[n:]).max()


@pytest.mark.parametrize("seed", range(4))
def test_set_solve_with_one_dof_rows_on_ks_own_pattern(seed):
    """Rows of one dof each (a wall, a flat: CᵀC diagonal, where K keeps every diagonal entry):
    the analysis is of K's own lower triangle, with no sum of patterns formed, and the set
    solve is still the saddle-point system's answer solved densely by LAPACK (1e-10, as
    above)."""
    from contactqp.model.factor import lower_triangle

    rng = np.random.default_rng(seed)
    n, m = 40, 12
    K = spring_chain(n, rng)
    C = np.zeros((m, n))
    C[np.arange(m), rng.choice(n, m, replace=False)] = rng.choice([-2.0, -1.0, 1.0, 2.0], m)
    f = rng.uniform(-1.0, 1.0, n)
    g = rng.uniform(-0.1, 0.1, m)
    model = build_sparse_model(contactqp.Problem(K, f, sp.csr_array(C), g))
    assert isinstance(model.factor, CholmodK)
    rows, columns, _ = lower_triangle(sp.csc_matrix(K))
    assert np.array_equal(model.factor.engine.rows, rows)
    assert np.array_equal(model.factor.engine.columns, columns)
    held = np.sort(rng.choice(m, 6, replace=False))
    u, lam = augmented_set(model, held).solve(model, model.P, model.g[held])
    saddle = np.block([[K.toarray(), C[held].T], [C[held], np.zeros((held.size, held.size))]])
    exact = np.linalg.solve(saddle, np.concatenate((f, g[held])))
    assert np.abs(u - exact[:n]).max() <= 1e-10 * np.abs(exact[:n]).max()
    assert np.abs(lam - exact[n:]).max() <= 1e-10 * np.abs(exact[n:]).max()


def test_diagonal_K_past_the_int32_keys():
    """n = 50 000 dofs (n² passes 2³¹: the pattern's keys need 64 bits), K = diag(k), a row
    −u_i <= g_i on every third dof, loads that push every second of those past it: closed
    form, u_i = f_i / k_i where the row is open; where it holds, u_i = −g_i and, from
    k_i u_i − λ_i = f_i, λ_i = −k_i g_i − f_i. Tolerance 1e-12: the answers are of order 1
    and each is a few operations on numbers of order 1."""
    rng = np.random.default_rng(7)
    n = 50_000
    k = rng.uniform(1.0, 3.0, n)
    held = np.arange(0, n, 3)
    f = np.zeros(n)
    f[held[::2]] = -2.0  # pushes u below −g: the row holds
    f[held[1::2]] = 0.5  # pulls away: open
    g = np.full(held.size, 0.25)
    C = sp.csr_array((-np.ones(held.size), (np.arange(held.size), held)), shape=(held.size, n))
    result = contactqp.solve(contactqp.Problem(sp.diags_array(k).tocsr(), f, C, g), "lagrange")
    u = f / k
    u[held[::2]] = -0.25
    lam = np.zeros(held.size)
    lam[::2] = -k[held[::2]] * 0.25 - f[held[::2]]
    assert result.verified
    assert np.abs(result.u - u).max() <= 1e-12
    assert np.abs(result.contact_force - lam).max() <= 1e-12


def always_update(monkeypatch) -> None:
    """Sets reached by rank updates of a factor (contactqp.model.updown) whatever they cost:
    every set after the first, however many rows it changes; no Woodbury."""
    from contactqp.model import augmented

    monkeypatch.setattr(augmented, "ROW_SHARE", 0.0)
    monkeypatch.setattr(augmented, "TAKEOVER_SHARE", 0.0)
    monkeypatch.setattr(augmented, "SOLVES_AFTER", 0)
    monkeypatch.setattr(augmented, "UPDATE_ROWS", 0)
    by_updates = augmented._by_updates

    def timeless(model, target):  # no measured time stands in their way either
        model.cache.takeover_seconds = 0.0
        if model.cache.modified is not None:
            model.cache.modified.row_seconds = 0.0
            model.cache.modified.column_seconds = None
        return by_updates(model, target)

    monkeypatch.setattr(augmented, "_by_updates", timeless)


@pytest.mark.parametrize("seed", range(40))
@pytest.mark.parametrize("route", ["cholmod", "superlu", "updates"])
def test_random_problems_exact_by_either_route(seed, route, monkeypatch):
    """The random spring networks of tests/test_problem_solve.py, by the augmented route
    (CHOLMOD), by it with every set after the first reached by rank updates of a factor, and
    by the Schur complement (SuperLU, as without the extra): each gives the exact rational
    answer within its own bounds (a verified answer is within its bound)."""
    if route == "superlu":
        monkeypatch.setattr(factor_module, "cholmod_installed", lambda: False)
    if route == "updates":
        from contactqp.model import updown

        if updown.library() is None:
            pytest.skip("CHOLMOD's library is not found beside cvxopt")
        always_update(monkeypatch)
    try:
        problem = random_problem(seed)
        u, lam = exact_answer(problem)
    except (contactqp.ContactqpError, Infeasible):
        pytest.skip("no u meets every row")
    try:
        result = contactqp.solve(problem, "lagrange")
    except contactqp.ContactqpError:
        return  # refused: nothing claimed
    if not result.verified:
        return
    assert np.abs(result.contact_force - lam).max() <= result.force_error_bound + 1e-12
    assert np.abs(result.u - u).max() <= result.displacement_error_bound + 1e-12


def test_hertz_by_both_routes_agree(monkeypatch):
    """The Hertz cylinder (contactqp.fem, 7 646 dofs): the augmented route and the Schur
    complement's find the same rows in contact and forces within the sum of their bounds;
    the augmented route spends one numeric factorisation per set and no flexibility column."""
    from contactqp.fem import cylinder_on_flat

    problem = cylinder_on_flat(zone=0.5, fine=0.05).problem
    by_sets = contactqp.solve(problem, "lagrange")
    monkeypatch.setattr(factor_module, "cholmod_installed", lambda: False)
    again = contactqp.Problem(problem.K, problem.f, problem.C, problem.g,
                              prescribed=problem.prescribed,
                              prescribed_values=problem.prescribed_values)
    by_schur = contactqp.solve(again, "lagrange")
    assert by_sets.verified and by_schur.verified
    assert np.array_equal(by_sets.contact_force > 0, by_schur.contact_force > 0)
    assert np.abs(by_sets.contact_force - by_schur.contact_force).max() <= (
        by_sets.force_error_bound + by_schur.force_error_bound)
    assert by_sets.info.get("active_set") == "primal-dual"
    assert by_sets.info["set_factorisations"] <= by_sets.iterations


@pytest.mark.parametrize(("released", "halves"), [
    ([191, 103, 53], True), ([18, 10, 5], True), ([55, 28, 14], True),
    ([71, 41, 16], False),  # the sphere's releases fall faster: 41/71 and then 16/41
    ([22, 12], False),  # two steps do not show a halving
    ([12, 6, 3], False),  # 3 rows: the set before's factor solves as few
    ([40, 20, 20], False)])
def test_releases_halve(released, halves):
    """Releasing ahead takes three releases in a row, each within 0.1 of half the one
    before, the last of 4 rows or more (the ratios worked out by hand)."""
    from contactqp.methods.lagrange import halving

    assert halving(released) is halves


def test_releasing_ahead_reaches_the_same_answer_in_fewer_sets(monkeypatch):
    """The Hertz cylinder at 6.4·10⁴ dofs pushed by 1 nm, whose releases past the contact's
    edge halve (18, 10, 5 rows): releasing ahead ends on the rows in contact and forces of
    the textbook loop (the halving test switched off) and of the Schur complement's route
    (SuperLU, a different loop and solve), within their bounds, in fewer factorisations (each
    set factorised: rank updates switched off)."""
    from contactqp.fem import cylinder_on_flat
    from contactqp.methods import lagrange
    from contactqp.model import updown

    monkeypatch.setattr(updown, "library", lambda: None)  # each set factorised: the sets
    # counted are the loop's (tests/test_updown.py: the same sets by rank updates)
    built = cylinder_on_flat(zone=0.5, fine=0.5 / 20000, growth=0.4, approach=1e-6).problem

    def fresh() -> contactqp.Problem:  # a new Problem: its own model, factor and sets
        return contactqp.Problem(built.K, built.f, built.C, built.g,
                                 prescribed=built.prescribed,
                                 prescribed_values=built.prescribed_values)

    ahead = contactqp.solve(fresh(), "lagrange")
    with monkeypatch.context() as patch:
        patch.setattr(lagrange, "halving", lambda released: False)
        textbook = contactqp.solve(fresh(), "lagrange")
    monkeypatch.setattr(factor_module, "cholmod_installed", lambda: False)
    by_schur = contactqp.solve(fresh(), "lagrange")
    assert ahead.verified and textbook.verified and by_schur.verified
    for other in (textbook, by_schur):
        assert np.array_equal(ahead.contact_force > 0, other.contact_force > 0)
        assert np.abs(ahead.contact_force - other.contact_force).max() <= (
            ahead.force_error_bound + other.force_error_bound)
    assert ahead.info["set_factorisations"] < textbook.info["set_factorisations"]
    assert ahead.iterations < textbook.iterations


def test_other_gaps_share_the_sets_not_their_answers():
    """A problem with other gaps (Problem.with_values) shares K's analysis and the sets'
    augmented matrices, not their answers: its forces equal those of the same problem built
    afresh (another model, nothing shared) within the two bounds."""
    from contactqp.fem import cylinder_on_flat

    problem = cylinder_on_flat(zone=0.5, fine=0.05).problem
    first = contactqp.solve(problem, "lagrange")
    moved = problem.with_values(g=problem.g + 0.001)
    shared = contactqp.solve(moved, "lagrange")
    afresh = contactqp.solve(contactqp.Problem(
        moved.K, moved.f, moved.C, moved.g, prescribed=moved.prescribed,
        prescribed_values=moved.prescribed_values), "lagrange")
    assert first.verified and shared.verified and afresh.verified
    assert np.abs(shared.contact_force - afresh.contact_force).max() <= (
        shared.force_error_bound + afresh.force_error_bound)
    assert shared.contact_force.sum() < first.contact_force.sum()  # wider gaps: less load


def rows_on_a_spring_chain(rng: np.random.Generator) -> tuple:
    """(the model of 30 springs in a row with 10 random rows of 1-3 dofs, CHOLMOD's factor;
    its W = C K⁻¹ Cᵀ from the dense inverse, LAPACK)."""
    n, m = 30, 10
    K = spring_chain(n, rng)
    C = random_rows(m, n, 3, (-1.0, 1.0, 2.0), rng)
    model = build_sparse_model(contactqp.Problem(K, rng.uniform(-1, 1, n), sp.csr_array(C),
                                                 rng.uniform(0.0, 0.1, m)))
    assert isinstance(model.factor, CholmodK)
    return model, C @ np.linalg.inv(K.toarray()) @ C.T


@pytest.mark.parametrize("seed", range(3))
def test_row_flexibility_in_blocks_equals_the_dense_inverse(seed, monkeypatch):
    """The rows' own stiffness 1/W_ii (the check's) and W_AA are formed a block of solved
    columns at a time, so that 10⁴ rows on 3.3·10⁵ dofs do not ask for K⁻¹Cᵀ at once (25 GiB;
    the check of a peer's answer ran out of memory there). With blocks of 3 columns here, both
    equal C K⁻¹ Cᵀ from the dense inverse of K (LAPACK) to 1e-12."""
    from contactqp.model import sparse as sparse_module

    model, W = rows_on_a_spring_chain(np.random.default_rng(seed))
    monkeypatch.setattr(sparse_module, "SOLVE_BLOCK", 3 * model.n_free)
    rows = np.array([7, 0, 3, 9, 4, 2, 8])  # any order, more rows than a block
    seen = model.seen_stiffness(rows)
    assert np.abs(seen * np.diagonal(W)[rows] - 1.0).max() <= 1e-12
    formed = model.flexibility(rows)
    assert np.abs(formed - W[np.ix_(rows, rows)]).max() <= 1e-12 * np.abs(W).max()


def test_each_rows_own_stiffness_is_solved_once(monkeypatch):
    """W_ii of a row, once solved (by W's block or by the check's own s), is kept with the
    factor: the rows' own stiffness 1/W_ii then asks solves for the rows not seen yet only
    (repeated rows once), and every value still equals the dense inverse's (1e-12). At 10³ rows
    on 2.4·10⁵ dofs each is a 0.1 s solve, and the check of pgs's answer asked them all again
    (48 s) after the LCP had formed W."""
    model, W = rows_on_a_spring_chain(np.random.default_rng(11))
    columns = []
    solve = model.factor.solve
    monkeypatch.setattr(model.factor, "solve",
                        lambda rhs: columns.append(rhs.shape[1] if rhs.ndim == 2 else 1)
                        or solve(rhs))
    model.flexibility(np.array([1, 4, 6]))
    assert columns == [3]
    rows = np.array([4, 6, 1, 6, 8, 2, 8])
    seen = model.seen_stiffness(rows)
    assert columns == [3, 2]  # rows 8 and 2 only
    assert np.abs(seen * np.diagonal(W)[rows] - 1.0).max() <= 1e-12
    assert np.abs(model.seen_stiffness(rows) - seen).max() == 0.0
    assert columns == [3, 2]



@pytest.mark.parametrize("seed", range(3))
def test_many_columns_by_cholespys_block_solves_equal_the_dense_inverse(seed, monkeypatch):
    """A job of solved columns (W of many rows, the check's rows) that pays for it goes to a
    second factor of K that cholespy makes once and solves a block of columns at a time
    (cvxopt's CHOLMOD solves column by column): W and the rows' own stiffness still equal the
    dense inverse's (LAPACK) to 1e-12. It pays where the columns, at BLOCK_SAVING of a
    CHOLMOD solve's column each, outweigh BLOCK_FACTOR of CHOLMOD's factorisation (both
    timed; set here): a job of 2 columns does not, one of 6 does, and the factor is then
    kept. Without cholespy the same job is the column-by-column solves, to the same
    numbers."""
    pytest.importorskip("cholespy")
    from contactqp.model import sparse as sparse_module

    model, W = rows_on_a_spring_chain(np.random.default_rng(100 + seed))
    monkeypatch.setattr(sparse_module, "SOLVE_BLOCK", 3 * model.n_free)  # 3 columns a block
    factor = model.factor
    assert factor.blocks is None and factor.factor_seconds > 0.0
    factor.solve(np.ones(model.n_free))
    assert factor.column_seconds > 0.0
    # a column takes 1 s; 3 columns' saving make up one factorisation, 4 pay for it
    factor.column_seconds = 1.0
    factor.factor_seconds = 3 * factor_module.BLOCK_SAVING / factor_module.BLOCK_FACTOR
    assert not factor.blocks_pay(3) and factor.blocks_pay(4)
    asked, rule = [], factor.blocks_pay

    def ask(columns: int) -> bool:  # the rule, with the columns left of each job recorded
        factor.column_seconds = 1.0
        asked.append(columns)
        return rule(columns)

    monkeypatch.setattr(factor, "blocks_pay", ask)
    few = model.flexibility(np.array([2, 5]))
    assert factor.blocks is None
    assert np.abs(few - W[np.ix_([2, 5], [2, 5])]).max() <= 1e-12 * np.abs(W).max()
    rows = np.array([9, 0, 3, 7, 1, 6])
    formed = model.flexibility(rows)
    made = factor.blocks
    assert made is not None
    assert np.abs(formed - W[np.ix_(rows, rows)]).max() <= 1e-12 * np.abs(W).max()
    others = np.array([8, 4, 2, 5, 0])  # 4 and 8 not seen yet: the check solves only those
    seen = model.seen_stiffness(others)
    assert np.abs(seen * np.diagonal(W)[others] - 1.0).max() <= 1e-12
    assert np.abs(model.flexibility(np.arange(10)) - W).max() <= 1e-12 * np.abs(W).max()
    assert factor.blocks is made  # one factorisation by cholespy, kept
    assert asked == [2, 6, 3, 2, 10, 7, 4, 1]  # each block asks with the columns left

    monkeypatch.setattr(factor_module, "cholespy_installed", lambda: False)
    plain, _ = rows_on_a_spring_chain(np.random.default_rng(100 + seed))
    plain.factor.factor_seconds = 0.0  # it would pay at once, but is not installed
    assert np.abs(plain.flexibility(rows) - formed).max() <= 1e-12 * np.abs(W).max()
    assert plain.factor.blocks is None


def test_a_k_cholespy_refuses_leaves_the_solves_to_cholmod_and_prints_nothing(capfd):
    """Where cholespy refuses K (not positive definite to its own pivots: here its values
    negated, which only cholespy reads, after CHOLMOD's factor was made), the job goes on by
    CHOLMOD's column solves to the dense inverse's W (1e-12), cholespy is not asked again, and
    CHOLMOD's warning from C does not reach standard output or error."""
    pytest.importorskip("cholespy")
    model, W = rows_on_a_spring_chain(np.random.default_rng(7))
    factor = model.factor
    factor.values = -factor.values  # what cholespy would factor; CHOLMOD holds K already
    factor.column_seconds, factor.factor_seconds = 1.0, 0.0  # any job pays
    assert factor.blocks_pay(2)
    formed = model.flexibility(np.arange(10))
    assert factor.blocks is False and not factor.blocks_pay(10**6)
    assert np.abs(formed - W).max() <= 1e-12 * np.abs(W).max()
    assert np.abs(model.flexibility(np.array([3, 1])) - W[np.ix_([3, 1], [3, 1])]).max() \
        <= 1e-12 * np.abs(W).max()
    printed = capfd.readouterr()
    assert printed.out == "" and printed.err == ""


@pytest.mark.parametrize("side", [15, 30])
def test_the_factors_planned_size_is_the_factors_own(side):
    """What the guard below reads from CHOLMOD's analysis: on a 2D grid Laplacian the column
    counts' sum equals the nonzeros of the numeric factor CHOLMOD then computes (cvxopt's
    getfactor), and the supernodes store at least those; a chain fills nothing (2n − 1) and a
    full matrix everything (n(n + 1)/2)."""
    from cvxopt import cholmod

    T = sp.diags([4.0 * np.ones(side), -np.ones(side - 1), -np.ones(side - 1)], [0, 1, -1])
    K = sp.csc_matrix(sp.kronsum(T, T))
    analysis = factor_module.Cholmod.of_pattern(K)
    count, stored = analysis.entries()
    analysis.factor("K", factor_module.lower_triangle(K)[2].astype(float))
    values = np.array(cholmod.getfactor(analysis.symbolic).V).reshape(-1)
    assert count == np.count_nonzero(values) and stored >= values.size
    n = 40
    chain = sp.csc_matrix(sp.diags([2.0 * np.ones(n), -np.ones(n - 1), -np.ones(n - 1)],
                                   [0, 1, -1]))
    assert factor_module.Cholmod.of_pattern(chain).entries()[0] == 2 * n - 1
    full = factor_module.Cholmod.of_pattern(sp.csc_matrix(np.ones((n, n))))
    assert full.entries()[0] == n * (n + 1) // 2


def test_a_factor_past_the_memory_available_is_one_line(monkeypatch, capfd):
    """Where the factor CHOLMOD plans needs more memory than the machine has, a SolverError
    naming both and engine='amg', before the numeric factorisation (at 1.1·10⁶ dofs in 3D it
    was killed by the kernel: 26.6 GB planned on 24 GB). The memory is lowered here."""
    n = 200
    f = np.zeros(n)
    f[-1] = 1.0
    problem = contactqp.Problem(spring_chain(n, np.random.default_rng(0)), f,
                                sp.csr_array(([1.0], ([0], [n - 1])), shape=(1, n)),
                                np.array([1e-3]))
    monkeypatch.setattr(factor_module, "available_memory", lambda: 1000)
    with pytest.raises(contactqp.SolverError,
                       match=r"K's Cholesky factor \(\d+ dofs\) needs .* GB .* this machine has "
                             r"0\.0 GB available: engine='amg'"):
        contactqp.solve(problem, "lagrange")
    assert capfd.readouterr() == ("", "")
    monkeypatch.setattr(factor_module, "available_memory", lambda: None)
    assert contactqp.solve(problem.with_values(f=problem.f), "lagrange").verified


def test_memory_where_the_system_does_not_say_what_is_available(monkeypatch):
    """Without Linux's MemAvailable the guard above reads all of the machine's memory, never
    the free pages alone (on macOS most memory is cache, and the free pages would refuse
    factors that fit)."""
    import builtins
    import os

    real_open = builtins.open

    def no_meminfo(path, *args, **kwargs):
        if str(path) == "/proc/meminfo":
            raise FileNotFoundError(path)
        return real_open(path, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", no_meminfo)
    found = factor_module.available_memory()
    page = os.sysconf("SC_PAGE_SIZE")
    assert found == os.sysconf("SC_PHYS_PAGES") * page
    assert found >= os.sysconf("SC_AVPHYS_PAGES") * page


@pytest.mark.parametrize("seed", range(4))
def test_rows_on_dofs_of_their_own_solve_their_gram_matrix_as_lapack_does(seed):
    """Rows that share no dof (C_A C_Aᵀ diagonal, as the Hertz models' rows are) are solved by
    the diagonal, with no sparse LU: (C_A C_Aᵀ)⁻¹b equals LAPACK's dense solve of C_A C_Aᵀ
    (1e-13 per entry) over entries from 1e-100 to 1e100. Rows that share a dof take the LU and
    still equal it; an empty row is a dependent one (None, with no warning)."""
    from contactqp.model.saddle import DiagonalFactor, gram_factor

    rng = np.random.default_rng(seed)
    m, n = 9, 30
    dofs = rng.permutation(n)
    C = np.zeros((m, n))
    for i, own in enumerate(np.array_split(dofs[: 2 * m], m)):  # 2 dofs of its own each
        C[i, own] = rng.choice([-1.0, 1.0], own.size) * 10.0 ** rng.uniform(-100, 100, own.size)

    def solved_as_lapack_does(rows: np.ndarray, diagonal: bool) -> None:
        factor, scale = gram_factor(sp.csr_array(rows))
        assert isinstance(factor, DiagonalFactor) == diagonal
        rhs = rng.standard_normal(rows.shape[0])
        x = scale * factor.solve(scale * rhs)
        exact = np.linalg.solve(rows @ rows.T, rhs)
        assert np.all(np.abs(x - exact) <= 1e-13 * np.abs(exact) + 1e-300)

    solved_as_lapack_does(C, diagonal=True)
    # a row that repeats two others: dependent
    assert gram_factor(sp.csr_array(np.vstack((C, C[0] + C[1])))) is None
    shared = np.zeros((1, n))
    shared[0, [dofs[0], dofs[-1]]] = 1.0  # a dof of row 0's and one of its own
    solved_as_lapack_does(np.vstack((C, shared)), diagonal=False)
    empty = C.copy()
    empty[3] = 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert gram_factor(sp.csr_array(empty)) is None


def test_rows_far_from_unit_entries_are_solved_past_the_steps_noise():
    """Rows whose entries are 1e30 and 1e-30 beside rows of order 1, on a chain of springs of
    order 1e20 (hostile: within the magnitudes a Problem takes). Lagrange's answer is verified,
    and it is the saddle-point system's on its set solved densely by LAPACK with each row scaled
    to a unit entry (u to 1e-9 of its largest, the force each row puts on its dof, λ_i c_i, to
    1e-9 of the largest). Uzawa's steps that stopped where their geometric tail, measured
    against F, was under 1e-15 left this answer 8.6e41 of F out of balance."""
    rng = np.random.default_rng(5)
    n = 30
    for scale in (1e-80, 1e-20, 1.0, 1e20):  # the draws of the hostile audit's run: its last
        k = rng.uniform(1.0, 10.0, n + 1) * scale
        f = rng.uniform(-1.0, 1.0, n) * scale
    K = sp.csr_array(sp.diags([-k[1:-1], k[:-1] + k[1:], -k[1:-1]], [-1, 0, 1]))
    dofs = np.array([2, 7, 11, 15, 20, 25])
    entries = np.array([1.0, -1.0, 1e-30, 1e30, 2.0, -3.0])
    C = np.zeros((6, n))
    C[np.arange(6), dofs] = entries
    g = np.full(6, 1e-4)
    result = contactqp.solve(contactqp.Problem(K, f, sp.csr_array(C), g), "lagrange")
    assert result.verified
    held = np.flatnonzero(np.asarray(result.contact_force) > 0.0)
    unit = C[held] / np.abs(entries[held])[:, None]  # each row scaled to an entry of ±1
    saddle = np.block([[K.toarray(), unit.T], [unit, np.zeros((held.size, held.size))]])
    exact = np.linalg.solve(saddle, np.concatenate((f, g[held] / np.abs(entries[held]))))
    u, pushes = exact[:n], exact[n:]  # pushes: λ_i |c_i|, the force on the dof
    assert np.all(pushes >= 0.0)  # the set is the answer's: every held row pushes ...
    assert np.all(C @ u - g <= 1e-9 * np.abs(g).max())  # ... and no row is passed
    assert np.abs(np.asarray(result.u) - u).max() <= 1e-9 * np.abs(u).max()
    found = np.asarray(result.contact_force)[held] * np.abs(entries[held])
    assert np.abs(found - pushes).max() <= 1e-9 * np.abs(pushes).max()
