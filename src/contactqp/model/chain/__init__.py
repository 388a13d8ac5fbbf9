"""A bar scene's model: the fast implementation of the model protocol
(:mod:`contactqp.model.base`) for chains of bars, one displacement per node.

- :mod:`~contactqp.model.chain.numbering`: the scene laid out as one chain of nodes, the
  :class:`Layout` (made once per scene, :func:`layout_of`), with the arrays the methods and
  the check read (:mod:`~contactqp.model.chain.arrays`) and what is computed from them
  (:mod:`~contactqp.model.chain.derived`);
- :mod:`~contactqp.model.chain.model`: the :class:`Model`: K in band storage, solves with K by
  statics or a banded Cholesky, the scales' terms by statics;
- :mod:`~contactqp.model.chain.condensed`: the problem condensed onto its contact nodes;
- :mod:`~contactqp.model.chain.quantities`: what methods read off a chain besides its solves
  (the strain formulation's rows, the stiffness the walls see, forces without circulation);
- :mod:`~contactqp.model.chain.floating`: bars with no support, and whether their contacts
  hold them (refused with the reason before any method runs);
- :mod:`~contactqp.model.chain.to_problem`: a scene's K, f, C, g as a
  :class:`~contactqp.Problem` (the contract test: a scene and its problem agree).
"""

from contactqp.model.chain.condensed import Condensed, condense, condensed_model
from contactqp.model.chain.floating import unheld_bars, wedged_bars, wedged_rows
from contactqp.model.chain.layout_names import (
    LONG_SEGMENTS,
    TOPOLOGY,
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
from contactqp.model.chain.numbering import layout_of
from contactqp.model.chain.quantities import elongation_rows, wall_stiffness, without_circulation
from contactqp.model.chain.to_problem import problem_from_scene

__all__ = ["LONG_SEGMENTS", "TOPOLOGY", "Condensed", "ContactRows", "Layout", "Model",
           "bar_groups", "bar_load_terms", "build_model", "condense", "condensed_model",
           "contact_forces_on_nodes", "count_up_to", "determinate_chain_solve", "element_forces",
           "elongation_rows", "in_set", "largest", "layout_of", "link_forces", "load_force_scale",
           "load_force_terms", "node_set", "penetration", "problem_from_scene", "run_ends",
           "run_starts", "scene_model", "seen_stiffness", "segment_reduce", "spread",
           "support_reactions", "unheld_bars", "wall_stiffness", "wedged_bars", "wedged_rows",
           "without_circulation"]
