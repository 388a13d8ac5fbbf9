"""Command line: ``contactqp`` (every method on the default scene), ``solve``, ``penalty-sweep``,
``curve``, ``solvers``: the parser and :func:`main`; the commands are in
:mod:`contactqp.cli_commands`, the input checks that need no parser in :mod:`contactqp.cli_input`.

Exit status (:data:`EXIT_CODES`): 0 when every answer asked for is verified and physical (for
the studies ``compare``, ``penalty-sweep`` and ``curve``, which show failing runs on purpose:
when their table was produced); 1 when ``solve`` computed an answer that fails its check or
has a wall pulling (the reason on stderr); 2 for bad input or options (one line naming the
field and the value); 3 for an unexpected error, which is a bug (one line, and where to report
it). Nothing prints a traceback."""

from __future__ import annotations

import argparse
import functools
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from contactqp import __version__
from contactqp.cli_commands import (
    BAD_INPUT,
    BUG,
    DEFAULT_OUT,
    EXIT_CODES,
    OK,
    STUDY_EXIT,
    charts_wanted,
    command_compare,
    command_curve,
    command_penalty_sweep,
    command_solve,
    command_solvers,
    out_folder,
)
from contactqp.cli_input import negative_numbers_joined, validate_out_folder
from contactqp.errors import ContactqpError
from contactqp.methods import CONTACT_KINDS, FORMULATIONS, METHODS
from contactqp.methods.lagrange import ACTIVE_SETS
from contactqp.model.sparse import ENGINES


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
    solve_parser.add_argument("--max-rows", type=int, dest="max_rows",
                              help="method pgs: the rows up to which it forms W (default 2000; "
                                   "more is a long run)")
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
    solve_parser.add_argument("--engine", default="direct", choices=ENGINES,
                              help="a problem file's solves with K: factorised (direct, the "
                                   "default) or conjugate gradients with pyamg's multigrid "
                                   "(amg, for models a factorisation does not fit)")
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


NUMBER_OPTIONS = ("--penalty", "--relaxation", "--tolerance", "--max-iterations", "--max-rows",
                  "--gamma0", "--theta", "--steps")


def _writes_charts(args: argparse.Namespace) -> bool:
    if args.handler is command_solvers or getattr(args, "json", False):
        return False
    if args.handler is command_solve:  # solve draws only when given --out
        return bool(getattr(args, "out", None)) and charts_wanted(args)
    return charts_wanted(args)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser().parse_args(negative_numbers_joined(argv, NUMBER_OPTIONS))
    try:
        if _writes_charts(args):  # before anything runs: found after, it was exit 3
            validate_out_folder(out_folder(args))
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
