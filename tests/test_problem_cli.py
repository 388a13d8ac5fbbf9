"""``contactqp solve problem.npz``: the table, JSON and exit codes of a scene, for a problem."""

import json

import numpy as np
import scipy.sparse as sp

import contactqp
from contactqp.cli import main


def pressed_chain(tmp_path, gap: float = 0.5):
    """Four unit springs in a chain from a support, a load of 1 at the tip and a wall
    ``gap`` beyond it: the tip moves 4 without the wall, so it closes the gap and the wall
    pushes with 1 − gap/4 (the spring chain's stiffness is 1/4)."""
    n = 4
    K = sp.diags_array([-np.ones(n - 1), 2.0 * np.ones(n), -np.ones(n - 1)], offsets=[-1, 0, 1])
    K = sp.lil_array(K)
    K[n - 1, n - 1] = 1.0
    C = sp.csr_array(([1.0], ([0], [n - 1])), shape=(1, n))
    problem = contactqp.Problem(sp.csr_array(K), np.eye(n)[n - 1], C, [gap])
    return contactqp.save_problem(problem, tmp_path / "chain.npz")


def test_solve_a_problem_file_prints_the_table_and_exits_0(tmp_path, capsys):
    path = pressed_chain(tmp_path)
    assert main(["solve", str(path)]) == 0
    out = capsys.readouterr().out
    assert "lagrange" in out and "yes" in out
    assert "0.875" in out  # 1 − 0.5/4, the closed form of the docstring


def test_solve_a_problem_as_json(tmp_path, capsys):
    path = pressed_chain(tmp_path)
    assert main(["solve", str(path), "--method", "penalty", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert abs(data["contact_force"][0] - 0.875) < 1e-6 and data["verified"]


def test_bad_input_exits_2_with_one_line(tmp_path, capsys):
    path = pressed_chain(tmp_path)
    assert main(["solve", str(path), "--method", "nitsche"]) == 2
    err = capsys.readouterr().err
    assert "nitsche needs the traction" in err and err.count("\n") == 1
    assert main(["solve", str(tmp_path / "none.npz")]) == 2
    assert "does not exist" in capsys.readouterr().err
