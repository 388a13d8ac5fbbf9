"""The sparse factorisations a user can install from wheels, on the Hertz models' K (issue 39:
"the sparse linear algebra chosen with numbers"; the table on docs/benchmarks.md).

    python benchmarks/factorisations.py [--quick] [--cache DIR] [--timeout S] [--out FILE]

On K on the free dofs of the meshes of benchmarks/scale.py (2D: 4.7·10⁴, 2.4·10⁵, 3.3·10⁵ and
8.8·10⁵ dofs; 3D: 3.3·10⁴ and 9·10⁴ dofs), the seven candidates of benchmarks/candidates.py
(SuperLU with COLAMD and with minimum degree, qdldl, CHOLMOD through cvxopt, kvxopt and
cholespy, PARDISO through pypardiso), each in a process of its own, stopped after
``--timeout`` s (default 240).

Per candidate: the factor-and-solve of one right-hand side (the median of three, the floor of
benchmarks/scale.py), a solve of 64 right-hand sides at once with the factor made (the cost of
W's columns, the check's rows), the largest residual of both over the right-hand side's
largest entry, and the process's peak memory over what it held with the model loaded. Each
line is printed as it is measured, and all of them are written to ``--out`` as JSON. A
candidate that is not installed (or does not import) says so. The meshes are built once into
the cache (scale.py's, default benchmarks/out/scale/problems). ``--quick``: the smallest mesh
only (4.7·10⁴ dofs, under a minute).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

import contactqp
from candidates import CANDIDATES, factor_and_solve
from scale import CASES, SMALL2D, level, problem_of

BLOCK = 64  # right-hand sides solved at once


def meshes() -> list[Any]:
    """scale.py's full-run cases, one per mesh, past 3·10⁴ dofs (a smaller floor is Python's
    own time): the 2D meshes but the smallest, and the 3D levels 3 and 4."""
    seen, cases = set(), []
    for case in CASES:
        large = (case.sweep in ("dofs2d", "rows2d") and case.mesh != SMALL2D
                 or case.sweep == "dofs3d" and case.mesh.fine <= level(3).fine)
        if case.runs_in != "quick" and large and case.mesh not in seen:
            seen.add(case.mesh)
            cases.append(case)
    return cases


def measure(path: Path, name: str) -> dict[str, Any]:
    """One candidate on the model saved at ``path`` (in this process)."""
    problem = contactqp.load_problem(path)
    free = np.setdiff1d(np.arange(problem.n), problem.prescribed)
    K = sp.csc_matrix(sp.csr_array(problem.K)[free][:, free])
    K.sort_indices()
    del problem
    rng = np.random.default_rng(0)
    rhs, block = np.ones(K.shape[0]), rng.standard_normal((K.shape[0], BLOCK))
    try:
        factor, solve = factor_and_solve(name, K)
    except ImportError as error:
        return {"name": name, "skipped": f"not installed ({error})"}
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    times = []
    for _ in range(3):
        start = time.perf_counter()
        x = solve(factor(), rhs)
        times.append(time.perf_counter() - start)
    made = factor()
    start = time.perf_counter()
    X = solve(made, block)
    block_seconds = time.perf_counter() - start
    residual = max(np.abs(K @ x - rhs).max() / np.abs(rhs).max(),
                   np.abs(K @ X - block).max() / np.abs(block).max())
    return {"name": name, "dofs": K.shape[0], "entries": K.nnz,
            "factor_and_solve": sorted(times)[1], "block_solve": block_seconds,
            "block": BLOCK, "residual": float(residual),
            "peak_mb": (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the smallest mesh only")
    parser.add_argument("--cache", type=Path, default=Path("benchmarks/out/scale/problems"))
    parser.add_argument("--timeout", type=float, default=240.0)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/out/factorisations.json"))
    parser.add_argument("--one", nargs=2, help=argparse.SUPPRESS)  # PATH NAME: a child's job
    args = parser.parse_args()
    if args.one:
        print(json.dumps(measure(Path(args.one[0]), args.one[1])))
        return
    found = []
    for case in meshes()[:1] if args.quick else meshes():
        path = args.cache / f"{case.mesh.key}.npz"
        problem_of(case, args.cache)  # built once into the cache
        for name in CANDIDATES:
            try:
                child = subprocess.run(
                    [sys.executable, __file__, "--one", str(path), name], capture_output=True,
                    text=True, timeout=args.timeout, check=False)
                lines = child.stdout.strip().splitlines()
                line = (json.loads(lines[-1]) if child.returncode == 0 and lines else
                        {"name": name, "skipped": f"failed: {child.stderr.strip()[-200:]}"})
            except subprocess.TimeoutExpired:
                line = {"name": name, "skipped": f"not done in {args.timeout:.0f} s"}
            line["mesh"] = case.mesh.key
            found.append(line)
            print(json.dumps(line), flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(found, indent=1))


if __name__ == "__main__":
    main()
