"""A stretch of a chain between held nodes, as the hull loop (:mod:`contactqp.methods.hull`)
settles it: u = u_free − w where w is linear in the compliance φ between held nodes and flat
beyond the outermost (:func:`displacements`, the numbers :func:`contactqp.model.spread`
gives), and the sub-stretches a stretch splits into as walls are held in it
(:class:`Stretch`).
"""

from __future__ import annotations

import numpy as np

from contactqp.model import Layout, spread

FEW_HELD = 32  # held nodes on one bar up to which u is worked out segment by segment


def displacements(layout: Layout, u_free: np.ndarray, pinned: np.ndarray, nodes: np.ndarray,
                  w_held: np.ndarray) -> np.ndarray:
    """u = u_free − w, w spread from its values ``w_held`` at the held ``nodes`` (the
    mask ``pinned``) as :func:`contactqp.model.spread` spreads it (the same numbers); on
    one bar worked out segment by segment where few nodes are held, and at the free
    nodes alone where most are (a patch: 5 % of the nodes). u at the held nodes is left
    for the caller."""
    if len(layout.scene.bars) > 1:
        u = spread(layout, nodes, w_held)
        return np.subtract(u_free, u, out=u)
    # on one bar its ends and held nodes are in order: no sort as spread's among bars
    phi = layout.chained_compliance
    n = phi.size
    x = np.concatenate((phi[:1], phi[nodes], phi[-1:]))
    w = np.concatenate((w_held[:1], w_held, w_held[-1:]))
    if nodes.size <= FEW_HELD:
        return _by_segment(phi, u_free, x, w, np.concatenate(([-1], nodes, [n])))
    if 4 * nodes.size < n:  # most nodes free: interpolate along the whole chain
        u = np.interp(phi, x, w)
        return np.subtract(u_free, u, out=u)
    free = np.flatnonzero(~pinned)
    u = np.empty(n)
    u[free] = u_free[free] - np.interp(phi[free], x, w)
    return u


def _by_segment(phi: np.ndarray, u_free: np.ndarray, x: np.ndarray, w: np.ndarray,
                at: np.ndarray) -> np.ndarray:
    """u = u_free − w at the nodes strictly between the nodes ``at`` (−1 and n at the
    ends), w linear in φ from (x, w) at each to the next: numpy.interp's arithmetic,
    slope·(φ − x_k) + w_k, segment by segment in place (3 ms → 0.5 ms on 10⁶ nodes: no
    search for each node's segment)."""
    u = np.empty(u_free.size)
    for k in range(at.size - 1):
        a, b = int(at[k]) + 1, int(at[k + 1])
        if a >= b:
            continue
        slope = (w[k + 1] - w[k]) / (x[k + 1] - x[k])
        part = np.subtract(phi[a:b], x[k], out=u[a:b])
        part *= slope
        part += w[k]
        np.subtract(u_free[a:b], part, out=part)
    return u


class Stretch:
    """Nodes ``first`` .. ``stop`` − 1 between the held nodes ``left`` and ``right`` (None: a
    free end there), and w = u_free − u at those two (None at a free end)."""

    def __init__(self, first: int, stop: int, left: int | None, right: int | None,
                 w_left: float | None, w_right: float | None) -> None:
        self.first, self.stop, self.left, self.right = first, stop, left, right
        self.w_left, self.w_right = w_left, w_right

    def anchors(self, inner: np.ndarray, w_inner: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The held nodes of the stretch with ``inner`` held too, in order, and w at each."""
        nodes, w = [inner], [w_inner]
        if self.left is not None:
            nodes.insert(0, [self.left])
            w.insert(0, [self.w_left])
        if self.right is not None:
            nodes.append([self.right])
            w.append([self.w_right])
        return np.concatenate(nodes).astype(np.intp), np.concatenate(w)

    def between(self, inner: np.ndarray, k: int, w_inner: np.ndarray) -> Stretch:
        """The sub-stretch between held nodes ``inner`` k − 1 and k (the ends beyond them)."""
        left = self.left if k == 0 else int(inner[k - 1])
        right = self.right if k == inner.size else int(inner[k])
        return Stretch(self.first if k == 0 else left + 1, self.stop if k == inner.size else right,
                       left, right,
                       self.w_left if k == 0 else float(w_inner[k - 1]),
                       self.w_right if k == inner.size else float(w_inner[k]))


__all__ = ["FEW_HELD", "Stretch", "displacements"]
