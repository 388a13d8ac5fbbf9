"""The commands of the command line (:mod:`contactqp.cli`): each reads its parsed arguments,
runs, prints, and returns its exit status (:data:`EXIT_CODES`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from contactqp import formatting
from contactqp.cli_input import chatter_to_stderr
from contactqp.problem import Problem
from contactqp.problem_files import load_problem
from contactqp.progress import Report
from contactqp.report import detail_table, table
from contactqp.result import Result
from contactqp.scene import Scene
from contactqp.solve import as_scene, solve
from contactqp.studies import (
    PenaltySweep,
    Run,
    compare,
    mesh_convergence,
    nitsche_sweep,
    penalty_sweep,
)

DEFAULT_OUT = "contactqp-out"
OK, NOT_VERIFIED, BAD_INPUT, BUG = 0, 1, 2, 3
EXIT_CODES = {
    OK: "every answer asked for is verified and physical (a study: its table was produced)",
    NOT_VERIFIED: "solve: the answer fails its check or a wall pulls (the reason on stderr)",
    BAD_INPUT: "bad input or options (one line naming the field and the value)",
    BUG: "an unexpected error inside contactqp: a bug, please report it",
}
STUDY_EXIT = ("exit status 0 when the table is produced, even where some runs fail their "
              "check: showing where each method fails is the point")


PROGRESS_AFTER = 5.0  # s: a longer run shows its progress on stderr, a line a second


def _progress(label: str) -> Report:
    """Progress lines on stderr for a run that goes on past PROGRESS_AFTER seconds."""
    return Report(f"contactqp: {label}", quiet=PROGRESS_AFTER)


def _scene(path: str | None) -> Scene | Problem:
    """The scene file, or a user's problem: an .npz bundle or a folder of .mtx files."""
    if path and (str(path).endswith(".npz") or Path(path).is_dir()):  # "" is no folder
        return load_problem(path)
    return as_scene(path)


def out_folder(args: argparse.Namespace) -> Path:
    """The folder for charts: --out, given before or after the command, or DEFAULT_OUT."""
    return Path(getattr(args, "out", None) or DEFAULT_OUT)


def charts_wanted(args: argparse.Namespace) -> bool:
    return not getattr(args, "no_charts", False)


def _print_runs(runs: list[Run], detail: bool) -> None:
    print(table(runs))
    if detail:
        print()
        print(detail_table(runs))


def _write_charts(result: Result, sweep: PenaltySweep, out: Path,
                  default_scene: bool) -> list[str]:
    """The scene's bar and penalty sweep; for the default scene also Nitsche's sweep and the
    mesh convergence, which are studies of the default scene alone."""
    from contactqp import plot  # matplotlib only when charts are asked for

    out.mkdir(parents=True, exist_ok=True)
    paths = [] if result.scene is None else [plot.save(plot.plot_bar(result), out / "bar.png")]
    paths.append(plot.save(plot.plot_penalty_sweep(sweep), out / "penalty_sweep.png"))
    if default_scene:
        paths += [plot.save(plot.plot_nitsche_sweep(nitsche_sweep()), out / "nitsche_sweep.png"),
                  plot.save(plot.plot_mesh_convergence(mesh_convergence()),
                            out / "mesh_convergence.png")]
    return paths


def _what(target: Scene | Problem) -> str:
    """The first line of a study: the scene and its parts, or the problem and its size."""
    if isinstance(target, Problem):
        units = f", {target.units}" if target.units else ""
        return (f"problem: {target.name or 'unnamed'} ({target.n} dofs, {target.m} contact "
                f"rows, {target.prescribed.size} prescribed{units})")
    bars = f"{len(target.bars)} bars, " if len(target.bars) > 1 else ""
    contacts = f", {len(target.contacts)} bar contact(s)" if target.contacts else ""
    return (f"scene: {target.name} ({bars}{target.n_elements} elements, "
            f"{len(target.walls)} wall(s){contacts})")


