"""Command line: ``contactqp`` (every method on the default scene), ``solve``, ``penalty-sweep``,
``curve``, ``solvers``.

Exit status (:data:`EXIT_CODES`): 0 when every answer asked for is verified and physical (for
the studies ``compare``, ``penalty-sweep`` and ``curve``, which show failing runs on purpose:
when their table was produced); 1 when ``solve`` computed an answer that fails its check or
has a wall pulling (the reason on stderr); 2 for bad input or options (one line naming the
field and the value); 3 for an unexpected error, which is a bug (one line, and where to report
it). Nothing prints a traceback.

(About 430 lines, past the ~400 the project keeps to: the commands and the parser that names
them as its handlers stay together; a parser module apart would import the commands and be
imported by them, a circle. The input checks that need no parser live in cli_input.)"""

from __future__ import annotations

import argparse
import functools
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from contactqp import __version__, formatting
from contactqp.cli_input import chatter_to_stderr, check_out_folder, negative_numbers_joined
from contactqp.errors import ContactqpError
from contactqp.methods import CONTACT_KINDS, FORMULATIONS, METHODS
from contactqp.methods.lagrange import ACTIVE_SETS
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


def _out(args: argparse.Namespace) -> Path:
    """The folder for charts: --out, given before or after the command, or DEFAULT_OUT."""
    return Path(getattr(args, "out", None) or DEFAULT_OUT)


def _charts_wanted(args: argparse.Namespace) -> bool:
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
    if _charts_wanted(args) and shown is not None:
        sweep = penalty_sweep(scene, progress=_progress("penalty sweep for the chart, solves"))
        for path in _write_charts(shown, sweep, _out(args), args.scene is None):
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
    for name in ("penalty", "relaxation", "ncp", "tolerance", "max_iterations", "active_set",
                 "gamma0", "theta"):
        if getattr(args, name) is not None:
            options[name] = getattr(args, name)
    options.update(_qp_options(args))
    if args.verbose:
        options["verbose"] = True
    with chatter_to_stderr(args.json):
        result = solve(_scene(args.scene), args.method, args.contact, args.formulation,
                       **options)
    if args.json:
        print(result.to_json())
    else:
        _print_runs([Run(result.label, result.contact, result)], args.detail)
    if result.scene is None:
        pass  # a problem has no bar to draw
    elif getattr(args, "out", None) and _charts_wanted(args):  # solve draws only when asked
        from contactqp import plot  # matplotlib only when a chart is asked for

        _out(args).mkdir(parents=True, exist_ok=True)
        path = plot.save(plot.plot_bar(result), _out(args) / "bar.png")
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
    if not _charts_wanted(args):
        return
    from contactqp import plot  # matplotlib only when charts are asked for

    _out(args).mkdir(parents=True, exist_ok=True)
    print(f"chart: {plot.save(getattr(plot, function)(*data), _out(args) / name)}")


def command_curve(args: argparse.Namespace) -> int:
    from contactqp.curve import first_contact_factor, load_path

    scene = _scene(args.scene)
    path = load_path(scene, steps=args.steps, progress=_progress("load path, steps"))
    if args.json:
        print(json.dumps(path.to_dict(), indent=2))
        return OK
    kink = first_contact_factor(scene)
    length = scene.unit_names[1]
    print(f"load path, {scene.name or 'problem'}: displacement of {path.where}"
          f"{f' ({length})' if length else ''} against the load factor; first contact closes "
          f"at t = {kink:.6g} (closed form)")
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


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, no usage block
        self.exit(2, f"contactqp: error: {message} (see contactqp --help)\n")


OUT_HELP = f"folder the charts are written to (default {DEFAULT_OUT})"
NO_CHARTS_HELP = "write no chart"
DETAIL_HELP = "also list every contact's force, exact force and penetration, and every reaction"


def _chart_options(parser: argparse.ArgumentParser, *, default: Any) -> None:
    """--out and --no-charts, before the command or after it: a command's own default is
    SUPPRESS, so that it does not hide the value given before the command."""
    parser.add_argument("--out", default=default, help=OUT_HELP)
    parser.add_argument("--no-charts", action="store_true", default=default, help=NO_CHARTS_HELP)


