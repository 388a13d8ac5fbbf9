"""The comparison table: runs of one scene or problem (:func:`contactqp.compare`), one row
each, in its units; numbered notes under it, each written once; every contact on request. The
one table every Result is printed in.

>>> import contactqp
>>> print(contactqp.table(contactqp.compare()))      # doctest: +SKIP
"""

from __future__ import annotations

import numpy as np

from contactqp import formatting
from contactqp.result import Result
from contactqp.studies import Run

VERIFIED_WORDS = {True: "yes", False: "NO"}
PULLS = "non-physical: a wall pulls"  # how the check's message says it (contactqp.check)
PULLS_KEY = ("(pulls): a contact pulls, which a rigid wall cannot (equality contact holds each "
             "node on its wall); the detail table (--detail) lists every contact's force")


def _largest_residual(result: Result) -> float:
    """The largest of the residuals ``verified`` is decided on (not the natural map)."""
    return max(v for name, v in result.residuals.items()
               if v is not None and name != "natural_map")


def _verdict(run: Run) -> str:
    r = run.result
    if r is None:
        return "failed"
    return VERIFIED_WORDS[r.verified] + ("" if r.physical else " (pulls)")


def _note(run: Run) -> str:
    """What the row alone does not say: why it failed, or what its check found (the pulling
    contacts are in the row's verdict, and each force in the detail)."""
    r = run.result
    if r is None:
        return f"failed: {run.error}"
    found = r.message.split(PULLS)[0].rstrip("; ")
    if not found:
        return ""
    claim = (f" (yet the solver reported {r.status!r})"
             if r.claimed_success and not r.verified else "")
    return f"{found}{claim}"


def _numbered(runs: list[Run]) -> tuple[list[str], list[str]]:
    """(each run's note mark, '' or '[k]'; the notes, each text once, in order of first use)."""
    texts: list[str] = []
    marks = []
    for run in runs:
        text = _note(run)
        if text and text not in texts:
            texts.append(text)
        marks.append(f"[{texts.index(text) + 1}]" if text else "")
    return marks, texts


def _first(runs: list[Run]) -> Result | None:
    return next((run.result for run in runs if run.result is not None), None)


def _units(runs: list[Run]) -> tuple[str, str]:
    """(force, length) labels of the runs' model ("" where it has none)."""
    first = _first(runs)
    return first.model.units if first is not None else ("", "")


def _force_scale(runs: list[Run]) -> float:
    return max((run.result.force_scale for run in runs if run.result is not None), default=1.0)


def _bracket(unit: str) -> str:
    return f"({unit})" if unit else ""


def table(runs: list[Run]) -> str:
    """The comparison table of ``runs``: one row per run (method, contact kind), in the scene's
    units, then its notes.

    Columns: the contact force (the one contact's, or the largest and (k/n) how many of the n
    contacts carry force: more than the check's 1e-5·F); with friction, the friction force
    (as the contact force) and how many contacts stick and slip; its error against the exact reference
    (the largest on any node, N; where the runs carry one, :attr:`Run.exact_error`); the
    largest penetration; the largest residual of the check; verified (``(pulls)``: a wall or a
    bar contact pulls); the time of the whole solve; the row's note. Each note (a failed
    check's reason, a method that could not solve the scene) is written once, however many
    rows share it; the stress beyond yield once, from the first verified answer.
    :func:`detail_table` lists every contact.

    Parameters
    ----------
    runs : list of Run
        The runs of :func:`contactqp.compare` (all on one scene).

    Returns
    -------
    str
        The table and its notes, one line each, ready to print.
    """
    force_unit, length_unit = _units(runs)
    scale = _force_scale(runs)
    exact = any(run.exact_force is not None for run in runs)
    marks, texts = _numbered(runs)
    header = [("method", ""), ("contact", ""), ("contact force", _bracket(force_unit))]
    friction = any(run.result is not None and run.result.friction is not None for run in runs)
    header += [("friction force", _bracket(force_unit)), ("stick/slip", "")] if friction else []
    header += [("error", _bracket(force_unit))] if exact else []
    header += [("penetration", _bracket(length_unit)), ("residual", ""), ("verified", ""),
               ("time", "(ms)"), ("note", "")]
    rows = []
    for run, mark in zip(runs, marks):
        r = run.result
        cells = [run.label, run.contact]
        if r is None:
            cells += [""] * (len(header) - 5) + ["failed", "", mark]
        else:
            error = run.exact_error
            cells += [formatting.forces_summary(r.contact_force, scale)]
            cells += _friction_cells(r, scale) if friction else []
            cells += [("-" if error is None else formatting.number(error, ".1e"))] if exact else []
            cells += [formatting.number(r.penetration.max(), ".3g") if r.penetration.size else "-",
                      formatting.number(_largest_residual(r), ".1e"), _verdict(run),
                      f"{1e3 * r.time:.2f}", mark]
        rows.append(cells)
    table_lines = formatting.text_table(header, rows).splitlines()  # never wrapped: a row
    lines = []  # broken across lines reads as two rows (the friction columns pass 100)
    if any(run.result is not None and not run.result.physical for run in runs):
        lines.append(PULLS_KEY)
    lines += [f"[{k}] {text}" for k, text in enumerate(texts, 1)]
    lines += [f"note: {line}" for line in _scene_notes(runs)]
    return "\n".join([*table_lines, *formatting.wrap("\n".join(lines)).splitlines()])


