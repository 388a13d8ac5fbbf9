"""The Hertz sphere at 10⁶ dofs: what a direct factorisation and an iterative solve of K cost
on this machine (issue 39's 3D goal; the measurements on docs/benchmarks.md, "3D at 10⁶ dofs").

    python benchmarks/route3d.py [--level 6.5] [--cholmod] [--set-solve] [--solve]
                                 [--engines direct,amg]

Builds the sphere of benchmarks/hertz3d.py's level k (``sphere_on_flat``, δ = 10 µm; level
6.5 has 1.1·10⁶ dofs, and building it takes about 4 minutes and 14 GB), then times on K on the
free dofs:

- pyamg's smoothed aggregation with the six rigid-body modes as its near null space (set-up),
  and conjugate gradients with it on K u = f (the loads of the prescribed approach) to a
  relative residual of 1e-10: iterations and time, then the same solve again (pyamg makes its
  coarsest level's solver at the first cycle, so the first solve's time holds it). pyamg is
  not a dependency of contactqp: without it, this part says so;
- with --cholmod, CHOLMOD through cvxopt: the symbolic analysis, the numeric factorisation and
  one solve. At level 6.5 the factorisation did not fit in 24 GB beside the model;
- with --set-solve (and pyamg), the step an iterative Lagrange method would repeat: the
  answer with lagrange's final set of rows held, by conjugate gradients to a relative residual
  of 1e-10 on the dofs those rows leave free (each row reads one dof, so holding it fixes
  that dof), preconditioned once by K's own hierarchy restricted to those dofs and once by a
  hierarchy of K_FF made for the set; iterations, time, and the distance to lagrange's
  answer over U. It runs lagrange
  first (CHOLMOD or SuperLU), so it is for the levels a direct factorisation fits;
- with --solve (and pyamg), the route built: ``contactqp.solve(problem, "lagrange",
  engine="amg")`` with its check (contactqp.model.iterative): the build of the model (the
  hierarchy), the solve and the check, the conjugate-gradient iterations of each solve, the
  verdict and its bounds, a and p₀ against Hertz's, and the peak memory; with --engines
  direct,amg the direct engine first, the same way. Alone (without the other options) it
  times nothing else.

Prints one line per step as it is measured, and the peak memory of the process.
"""

from __future__ import annotations

import argparse
import resource
import time
from typing import Any

import numpy as np
import scipy.sparse as sp

import contactqp
from contactqp.fem import sphere_on_flat
from hertz3d import APPROACH, ZONE, level_sizes


