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


def test_compare_of_a_problem_file_tables_every_method_and_draws_no_bars(tmp_path, capsys):
    path = pressed_chain(tmp_path)
    out = tmp_path / "charts"
    assert main(["compare", str(path), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert text.splitlines()[0].startswith("problem: ")  # what was read, before the table
    rows = [line for line in text.splitlines() if line.startswith(("lagrange ", "lemke "))]
    assert len(rows) >= 2 and all("0.875" in row and " yes " in row for row in rows)
    charts = {p.name for p in out.iterdir()}
    assert charts and all(name.endswith(".png") for name in charts)
    assert not any("bar" in name or "scene" in name for name in charts)  # no bars to draw


def test_penalty_sweep_of_a_problem_file_converges_to_the_closed_form(tmp_path, capsys):
    path = pressed_chain(tmp_path)
    assert main(["penalty-sweep", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    force = np.array([row[0] for row in data["contact_force"]])
    # the penalty force ε(1 − k g)/(k + ε), k = 1/4: below the exact 0.875, rising to it
    k, eps = 0.25, np.array(data["penalty"])
    low = eps <= 1e8  # past that the penalty solve loses digits, as the sweep says
    assert low.sum() >= 3
    np.testing.assert_allclose(force[low], eps[low] * (1.0 - k * 0.5) / (k + eps[low]),
                               rtol=1e-7)  # ≥ (ε/k)·2.2e-16, the solve's round-off
    assert data["reference_contact_force"] == [np.float64(0.875)] or abs(
        data["reference_contact_force"][0] - 0.875) < 1e-12
    assert main(["penalty-sweep", str(path), "--out", str(tmp_path / "o")]) == 0
    assert (tmp_path / "o" / "penalty_sweep.png").is_file()
    assert "ε" in capsys.readouterr().out


def test_curve_of_a_problem_file_follows_the_loaded_dof(tmp_path, capsys):
    path = pressed_chain(tmp_path)
    assert main(["curve", str(path), "--json", "--steps", "5"]) == 0
    data = json.loads(capsys.readouterr().out)
    t = np.array(data["load_factor"])
    tip = np.array(data["methods"]["lagrange"]["load_point_displacement"])
    # the tip moves 4t until it meets the wall at 0.5 (t = 1/8), then stays there
    np.testing.assert_allclose(tip, np.minimum(4.0 * t, 0.5), rtol=1e-9, atol=1e-12)
    assert main(["curve", str(path), "--out", str(tmp_path / "o")]) == 0
    text = capsys.readouterr().out
    assert "dof 3" in text.splitlines()[0] and (tmp_path / "o" / "load_path.png").is_file()
