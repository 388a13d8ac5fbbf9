"""contactqp.Problem: every bad input is one ProblemError line naming the field and the value;
.npz and Matrix Market files give back the same arrays; the sparse model's operations agree
with dense linear algebra."""

import numpy as np
import pytest
import scipy.sparse as sp

import contactqp
from contactqp.errors import ProblemError, SceneError
from contactqp.model.sparse import build_sparse_model


def chain(n: int = 5) -> sp.csr_array:
    """A spring chain 0–1–…–(n−1), unit springs, the first dof also tied to the ground."""
    K = sp.diags_array([-np.ones(n - 1), 2.0 * np.ones(n), -np.ones(n - 1)], offsets=[-1, 0, 1])
    K = sp.lil_array(K)
    K[n - 1, n - 1] = 1.0
    return sp.csr_array(K)


def arrays(**changes):
    base = {"K": chain(), "f": np.array([0, 0, 0, 0, 1.0]),
            "C": sp.csr_array(np.array([[0, 0, 0, 0, 1.0], [0, 0, 1.0, 0, 0]])),
            "g": np.array([0.5, 2.0])}
    return {**base, **changes}


def test_a_valid_problem_keeps_plain_arrays():
    problem = contactqp.Problem(**arrays(), prescribed=[0], names=["tip", "middle"])
    assert isinstance(problem.K, sp.csr_array) and isinstance(problem.C, sp.csr_array)
    assert problem.kinds == ("inequality", "inequality")
    assert problem.prescribed.tolist() == [0] and problem.prescribed_values.tolist() == [0.0]
    assert (problem.n, problem.m) == (5, 2)


BAD = [
    ({"f": np.ones(4)}, "K must be 4x4"),
    ({"f": np.array([0, 0, np.inf, 0, 1.0])}, "f[2] must be finite, got inf"),
    ({"g": np.array([0.5, np.nan])}, "g[1] must be finite, got nan"),
    ({"g": np.ones(3)}, "C must be 3x5"),
    ({"K": chain() + sp.csr_array(([1e-3], ([0], [1])), shape=(5, 5))},
     "K must be symmetric: K[0, 1]"),
    ({"K": chain() - 5.0 * sp.eye_array(5)}, "K must be positive semidefinite, but K[0, 0]"),
    ({"C": sp.csr_array(np.array([[0, 0, 0, 0, 1.0], [0, 0, 0, 0, 0]]))},
     "C row 1 (row[1]) is zero"),
    ({"C": sp.csr_array(np.array([[0, 0, 0, 0, 1.0], [0, 0, 0, 0, 2.0]])),
      "g": np.array([0.5, 1.0])},
     "C rows 0 (row[0]) and 1 (row[1]) are the same constraint"),
    ({"C": sp.csr_array(np.array([[0, 0, 0, 0, 1.0], [0, 0, 0, 0, 2.0]])),
      "kinds": ["equality", "inequality"], "g": np.array([0.5, 0.8])},
     "are parallel and their gaps (0.5 and 0.4 per unit row) leave no u"),
    ({"C": sp.csr_array(np.array([[0, 0, 0, 0, 1.0], [0, 0, 0, 0, -1.0]])),
      "g": np.array([0.5, -0.7])}, "are opposite and their gaps (0.5 and -0.7 per unit row)"),
    ({"C": sp.csr_array(np.array([[0, 0, 0, 0, 1.0], [1.0, 0, 0, 0, 0]])),
      "prescribed": [0]}, "contact row 1 touches prescribed dofs only"),
    ({"prescribed": [7]}, "prescribed dof 7 is outside 0..4"),
    ({"prescribed": [1, 1]}, "prescribed dof 1 is listed twice"),
    ({"prescribed": [1], "prescribed_values": [1.0, 2.0]}, "prescribed_values must have shape (1,)"),
    ({"kinds": ["inequality", "sideways"]}, "kinds must be one of inequality, equality"),
    ({"names": ["only one"]}, "names must be 2 strings"),
    ({"f": "loads"}, "f must be an array of numbers"),
]


