"""The command line end to end (contactqp.cli): the main job, solve --json, penalty-sweep, curve,
bad input, exit statuses and units.

Glossary: F load (N) at node 2, g gap (m), f compliance Σ L/(EA) from the support to the wall
node (m/N), f₂ the same up to the load node, λ = (F f₂ − g) / f the contact force (N).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

import contactqp
from closed_forms import DEFAULT_E as E
from closed_forms import DEFAULT_F as F
from closed_forms import DEFAULT_GAP as GAP
from closed_forms import DEFAULT_SCENE
from contactqp.cli import main

EXAMPLES = sorted((Path(__file__).parent.parent / "examples").glob("*.toml"))

DIAMETERS_MID = [0.0375, 0.0325, 0.0275, 0.0225]  # m, mid-length of 40 → 20 mm over 4 elements


def closed_form_force() -> float:
    flex = [0.25 / (E * math.pi * d**2 / 4) for d in DIAMETERS_MID]
    return (F * sum(flex[:2]) - GAP) / sum(flex)


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


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


BAD_FILES = [  # (a scene file, words of the one error line)
    (("[material]\nyoungs_modulus = 2e11\n[bar]\nlength = 1.0\nareas = ['1e-3']\n"
     "[[support]]\nnode = 0\n"), ["bar.areas[0]", "'1e-3'"]),
    (("[material]\nyoungs_modulus = 2e11\n[bar]\nlength = 1.0\nareas = [true]\n"
     "[[support]]\nnode = 0\n"), ["bar.areas[0]", "True"]),
    (("[material]\nyoungs_modulus = true\n[bar]\nlength = 1.0\nareas = [1e-3]\n"
     "[[support]]\nnode = 0\n"), ["youngs_modulus", "True"]),
    (("[material]\nyoungs_modulus = 2e11\n[bar]\nlength = 1.0\nelements = 1000000000000\n"
     "section = { shape = 'circle', diameter_start = 0.04, diameter_end = 0.02 }\n"
     "[[support]]\nnode = 0\n"), ["bar.elements"]),
    (("units = 'cm'\n[material]\nyoungs_modulus = 2e11\n[bar]\nlength = 1.0\nareas = [1e-3]\n"
     "[[support]]\nnode = 0\n"), ["units", "'cm'"]),
    (("[material]\nyoungs_modulus = 2e11\n[bar]\nlength = 1.0\nareas = [1e-3]\n"
     "[[support]]\nnode = 0\n[[load]]\nnode = 1\nforce = 1e308\n"), ["load[0].force"]),
    (("[material]\nyoungs_modulus = 2e11\n[bar]\nlength = 1.0\nareas = [1e-3, 1e-3]\n"
     "[[support]]\nnode = 0\n[[wall]]\nnode = 1\ngap = 1e-4\nside = '+'\n"
     "[[wall]]\nnode = 1\ngap = -2e-4\nside = '-'\n"), ["wall[0]", "wall[1]", "node 1"]),
]


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
    for name in ("bar.png", "penalty_sweep.png", "nitsche_sweep.png", "mesh_convergence.png"):
        path = tmp_path / name
        assert f"chart: {path}" in out
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert max(len(line) for line in out.splitlines()) <= 120  # a compact table


def test_compare_of_a_scene_file_draws_that_scene_and_says_what_it_leaves(capsys, tmp_path):
    """The mesh convergence and Nitsche's sweep study the default scene: a scene file's
    comparison draws its own bar and penalty sweep, not them (they were the same files for
    every scene), and says so."""
    scene = next(path for path in EXAMPLES if path.name == "two_bars.toml")
    code, out, _ = run(capsys, "compare", str(scene), "--out", str(tmp_path))
    assert code == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bar.png", "penalty_sweep.png"]
    assert "study the default scene" in out
    assert "two bars" in out.splitlines()[0]


def test_compare_detail_lists_every_contact(capsys):
    """--detail: a line per run and contact row (the two-spring closed form, 6000 N, as the
    exact force), and per support."""
    scene = next(path for path in EXAMPLES if path.name == "two_bars.toml")
    code, out, _ = run(capsys, "compare", str(scene), "--no-charts", "--detail")
    assert code == 0
    lagrange = [line.split() for line in out.splitlines()
                if line.startswith("lagrange ") and "inequality" in line and "[" in line]
    contact = next(row for row in lagrange if row[2] == "contact[0]")
    assert float(contact[3]) == pytest.approx(6000.0, rel=1e-12) and contact[4] == "6000"
    assert [row[2] for row in lagrange if row[2].startswith("support")] == ["support[0]",
                                                                           "support[1]"]
    code, plain, _ = run(capsys, "compare", str(scene), "--no-charts")
    assert "contact[0]" not in plain


@pytest.mark.parametrize(("argv", "written"), [
    (["--out", "{out}", "compare", "--no-charts"], []),
    (["--out", "{out}", "--no-charts"], []),  # the main job
    (["penalty-sweep", "--out", "{out}", "--no-charts"], []),
    (["penalty-sweep", "--out", "{out}"], ["penalty_sweep.png"]),
    (["penalty-sweep", "--out", "{out}", "--json"], []),  # JSON instead of table and chart
    (["curve", "--steps", "3", "--out", "{out}", "--no-charts"], []),
    (["curve", "--steps", "3", "--out", "{out}"], ["load_path.png"]),
    (["solve"], []),  # solve draws only when asked: nothing, not even in the cwd
    (["solve", "--out", "{out}"], ["bar.png"]),
    (["--no-charts", "solve", "--out", "{out}"], []),
])
def test_every_chart_option_does_what_it_says(capsys, tmp_path, monkeypatch, argv, written):
    """--out (before or after the command), --no-charts and --json, run in an empty folder:
    exactly the charts asked for are written, and only into --out."""
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "charts"
    assert main([a.replace("{out}", str(out)) for a in argv]) == 0
    capsys.readouterr()
    found = sorted(p.name for p in out.iterdir()) if out.exists() else []
    assert found == written
    assert [p.name for p in tmp_path.iterdir() if p != out] == []  # nothing in the cwd


def test_out_given_before_the_command_is_used(capsys, tmp_path):
    """`contactqp --out DIR curve` wrote into contactqp-out/: the command's own default hid
    the value given before it."""
    assert main(["--out", str(tmp_path / "before"), "curve", "--steps", "3"]) == 0
    assert main(["curve", "--steps", "3", "--out", str(tmp_path / "after")]) == 0
    capsys.readouterr()
    assert (tmp_path / "before" / "load_path.png").exists()
    assert (tmp_path / "after" / "load_path.png").exists()


def test_solve_detail_and_json_with_out(capsys, tmp_path):
    """solve --detail lists the wall's force and the support's reaction (the closed form);
    solve --json --out keeps stdout JSON and names the chart on stderr."""
    code, out, _ = run(capsys, "solve", "--detail")
    assert code == 0
    wall = next(line.split() for line in out.splitlines() if " wall[0] " in line)
    assert float(wall[3]) == pytest.approx(closed_form_force(), rel=1e-9)  # 10 digits
    support = next(line.split() for line in out.splitlines() if " support[0] " in line)
    assert float(support[3]) == pytest.approx(-(F - closed_form_force()), rel=1e-9)
    code, out, err = run(capsys, "solve", "--json", "--out", str(tmp_path))
    assert code == 0 and json.loads(out)["verified"] is True
    assert f"chart: {tmp_path / 'bar.png'}" in err and (tmp_path / "bar.png").exists()


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
    # Clarabel at default accuracy: ~3e-10 of the force (the accuracy table of docs/howto/qp_solvers.md); exact: 1e-12
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


def test_penalty_sweep_table_has_the_augmented_method(capsys):
    """Each ε's row has the augmented method's force, error, updates and verdict; at ε = 1 N/m
    it stops at its cap of 100 updates (each shrinks the error by 1/(1 + ε f) ≈ 1 − 1e-8)."""
    code, out, _ = run(capsys, "penalty-sweep", "--no-charts")
    assert code == 0
    header = out.splitlines()[1]
    assert "augmented force" in header and "updates" in header
    first = out.splitlines()[4].split()
    assert first[0] == "1e+00" and first[-3:] == ["100", "(cap)", "NO"]
    assert "augmented Lagrangian: verified from ε = " in out


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
    monkeypatch.setitem(qp._LOADED, "osqp", None)  # as if osqp were not installed
    code, out, _ = run(capsys, "solvers")
    line = next(row for row in out.splitlines() if row.startswith("osqp/"))
    assert " no " in line and "pip install" in line


@pytest.mark.parametrize(("text", "words"), BAD_FILES)
def test_bad_scene_files_are_one_line_and_exit_2(capsys, tmp_path, text, words):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    code = main(["solve", str(path)])
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    for word in words:
        assert word in err, err


def test_an_impossible_scene_file_exits_2_from_compare(capsys, tmp_path):
    path = tmp_path / "impossible.toml"
    path.write_text(BAD_FILES[-1][0])
    code = main(["compare", str(path), "--no-charts"])
    _, err = capsys.readouterr()
    assert code == 2 and "no position" in err and "Traceback" not in err


def test_solve_exits_1_when_the_answer_fails_its_check(capsys):
    code = main(["solve", "--method", "penalty", "--penalty", "1e8"])
    out, err = capsys.readouterr()
    assert code == 1
    assert "not verified" in err and "residual" in err and len(err.strip().splitlines()) == 1
    assert "NO" in out  # the table still shows the answer


def test_solve_exits_0_when_verified(capsys):
    assert main(["solve", "--method", "penalty"]) == 0


def test_studies_exit_0_with_failing_rows_and_say_so(capsys):
    assert main(["penalty-sweep", "--no-charts"]) == 0  # ε = 1 fails its check on purpose
    out, _ = capsys.readouterr()
    assert "NO" in out
    with pytest.raises(SystemExit):
        main(["compare", "--help"])
    assert "exit status 0 when the table is produced" in capsys.readouterr().out


def test_an_unexpected_error_is_one_line_and_exit_3(capsys, monkeypatch):
    from contactqp import cli_commands

    def broken(*args, **kwargs):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(cli_commands, "solve", broken)
    code = main(["solve"])
    _, err = capsys.readouterr()
    assert code == 3 and len(err.strip().splitlines()) == 1
    assert "internal error: ZeroDivisionError" in err and "bug" in err
    assert "Traceback" not in err


def test_help_documents_the_exit_statuses(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    assert all(f"{code}:" in out for code in (0, 1, 2, 3))


def test_version_is_the_packages_version(capsys):
    """contactqp --version prints the version the package was installed as (its metadata,
    written from pyproject.toml), exits 0 and solves nothing."""
    from importlib.metadata import version

    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"contactqp {version('contactqp')}"


def test_what_is_printed_and_written_is_in_the_scenes_units(capsys, tmp_path):
    path = tmp_path / "mm.toml"
    path.write_text(contactqp.scene_to_toml(contactqp.convert_units(DEFAULT_SCENE, "mm-N-MPa")))
    assert main(["solve", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["units"] == "mm-N-MPa"
    assert data["penetration"][0] == pytest.approx(
        contactqp.solve(DEFAULT_SCENE).penetration[0] * 1e3, abs=1e-12)
    assert main(["solve", str(path)]) == 0
    names, units = capsys.readouterr().out.splitlines()[:2]
    # the units line sits under the names: contact force in N, penetration in mm
    assert units[names.index("contact force"):].split()[:2] == ["(N)", "(mm)"]
    assert main(["penalty-sweep", str(path), "--no-charts"]) == 0
    out = capsys.readouterr().out
    assert "(N/mm)" in out.splitlines()[2] and "N/mm (force error" in out


def test_curve_cli_json(capsys):
    assert main(["curve", "--steps", "4", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["load_factor"] == pytest.approx([0, 1 / 3, 2 / 3, 1])
    for name in ("lagrange", "equality", "penalty", "qp"):
        entry = data["methods"][name]
        assert len(entry["load_point_displacement"]) == 4
        assert [len(row) for row in entry["contact_force"]] == [1] * 4
        assert [len(row) for row in entry["penetration"]] == [1] * 4
    assert main(["curve", "--steps", "1"]) == 2
    assert "steps must be a whole number >= 2" in capsys.readouterr().err


def test_curve_cli_table_and_chart(tmp_path, capsys):
    assert main(["curve", "--steps", "3", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "first contact closes at t = 0.0703" in out
    assert (tmp_path / "load_path.png").stat().st_size > 0


def test_the_complementarity_options_reach_their_methods(capsys):
    """--relaxation, --max-iterations: one PSOR sweep on the default scene is not the answer
    (exit 1, flagged); --ncp picks Newton's NCP function (the Result says which)."""
    code, out, _ = run(capsys, "solve", "--method", "pgs", "--relaxation", "1.5",
                       "--max-iterations", "1", "--json")
    data = json.loads(out)
    assert code == 1 and data["info"]["relaxation"] == 1.5 and data["iterations"] == 1
    assert data["verified"] is False
    code, out, _ = run(capsys, "solve", "--method", "semismooth_newton", "--ncp",
                       "fischer-burmeister", "--json")
    assert code == 0 and json.loads(out)["info"]["ncp"] == "fischer-burmeister"
    code, _, err = run(capsys, "solve", "--method", "pgs", "--relaxation", "2.5")
    assert code == 2 and "relaxation must be in (0, 2)" in err


