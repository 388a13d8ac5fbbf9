"""Command line: ``contactqp`` (every method on the default scene), ``solve``, ``penalty-sweep``,
``curve``, ``solvers``.

Exit status (:data:`EXIT_CODES`): 0 when every answer asked for is verified and physical (for
the studies ``compare``, ``penalty-sweep`` and ``curve``, which show failing runs on purpose:
when their table was produced); 1 when ``solve`` computed an answer that fails its check or
has a wall pulling (the reason on stderr); 2 for bad input or options (one line naming the
field and the value); 3 for an unexpected error, which is a bug (one line, and where to report
it). Nothing prints a traceback."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from contactqp import __version__
from contactqp.errors import ContactqpError
from contactqp.methods import CONTACT_KINDS, FORMULATIONS, METHODS
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


def _scene(path: str | None) -> Scene:
    return as_scene(path)


def _values(values: np.ndarray, digits: int) -> str:
    return ", ".join(f"{v:.{digits}g}" for v in values) if len(values) else "-"


def _largest_residual(result: Result) -> float:
    """The largest of the residuals ``verified`` is decided on (not the natural map)."""
    return max(v for name, v in result.residuals.items()
               if v is not None and name != "natural_map")


def table(runs: list[Run]) -> str:
    """The comparison table: one row per method and contact kind, in the scene's units."""
    scene = next((run.result.scene for run in runs if run.result is not None), None)
    unit = (scene or as_scene(None)).unit
    header = ("method", "contact", f"contact force ({unit.force})",
              f"penetration ({unit.length})", f"support reaction ({unit.force})",
              "residual", "verified", "time (ms)")
    rows = []
    for run in runs:
        r = run.result
        if r is None:
            rows.append((run.label, run.contact, f"failed: {run.error}", "", "", "", "no", ""))
            continue
        verified = "yes" if r.verified else "NO"
        if not r.physical:
            verified += " (pulls)"
        rows.append((run.label, r.contact, _values(r.contact_force, 10), _values(r.penetration, 3),
                     _values(r.reactions, 10), f"{_largest_residual(r):.1e}", verified,
                     f"{1e3 * r.time:.2f}"))
    widths = [max(len(str(row[i])) for row in (header, *rows)) for i in range(len(header))]
    lines = ["  ".join(str(c).ljust(w) for c, w in zip(row, widths)).rstrip()
             for row in (header, *rows)]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def notes(runs: list[Run]) -> list[str]:
    """What the table alone does not say: failed checks, pulling walls, stress past yield."""
    out: list[str] = []
    for run in runs:
        r = run.result
        if r is not None and r.message:
            claim = (f" (yet the solver reported {r.status!r})"
                     if r.claimed_success and not r.verified else "")
            out.append(f"{run.label} ({run.contact}): {r.message}{claim}")
    reference = next((run.result for run in runs if run.result is not None and run.result.verified),
                     None)  # one stress note, from the first verified answer
    if reference is not None:
        out.extend(f"{reference.label}: {w}" for w in reference.warnings if w.startswith("stress"))
    return out


def _write_charts(result: Result, sweep: PenaltySweep, out: Path) -> list[str]:
    from contactqp import plot  # matplotlib only when charts are asked for

    out.mkdir(parents=True, exist_ok=True)
    return [plot.save(plot.plot_bar(result), out / "bar.png"),
            plot.save(plot.plot_penalty_sweep(sweep), out / "penalty_sweep.png"),
            plot.save(plot.plot_nitsche_sweep(nitsche_sweep()), out / "nitsche_sweep.png"),
            plot.save(plot.plot_mesh_convergence(mesh_convergence()), out / "mesh_convergence.png")]


def command_compare(args: argparse.Namespace) -> int:
    scene = _scene(args.scene)
    runs = compare(scene)
    bars = f"{len(scene.bars)} bars, " if len(scene.bars) > 1 else ""
    contacts = f", {len(scene.contacts)} bar contact(s)" if scene.contacts else ""
    print(f"scene: {scene.name} ({bars}{scene.n_elements} elements, {len(scene.walls)} wall(s)"
          f"{contacts})")
    print(table(runs))
    for line in notes(runs):
        print(f"note: {line}")
    answers = [r.result for r in runs if r.result is not None]
    shown = next((r for r in answers if r.verified and r.physical), answers[0] if answers else None)
    if not args.no_charts and shown is not None:
        for path in _write_charts(shown, penalty_sweep(scene), Path(args.out)):
            print(f"chart: {path}")
    return OK


