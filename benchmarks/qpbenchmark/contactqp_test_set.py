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


class ContactqpTestSet(qpbenchmark.TestSet):
    """The problems in problems/*.npz, smallest first."""

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
        """Dense (qpbenchmark converts them back to sparse for the sparse-only solvers, and
        the dense-only ones take nothing else: up to 10³ unknowns, a few MB each)."""
        for path in sorted(PROBLEMS.glob("*.npz"), key=lambda p: (p.stat().st_size, p.name)):
            yield qpbenchmark.Problem.from_qpsolvers(load(path), path.stem).to_dense()