def parser() -> argparse.ArgumentParser:
    top = _Parser(prog="contactqp", description="Contact of elastic bars by Lagrange "
                  "multipliers, penalty and QP solvers. With no command: every method on the "
                  "default scene, one comparison table and charts.",
                  epilog="exit status: " + "; ".join(f"{code}: {text}"
                                                     for code, text in EXIT_CODES.items()))
    top.add_argument("--version", action="version", version=f"contactqp {__version__}")
    _chart_options(top, default=None)
    top.set_defaults(handler=command_compare, scene=None)
    commands = top.add_subparsers(dest="command", parser_class=_Parser)

    scene_command = functools.partial(_scene_command, commands)
    _compare_command(scene_command)
    _solve_command(scene_command)
    _penalty_sweep_command(scene_command)
    _curve_command(scene_command)
    commands.add_parser("solvers", help="installed QP backends and solvers, and how to add more"
                        ).set_defaults(handler=command_solvers)
    return top


SceneCommand = Callable[..., argparse.ArgumentParser]


def _scene_command(commands: Any, name: str, handler: Callable, help_text: str,
                   epilog: str | None = None) -> argparse.ArgumentParser:
    """A command that takes a scene file (optional: the default scene)."""
    sub = commands.add_parser(name, help=help_text, description=help_text, epilog=epilog)
    sub.add_argument("scene", nargs="?", help="scene TOML file (default: the default scene); "
                     "solve also takes a problem: an .npz bundle or a folder of K.mtx, "
                     "f.mtx, C.mtx, g.mtx (contactqp.save_problem)")
    sub.set_defaults(handler=handler)
    return sub


def _compare_command(scene_command: SceneCommand) -> None:
    """The command compare: every method on a scene, one table, charts."""
    compare_parser = scene_command(
        "compare", command_compare, "every method on a scene, one table; charts of the scene "
        "(with no scene, also Nitsche's γ₀ sweep and the mesh convergence of the default scene)",
        STUDY_EXIT)
    _chart_options(compare_parser, default=argparse.SUPPRESS)
    compare_parser.add_argument("--detail", action="store_true", help=DETAIL_HELP)


def _solve_command(scene_command: SceneCommand) -> None:
    """The command solve: one method, its options."""
    solve_parser = scene_command(
        "solve", command_solve, "solve a scene by one method",
        "exit status 0 when the answer is verified and physical, 1 when it fails its check or "
        "a wall pulls (the reason on stderr), 2 for bad input")
    solve_parser.add_argument("--out", default=argparse.SUPPRESS,
                              help="draw the deformed bar into this folder (bar.png); by "
                                   "default solve writes no file")
    solve_parser.add_argument("--detail", action="store_true", help=DETAIL_HELP)
    solve_parser.add_argument("--method", default="lagrange", choices=list(METHODS))
    solve_parser.add_argument("--contact", default="inequality", choices=CONTACT_KINDS)
    solve_parser.add_argument("--formulation", default="auto", choices=("auto", *FORMULATIONS),
                              help="full, condensed (contact nodes only) or strain (lagrange, qp)")
    solve_parser.add_argument("--penalty", type=float,
                              help="penalty ε (force per length in the scene's units), methods "
                                   "penalty (default 1e6 x the stiffness the walls see; the "
                                   "textbook's is 1e14 N/m) and augmented (default 100 x it)")
    solve_parser.add_argument("--relaxation", type=float,
                              help="ω of projected SOR, method pgs (default 1: Gauss–Seidel)")
    solve_parser.add_argument("--ncp", choices=("min", "fischer-burmeister"),
                              help="NCP function, method semismooth_newton (default min)")
    solve_parser.add_argument("--tolerance", type=float,
                              help="stopping tolerance: methods augmented (relative change of "
                                   "λ), pgs and semismooth_newton (natural-map residual)")
    solve_parser.add_argument("--max-iterations", type=int, dest="max_iterations",
                              help="steps, sweeps or pivots at most (every method but qp)")
    solve_parser.add_argument("--active-set", dest="active_set", choices=ACTIVE_SETS,
                              help="method lagrange: the hull's active set (default where it "
                                   "applies) or the rows passed, added one step at a time")
    solve_parser.add_argument("--gamma0", type=float,
                              help="γ₀ of method nitsche, γ = γ₀·EA/h (default 100)")
    solve_parser.add_argument("--theta", type=float,
                              help="θ of method nitsche: 1 (symmetric, the default), 0 or -1 "
                                   "(skew-symmetric, stable for every γ₀)")
    solve_parser.add_argument("--backend", help="QP backend, method qp (see contactqp solvers)")
    solve_parser.add_argument("--solver", help="QP solver of the backend, method qp")
    solve_parser.add_argument("--accuracy", choices=("default", "high"), help="method qp")
    solve_parser.add_argument("--scale", choices=("on", "off"), help="non-dimensionalise the QP")
    solve_parser.add_argument("--json", action="store_true", help="print the Result as JSON")
    solve_parser.add_argument("--verbose", action="store_true",
                              help="let the QP solver print its progress")


