"""Refusals before any solve: what a scene's or a problem's constraints leave impossible or
undetermined, found from the constraints alone (no factorisation, no method).

- :mod:`~contactqp.feasibility.graph`: a scene's constraint graph (walls, bar contacts,
  supports): no position for a node, contact forces rigid contact leaves undetermined,
  equality conflicts;
- :mod:`~contactqp.feasibility.rows`: a problem's contact rows: no zero row, no constraint
  twice, rows some u meets all at once (else named, with the Farkas weights).

A bar with no support that its contacts do not hold is the chain model's to say
(:mod:`contactqp.model.chain.floating`): it needs the numbering.
"""

from contactqp.feasibility.graph import (
    constraint_graph,
    equality_conflict,
    impossible_constraints,
    indeterminate_contacts,
    shortest_paths,
    tight_cycles,
)
from contactqp.feasibility.rows import ABSURD_MOVE, conflicting_rows, row_conflict

__all__ = ["ABSURD_MOVE", "conflicting_rows", "constraint_graph", "equality_conflict",
           "impossible_constraints", "indeterminate_contacts", "row_conflict", "shortest_paths",
           "tight_cycles"]
