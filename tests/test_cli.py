"""The command line end to end: the main job, solve --json, penalty-sweep, and bad input.

Glossary: F load (N) at node 2, g gap (m), f flexibility Σ L/(EA) from the support to the wall
node (m/N), f₂ the same up to the load node, λ = (F f₂ − g) / f the contact force (N).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest

from contactqp.cli import main

E, F, GAP = 210e9, 565486.67, 1e-4
DIAMETERS_MID = [0.0375, 0.0325, 0.0275, 0.0225]  # m, mid-length of 40 → 20 mm over 4 elements


def closed_form_force() -> float:
    flex = [0.25 / (E * math.pi * d**2 / 4) for d in DIAMETERS_MID]
    return (F * sum(flex[:2]) - GAP) / sum(flex)


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_main_job_prints_every_method_and_writes_charts(capsys, tmp_path):
    code, out, _ = run(capsys, "--out", str(tmp_path))
    assert code == 0
    rows = [line for line in out.splitlines() if line.startswith(("lagrange", "penalty", "qp"))]
    kinds = {(r.split()[0], "inequality" if " inequality " in r else "equality") for r in rows}
    assert kinds >= {(m, c) for m in ("lagrange", "penalty") for c in ("inequality", "equality")}
    lagrange = next(r for r in rows if r.startswith("lagrange") and " inequality " in r)
    # the table prints 10 significant digits: agreement to 1e-9 relative
    assert float(lagrange.split()[2]) == pytest.approx(closed_form_force(), rel=1e-9)
    assert "stress beyond yield" in out
    for name in ("bar.png", "penalty_sweep.png"):
        path = tmp_path / name
        assert f"chart: {path}" in out
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_solve_json_has_the_contract_keys_and_the_closed_form(capsys):
    code, out, _ = run(capsys, "solve", "--json")
    assert code == 0
    data = json.loads(out)
    for key in ("u", "contact_force", "reactions", "penetration", "verified", "residuals",
                "method", "time"):
        assert key in data
    assert data["method"] == "lagrange" and data["verified"] is True
    # an exact method: only round-off separates it from the closed form
    assert data["contact_force"][0] == pytest.approx(closed_form_force(), rel=1e-12)
    assert data["u"][4] == pytest.approx(GAP, rel=1e-12)
    assert data["reactions"][0] == pytest.approx(-(F - closed_form_force()), rel=1e-12)


@pytest.mark.parametrize(("formulation", "method"), [("condensed", "qp"), ("strain", "qp"),
                                                    ("strain", "lagrange")])
def test_solve_formulations_give_the_closed_form(capsys, formulation, method):
    code, out, _ = run(capsys, "solve", "--method", method, "--formulation", formulation,
                       "--json")
    assert code == 0
    data = json.loads(out)
    assert data["verified"] is True
    # Clarabel at default accuracy: ~3e-10 of the force (README accuracy table); exact: 1e-12
    assert data["contact_force"][0] == pytest.approx(closed_form_force(), rel=1e-8)
    if formulation == "strain":  # the tie rows' multipliers are the element forces
        assert data["info"]["element_force"][3] == pytest.approx(-closed_form_force(), rel=1e-8)


def test_solve_strain_with_the_penalty_method_is_one_line(capsys):
    code, _, err = run(capsys, "solve", "--method", "penalty", "--formulation", "strain")
    assert code == 2
    assert "formulation='strain'" in err and len(err.strip().splitlines()) == 1


def test_solve_equality_on_an_open_gap_reports_a_pulling_wall(capsys, tmp_path):
    scene = tmp_path / "open.toml"
    scene.write_text(
        "[material]\nyoungs_modulus = 210e9\n[bar]\nlength = 1.0\nareas = [1e-3, 1e-3]\n"
        "[[support]]\nnode = 0\n[[load]]\nnode = 2\nforce = 1000.0\n"
        "[[wall]]\nnode = 2\ngap = 1e-3\n"
    )
    code, out, err = run(capsys, "solve", str(scene), "--contact", "equality", "--json")
    assert code == 1  # an answer, but a wall pulls: the documented exit status
    assert "pulls" in err and len(err.strip().splitlines()) == 1
    data = json.loads(out)
    # u = g forced: the wall must pull with k·g − F, k = EA/L for the whole 1 m bar
    assert data["contact_force"][0] == pytest.approx(-(210e9 * 1e-3 * 1e-3 - 1000.0), rel=1e-12)
    assert data["physical"] is False and "pulls" in data["message"]
    code, out, _ = run(capsys, "solve", str(scene), "--json")
    assert code == 0
    data = json.loads(out)
    assert data["contact_force"] == [0.0]
    # the free tip moves F L/(EA) = 1000/(210e6) m, so the gap stays open by g − that
    assert data["penetration"][0] == pytest.approx(1000.0 / 210e6 - 1e-3, rel=1e-12)


def test_penalty_sweep_json_converges_then_loses_digits(capsys):
    code, out, _ = run(capsys, "penalty-sweep", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["penalty"][0] == 1.0 and data["penalty"][-1] == 1e20
    errors = data["force_error"]
    # while ε f << 1 is left behind, the error is 1/(1 + ε f): check it at ε = 1e12
    flexibility = sum(0.25 / (E * math.pi * d**2 / 4) for d in DIAMETERS_MID)
    i = data["penalty"].index(1e12)
    assert errors[i] == pytest.approx(1.0 / (1.0 + 1e12 * flexibility), rel=1e-6)
    assert 1e14 <= data["converged_up_to"] < 1e20
    assert data["verified"][data["penalty"].index(1e14)] is True


GOOD = {
    "material": "[material]\nyoungs_modulus = 1e9\n",
    "bar": "[bar]\nlength = 1.0\nareas = [1e-3, 1e-3]\n",
    "support": "[[support]]\nnode = 0\n",
}
BAD_SCENES = [  # (part replaced or added, its bad text, what the error line must name)
    ("material", "[material]\nyoungs_modulus = -1.0\n", "material.youngs_modulus"),
    ("material", "[material]\nyoungs_modulus = nan\n", "material.youngs_modulus"),
    ("bar", "[bar]\nlength = 1.0\nareas = [1e-3, 0.0]\n", "bar.areas[1]"),
    ("bar", "[bar]\nlength = inf\nareas = [1e-3]\n", "bar.length"),
    ("bar", "[bar\nlength = 1.0\n", "not valid TOML"),
    ("support", "", "no support"),
    ("support", "[[support]]\nnode = 3\n", "support[0].node = 3"),
    ("load", "[[load]]\nnode = 7\nforce = 1.0\n", "load[0].node = 7"),
    ("wall", "[[wall]]\nnode = 5\ngap = 0.0\n", "wall[0].node = 5"),
    ("wall", "[[wall]]\nnode = 1\ngap = 'near'\n", "wall[0].gap"),
]


@pytest.mark.parametrize(("part", "text", "expected"), BAD_SCENES)
def test_bad_scene_files_exit_2_with_one_line(capsys, tmp_path, part, text, expected):
    path = tmp_path / "bad.toml"
    path.write_text("".join({**GOOD, part: text}.values()))
    code, out, err = run(capsys, "solve", str(path))
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and expected in err
    assert "Traceback" not in err


def test_missing_file_and_unknown_method_exit_2(capsys, tmp_path):
    code, _, err = run(capsys, "solve", str(tmp_path / "nowhere.toml"))
    assert code == 2 and "does not exist" in err and "nowhere.toml" in err
    with pytest.raises(SystemExit) as stop:
        main(["solve", "--method", "magic"])
    assert stop.value.code == 2
    assert "magic" in capsys.readouterr().err


def test_bad_penalty_value_names_the_option(capsys):
    code, _, err = run(capsys, "solve", "--method", "penalty", "--penalty", "-5")
    assert code == 2 and "penalty" in err and "-5" in err


def test_python_dash_m_runs_the_cli():
    done = subprocess.run([sys.executable, "-m", "contactqp", "solve", "--json"],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["verified"] is True


def test_solvers_lists_installed_pairs_and_install_hints(capsys, monkeypatch):
    from contactqp.methods import qp

    code, out, _ = run(capsys, "solvers")
    assert code == 0
    installed = [f"{r.backend}/{r.solver}" for r in qp.available_qp_solvers() if r.available]
    assert installed and all(pair in out for pair in installed)
    monkeypatch.setitem(qp.BACKENDS, "osqp", None)  # as if osqp were not installed
    code, out, _ = run(capsys, "solvers")
    line = next(row for row in out.splitlines() if row.startswith("osqp/"))
    assert " no " in line and "pip install" in line