def _qp_options(args: argparse.Namespace) -> dict[str, Any]:
    given = {"backend": args.backend, "solver": args.solver, "accuracy": args.accuracy,
             "scale": None if args.scale is None else args.scale == "on"}
    return {k: v for k, v in given.items() if v is not None}


def command_solve(args: argparse.Namespace) -> int:
    options: dict[str, Any] = {}
    for name in ("penalty", "relaxation", "ncp", "tolerance", "max_iterations"):
        if getattr(args, name) is not None:
            options[name] = getattr(args, name)
    options.update(_qp_options(args))
    if args.verbose:
        options["verbose"] = True
    result = solve(_scene(args.scene), args.method, args.contact, args.formulation, **options)
    if args.json:
        print(result.to_json())
    else:
        print(table([Run(result.label, result.contact, result)]))
        for line in notes([Run(result.label, result.contact, result)]):
            print(f"note: {line}")
    if result.verified and result.physical:
        return OK
    print(f"contactqp: the answer is not verified: {result.message}", file=sys.stderr)
    return NOT_VERIFIED


def command_penalty_sweep(args: argparse.Namespace) -> int:
    scene = _scene(args.scene)
    sweep = penalty_sweep(scene, contact=args.contact)
    if args.json:
        print(json.dumps(sweep.to_dict(), indent=2, allow_nan=False))
        return OK
    unit = scene.unit
    print(f"penalty sweep, {scene.name}, {args.contact} contact; Lagrange contact force "
          f"{_values(sweep.reference.contact_force, 10)} {unit.force}")
    print(f"{'ε (' + unit.stiffness + ')':>9}  {'contact force (' + unit.force + ')':>20}  "
          f"{'penetration (' + unit.length + ')':>16}  {'force error':>11}  verified  "
          f"{'augmented':>11}  updates")
    rows = zip(sweep.penalties, sweep.runs, sweep.force_error, sweep.augmented_error,
               sweep.augmented_iterations)
    for eps, run, error, augmented, updates in rows:
        if run.result is None:
            print(f"{eps:9.0e}  failed: {run.error}")
            continue
        r = run.result
        print(f"{eps:9.0e}  {_values(r.contact_force, 10):>20}  {_values(r.penetration, 4):>16}  "
              f"{error:11.2e}  {'yes' if r.verified else 'NO':<8}  {augmented:11.2e}  {updates}")
    print(sweep.summary())
    _chart(args, "plot_penalty_sweep", "penalty_sweep.png", sweep)
    return OK


def _chart(args: argparse.Namespace, function: str, name: str, *data: Any) -> None:
    """Draw ``plot.<function>(*data)`` into ``args.out``/``name`` unless --no-charts."""
    if args.no_charts:
        return
    from contactqp import plot  # matplotlib only when charts are asked for

    Path(args.out).mkdir(parents=True, exist_ok=True)
    print(f"chart: {plot.save(getattr(plot, function)(*data), Path(args.out) / name)}")


def command_curve(args: argparse.Namespace) -> int:
    from contactqp.curve import first_contact_factor, load_path

    scene = _scene(args.scene)
    path = load_path(scene, steps=args.steps)
    if args.json:
        print(json.dumps(path.to_dict(), indent=2))
        return OK
    kink = first_contact_factor(scene)
    print(f"load path, {scene.name}: displacement of node {path.load_node} "
          f"({scene.unit.length}) against the load factor; first contact closes at "
          f"t = {kink:.6g} (closed form)")
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