@pytest.mark.parametrize(("argv", "solver", "options"), [
    (["--method", "qp", "--backend", "osqp"], "osqp", {"backend": "osqp"}),
    (["--method", "qp", "--backend", "qpsolvers", "--solver", "daqp"], "qpsolvers/daqp",
     {"backend": "qpsolvers", "solver": "daqp"}),
    (["--method", "qp", "--accuracy", "high"], "clarabel", {"accuracy": "high"}),
    (["--method", "qp", "--scale", "off"], "clarabel", {"scale": False}),
    (["--method", "augmented", "--tolerance", "1e-6"], "augmented", {"tolerance": 1e-6}),
])
def test_the_solver_options_reach_the_result(capsys, argv, solver, options):
    """Each QP and tolerance option of solve arrives in the Result (its solver and options)."""
    if options.get("solver") == "daqp":
        pytest.importorskip("daqp", reason="daqp is an optional solver: pip install daqp")
    code, out, _ = run(capsys, "solve", *argv, "--json")
    data = json.loads(out)
    assert code == 0 and data["solver"] == solver and data["options"] == options


@pytest.mark.parametrize(("argv", "solver", "options"), [
    (["--method", "nitsche", "--gamma0", "3", "--theta", "-1"], "nitsche",
     {"gamma0": 3.0, "theta": -1.0}),
    (["--method", "lagrange", "--active-set", "passed"], "lagrange", {"active_set": "passed"}),
])
def test_the_method_options_reach_the_result(capsys, argv, solver, options):
    code, out, _ = run(capsys, "solve", *argv, "--json")
    data = json.loads(out)
    assert code == 0 and data["solver"] == solver and data["options"] == options


