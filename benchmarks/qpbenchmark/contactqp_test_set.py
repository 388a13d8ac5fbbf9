"""contactqp's contact problems as a qpbenchmark test set.

    python benchmarks/qpbenchmark/export.py          # writes problems/ (once)
    qpbenchmark benchmarks/qpbenchmark/contactqp_test_set.py run

Each problem is the QP of an elastic bar scene against rigid walls (contactqp), in SI units
and scaled to order one: minimise ½ xᵀKx − Pᵀx subject to C x <= g, K the stiffness of a
chain (tridiagonal, positive definite; only positive semidefinite in the free_bar,
held_by_contact and free_bars problems, whose bars have no support and are held by their
contacts alone), C one row per wall (or bar contact). Two 2D problems from scikit-fem join
them: hertz_coarse (a plane-strain cylinder on a rigid flat, 7 499 unknowns, 17 rows) and
block_wavy (a block on a wavy foundation, 1 640 unknowns, 41 rows), K a P1 elasticity
stiffness. Its duals are the contact forces; problems/exact.json holds the exact ones
(benchmarks/qpbenchmark/README.md).
qpbenchmark loads this file and instantiates ContactqpTestSet (the name it derives from the
file's).
"""

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import qpsolvers
import scipy.sparse as sp

import qpbenchmark

PROBLEMS = Path(__file__).resolve().parent / "problems"


def load(path: Path) -> qpsolvers.Problem:
    """The qpsolvers.Problem of a file export.py wrote (P and G as CSC parts; contactqp is not
    needed to run the test set)."""
    data = np.load(path)

    def matrix(name: str) -> sp.csc_matrix:
        return sp.csc_matrix((data[f"{name}_data"], data[f"{name}_indices"],
                              data[f"{name}_indptr"]), shape=tuple(data[f"{name}_shape"]))

    return qpsolvers.Problem(matrix("P"), data["q"], matrix("G"), data["h"])


DENSE_UP_TO = 1000  # unknowns up to which problems are handed over dense

# Known timeouts, as qpbenchmark's own test sets record theirs (counted as a failure, not run):
# solvers with no time-limit parameter that ran far past the 10 s limit (measured on this test
# set, 2026-11-23) on every problem with more unknowns than the first number. DAQP (dense)
# ran past 90 s on the 10⁴-element bar and stalled the run; ProxQP took 33 to 116 s on the
# 10⁵-element bar (each setting, SI and scaled).
KNOWN_TIMEOUTS = {"daqp": (DENSE_UP_TO, 90.0), "proxqp": (10_000, 116.0)}


class ContactqpTestSet(qpbenchmark.TestSet):
    """The problems in problems/*.npz, smallest first."""

    def __init__(self) -> None:
        super().__init__()
        for path in PROBLEMS.glob("*.npz"):
            unknowns = load(path).P.shape[0]
            for solver, (above, seconds) in KNOWN_TIMEOUTS.items():
                if unknowns > above:
                    for settings in self.solver_settings:
                        self.known_solver_timeouts[(path.stem, solver, settings)] = seconds

    @property
    def description(self) -> str:
        return ("Contact of elastic bars against rigid walls (contactqp): the QP of a "
                "stiffness chain with one inequality per contact, in SI units and scaled; the "
                "duals are the contact forces, known exactly. The Hessian is positive "
                "definite but in the free_bar, held_by_contact and free_bars problems, where "
                "bars with no support are held by their contacts alone (positive "
                "semidefinite). Two 2D elasticity problems (scikit-fem, P1 plane strain: a "
                "cylinder on a rigid flat, a block on a wavy foundation) join them.")

    @property
    def title(self) -> str:
        return "contactqp contact test set"

    @property
    def sparse_only(self) -> bool:
        return False

    def __iter__(self) -> Iterator[qpbenchmark.Problem]:
        """Dense up to DENSE_UP_TO unknowns (qpbenchmark converts them back to sparse for the
        sparse-only solvers, and the dense-only ones take nothing else), sparse beyond (a
        dense 10⁴ x 10⁴ matrix is 800 MB: the dense-only solvers refuse it)."""
        for path in sorted(PROBLEMS.glob("*.npz"), key=lambda p: (p.stat().st_size, p.name)):
            problem = qpbenchmark.Problem.from_qpsolvers(load(path), path.stem)
            yield problem.to_dense() if problem.P.shape[0] <= DENSE_UP_TO else problem