@pytest.mark.parametrize(("changes", "message"), BAD, ids=[m for _, m in BAD])
def test_every_bad_input_is_one_line_naming_the_field(changes, message):
    with pytest.raises(ProblemError) as raised:
        contactqp.Problem(**arrays(**changes))
    text = str(raised.value)
    assert message in text and "\n" not in text
    assert isinstance(raised.value, SceneError)  # the handlers of bad input take it


def test_a_mode_nothing_holds_is_named_when_the_model_is_built():
    # no prescribed dof, no ground spring: the chain floats along the rigid translation, and
    # no contact row holds dofs 0..3 ... but row 0 touches dof 4, so the mode IS touched;
    # a second, separate pair of dofs 5, 6 joined by a spring and touched by nothing floats
    K = sp.block_diag((chain(), sp.csr_array(np.array([[1.0, -1.0], [-1.0, 1.0]])))).tocsr()
    problem = contactqp.Problem(K, np.zeros(7), sp.csr_array(np.eye(1, 7, 4)), [0.5])
    with pytest.raises(ProblemError, match="nothing holds the model along a mode") as raised:
        build_sparse_model(problem)
    assert "dof 5" in str(raised.value) and "dof 6" in str(raised.value)


@pytest.mark.parametrize("name", ["p.npz", "matrices"])
def test_files_give_back_the_same_problem(tmp_path, name):
    problem = contactqp.Problem(**arrays(), prescribed=[0], prescribed_values=[0.25],
                                kinds=["inequality", "equality"], names=["tip", "mid"],
                                units="N, mm", name="chain")
    path = contactqp.save_problem(problem, tmp_path / name)
    back = contactqp.load_problem(path)
    assert abs(back.K - problem.K).max() == 0.0 and abs(back.C - problem.C).max() == 0.0
    assert np.array_equal(back.f, problem.f) and np.array_equal(back.g, problem.g)
    assert back.kinds == problem.kinds and back.names == problem.names
    assert back.prescribed_values.tolist() == [0.25] and back.units == "N, mm"


def test_matrix_market_files_alone_make_a_problem(tmp_path):
    import scipy.io
    scipy.io.mmwrite(tmp_path / "K.mtx", sp.coo_matrix(chain()))
    scipy.io.mmwrite(tmp_path / "C.mtx", sp.coo_matrix(arrays()["C"]))
    scipy.io.mmwrite(tmp_path / "f.mtx", arrays()["f"].reshape(-1, 1))
    scipy.io.mmwrite(tmp_path / "g.mtx", arrays()["g"].reshape(-1, 1))
    problem = contactqp.load_problem(tmp_path, prescribed=[0])
    assert problem.n == 5 and problem.prescribed.tolist() == [0]


def test_missing_files_are_one_line(tmp_path):
    with pytest.raises(ProblemError, match="does not exist"):
        contactqp.load_problem(tmp_path / "nothing.npz")
    with pytest.raises(ProblemError, match="lacks K.mtx, f.mtx, C.mtx, g.mtx"):
        contactqp.load_problem(tmp_path)


def test_the_sparse_model_agrees_with_dense_algebra():
    problem = contactqp.Problem(**arrays(), prescribed=[0], prescribed_values=[0.1])
    model = build_sparse_model(problem)
    K = problem.K.toarray()
    free = [1, 2, 3, 4]
    P = problem.f[free] - K[np.ix_(free, [0])] @ [0.1]
    u0 = np.linalg.solve(K[np.ix_(free, free)], P)
    assert np.allclose(model.free_displacement, u0, rtol=1e-13, atol=1e-15)
    C = problem.C.toarray()[:, free]
    W = C @ np.linalg.solve(K[np.ix_(free, free)], C.T)
    assert np.allclose(model.flexibility(np.array([1, 0])), W[np.ix_([1, 0], [1, 0])],
                       rtol=1e-13)
    u = model.full_displacements(u0)
    assert u[0] == 0.1 and np.allclose(model.reactions(u), K[0] @ u - problem.f[0])
    # F: the largest load (1) against the prescribed motion's force K_10 · 0.1 = 0.1
    assert model.force_scale == 1.0