def test_every_method_option_is_a_flag_of_solve():
    """Whatever a user can pass to a method from Python, the command line can pass too."""
    from contactqp.cli import parser
    from contactqp.methods import METHODS

    solve_parser = parser()._subparsers._group_actions[0].choices["solve"]
    flags = {flag for action in solve_parser._actions for flag in action.option_strings}
    wanted = {"--" + name.replace("_", "-") for m in METHODS.values() for name in m.options}
    assert wanted - flags == set()


@pytest.mark.parametrize(("argv", "words"), [
    (["solve", "--method", "pgs", "--tolerance", "-1e-3"], ["tolerance", "-0.001"]),
    (["solve", "--method", "penalty", "--penalty", "-1e6"], ["penalty", "-1000000.0"]),
    (["solve", "--method", "penalty", "--penalty", "1e300"], ["penalty = 1e+300",
                                                             "outside the range"]),
    (["solve", "--method", "nitsche", "--gamma0", "1e300"], ["gamma0 = 1e+300"]),
    (["solve", "--method", "nitsche", "--theta", "0.5"], ["theta must be one of 1, 0, -1"]),
    (["curve", "--steps", "-5"], ["steps", "-5"]),
    (["curve", "--steps", "100000000"], ["steps = 100000000", "10000 times at most"]),
])
def test_a_negative_or_huge_number_reaches_its_check(capsys, argv, words):
    """argparse read ``-1e-3`` as an option ("expected one argument"); each value now reaches
    the check that names it, and 1e300 is out of range as a scene number would be."""
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    for word in words:
        assert word in err


