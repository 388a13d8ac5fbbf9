"""A scene laid out as one chain of nodes (:mod:`~contactqp.model.chain.numbering`: the numbering
and the arrays along the chain, :class:`Layout`) and what is computed from it
(:mod:`~contactqp.model.chain.derived`: forces along the chain, seen stiffness, the force scales,
bar grouping).
"""

from contactqp.model.chain.derived import (
    LONG_SEGMENTS,
    bar_groups,
    bar_load_terms,
    contact_forces_on_nodes,
    count_up_to,
    element_forces,
    in_set,
    largest,
    link_forces,
    load_force_scale,
    load_force_terms,
    node_set,
    penetration,
    run_ends,
    run_starts,
    seen_stiffness,
    segment_reduce,
    spread,
)
from contactqp.model.chain.numbering import TOPOLOGY, ContactRows, Layout

__all__ = ["LONG_SEGMENTS", "TOPOLOGY", "ContactRows", "Layout", "bar_groups", "bar_load_terms", "contact_forces_on_nodes",
           "count_up_to", "element_forces", "in_set", "largest", "link_forces",
           "load_force_scale", "load_force_terms", "node_set", "penetration", "run_ends",
           "run_starts", "seen_stiffness", "segment_reduce", "spread"]
