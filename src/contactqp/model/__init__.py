"""Scene → model: everything later stages need to know about the algebra.

- :mod:`contactqp.model.chain.layout_names` (re-exported here, and as ``contactqp.model.chain.layout_names``): the
  numbering of the nodes and the arrays along the chain (element stiffnesses, compliance,
  contact rows, nodal loads), and what is computed from them;
- :mod:`~contactqp.model.chain.model`: the Model, K (band), P, C, g, the solves with K, the scales
  F and U;
- :mod:`~contactqp.model.chain.condensed`: the problem condensed onto the contact nodes;
- :mod:`~contactqp.model.chain.quantities`: what methods read off a model besides its solves with K
  (the strain formulation's rows, the stiffness the walls see, forces without circulation).
"""

from contactqp.model.base import ContactModel, ScaleTerms
from contactqp.model.chain.condensed import Condensed, condense, condensed_model
from contactqp.model.chain.layout_names import (
    LONG_SEGMENTS,
    ContactRows,
    Layout,
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
from contactqp.model.chain.model import (
    Model,
    build_model,
    determinate_chain_solve,
    scene_model,
    support_reactions,
)
from contactqp.model.chain.quantities import elongation_rows, wall_stiffness, without_circulation

__all__ = [
    "LONG_SEGMENTS",
    "Condensed",
    "ContactModel",
    "ContactRows",
    "Layout",
    "Model",
    "ScaleTerms",
    "bar_groups",
    "bar_load_terms",
    "build_model",
    "condense",
    "condensed_model",
    "contact_forces_on_nodes",
    "count_up_to",
    "determinate_chain_solve",
    "element_forces",
    "elongation_rows",
    "in_set",
    "largest",
    "link_forces",
    "load_force_scale",
    "load_force_terms",
    "node_set",
    "penetration",
    "run_ends",
    "run_starts",
    "scene_model",
    "seen_stiffness",
    "segment_reduce",
    "spread",
    "support_reactions",
    "wall_stiffness",
    "without_circulation",
]