@pytest.mark.parametrize(("out", "words"), [
    ("/dev/null", ["--out '/dev/null'", "is a file, not a folder"]),
    ("{file}", ["is a file, not a folder"]),
    ("{file}/charts", ["is a file, not a folder"]),  # its parent is the file
    ("/proc/contactqp-charts", ["--out '/proc/contactqp-charts'", "cannot be written"]),
])
@pytest.mark.parametrize("command", [[], ["compare"], ["penalty-sweep"], ["curve"], ["solve"]])
def test_an_out_that_cannot_take_the_charts_is_refused_before_anything_runs(
        capsys, monkeypatch, tmp_path, out, words, command):
    """--out at a file or a place that cannot be written: exit 2 and one line naming it,
    before the comparison (or any solve) runs; it was exit 3 after the whole comparison."""
    from contactqp import cli_commands

    def never(*args, **kwargs):
        raise AssertionError("ran before --out was checked")

    for name in ("compare", "penalty_sweep", "solve", "as_scene"):
        monkeypatch.setattr(cli_commands, name, never)
    file = tmp_path / "a_file"
    file.write_text("")
    code, printed, err = run(capsys, *command, "--out", out.replace("{file}", str(file)))
    assert code == 2 and printed == "" and len(err.strip().splitlines()) == 1
    for word in words:
        assert word in err


