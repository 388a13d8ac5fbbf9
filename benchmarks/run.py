"""The benchmarks, one entry point: named groups of cases, each measured against a floor from
the same run (one banded factor-and-solve of K) and, where it has one, an exact reference.

    python benchmarks/run.py [--cases matrix,taper,walls,contacts,overhead,loop,speed,lcp,
                              guarantee,fem,friction]
                             [--quick] [--out DIR] [--scenes N] [--seed S]
    python benchmarks/run.py --check DIR       # is a matrix output folder complete? (CI)

    matrix     speed against accuracy for every method, solver, formulation, scaling and
               accuracy over 14 cases, against contactqp.reference; CSV, JSON, best.md and
               four charts (benchmarks/matrix.py). The default group; --quick: the small cases
    taper      the tapered bar from 10² to 10⁶ elements, one wall (benchmarks/groups.py)
    walls      a wall at every node, 10² to 10⁵ contacts (benchmarks/groups.py)
    contacts   iterations and time against 10³ … 10⁶ contacts, every method, three obstacles
               (one-sided, a two-sided channel, a flat patch) (benchmarks/contacts.py)
    overhead   what the QP method costs on top of a direct solver call; start-up
               (benchmarks/groups.py)
    loop       the library call in a user's loop: one solve and many load cases of the default
               scene against hand-written numpy doing the same job (benchmarks/loop.py)
    speed      issue 28's figures in one table: solve at 10⁶ elements, 10⁵ walls warm and on
               a first solve (also in a fresh process), the check's time over the method's,
               the default scene, prepared.solve and solve_many against numpy; the build's,
               the method's and the check's time apart (benchmarks/speed.py)
    lcp        the complementarity methods (lemke, pgs/psor, semismooth newton): iterations
               against the mesh and the stiffness contrast (benchmarks/lcp.py)
    guarantee  does verified mean right? every method on --scenes random scenes against the
               exact reference (benchmarks/guarantee.py)
    fem        the 2D cases (scikit-fem: the Hertz cylinder at two meshes, the block on a wavy
               foundation) by every method and QP solver, timed and judged (benchmarks/fem2d.py)
    friction   the friction cases (the frictional bed in 2D and 3D, Cattaneo–Mindlin under
               Tresca and Coulomb, three one-node Coulomb cases) by every method and QP solver
               that takes friction, timed and judged against exact answers; the refusals with
               their reasons (benchmarks/friction_group.py)

Case builders and timing: benchmarks/cases.py. Outputs go to DIR (default benchmarks/out),
one subfolder per group.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import contacts
import fem2d
import friction_group
import groups
import guarantee
import lcp
import loop
import matrix
import speed

CASES = ("matrix", "taper", "walls", "contacts", "overhead", "loop", "speed", "lcp", "guarantee",
         "fem", "friction")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", default="matrix",
                        help=f"comma-separated groups: {', '.join(CASES)} (default matrix)")
    parser.add_argument("--quick", action="store_true", help="small cases only")
    parser.add_argument("--out", default="benchmarks/out", help="output folder")
    parser.add_argument("--scenes", type=int, default=1000, help="guarantee: random scenes")
    parser.add_argument("--seed", type=int, default=2026, help="guarantee: their seed")
    parser.add_argument("--floating", type=float, default=0.0,
                        help="guarantee: the chance that a bar has no support (held by contact)")
    parser.add_argument("--check", metavar="DIR", help="check a matrix output folder and stop")
    args = parser.parse_args(argv)
    if args.check:
        problems = matrix.check_outputs(Path(args.check))
        for problem in problems:
            print(f"benchmark output: {problem}", file=sys.stderr)
        print(f"benchmark output in {args.check}: {'incomplete' if problems else 'complete'}")
        return 1 if problems else 0
    chosen = args.cases.split(",")
    unknown = [name for name in chosen if name not in CASES]
    if unknown:
        parser.error(f"unknown group {unknown[0]!r}; groups: {', '.join(CASES)}")
    out, status = Path(args.out), 0
    for name in chosen:
        print(f"== {name}", flush=True)
        if name == "matrix":
            matrix.main(args.quick, out / "matrix")
        elif name == "contacts":
            contacts.main(args.quick, out / "contacts")
        elif name == "loop":
            loop.main(args.quick, out / "loop")
        elif name == "speed":
            speed.main(args.quick, out / "speed")
        elif name == "fem":
            fem2d.main(args.quick, out / "fem")
        elif name == "friction":
            friction_group.main(args.quick, out / "friction")
        elif name == "lcp":
            lcp.main(args.quick, out / "lcp")
        elif name == "guarantee":
            scenes = min(args.scenes, 100) if args.quick else args.scenes
            status |= guarantee.main(scenes, args.seed, out / "guarantee", args.floating)
        else:
            groups.GROUPS[name](args.quick, out / name)
    return status


if __name__ == "__main__":
    sys.exit(main())
