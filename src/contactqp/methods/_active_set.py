"""One active-set loop for every method that enforces unilateral contact by equalities."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from contactqp.errors import SolverError
from contactqp.model import Model, bar_groups
from contactqp.model.chain.floating import wedged_rows

Step = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
Update = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


# An active-set decision ignores penetrations and pulls below this fraction of the
# displacement and force scales: round-off, not contact.
DECISION_RTOL = 1e-12


def displacement_tolerance(u: np.ndarray, g: np.ndarray, P: np.ndarray, K) -> float:
    """DECISION_RTOL of the displacement scale max(‖u‖, ‖g‖, ‖P‖ / max diag K): the last term
    keeps it physical when the exact u is 0 (closed zero gaps)."""
    return DECISION_RTOL * max(np.abs(u).max(initial=0.0), np.abs(g).max(initial=0.0),
                               np.abs(P).max(initial=0.0) / K.diagonal().max())


class ActiveSetCycle(SolverError):
    """The active-set loop came back to a set it had left."""


def default_max_iterations(n_rows: int) -> int:
    return 50 + 2 * n_rows




def pinning(model: Model) -> Callable[[np.ndarray], np.ndarray]:
    """For a scene with bars that have no support (:attr:`Model.floating`): a function that
    adds to an active set the rows that stop each group of such bars the set leaves free
    (joined to no support or wall by active rows), in the direction its net load moves it
    (both ways when that is 0): where nothing holds a bar, K + the active rows is singular.
    The identity for every other scene."""
    if not model.floating:
        return lambda active: active
    layout, scene = model.layout, model.scene
    bars = len(scene.bars)
    net = layout.bar_loads
    ahead, behind = layout.row_bars  # per row: the bars it stops in +x and in −x (−1: none)
    ends = np.column_stack((ahead, behind))
    ends[ends < 0] = bars  # a wall's fixed side: the ground (bar_groups' last vertex)
    # a wedged bar (no load, walls with no room) is pinned by its + walls alone: its − walls
    # too would be a row twice over where both sides face one node, a singular system
    never = wedged_rows(scene) & (ahead < 0)

    def pin(active: np.ndarray) -> np.ndarray:
        active = np.array(active, dtype=bool)
        while True:
            labels = bar_groups(layout, active)  # the ground's label last
            free = np.flatnonzero(labels[:-1] != labels[-1])
            if free.size == 0:
                return active
            push = np.bincount(labels[free], net[free], minlength=bars + 1)  # per group
            crossing = labels[ends[:, 0]] != labels[ends[:, 1]]  # not inside one group
            adding = np.zeros_like(active)
            for stops, sign in ((ahead, 1.0), (behind, -1.0)):
                moved = np.isin(stops, free)
                toward = sign * push[labels[np.maximum(stops, 0)]] >= 0.0
                adding |= moved & toward & crossing & ~active & ~never
            if not adding.any():
                return active
            active |= adding

    return pin


def active_set_loop(n_rows: int, step: Step, update: Update, *, method: str,
                    max_iterations: int | None = None,
                    start: np.ndarray | None = None,
                    pin: Callable[[np.ndarray], np.ndarray] | None = None,
                    ) -> tuple[np.ndarray, np.ndarray, int]:
    """Iterate ``active -> step(active) = (u, λ) -> update(active, u, λ)`` to a fixed point.

    Starts from ``start`` (default: every wall open). ``pin``: applied to every set before
    it is solved (:func:`pinning`). Returns (u, λ, iterations). It terminates: a set that
    comes back (a cycle) or more than ``max_iterations`` steps is a SolverError that says so.
    """
    limit = default_max_iterations(n_rows) if max_iterations is None else int(max_iterations)
    pin = pin or (lambda active: active)
    active = pin(np.zeros(n_rows, dtype=bool) if start is None else np.asarray(start, dtype=bool))
    seen = {active.tobytes()}
    for iteration in range(1, limit + 1):
        u, lam = step(active)
        following = pin(update(active, u, lam))
        if np.array_equal(following, active):
            return u, lam, iteration
        key = following.tobytes()
        if key in seen:
            raise ActiveSetCycle(
                f"{method}: the active-set loop cycles (walls in contact "
                f"{np.flatnonzero(following).tolist()} came back after {iteration} steps)"
            )
        seen.add(key)
        active = following
    raise SolverError(f"{method}: the active-set loop did not settle in {limit} steps")