def test_an_out_with_missing_parents_is_made(capsys, tmp_path):
    out = tmp_path / "not" / "yet" / "there"
    assert main(["solve", "--out", str(out)]) == 0
    capsys.readouterr()
    assert (out / "bar.png").stat().st_size > 0


def test_a_bad_scene_with_an_out_to_be_made_leaves_no_folder(capsys, tmp_path):
    out = tmp_path / "charts" / "deep"
    assert main(["compare", str(tmp_path / "missing.toml"), "--out", str(out)]) == 2
    capsys.readouterr()
    assert not (tmp_path / "charts").exists()


def test_a_scene_file_with_units_as_a_list_exits_2(capsys, tmp_path):
    path = tmp_path / "units.toml"
    path.write_text("units = []\n" + "".join(GOOD.values()), encoding="utf-8")
    code, _, err = run(capsys, "solve", str(path))
    assert code == 2 and "units must be one of 'SI', 'mm-N-MPa', got []" in err


def test_verbose_lets_the_solver_print(capfd):
    """--verbose: OSQP's banner (the solver's own C code) on stdout, or with --json on stderr,
    so that the JSON is JSON alone; without --verbose, silence."""
    assert main(["solve", "--method", "qp", "--backend", "osqp", "--verbose"]) == 0
    assert "OSQP" in capfd.readouterr().out
    assert main(["solve", "--method", "qp", "--backend", "osqp", "--verbose", "--json"]) == 0
    out, err = capfd.readouterr()
    assert "OSQP" in err and json.loads(out)["solver"] == "osqp"
    assert main(["solve", "--method", "qp", "--backend", "osqp", "--json"]) == 0
    out, err = capfd.readouterr()
    assert "OSQP" not in out.replace('"osqp"', "") and err == ""


def test_penalty_sweep_contact_option(capsys):
    """--contact equality: the sweep of the textbook form (the same force on the default
    scene, where the wall pushes: the closed form λ)."""
    code, out, _ = run(capsys, "penalty-sweep", "--contact", "equality", "--json")
    assert code == 0
    assert json.loads(out)["reference_contact_force"][0] == pytest.approx(closed_form_force(),
                                                                       rel=1e-12)
    code, out, _ = run(capsys, "penalty-sweep", "--contact", "equality", "--no-charts")
    assert "equality contact" in out.splitlines()[0]


@pytest.mark.parametrize("argv", [["curve", "--steps", "3"], ["penalty-sweep"], ["compare"]])
def test_a_long_run_shows_its_progress_on_stderr(capsys, monkeypatch, argv):
    """Past PROGRESS_AFTER seconds (here 0, so that no test waits) a run says on stderr how
    far it is, and ends with "done"; the table on stdout is unchanged."""
    from contactqp import cli_commands

    monkeypatch.setattr(cli_commands, "PROGRESS_AFTER", 0.0)
    code, out, err = run(capsys, *argv, "--no-charts")
    assert code == 0 and out
    lines = err.splitlines()
    assert lines and all(line.startswith("contactqp: ") and " of " in line for line in lines)
    assert lines[-1].endswith("done")


def test_an_unloaded_bar_between_two_zero_gap_walls_is_solved_at_zero(capsys, tmp_path):
    """Its place is forced (u = 0) though nothing presses it: exit 0, no contact force."""
    path = tmp_path / "wedged.toml"
    path.write_text("[material]\nyoungs_modulus = 2e11\n[bar]\nlength = 1.0\narea = 1e-4\n"
                    "elements = 2\n[[wall]]\nnode = 2\ngap = 0.0\n[[wall]]\nnode = 2\n"
                    "gap = 0.0\nside = \"-\"\n", encoding="utf-8")
    code, out, _ = run(capsys, "solve", str(path), "--json")
    data = json.loads(out)
    assert code == 0 and data["u"] == [0.0, 0.0, 0.0] and data["contact_force"] == [0.0, 0.0]


def test_an_empty_scene_path_exits_2_saying_so(capsys):
    code, out, err = run(capsys, "solve", "")
    assert code == 2 and out == "" and err == "contactqp: error: scene file path is empty ('')\n"


def test_a_scene_file_that_starts_with_a_byte_order_mark_is_read(capsys, tmp_path):
    """Some editors write a UTF-8 byte-order mark: it was "Invalid statement (line 1,
    column 1)" with no word of the mark."""
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + "".join(GOOD.values()).encode("utf-8"))
    code, _, err = run(capsys, "solve", str(path))
    assert code == 0 and err == ""
