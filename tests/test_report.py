"""The comparison table (contactqp.report) and how it writes numbers (contactqp.formatting):
one compact row per run, the error against the exact reference, notes written once, no "-0".

Glossary: λ the contact force of a row (N), λ_exact the exact reference's (contactqp.reference,
independent of the methods), F the scene's force scale (N).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import contactqp
from closed_forms import EXAMPLES, default_closed_form
from contactqp import formatting
from contactqp.reference import reference

WALLS = next(path for path in EXAMPLES if path.name == "wall_at_every_node.toml")
MAX_WIDTH = 120  # characters: a row fits a terminal beside an editor


@pytest.fixture(scope="module")
def walls():
    """Every method on a bar with a wall beside each of its 8 free nodes (one carries force)."""
    scene = contactqp.load_scene(WALLS)
    return scene, contactqp.compare(scene)


def cells(line: str) -> list[str]:
    return re.split(r"\s{2,}", line.strip())


def rows_of(text: str, runs) -> dict[tuple[str, str], str]:
    """(label, contact) -> the table's line for that run."""
    lines = text.splitlines()
    return {(run.label, run.contact): next(line for line in lines
                                           if line.startswith(f"{run.label} ")
                                           and f" {run.contact} " in line)
            for run in runs}


def test_rows_are_compact_on_many_walls(walls):
    """~300 characters a row before: now every line, notes included, fits MAX_WIDTH."""
    _, runs = walls
    text = contactqp.table(runs)
    assert max(len(line) for line in text.splitlines()) <= MAX_WIDTH
    assert max(len(line) for line in contactqp.detail_table(runs).splitlines()) <= MAX_WIDTH


def test_no_number_is_written_minus_zero(walls):
    """HiGHS returns −0.0 forces: neither the table nor the detail prints '-0' (or '-0.00')."""
    _, runs = walls
    for text in (contactqp.table(runs), contactqp.detail_table(runs)):
        negative_zero = [t for t in re.findall(r"-[\d.]+(?:e[-+]\d+)?", text) if float(t) == 0.0]
        assert not negative_zero


def test_the_error_column_is_the_distance_to_the_exact_reference(walls):
    """error = max |λ − λ_exact| (one wall per node here), λ_exact from contactqp.reference."""
    scene, runs = walls
    exact = reference(scene).contact_force
    lines = rows_of(contactqp.table(runs), runs)
    checked = 0
    for run in runs:
        if run.result is None:
            continue
        error_cell = cells(lines[(run.label, run.contact)])[3]
        if run.contact == "equality":  # the reference is unilateral: nothing to compare with
            assert run.exact_error is None and error_cell == "-"
            continue
        expected = float(np.abs(run.result.contact_force - exact).max())
        assert run.exact_error == pytest.approx(expected, rel=1e-12, abs=1e-300)  # one sum
        assert error_cell == formatting.number(expected, ".1e")
        checked += 1
    assert checked >= 10


def test_the_force_column_summarises_many_contacts(walls):
    """The largest force and how many of the 8 walls carry force, as the reference has it."""
    scene, runs = walls
    exact = reference(scene).contact_force
    lagrange = rows_of(contactqp.table(runs), runs)[("lagrange", "inequality")]
    carrying = int(np.count_nonzero(exact > 1e-5 * contactqp.solve(scene).force_scale))
    # Lagrange is exact to round-off (~1e-10 N here): its 10 digits are the reference's
    assert cells(lagrange)[2] == f"{exact.max():.10g} ({carrying}/{exact.size})"
    assert carrying == 1


def test_failures_have_their_own_column_and_each_note_is_written_once(walls):
    """Nitsche refuses interior walls for both contact kinds: 'failed' in the verified column,
    no message in the force column, and its message once under the table."""
    _, runs = walls
    text = contactqp.table(runs)
    lines = rows_of(text, runs)
    nitsche = [lines[("nitsche", kind)] for kind in ("inequality", "equality")]
    message = next(run.error for run in runs if run.label == "nitsche")
    for line in nitsche:
        assert cells(line)[2:] == ["failed", "[1]"]
    assert sum(message in line for line in text.replace("\n    ", " ").splitlines()) == 1
    notes = contactqp.report.notes(runs)  # this scene has no yield stress: numbered notes only
    assert len(notes) == len(set(notes)) >= 2
    assert sum(bool(re.match(r"\[\d+\] ", line)) for line in text.splitlines()) == len(notes)
    # equality contact's pulling walls are the verdict's '(pulls)', explained once
    assert text.count("(pulls): a contact pulls") == 1
    assert "yes (pulls)" in lines[("lagrange", "equality")]


def test_detail_lists_every_contact_with_the_exact_force(walls):
    """--detail: one line per run and wall, the exact force beside it; open walls show 0."""
    scene, runs = walls
    exact = reference(scene).contact_force
    detail = contactqp.detail_table(runs)
    answered = [run for run in runs if run.result is not None]
    wall_lines = [line for line in detail.splitlines() if " wall[" in line]
    assert len(wall_lines) == len(answered) * len(scene.walls)
    lagrange = [cells(line) for line in wall_lines if line.startswith("lagrange ")
                and " inequality " in line]
    scale = runs[0].result.force_scale
    assert [row[2] for row in lagrange] == [f"wall[{i}]" for i in range(8)]
    assert [row[4] for row in lagrange] == [formatting.force(f, scale) for f in exact]
    assert [row[3] for row in lagrange] == [row[4] for row in lagrange]  # exact to 10 digits


def test_one_result_has_no_error_column_and_the_closed_form():
    """A Run without a reference (as `contactqp solve` prints): no error column."""
    result = contactqp.solve()
    _, lam = default_closed_form()
    text = contactqp.table([contactqp.Run(result.label, result.contact, result)])
    header, units, _, row = text.splitlines()[:4]
    assert "error" not in header and units.split() == ["(N)", "(m)", "(ms)"]
    assert cells(row)[:3] == ["lagrange", "inequality", f"{lam:.10g}"]


@pytest.mark.parametrize(("value", "scale", "text"), [
    (486212.78474431, 5.65e5, "486212.7847"),  # 10 significant digits of F
    (1.729615476e-11, 5.65e5, "0"),  # an open wall's round-off, below F's 10th digit
    (-7.5e-12, 5.65e5, "0"),  # and never '-0'
    (-0.0, 5.65e5, "0"),
    (2.554154518e-4, 5.65e5, "0.0003"),  # Clarabel's force on an open wall: what F's digits show
    (-29791.13409, 5.65e5, "-29791.1341"),
    (1234.5, float("nan"), "1234.5"),  # no scale: as it is
])
def test_a_force_is_written_to_ten_digits_of_the_force_scale(value, scale, text):
    assert formatting.force(value, scale) == text


def test_number_never_writes_minus_zero():
    assert formatting.number(-0.0, ".1e") == "0"
    assert formatting.number(-1e-7, ".2f") == "0.00"
    assert formatting.number(-1e-7, ".1e") == "-1.0e-07"
