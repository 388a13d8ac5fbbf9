"""What a user can get wrong, and what a user sees: every bad input one clear line, impossible
scenes refused with the constraints that conflict, exit statuses that say whether the answer
holds, solvers that print nothing, and units.

Each bad input names its field (or option) and its value, raises a ContactqpError from Python
and ends the command line with one line on stderr and exit status 2; none reaches a traceback.
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import contactqp
from contactqp import Bar, BarContact, Load, Scene, Support, Wall
from contactqp.cli import main
from contactqp.random_scenes import random_scene

SEED = contactqp.seed_scene()
BAR = Bar.from_areas([1e-4, 1e-4], 2e11, length=2.0)


def two_bars(walls, contacts) -> Scene:
    return Scene((BAR, BAR), (Support(0, 0), Support(2, 1)), (), walls, contacts=contacts)


# --------------------------------------------------------------------------------------------
# Bad input from Python: one ContactqpError naming the field and the value

BAD_CALLS = [  # (what, call, words the message must contain)
    ("E as text", lambda: Bar.from_areas([1e-4], "210e9", length=1.0),
     ["youngs_modulus", "'210e9'"]),
    ("area a boolean", lambda: Bar.from_areas([True], 2e11, length=1.0), ["bar.areas[0]", "True"]),
    ("area as text", lambda: Bar.from_areas([1e-4, "1e-4"], 2e11, length=1.0),
     ["bar.areas[1]", "'1e-4'"]),
    ("max_iterations text", lambda: contactqp.solve(SEED, max_iterations="abc"),
     ["max_iterations", "'abc'"]),
    ("max_iterations NaN", lambda: contactqp.solve(SEED, max_iterations=math.nan),
     ["max_iterations", "nan"]),
    ("max_iterations 2.5", lambda: contactqp.solve(SEED, "penalty", max_iterations=2.5),
     ["max_iterations", "2.5"]),
    ("max_iterations 0", lambda: contactqp.solve(SEED, max_iterations=0), ["max_iterations", "0"]),
    ("max_iterations -1", lambda: contactqp.solve(SEED, "augmented", max_iterations=-1),
     ["max_iterations", "-1"]),
    ("tolerance -1", lambda: contactqp.solve(SEED, "augmented", tolerance=-1),
     ["tolerance", "-1"]),
    ("tolerance NaN", lambda: contactqp.solve(SEED, "augmented", tolerance=math.nan),
     ["tolerance", "nan"]),
    ("tolerance text", lambda: contactqp.solve(SEED, "augmented", tolerance="x"),
     ["tolerance", "'x'"]),
    ("penalty True", lambda: contactqp.solve(SEED, "penalty", penalty=True), ["penalty", "True"]),
    ("method a list", lambda: contactqp.solve(SEED, ["lagrange"]), ["method", "['lagrange']"]),
    ("scene a number", lambda: contactqp.solve(3), ["scene", "int"]),
    ("verbose text", lambda: contactqp.solve(SEED, "qp", verbose="yes"), ["verbose", "'yes'"]),
    ("too many elements", lambda: Bar.tapered_circle(1.0, 10**12, 0.04, 0.02, 2e11),
     ["bar.elements", "1000000000000"]),
    ("E 1e300", lambda: Bar.from_areas([1e10], 1e300, length=1.0),
     ["youngs_modulus", "1e+300"]),
    ("load 1e308", lambda: SEED.with_loads((Load(2, 1e308),)), ["load[0].force", "1e+308"]),
    ("name a number", lambda: Scene(BAR, (Support(0),), name=3), ["name", "3"]),
    ("units unknown", lambda: Scene(BAR, (Support(0),), units="inch"), ["units", "'inch'"]),
    ("check with a short u", lambda: contactqp.check(SEED, [0.0], [0.0], [0.0], "inequality"),
     ["u", "5"]),
]


@pytest.mark.parametrize(("what", "call", "words"), BAD_CALLS, ids=[c[0] for c in BAD_CALLS])
def test_bad_python_input_is_one_clear_error(what, call, words):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning on the way either
        with pytest.raises(contactqp.ContactqpError) as error:
            call()
    message = str(error.value)
    assert "\n" not in message
    for word in words:
        assert word in message, message


def test_solve_reads_a_scene_file_given_its_path(tmp_path):
    path = tmp_path / "seed.toml"
    path.write_text(contactqp.scene_to_toml(SEED))
    by_path = contactqp.solve(str(path))
    assert by_path.contact_force.tolist() == contactqp.solve(SEED).contact_force.tolist()
    assert by_path.scene.name == SEED.name


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


# --------------------------------------------------------------------------------------------
# Impossible scenes: the difference constraints have a negative cycle


@pytest.mark.parametrize(("plus", "minus"), [(-1e-4, -1e-4), (1e-4, -2e-4)])
def test_walls_that_leave_a_node_no_position_are_refused(plus, minus):
    """"+" wall: u <= plus; "−" wall: u >= −minus. No u when plus + minus < 0 (two press fits,
    or u <= 1e-4 and u >= 2e-4)."""
    with pytest.raises(contactqp.SceneError) as error:
        SEED.with_walls((Wall(4, plus, "+"), Wall(4, minus, "-")))
    message = str(error.value)
    assert f"wall[0] (u ≤ {plus:g} m at node 4)" in message
    assert f"wall[1] (u ≥ {-minus:g} m at node 4)" in message
    assert "no position" in message


def test_walls_that_just_clamp_a_node_are_a_scene():
    """plus + minus = 0: one position, u = plus, which both walls allow."""
    scene = SEED.with_walls((Wall(4, 1e-4, "+"), Wall(4, -1e-4, "-")))
    result = contactqp.solve(scene)
    assert result.u[4] == pytest.approx(1e-4, rel=1e-12)  # held at the one position
    assert result.verified


def test_a_conflict_through_a_bar_contact_names_every_constraint():
    """bar 0 node 2 pushed to u <= −1e-4, bar 1 node 0 to u >= 2e-4, and the contact
    u(1, 0) − u(0, 2) <= 0: 2e-4 <= u(1, 0) <= u(0, 2) <= −1e-4, impossible by 3e-4."""
    with pytest.raises(contactqp.SceneError) as error:
        two_bars((Wall(2, -1e-4, "+", 0), Wall(0, -2e-4, "-", 1)), (BarContact(1, 0, 0, 2, 0.0),))
    message = str(error.value)
    for name in ("wall[0]", "wall[1]", "contact[0]"):
        assert name in message
    assert "0 ≤ -0.0003 m" in message


def test_the_same_walls_with_room_are_a_scene():
    scene = two_bars((Wall(2, -1e-4, "+", 0), Wall(0, 2e-4, "-", 1)), (BarContact(1, 0, 0, 2, 0.0),))
    assert contactqp.solve(scene).verified


def test_equality_through_a_bar_contact_that_fixes_a_node_twice_is_refused():
    scene = two_bars((Wall(2, 1e-4, "+", 0), Wall(0, 1e-4, "-", 1)), (BarContact(1, 0, 0, 2, 0.0),))
    with pytest.raises(contactqp.OptionError) as error:
        contactqp.solve(scene, contact="equality")
    assert all(name in str(error.value) for name in ("wall[0]", "wall[1]", "contact[0]"))


def test_an_impossible_scene_file_exits_2_from_compare(capsys, tmp_path):
    path = tmp_path / "impossible.toml"
    path.write_text(BAD_FILES[-1][0])
    code = main(["compare", str(path), "--no-charts"])
    _, err = capsys.readouterr()
    assert code == 2 and "no position" in err and "Traceback" not in err


# --------------------------------------------------------------------------------------------
# Exit statuses


def test_solve_exits_1_when_the_answer_fails_its_check(capsys):
    code = main(["solve", "--method", "penalty", "--penalty", "1e8"])
    out, err = capsys.readouterr()
    assert code == 1
    assert "not verified" in err and "residual" in err and len(err.strip().splitlines()) == 1
    assert "NO" in out  # the table still shows the answer


def test_solve_exits_0_when_verified(capsys):
    assert main(["solve", "--method", "penalty"]) == 0


def test_studies_exit_0_with_failing_rows_and_say_so(capsys):
    assert main(["penalty-sweep"]) == 0  # ε = 1 fails its check on purpose
    out, _ = capsys.readouterr()
    assert "NO" in out
    with pytest.raises(SystemExit):
        main(["compare", "--help"])
    assert "exit status 0 when the table is produced" in capsys.readouterr().out


def test_an_unexpected_error_is_one_line_and_exit_3(capsys, monkeypatch):
    from contactqp import cli

    def broken(*args, **kwargs):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(cli, "solve", broken)
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


# --------------------------------------------------------------------------------------------
# Silence


SOLVERS = [s for s in contactqp.available_qp_solvers() if s.available]


@pytest.mark.parametrize("info", SOLVERS, ids=[f"{s.backend}-{s.solver}" for s in SOLVERS])
def test_no_solver_prints_anything(capfd, info):
    """On an open gap (OSQP's "Polishing not needed") and on the default scene, at both
    accuracies, through file descriptors 1 and 2 (C code included)."""
    for scene in (SEED.with_walls((Wall(4, 2e-3),)), SEED):
        for accuracy in ("default", "high"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # Python warnings are not printing
                contactqp.solve(scene, "qp", backend=info.backend, solver=info.solver,
                                accuracy=accuracy)
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_verbose_lets_the_solver_talk(capfd):
    contactqp.solve(SEED, "qp", backend="osqp", verbose=True)
    out, _ = capfd.readouterr()
    assert "OSQP" in out


# --------------------------------------------------------------------------------------------
# Units


def test_a_scene_file_declares_its_units(tmp_path):
    """The default scene in mm, N, MPa: lengths in mm, areas in mm², E in MPa, gaps in mm."""
    text = contactqp.scene_to_toml(contactqp.convert_units(SEED, "mm-N-MPa"))
    assert 'units = "mm-N-MPa"' in text
    path = tmp_path / "mm.toml"
    path.write_text(text)
    scene = contactqp.load_scene(path)
    assert scene.units == "mm-N-MPa"
    assert scene.walls[0].gap == pytest.approx(0.1, rel=1e-15)  # 0.1 mm
    assert scene.bar.youngs_modulus[0] == pytest.approx(210e3, rel=1e-15)  # MPa
    assert scene.bar.lengths.sum() == pytest.approx(1000.0, rel=1e-15)  # mm


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 2**32 - 1))
def test_every_method_gives_the_same_physical_answer_in_both_unit_systems(seed):
    """The same scene in SI and in mm-N-MPa: forces in N alike, displacements 1000 times
    larger in mm. Every method and installed solver at its defaults gives the same answer in
    both, to within the two Results' own error bounds, and the same verdict where the answer is
    clear of the tolerances (the verdicts may only differ within a factor 10 of them)."""
    scene = random_scene(np.random.default_rng(seed), max_bars=2)
    mm = contactqp.convert_units(scene, "mm-N-MPa")
    runs = [("lagrange", {}), ("penalty", {}), ("augmented", {})]
    runs += [("qp", {"backend": s.backend, "solver": s.solver}) for s in SOLVERS]
    for method, options in runs:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                si, in_mm = (contactqp.solve(s, method, **options) for s in (scene, mm))
            except contactqp.SolverError:  # a method that fails says so (an active-set cycle)
                continue
        if not (si.verified and in_mm.verified):
            margin = max(si.residuals["force"], in_mm.residuals["force"],
                         si.residuals["displacement"], in_mm.residuals["displacement"])
            assert si.verified == in_mm.verified or 1e-6 <= margin <= 1e-4 or not (
                np.isfinite(si.u).all() and np.isfinite(in_mm.u).all()), (method, options)
            continue
        assert in_mm.force_scale == pytest.approx(si.force_scale, rel=1e-12)
        # U = ‖K⁻¹P‖: one solve with K, whose condition on these scenes (areas over five
        # decades) reaches ~1e10: 1e-6 covers its round-off in either unit system
        assert in_mm.displacement_scale == pytest.approx(1e3 * si.displacement_scale, rel=1e-6)
        assert np.abs(in_mm.contact_force - si.contact_force).max(initial=0.0) <= (
            si.force_error_bound + in_mm.force_error_bound + 1e-12 * si.force_scale)
        assert np.abs(in_mm.u / 1e3 - si.u).max() <= (
            si.displacement_error_bound + in_mm.displacement_error_bound / 1e3
            + 1e-12 * si.displacement_scale)


def test_the_penalty_default_is_the_same_physical_stiffness_in_both(capsys):
    si = contactqp.solve(SEED, "penalty")
    mm = contactqp.solve(contactqp.convert_units(SEED, "mm-N-MPa"), "penalty")
    assert mm.info["penalty"] == pytest.approx(si.info["penalty"] / 1e3, rel=1e-12)  # N/mm
    assert si.verified == mm.verified is True
    # the same ε/s = 1e8 in both; K rounds differently in each: ε/s × 1e-16 = 1e-8 apart
    assert mm.contact_force[0] == pytest.approx(si.contact_force[0], rel=1e-8)


def test_what_is_printed_and_written_is_in_the_scenes_units(capsys, tmp_path):
    path = tmp_path / "mm.toml"
    path.write_text(contactqp.scene_to_toml(contactqp.convert_units(SEED, "mm-N-MPa")))
    assert main(["solve", str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["units"] == "mm-N-MPa"
    assert data["penetration"][0] == pytest.approx(
        contactqp.solve(SEED).penetration[0] * 1e3, abs=1e-12)
    assert main(["solve", str(path)]) == 0
    out = capsys.readouterr().out
    assert "penetration (mm)" in out and "contact force (N)" in out
    assert main(["penalty-sweep", str(path), "--no-charts"]) == 0
    out = capsys.readouterr().out
    assert "ε (N/mm)" in out and "N/mm (force error" in out


def test_the_yield_check_works_in_both_unit_systems():
    """Element 1 carries F − λ (the wall takes λ, the support the rest) over its mid-length
    circle of 32.5 mm: 469.7 MPa against 200 MPa, in both unit systems."""
    E, F, gap = 210e9, 565486.67, 1e-4
    flexibility = [0.25 / (E * math.pi * d**2 / 4) for d in (0.0375, 0.0325, 0.0275, 0.0225)]
    lam = (F * sum(flexibility[:2]) - gap) / sum(flexibility)
    stress = (F - lam) / (math.pi * 0.0325**2 / 4)  # Pa
    for units in ("SI", "mm-N-MPa"):
        result = contactqp.solve(contactqp.convert_units(SEED, units))
        warning = next(w for w in result.warnings if w.startswith("stress beyond yield"))
        assert f"element 1 carries {stress / 1e6:.1f} MPa" in warning, warning
        assert result.stress_ratio == pytest.approx(stress / 200e6, rel=1e-12)  # ulps