def command_compare(args: argparse.Namespace) -> int:
    scene = _scene(args.scene)
    runs = compare(scene, progress=_progress("compare, runs"))
    print(_what(scene))
    _print_runs(runs, getattr(args, "detail", False))
    answers = [r.result for r in runs if r.result is not None]
    shown = next((r for r in answers if r.verified and r.physical), answers[0] if answers else None)
    if charts_wanted(args) and shown is not None:
        sweep = penalty_sweep(scene, progress=_progress("penalty sweep for the chart, solves"))
        for path in _write_charts(shown, sweep, out_folder(args), args.scene is None):
            print(f"chart: {path}")
        if args.scene is not None:
            print("(Nitsche's γ₀ sweep and the mesh convergence study the default scene: "
                  "`contactqp compare` without a scene draws them)")
    return OK


def _qp_options(args: argparse.Namespace) -> dict[str, Any]:
    given = {"backend": args.backend, "solver": args.solver, "accuracy": args.accuracy,
             "scale": None if args.scale is None else args.scale == "on"}
    return {k: v for k, v in given.items() if v is not None}


def command_solve(args: argparse.Namespace) -> int:
    options: dict[str, Any] = {}
    for name in ("penalty", "relaxation", "ncp", "tolerance", "max_iterations", "max_rows",
                 "active_set", "gamma0", "theta"):
        if getattr(args, name) is not None:
            options[name] = getattr(args, name)
    options.update(_qp_options(args))
    if args.verbose:
        options["verbose"] = True
    with chatter_to_stderr(args.json):
        result = solve(_scene(args.scene), args.method, args.contact, args.formulation,
                       engine=args.engine, **options)
    if args.json:
        print(result.to_json())
    else:
        _print_runs([Run(result.label, result.contact, result)], args.detail)
    if result.scene is None:
        pass  # a problem has no bar to draw
    elif getattr(args, "out", None) and charts_wanted(args):  # solve draws only when asked
        from contactqp import plot  # matplotlib only when a chart is asked for

        out_folder(args).mkdir(parents=True, exist_ok=True)
        path = plot.save(plot.plot_bar(result), out_folder(args) / "bar.png")
        print(f"chart: {path}", file=sys.stderr if args.json else sys.stdout)
    if result.verified and result.physical:
        return OK
    print(f"contactqp: the answer is not verified: {result.message}", file=sys.stderr)
    return NOT_VERIFIED


def _sweep_header(units: tuple[str, str]) -> list[tuple[str, str]]:
    force, length = (f"({name})" if name else "" for name in units)
    stiffness = f"({units[0]}/{units[1]})" if all(units) else ""
    return [("ε", stiffness), ("penalty force", force), ("penetration", length),
            ("rel. error", ""), ("verified", ""), ("augmented force", force),
            ("rel. error", ""), ("updates", ""), ("verified", "")]


def _sweep_row(eps: float, sweep: PenaltySweep, i: int) -> list[str]:
    """Row ``i`` of the penalty-sweep table: the penalty's contact force, largest penetration,
    relative force error against Lagrange and verdict; the augmented method's force, error,
    updates (``(cap)``: it stopped at its cap and returned its last iterate) and verdict."""
    scale = sweep.reference.force_scale

    def cells(run: Run, error: float) -> list[str]:  # force, error, verdict
        r = run.result
        if r is None:
            return ["failed", "", ""]
        return [formatting.forces_summary(r.contact_force, scale),
                formatting.number(error, ".2e"), "yes" if r.verified else "NO"]

    penalty, augmented = sweep.runs[i], sweep.augmented_runs[i]
    depth = ("" if penalty.result is None
             else formatting.number(penalty.result.penetration.max(initial=0.0), ".4g"))
    updates = ("" if augmented.result is None else f"{sweep.augmented_iterations[i]}"
               + (" (cap)" if sweep.augmented_capped[i] else ""))
    left = cells(penalty, sweep.force_error[i])
    right = cells(augmented, sweep.augmented_error[i])
    left.insert(1, depth)
    right.insert(2, updates)
    return [f"{eps:.0e}", *left, *right]


