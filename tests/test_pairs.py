"""contactqp.check.chain.bar_contacts: which pushing bar contacts move, the groups of bars they join, and what
they pass on to the held nodes.

Every expected value is worked out by hand from the scene as drawn (node numbers in the
layout's global numbering, bar after bar) or from the jumps given; the bound they make is held
to the exact reference in tests/test_guarantee.py (a wall beside one pushing contact, and
beyond two).
"""

from __future__ import annotations

import numpy as np
import pytest

import contactqp
from contactqp.check.chain.bar_contacts import pushing_pairs, through_pairs


def four_bars() -> contactqp.Scene:
    """Bars 0–1 tied by contact 0 and bars 1–2 by contact 1 (one group of three bars); bar 3
    tied to bar 2's support node by contact 2 (it cannot move: a supported end). Each bar two
    elements (three nodes): global nodes 0–2, 3–5, 6–8, 9–11."""
    bar = contactqp.Bar(lengths=np.full(2, 0.5), areas=np.full(2, 1e-4),
                        youngs_modulus=np.full(2, 2e11))
    return contactqp.Scene(
        bars=(bar,) * 4,
        supports=(contactqp.Support(node=0, bar=0), contactqp.Support(node=1, bar=2)),
        loads=(contactqp.Load(node=2, force=1e3, bar=0), contactqp.Load(node=1, force=1e3, bar=1),
               contactqp.Load(node=2, force=-1e3, bar=3)),
        walls=(),
        contacts=(contactqp.BarContact(bar_a=0, node_a=2, bar_b=1, node_b=0, gap=0.0),
                  contactqp.BarContact(bar_a=1, node_a=2, bar_b=2, node_b=0, gap=0.0),
                  contactqp.BarContact(bar_a=3, node_a=2, bar_b=2, node_b=1, gap=0.0)))


def test_the_pushing_contacts_their_ends_and_which_can_move():
    layout = four_bars().layout
    ends, moving, group = pushing_pairs(layout, np.array([True, True, True]))
    assert ends.tolist() == [[2, 3], [5, 6], [11, 7]]
    assert moving.tolist() == [True, True, False]  # contact 2's end at node 7 is a support
    assert group.tolist() == [group[0], group[0]]  # the two that move: one group of bars


def test_a_contact_that_does_not_push_is_left_out():
    layout = four_bars().layout
    ends, moving, group = pushing_pairs(layout, np.array([True, False, True]))
    assert ends.tolist() == [[2, 3], [11, 7]]
    assert moving.tolist() == [True, False]
    assert group.size == 1


def test_no_pushing_contact_makes_nothing():
    layout = four_bars().layout
    ends, moving, group = pushing_pairs(layout, np.zeros(3, dtype=bool))
    assert ends.shape == (0, 2) and moving.size == 0 and group.size == 0
    assert through_pairs(np.array([0, 2]), np.array([1.0, 2.0]), ends, group, 5.0) == 0.0


@pytest.mark.parametrize("moves", [0.0, 0.25])
def test_each_group_passes_on_both_ends_of_each_of_its_contacts(moves):
    held = np.array([0, 2, 3, 5, 6, 9, 10])
    jumps = np.array([7.0, -1.0, 2.0, -0.5, 4.0, 3.0, -8.0])  # one per held node
    ends = np.array([[2, 3], [5, 6], [9, 10]])
    group = np.array([0, 0, 1])
    # group 0: |−1| + |2| and |−0.5| + |4|, and 2·moves for each contact; group 1: 3 + 8
    expected = max(1.0 + 2.0 + 0.5 + 4.0 + 4.0 * moves, 3.0 + 8.0 + 2.0 * moves)
    assert through_pairs(held, jumps, ends, group, moves) == pytest.approx(expected, rel=1e-15)
