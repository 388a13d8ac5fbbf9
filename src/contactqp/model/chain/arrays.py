"""What the methods and the check read from a :class:`~contactqp.model.chain.layout_names.Layout` beyond its
numbering, each made once per layout: the loads summed along the chain and their force scale,
the press-fit forces, the compliance each row sees with the supports held, the walls of each
side, the nodes of the outside forces, and the sets the check keeps per held set
(:func:`contactqp.check.chain.spans.kept`). :class:`SolvingArrays` is a base of Layout; the arrays that do
not depend on the load values or the gaps are shared by :meth:`Layout.with_values`
(:data:`contactqp.model.chain.numbering.TOPOLOGY`, :data:`~contactqp.model.chain.numbering.SAME_GAPS`).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from contactqp.model.chain.derived import (
    _read_only,
    largest,
    load_force_terms,
    seen_stiffness,
    wall_arrays,
)


class SolvingArrays:
    """The cached arrays above, read through a Layout (``self`` is one)."""

    @cached_property
    def running_load(self) -> np.ndarray:
        """S_j = Σ_(i<=j) P_i, the nodal loads summed over the chain (N)."""
        return _read_only(np.cumsum(self.nodal_loads))

    @cached_property
    def compliance_load(self) -> np.ndarray:
        """1/k of each link times the running load at its start (:attr:`running_load`), 0 past
        the last node (inf × 0 at a junction is left NaN: never summed over)."""
        with np.errstate(invalid="ignore"):
            return _read_only(self.link_compliance * np.append(self.running_load[:-1], 0.0))

    @cached_property
    def load_size(self) -> float:
        """‖nodal loads‖∞ (N), once per scene: the hull's force tolerance starts from it."""
        return largest(self.nodal_loads)

    @cached_property
    def load_scale(self) -> float:
        """:func:`load_force_scale`, once per scene (from :attr:`load_terms`)."""
        return largest(self.load_terms)

    @cached_property
    def load_terms(self) -> np.ndarray:
        """:func:`load_force_terms`, once per scene: a batch reads them case by case."""
        return _read_only(load_force_terms(self))

    @cached_property
    def press_fit_force(self) -> float:
        """The largest force that pushes a press fit apart (a wall that starts past its node,
        or two bars that start into each other: gap < 0): abs(gap) × the stiffness the row sees
        with the supports held (N); 0 without one."""
        return float(np.max(self.press_fit_forces, initial=0.0))

    @cached_property
    def press_fit_forces(self) -> np.ndarray:
        """Per contact row, the force that pushes its press fit apart (:attr:`press_fit_force`):
        for a wall its node's seen stiffness, for a bar contact its two ends' in series (a
        supported end is rigid); 0 for a row with gap >= 0."""
        gaps = self.rows.gap
        forces = np.zeros(gaps.size)
        press = gaps < 0.0
        if press.any():
            with np.errstate(divide="ignore"):
                forces[press] = -gaps[press] / self.row_compliance[press]
        return _read_only(forces)

    @cached_property
    def row_compliance(self) -> np.ndarray:
        """Per contact row, the compliance it sees with the supports held (m/N): a wall's
        node's 1/s, a bar contact's two ends' in series (a supported end adds nothing)."""
        rows, nodes, _, gaps = self.rows
        entry = ~self.support_mask[nodes]
        stiffness = seen_stiffness(self, np.zeros(0, dtype=np.intp), nodes[entry])
        with np.errstate(divide="ignore"):
            return _read_only(np.bincount(rows[entry], 1.0 / stiffness, minlength=gaps.size))

    @cached_property
    def walls_by_side(self) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        """Per side (+1: u <= gap, −1: −u <= gap): the gap of the wall at every global node
        (inf where none) and its row (−1 where none). A scene has at most one wall per node
        and side (contactqp.scene refuses more); walls at supports are left out."""
        return wall_arrays(self)

    @cached_property
    def outside_nodes(self) -> np.ndarray:
        """The node of every force from outside but the distributed loads' (the point loads,
        each contact row's nonzeros, the supports), in the order the check lists them
        (:func:`contactqp.check.external_forces`)."""
        return _read_only(np.concatenate((self.load_nodes, self.rows.node,
                                          self.support_nodes)).astype(np.intp))

    @cached_property
    def load_entries(self) -> tuple[np.ndarray, np.ndarray]:
        """(node, force) of every load as the check lists them: the point loads, then the
        distributed loads' nodal forces where they are not 0; once per scene, since they
        depend on the loads alone."""
        nodes, loads = self.load_nodes, self.scene.load_forces
        if self.scene.distributed:
            spread = self.distributed_nodal_loads
            at = np.flatnonzero(spread)
            nodes, loads = np.concatenate((nodes, at)), np.concatenate((loads, spread[at]))
        return _read_only(nodes), _read_only(np.asarray(loads, dtype=float))

    @cached_property
    def external_nodes(self) -> np.ndarray:
        """The node of every force from outside (:attr:`outside_nodes` with the distributed
        loads' nodes after the point loads'), in the order of
        :func:`contactqp.check.external_forces`."""
        if not self.scene.distributed:
            return self.outside_nodes
        rows_and_supports = self.outside_nodes[self.load_nodes.size:]
        return _read_only(np.concatenate((self.load_entries[0], rows_and_supports)))

    @cached_property
    def softest(self) -> float:
        """The smallest element stiffness (N/m): :attr:`contactqp.model.Model.force_scale`
        of a scene that nothing loads."""
        return float(self.element_stiffness.min())

    @cached_property
    def held_cache(self) -> dict:
        """What the check works out from a set of held nodes alone, for the last few sets
        (:func:`contactqp.check.chain.spans.kept`): it depends on where things sit and on the stiffnesses,
        never on the load values or the gaps, so the layouts of :meth:`with_values` share it."""
        return {}

    @cached_property
    def wall_nodes_by_side(self) -> dict[int, np.ndarray]:
        """Per side, the global nodes that have a wall on it, sorted (walls at supports left
        out, as in :attr:`walls_by_side`): where the walls sit, so shared by
        :meth:`with_values`."""
        rows, walls = self.rows, len(self.scene.walls)
        node, sign = rows.node[:walls], rows.coefficient[:walls]
        return {side: _read_only(np.sort(node[(sign == side) & ~self.support_mask[node]]))
                for side in (1, -1)}


__all__ = ["SolvingArrays"]