def command_penalty_sweep(args: argparse.Namespace) -> int:
    scene = _scene(args.scene)
    sweep = penalty_sweep(scene, contact=args.contact, progress=_progress("penalty sweep, solves"))
    if args.json:
        print(json.dumps(sweep.to_dict(), indent=2, allow_nan=False))
        return OK
    scale = sweep.reference.force_scale
    force = scene.unit_names[0]
    print(f"penalty sweep, {scene.name or 'problem'}, {args.contact} contact; Lagrange contact "
          f"force {formatting.forces_summary(sweep.reference.contact_force, scale)} {force}"
          .rstrip())
    print(formatting.text_table(_sweep_header(scene.unit_names), [
        _sweep_row(eps, sweep, i) for i, eps in enumerate(sweep.penalties)]))
    for run in (*sweep.runs, *sweep.augmented_runs):
        if run.result is None:
            print(f"{run.label}: failed: {run.error}")
    print(formatting.wrap(sweep.summary()))
    _chart(args, "plot_penalty_sweep", "penalty_sweep.png", sweep)
    return OK


def _chart(args: argparse.Namespace, function: str, name: str, *data: Any) -> None:
    """Draw ``plot.<function>(*data)`` into the --out folder as ``name`` unless --no-charts."""
    if not charts_wanted(args):
        return
    from contactqp import plot  # matplotlib only when charts are asked for

    out_folder(args).mkdir(parents=True, exist_ok=True)
    print(f"chart: {plot.save(getattr(plot, function)(*data), out_folder(args) / name)}")


def command_curve(args: argparse.Namespace) -> int:
    from contactqp.curve import first_contact_factor, load_path

    scene = _scene(args.scene)
    path = load_path(scene, steps=args.steps, progress=_progress("load path, steps"))
    if args.json:
        print(json.dumps(path.to_dict(), indent=2))
        return OK
    # with friction no closed form says where the first contact closes (Tresca's friction
    # acts on an open contact too): the curve alone
    friction = getattr(scene, "T", None) is not None or bool(getattr(scene, "beds", ()))
    kink = None if friction else first_contact_factor(scene)
    length = scene.unit_names[1]
    print(f"load path, {scene.name or 'problem'}: displacement of {path.where}"
          f"{f' ({length})' if length else ''} against the load factor"
          + ("; with friction, each step an increment from the last" if friction else
             f"; first contact closes at t = {kink:.6g} (closed form)"))
    names = list(path.methods)
    print(f"{'t':>7}  " + "  ".join(f"{n:>14}" for n in names))
    for i, t in enumerate(path.load_factor):
        cells = []
        for n in names:
            m = path.methods[n]
            mark = "" if m.verified[i] and m.physical[i] else "!"
            cells.append(f"{m.load_point_displacement[i]:13.6g}{mark or ' '}")
        print(f"{t:7.4f}  " + "  ".join(cells))
    if any(not (m.verified.all() and m.physical.all()) for m in path.methods.values()):
        print("! the step's Result failed its check or a wall pulls (equality contact before the "
              "wall is reached; a soft penalty's penetration)")
    _chart(args, "plot_load_path", "load_path.png", path, kink)
    return OK


def command_solvers(args: argparse.Namespace) -> int:
    from contactqp.methods.qp import DEFAULT_BACKEND, available_qp_solvers

    rows = available_qp_solvers()
    width = max(len(f"{r.backend}/{r.solver}") for r in rows)
    print(f"{'backend/solver':<{width}}  installed  to add it")
    for r in rows:
        print(f"{r.backend + '/' + r.solver:<{width}}  {'yes' if r.available else 'no ':<9}  "
              f"{r.install}".rstrip())
    print(f"default: --method qp --backend {DEFAULT_BACKEND}; the comparison table runs every "
          "installed pair")
    return OK
