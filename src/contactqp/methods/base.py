"""What every method shares: the answer it returns (:class:`Solution`), which the pipeline
turns into a checked Result (:mod:`contactqp.result`); a method never sees the Result, nor the
check."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Solution:
    """What a method returns: free-node displacements (m) and one contact force per contact
    row (N)."""

    u_free: np.ndarray
    contact_force: np.ndarray
    solver: str
    iterations: int = 1
    status: str = "solved"  # the solver's own claim, recorded, never trusted
    claimed_success: bool = True
    info: dict[str, Any] = field(default_factory=dict)
    # every node's displacement, 0 at the supports, where the method has it over the whole
    # chain (the hull): the Result takes it as it is instead of placing u_free again
    u_nodes: np.ndarray | None = field(default=None, repr=False, compare=False)


__all__ = ["Solution"]