def _penalty_sweep_command(scene_command: SceneCommand) -> None:
    """The command penalty-sweep: ε from 1 to 1e20 N/m."""
    sweep_parser = scene_command("penalty-sweep", command_penalty_sweep,
                                 "penetration and contact force for ε = 1, 1e5, 1e6 … 1e20 N/m",
                                 STUDY_EXIT)
    _chart_options(sweep_parser, default=argparse.SUPPRESS)
    sweep_parser.add_argument("--contact", default="inequality", choices=CONTACT_KINDS)
    sweep_parser.add_argument("--json", action="store_true",
                              help="print the sweep as JSON (instead of the table and the chart)")


def _curve_command(scene_command: SceneCommand) -> None:
    """The command curve: the loads stepped from 0 to 1."""
    curve_parser = scene_command("curve", command_curve,
                                 "force-displacement curve: the loads stepped from 0 to 1",
                                 STUDY_EXIT)
    _chart_options(curve_parser, default=argparse.SUPPRESS)
    curve_parser.add_argument("--steps", type=int, default=21,
                              help="load factors from 0 to 1, both included (default %(default)s)")
    curve_parser.add_argument("--json", action="store_true",
                              help="print the curves as JSON (instead of the table and the chart)")


NUMBER_OPTIONS = ("--penalty", "--relaxation", "--tolerance", "--max-iterations", "--gamma0",
                  "--theta", "--steps")


def _writes_charts(args: argparse.Namespace) -> bool:
    if args.handler is command_solvers or getattr(args, "json", False):
        return False
    if args.handler is command_solve:  # solve draws only when given --out
        return bool(getattr(args, "out", None)) and _charts_wanted(args)
    return _charts_wanted(args)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser().parse_args(negative_numbers_joined(argv, NUMBER_OPTIONS))
    try:
        if _writes_charts(args):  # before anything runs: found after, it was exit 3
            check_out_folder(_out(args))
        return args.handler(args)
    except ContactqpError as error:
        print(f"contactqp: error: {error}", file=sys.stderr)
        return BAD_INPUT
    except BrokenPipeError:  # output piped into head & co.: stop quietly
        sys.stderr.close()
        return OK
    except KeyboardInterrupt:
        print("contactqp: interrupted", file=sys.stderr)
        return 130
    except Exception as error:  # noqa: BLE001 - a bug: one line, never a traceback
        where = error.__traceback__
        while where is not None and where.tb_next is not None:
            where = where.tb_next
        place = "" if where is None else (f" at {Path(where.tb_frame.f_code.co_filename).name}:"
                                          f"{where.tb_lineno}")
        print(f"contactqp: internal error: {type(error).__name__}: {error}{place}. This is a bug "
              "in contactqp; please report it with the command and the scene file.",
              file=sys.stderr)
        return BUG


if __name__ == "__main__":
    sys.exit(main())