def parser() -> argparse.ArgumentParser:
    top = _Parser(prog="contactqp", description="Contact of elastic bars by Lagrange "
                  "multipliers, penalty and QP solvers. With no command: every method on the "
                  "default scene, one comparison table and charts.",
                  epilog="exit status: " + "; ".join(f"{code}: {text}"
                                                     for code, text in EXIT_CODES.items()))
    top.add_argument("--version", action="version", version=f"contactqp {__version__}")
    top.add_argument("--out", default=DEFAULT_OUT, help="folder for charts (default %(default)s)")
    top.add_argument("--no-charts", action="store_true", help="write no PNG files")
    top.set_defaults(handler=command_compare, scene=None)
    commands = top.add_subparsers(dest="command", parser_class=_Parser)

    def scene_command(name: str, handler, help_text: str,
                      epilog: str | None = None) -> argparse.ArgumentParser:
        sub = commands.add_parser(name, help=help_text, description=help_text, epilog=epilog)
        sub.add_argument("scene", nargs="?", help="scene TOML file (default: the default scene)")
        sub.add_argument("--out", default=DEFAULT_OUT, help="folder for charts")
        sub.add_argument("--no-charts", action="store_true", help="write no PNG files")
        sub.set_defaults(handler=handler)
        return sub

    scene_command("compare", command_compare, "every method on a scene, one table",
                  STUDY_EXIT)
    solve_parser = scene_command(
        "solve", command_solve, "solve a scene by one method",
        "exit status 0 when the answer is verified and physical, 1 when it fails its check or "
        "a wall pulls (the reason on stderr), 2 for bad input")
    solve_parser.add_argument("--method", default="lagrange", choices=list(METHODS))
    solve_parser.add_argument("--contact", default="inequality", choices=CONTACT_KINDS)
    solve_parser.add_argument("--formulation", default="auto", choices=("auto", *FORMULATIONS),
                              help="full, condensed (contact nodes only) or strain (lagrange, qp)")
    solve_parser.add_argument("--penalty", type=float,
                              help="penalty ε (force per length in the scene's units; default "
                                   "1e6 x the stiffness the walls see), methods penalty and "
                                   "augmented; the textbook's is 1e14 (N/m)")
    solve_parser.add_argument("--relaxation", type=float,
                              help="ω of projected SOR, method pgs (default 1: Gauss–Seidel)")
    solve_parser.add_argument("--ncp", choices=("min", "fischer-burmeister"),
                              help="NCP function, method semismooth_newton (default min)")
    solve_parser.add_argument("--tolerance", type=float,
                              help="stopping tolerance: methods augmented (relative change of "
                                   "λ), pgs and semismooth_newton (natural-map residual)")
    solve_parser.add_argument("--max-iterations", type=int, dest="max_iterations",
                              help="steps, sweeps or pivots at most (every method but qp)")
    solve_parser.add_argument("--backend", help="QP backend, method qp (see contactqp solvers)")
    solve_parser.add_argument("--solver", help="QP solver of the backend, method qp")
    solve_parser.add_argument("--accuracy", choices=("default", "high"), help="method qp")
    solve_parser.add_argument("--scale", choices=("on", "off"), help="non-dimensionalise the QP")
    solve_parser.add_argument("--json", action="store_true", help="print the Result as JSON")
    solve_parser.add_argument("--verbose", action="store_true",
                              help="let the QP solver print its progress")
    sweep_parser = scene_command("penalty-sweep", command_penalty_sweep,
                                 "penetration and contact force for ε = 1, 1e5, 1e6 … 1e20 N/m",
                                 STUDY_EXIT)
    sweep_parser.add_argument("--contact", default="inequality", choices=CONTACT_KINDS)
    sweep_parser.add_argument("--json", action="store_true", help="print the sweep as JSON")
    curve_parser = scene_command("curve", command_curve,
                                 "force-displacement curve: the loads stepped from 0 to 1",
                                 STUDY_EXIT)
    curve_parser.add_argument("--steps", type=int, default=21,
                              help="load factors from 0 to 1, both included (default %(default)s)")
    curve_parser.add_argument("--json", action="store_true", help="print the curves as JSON")
    commands.add_parser("solvers", help="installed QP backends and solvers, and how to add more"
                        ).set_defaults(handler=command_solvers)
    return top


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
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
