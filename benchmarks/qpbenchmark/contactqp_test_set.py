"""contactqp's contact problems as a qpbenchmark test set.

    python benchmarks/qpbenchmark/export.py          # writes problems/ (once)
    qpbenchmark benchmarks/qpbenchmark/contactqp_test_set.py run

Each problem is the QP of an elastic bar scene against rigid walls (contactqp), in SI units
and scaled to order one: minimise ½ xᵀKx − Pᵀx subject to C x <= g, K the stiffness of a
chain (tridiagonal, positive definite), C one row per wall (or bar contact). Its duals are the
contact forces; problems/exact.json holds the exact ones (benchmarks/qpbenchmark/README.md).
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


class ContactqpTestSet(qpbenchmark.TestSet):
    """The problems in problems/*.npz, smallest first."""

    def __init__(self) -> None:
        super().__init__()
        # DAQP (dense, no time-limit parameter) ran past the 10 s limit for more than 90 s on
        # the 10⁴-unknown bar and stalled the run: a known timeout, as qpbenchmark's own test
        # sets record theirs (counted as a failure, not run)
        for path in PROBLEMS.glob("*.npz"):
            if load(path).P.shape[0] > DENSE_UP_TO:
                for settings in self.solver_settings:
                    self.known_solver_timeouts[(path.stem, "daqp", settings)] = 90.0

    @property
    def description(self) -> str:
        return ("Contact of elastic bars against rigid walls (contactqp): the QP of a "
                "stiffness chain with one inequality per contact, in SI units and scaled; the "
                "duals are the contact forces, known exactly.")

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
