"""A user's own model at the size of the Hertz mesh: the exact method and its check against one
sparse factor-and-solve of K in the same run.

    python benchmarks/problem.py [--nx 300] [--ny 280] [--repeat 3]
                                 [--methods lagrange,penalty,augmented,qp/clarabel,qp/osqp]

The problem: a 2D grid of nx x ny nodes, one unknown each (the vertical displacement u; K the
5-point Laplacian times a stiffness, from scipy.sparse kron products), the top edge pushed
down by δ (prescribed), every node of the bottom edge kept above a circular obstacle of radius
R: −u_i <= x_i² / (2R), one contact row each (nx rows). A rigid move of the body by −δ passes
the obstacle over half-width √(2Rδ); the answer touches over less. Prints, for each repeat,
the floor (SuperLU factor-and-solve of K, minimum-degree ordering and COLAMD), then each
method's time end to end (model, method, check) and its ratio to the floor.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import contactqp
from contactqp.model.sparse import ORDERING, factorise


def laplace_problem(nx: int = 300, ny: int = 280, press: float = 0.02,
                    radius: float = 2.0) -> contactqp.Problem:
    """The grid problem of the module docstring (unit square-ish cells of size 1/nx)."""
    def second_difference(k: int) -> sp.sparray:
        return sp.diags_array([-np.ones(k - 1), 2.0 * np.ones(k), -np.ones(k - 1)],
                              offsets=[-1, 0, 1])

    K = sp.kron(sp.eye_array(ny), second_difference(nx)) + sp.kron(second_difference(ny),
                                                                   sp.eye_array(nx))
    # every edge a natural boundary (undo the Dirichlet ends of the 1D stencils): the top is
    # held by its prescribed motion, the bottom by the obstacle alone
    ends = np.zeros((ny, nx))
    ends[:, [0, -1]] += 1.0
    ends[[0, -1], :] += 1.0
    K = sp.csr_array(K - sp.diags_array(ends.reshape(-1)))
    top = np.arange((ny - 1) * nx, ny * nx)
    bottom = np.arange(nx)
    x = (bottom - (nx - 1) / 2.0) / nx
    C = sp.csr_array((-np.ones(nx), (np.arange(nx), bottom)), shape=(nx, nx * ny))
    return contactqp.Problem(K, np.zeros(nx * ny), C, x**2 / (2.0 * radius), prescribed=top,
                             prescribed_values=np.full(nx, -press), name=f"grid {nx}x{ny}")


def floor(problem: contactqp.Problem, ordering: str) -> float:
    """One SuperLU factor-and-solve of K (the free dofs), seconds."""
    free = np.setdiff1d(np.arange(problem.n), problem.prescribed)
    K = sp.csc_matrix(problem.K[free][:, free])
    start = time.perf_counter()
    if ordering == ORDERING:
        factorise(K).solve(np.ones(free.size))
    else:
        spla.splu(K, permc_spec=ordering).solve(np.ones(free.size))
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--nx", type=int, default=300)
    parser.add_argument("--ny", type=int, default=280)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--methods", default="lagrange")
    args = parser.parse_args()
    problem = laplace_problem(args.nx, args.ny)
    print(f"{problem.n} dofs, {problem.m} contact rows")
    for _ in range(args.repeat):
        base = floor(problem, ORDERING)
        colamd = floor(problem, "COLAMD")
        print(f"floor: factor-and-solve {base:.3f} s (minimum degree), {colamd:.3f} s (COLAMD)")
        for name in args.methods.split(","):
            method, _, backend = name.partition("/")  # "qp/osqp": the QP method by OSQP
            options = {"backend": backend} if backend else {}
            start = time.perf_counter()
            result = contactqp.solve(problem, method, **options)
            total = time.perf_counter() - start
            t = result.timings
            print(f"  {name:18s} {total:.3f} s = {total / base:.2f} x floor (model "
                  f"{t['build']:.3f}, method {t['solve']:.3f}, check {t['check']:.3f} = "
                  f"{t['check'] / base:.2f} x); {result.iterations} iterations, "
                  f"{result.info.get('columns', '-')} columns, "
                  f"{int(np.count_nonzero(result.contact_force > 0))} rows push, "
                  f"verified {result.verified}"
                  + ("" if result.verified else f" ({result.message[:120]})"))


if __name__ == "__main__":
    main()
