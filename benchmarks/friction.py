"""Tresca in 2D at about 10⁵ dofs: the exact route with its check against Clarabel called
directly on the same QP, in the same run, each as a multiple of the floor.

    python benchmarks/friction.py [--fine 45] [--repeats 2] [--out friction.json]

The case: the Cattaneo–Mindlin cylinders of :mod:`contactqp.friction.cattaneo` (R = 10,
E = 210e3, ν = 0.3, a/R ≈ 0.03, elements of a/``fine`` along the contact strip; 103 016 dofs
and 195 contact pairs at fine = 45), pressed (Coulomb, μ = 0.3), then sheared by moving the
caps sideways under Tresca's law with the bound s = μλ_N of the pressed state, the slip
measured from it (``previous=``): Q/μP ≈ 0.5.

- **floor**: one SuperLU factor-and-solve of K on the free dofs (the faster of COLAMD and
  minimum degree in symmetric mode), what any method on this K pays at least once;
- **exact route**: ``contactqp.solve(problem, "lagrange", previous=...)`` on a new Problem
  (its friction model built and K factorised inside the timing), with the check that makes
  ``verified``;
- **Clarabel directly**: the same primal QP (u, t) as :func:`contactqp.friction.qp.primal_qp`
  writes it, handed to Clarabel with its defaults and with tolerances 1e-10; its build (the
  QP's matrices) and solve timed, no check; its friction forces compared with the check's
  reference;
- **qp through contactqp**: ``contactqp.solve(problem, "qp")`` end to end (Clarabel at 1e-10,
  and the check).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import contactqp
from contactqp.friction.cattaneo import cattaneo_cylinders
from contactqp.friction.law import tresca
from contactqp.friction.model import problem_friction_model
from contactqp.friction.qp import TIGHT, primal_qp

R, E, NU, MU = 10.0, 210e3, 0.3, 0.3
APPROACH, SHIFT = 0.0377, 0.008767  # cap motions: a/R ≈ 0.03, then Q/μP ≈ 0.5


def floor(problem: contactqp.Problem) -> float:
    """One SuperLU factor-and-solve of K on the free dofs (seconds), the faster ordering."""
    free = np.setdiff1d(np.arange(problem.n), problem.prescribed)
    K = sp.csc_matrix(problem.K[free][:, free])
    times = []
    for options in ({}, {"permc_spec": "MMD_AT_PLUS_A", "diag_pivot_thresh": 0.0,
                         "options": {"SymmetricMode": True}}):
        start = time.perf_counter()
        spla.splu(K, **options).solve(np.ones(free.size))
        times.append(time.perf_counter() - start)
    return min(times)


def clarabel_directly(problem: contactqp.Problem, previous_u: np.ndarray, settings: dict,
                      reference: np.ndarray, force_scale: float) -> dict:
    """Clarabel on the primal QP of the increment: build and solve seconds, iterations and the
    largest error of its forces against the exact route's (verified to 1e-14), over the
    largest contact force and over the check's force scale F (which the prescribed caps'
    pull makes several hundred times larger here)."""
    import clarabel

    model = problem_friction_model(problem)
    start = time.perf_counter()
    qp = primal_qp(model, tresca(model, problem.slip_bound), model.slip_origin(previous_u))
    options = clarabel.DefaultSettings()
    options.verbose = False
    for key, value in settings.items():
        setattr(options, key, value)
    solver = clarabel.DefaultSolver(sp.csc_matrix(sp.triu(qp.P)), qp.q, sp.csc_matrix(qp.G),
                                    qp.h, [clarabel.NonnegativeConeT(qp.h.size)], options)
    built = time.perf_counter()
    found = solver.solve()
    solved = time.perf_counter()
    error = float(np.abs(qp.forces(model, np.asarray(found.z)) - reference).max())
    return {"build": built - start, "solve": solved - built, "total": solved - start,
            "iterations": int(found.iterations), "status": str(found.status),
            "force_error_over_largest": error / float(np.abs(reference).max()),
            "force_error_over_F": error / force_scale}


def run(fine: float, repeats: int) -> dict:
    a = 0.03 * R
    cylinders = cattaneo_cylinders(R, E, NU, zone=1.25 * a, fine=a / fine, growth=0.05)
    pressed = contactqp.Problem(**cylinders.arrays, mu=MU,
                                prescribed_values=cylinders.cap_values(APPROACH, 0.0))
    normal = contactqp.solve(pressed)
    arrays = {**cylinders.arrays, "prescribed_values": cylinders.cap_values(APPROACH, SHIFT),
              "slip_bound": MU * normal.contact_force}
    out = {"dofs": pressed.n, "contacts": pressed.m, "runs": []}
    for _ in range(repeats):
        base = floor(pressed)
        problem = contactqp.Problem(**arrays)  # a new Problem: its model is built in the timing
        start = time.perf_counter()
        exact = contactqp.solve(problem, "lagrange", previous=normal)
        exact_seconds = time.perf_counter() - start
        reference = np.concatenate([exact.contact_force, exact.friction_force.ravel()])
        row = {"floor": base, "exact": exact_seconds, "exact_timings": exact.timings,
               "exact_verified": exact.verified, "force_scale": exact.force_scale,
               "largest_contact_force": float(np.abs(reference).max()),
               "exact_force_bound_over_F": exact.force_error_bound / exact.force_scale,
               "stick_over_slip": [int(exact.stick.sum()), int((~exact.stick).sum())],
               "Q_over_muP": float(exact.friction_force.sum()
                                   / (MU * exact.contact_force.sum()))}
        for label, settings in (("clarabel default", {}),
                                ("clarabel 1e-10", TIGHT["clarabel"])):
            row[label] = clarabel_directly(problem, normal.u, settings, reference,
                                           exact.force_scale)
        start = time.perf_counter()
        through = contactqp.solve(contactqp.Problem(**arrays), "qp", previous=normal)
        row["qp through contactqp"] = {"total": time.perf_counter() - start,
                                       "verified": through.verified,
                                       "force_bound_over_F": through.force_error_bound
                                       / through.force_scale}
        out["runs"].append(row)
    return out


def table(out: dict) -> str:
    """A Markdown table: each route's seconds and multiple of the floor, per run."""
    header = ("| run | floor (s) | exact route + check (s, x floor) | Clarabel default (s, x "
              "floor, error / largest force) | Clarabel 1e-10 (s, x floor, error / largest "
              "force) | qp via contactqp (s, x floor, verified) |")
    lines = [f"Tresca 2D, {out['dofs']} dofs, {out['contacts']} contacts", "", header,
             "|---|---|---|---|---|---|"]
    for i, row in enumerate(out["runs"]):
        base = row["floor"]
        cells = [f"{row['exact']:.2f}, {row['exact'] / base:.1f}x"]
        for label in ("clarabel default", "clarabel 1e-10"):
            found = row[label]
            cells.append(f"{found['total']:.2f}, {found['total'] / base:.1f}x, "
                         f"{found['force_error_over_largest']:.1e}")
        through = row["qp through contactqp"]
        cells.append(f"{through['total']:.2f}, {through['total'] / base:.1f}x, "
                     f"{'yes' if through['verified'] else 'no'} (bound "
                     f"{through['force_bound_over_F']:.1e} F)")
        lines.append(f"| {i + 1} | {base:.2f} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fine", type=float, default=45.0, help="a / element size")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--out", default=None, help="write the runs as JSON here")
    args = parser.parse_args()
    out = run(args.fine, args.repeats)
    print(table(out))
    if args.out:
        with open(args.out, "w") as stream:
            json.dump(out, stream, indent=1)


if __name__ == "__main__":
    main()