def peak_gb() -> float:
    """The process's peak resident memory (GB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6


def rigid_body_modes(points: np.ndarray, dofs: int) -> np.ndarray:
    """The three translations and three rotations of the nodes ``points`` (3 x nodes), as
    columns over the dofs numbered node by node (x, y, z of node 0, then node 1, ...)."""
    node, component = np.arange(dofs) // 3, np.arange(dofs) % 3
    x, y, z = points[0][node], points[1][node], points[2][node]
    modes = np.zeros((dofs, 6))
    for c in range(3):
        modes[component == c, c] = 1.0
    along = [component == c for c in range(3)]
    modes[along[0], 3], modes[along[1], 3] = -y[along[0]], x[along[1]]  # about z
    modes[along[1], 4], modes[along[2], 4] = -z[along[1]], y[along[2]]  # about x
    modes[along[2], 5], modes[along[0], 5] = -x[along[2]], z[along[0]]  # about y
    return modes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--level", type=float, default=6.5, help="the sphere's level")
    parser.add_argument("--cholmod", action="store_true", help="also factor K by CHOLMOD")
    parser.add_argument("--set-solve", action="store_true",
                        help="also the set solve by conjugate gradients (needs pyamg)")
    parser.add_argument("--solve", action="store_true",
                        help="solve with lagrange and engine='amg', checked (needs pyamg)")
    parser.add_argument("--engines", default="amg",
                        help="with --solve, the engines in turn (e.g. direct,amg)")
    args = parser.parse_args()
    fine, growth = level_sizes(args.level)
    start = time.perf_counter()
    model = sphere_on_flat(zone=ZONE, fine=fine, growth=growth, approach=APPROACH)
    problem = model.problem
    print(f"level {args.level:g}: {problem.n} dofs, {problem.m} rows; built in "
          f"{time.perf_counter() - start:.1f} s, peak {peak_gb():.1f} GB", flush=True)
    if args.solve:
        for engine in args.engines.split(","):
            solve_by(model, engine)
        if not (args.cholmod or args.set_solve):
            return
    free = np.setdiff1d(np.arange(problem.n), problem.prescribed)
    whole = sp.csr_array(problem.K)
    K = sp.csr_matrix(whole[free][:, free])
    f = problem.f[free] - whole[free][:, problem.prescribed] @ problem.prescribed_values
    print(f"K on the free dofs: {K.shape[0]} x {K.shape[0]}, {K.nnz} entries", flush=True)
    try:
        import pyamg
    except ImportError:
        print("pyamg is not installed (pip install pyamg): no iterative solve")
    else:
        start = time.perf_counter()
        modes = rigid_body_modes(model.mesh.p, problem.n)[free]
        hierarchy = pyamg.smoothed_aggregation_solver(K, B=modes, max_coarse=500)
        print(f"pyamg {pyamg.__version__} set-up: {time.perf_counter() - start:.1f} s, "
              f"{len(hierarchy.levels)} levels, peak {peak_gb():.1f} GB", flush=True)
        residuals: list[float] = []
        start = time.perf_counter()
        u = hierarchy.solve(f, tol=1e-10, accel="cg", maxiter=500, residuals=residuals)
        seconds = time.perf_counter() - start
        relative = np.linalg.norm(f - K @ u) / np.linalg.norm(f)
        print(f"conjugate gradients: {len(residuals) - 1} iterations, {seconds:.1f} s, "
              f"relative residual {relative:.1e}", flush=True)
        again: list[float] = []
        start = time.perf_counter()
        hierarchy.solve(f, tol=1e-10, accel="cg", maxiter=500, residuals=again)
        print(f"the same solve again (pyamg makes its coarsest level's solver at the first "
              f"cycle): {len(again) - 1} iterations, {time.perf_counter() - start:.1f} s",
              flush=True)
        if args.set_solve:
            set_solves(problem, free, K, f, hierarchy, modes)
    if args.cholmod:
        from cvxopt import cholmod, matrix, spmatrix

        lower = sp.tril(K, format="coo")
        held = spmatrix(lower.data, lower.row, lower.col, K.shape)
        start = time.perf_counter()
        factor = cholmod.symbolic(held)
        print(f"CHOLMOD symbolic: {time.perf_counter() - start:.1f} s", flush=True)
        start = time.perf_counter()
        cholmod.numeric(held, factor)
        print(f"CHOLMOD numeric: {time.perf_counter() - start:.1f} s, peak {peak_gb():.1f} GB",
              flush=True)
        rhs = matrix(f)
        start = time.perf_counter()
        cholmod.solve(factor, rhs)
        print(f"CHOLMOD solve: {time.perf_counter() - start:.1f} s", flush=True)


def solve_by(model: Any, engine: str) -> None:
    """lagrange with ``engine`` and its check on the sphere (module docstring)."""
    from contactqp.fem import measure_sphere
    from contactqp.model.sparse import problem_model

    start = time.perf_counter()
    result = contactqp.solve(model.problem, "lagrange", engine=engine)
    seconds = time.perf_counter() - start
    timings = ", ".join(f"{k} {v:.1f} s" for k, v in result.timings.items())
    factor = problem_model(model.problem, engine).factor
    setup = (f"; the hierarchy's set-up {factor.setup_seconds:.1f} s" if engine == "amg"
             else "")
    print(f"lagrange, engine={engine!r}: {seconds:.1f} s ({timings}{setup}), verified "
          f"{result.verified}, force bound {result.force_error_bound:.1e}, displacement bound "
          f"{result.displacement_error_bound:.1e}, "
          f"{int(np.count_nonzero(result.contact_force > 0))} rows in contact, "
          f"peak {peak_gb():.1f} GB", flush=True)
    if engine == "amg":
        print(f"conjugate-gradient iterations per solve: {factor.iterations}", flush=True)
    hertz = measure_sphere(model, result.contact_force, resolution=result.force_error_bound)
    a_off = hertz.contact_radius / hertz.hertz_contact_radius - 1.0
    p0_off = hertz.peak_pressure / hertz.hertz_peak_pressure - 1.0
    print(f"P = {hertz.load:.6g} N: a {hertz.contact_radius:.5g} against Hertz's "
          f"{hertz.hertz_contact_radius:.5g} ({a_off:+.2%}), p0 {hertz.peak_pressure:.5g} "
          f"against {hertz.hertz_peak_pressure:.5g} ({p0_off:+.2%})", flush=True)


def set_solves(problem: contactqp.Problem, free: np.ndarray, K: sp.csr_matrix, f: np.ndarray,
               hierarchy: Any, modes: np.ndarray) -> None:
    """The answer on lagrange's final set by conjugate gradients (module docstring)."""
    import pyamg
    import scipy.sparse.linalg as spla

    start = time.perf_counter()
    result = contactqp.solve(problem, "lagrange")
    held_rows = np.flatnonzero(result.contact_force > 0.0)
    print(f"lagrange: {time.perf_counter() - start:.1f} s, verified {result.verified}, "
          f"{held_rows.size} rows in contact", flush=True)
    C = sp.csr_array(problem.C)[:, free]
    if not np.all(np.diff(C.indptr) == 1):
        print("a row reads more than one dof: no set solve by fixed dofs here")
        return
    dofs = C.indices[C.indptr[held_rows]]
    fixed = problem.g[held_rows] / C.data[C.indptr[held_rows]]  # each held row on its gap
    rest = np.setdiff1d(np.arange(K.shape[0]), dofs)
    rows_rest = K[rest]
    K_rest = sp.csr_matrix(rows_rest[:, rest])
    rhs = f[rest] - rows_rest[:, dofs] @ fixed
    U = result.displacement_scale

    def report(label: str, u_rest: np.ndarray, steps: int, seconds: float) -> None:
        u = np.zeros(K.shape[0])
        u[rest], u[dofs] = u_rest, fixed
        off = np.abs(u - result.u[free]).max() / U
        print(f"set solve, {label}: {steps} iterations, {seconds:.1f} s; off lagrange's answer "
              f"by {off:.1e} of U", flush=True)

    whole = hierarchy.aspreconditioner(cycle="V")

    def restricted(x: np.ndarray) -> np.ndarray:  # K's hierarchy on the dofs left free
        padded = np.zeros(K.shape[0])
        padded[rest] = x
        return (whole @ padded)[rest]

    steps = [0]
    start = time.perf_counter()
    u_rest, _ = spla.cg(K_rest, rhs, rtol=1e-10, maxiter=2000,
                        M=spla.LinearOperator(K_rest.shape, matvec=restricted),
                        callback=lambda _: steps.__setitem__(0, steps[0] + 1))
    report("K's hierarchy restricted", u_rest, steps[0], time.perf_counter() - start)
    start = time.perf_counter()
    own = pyamg.smoothed_aggregation_solver(K_rest, B=modes[rest], max_coarse=500)
    own.aspreconditioner(cycle="V") @ np.zeros(rest.size)  # its coarsest solver made here
    made = time.perf_counter() - start
    residuals: list[float] = []
    start = time.perf_counter()
    u_rest = own.solve(rhs, tol=1e-10, accel="cg", maxiter=500, residuals=residuals)
    report(f"a hierarchy of K_FF of its own (set-up {made:.1f} s)", u_rest,
           len(residuals) - 1, time.perf_counter() - start)


if __name__ == "__main__":
    main()