def _friction_cells(result: Result, scale: float) -> list[str]:
    """The friction columns: the largest friction force (and how many contacts carry one, as
    the contact force's column counts them), and how many contacts stick and slip."""
    if result.friction is None:
        return ["-", "-"]
    sizes = np.linalg.norm(np.asarray(result.friction_force, dtype=float), axis=1)
    state = np.asarray(result.state)
    return [formatting.forces_summary(sizes, scale),
            f"{int(np.sum(state == 'stick'))}/{int(np.sum(state == 'slip'))}"]


def _scene_notes(runs: list[Run]) -> list[str]:
    """The stress beyond yield, once, from the first verified answer."""
    first = next((run.result for run in runs if run.result is not None and run.result.verified),
                 None)
    if first is None:
        return []
    return [f"{first.label}: {w}" for w in first.warnings if w.startswith("stress")]


def notes(runs: list[Run]) -> list[str]:
    """The notes :func:`table` prints under its rows, each once: why a run failed or what its
    check found, then the stress beyond yield."""
    return [*_numbered(runs)[1], *_scene_notes(runs)]


def detail_table(runs: list[Run]) -> str:
    """Every contact of every run: its force, the exact force where the runs carry the exact
    reference, and its penetration; then every support's reaction; in the scene's units.

    Parameters
    ----------
    runs : list of Run
        The runs of :func:`contactqp.compare` (all on one scene).

    Returns
    -------
    str
        One line per run and contact, then per support, ready to print.
    """
    first = _first(runs)
    if first is None:
        return "no run produced an answer"
    (force_unit, length_unit), scale = _units(runs), _force_scale(runs)
    names = first.names
    supports = ("support" if first.scene is not None else "prescribed dof")
    header = [("method", ""), ("contact", ""), ("where", ""), ("force", _bracket(force_unit)),
              ("exact", _bracket(force_unit)), ("penetration", _bracket(length_unit))]
    rows = []
    for run in runs:
        r = run.result
        if r is None:
            continue
        exact = run.exact_force if run.exact_force is not None else np.full(len(names), np.nan)
        for name, force, known, depth in zip(names, r.contact_force, exact, r.penetration):
            rows.append([run.label, run.contact, name, formatting.force(force, scale),
                         "" if np.isnan(known) else formatting.force(known, scale),
                         formatting.number(depth, ".3g")])
        rows += [[run.label, run.contact, f"{supports}[{i}]", formatting.force(reaction, scale),
                  "", ""] for i, reaction in enumerate(r.reactions)]
    return formatting.text_table(header, rows)


__all__ = ["detail_table", "notes", "table"]
