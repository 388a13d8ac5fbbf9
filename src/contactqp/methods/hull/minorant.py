"""The greatest convex minorant of points (x, y), x increasing: its vertices and the slope of
every step (the isotonic regression of the steps' slopes, weighted by the steps of x), found
as the lower hull in numpy. The hull active set (:mod:`contactqp.methods.hull`) adds the
minorant's vertices of each passed stretch's signed gaps; scipy.optimize.isotonic_regression
gives the same slopes, but importing it took 0.2-0.3 s on the first solve of every process
that met a passed wall, so it is used only for a very lopsided hull.
"""

from __future__ import annotations

import numpy as np

from contactqp.model import run_starts


def minorant_vertices(x: np.ndarray, y: np.ndarray, clip: int) -> np.ndarray:
    """Indices of the vertices of the greatest convex minorant of the points (x, y), x
    increasing: the slopes' isotonic regression, weighted by the steps of x, changes value
    there. ``clip`` −1: slopes <= 0 (a free end on the right: nothing pulls beyond the last
    contact, so the minorant ends flat, its last vertex the lowest point); +1: slopes >= 0
    (a free end on the left); 0: both ends held (the first and last points, at 0)."""
    if x.size < 2:
        return np.zeros(x.size, dtype=np.intp)
    hull = _hull_corners(x, y)
    if hull is None:  # rare: a very lopsided hull; the slope of every step from scipy
        corners, slope = np.arange(x.size), _isotonic_slopes(x, y)
    else:  # the slope of each segment between the hull's corners
        corners, slope = hull
    if clip < 0:
        slope = np.minimum(slope, 0.0)
    elif clip > 0:
        slope = np.maximum(slope, 0.0)
    vertices = corners[1:-1][slope[1:] != slope[:-1]]
    if clip > 0 and slope[0] > 0.0:  # the minorant rises from the first point: its lowest
        vertices = np.concatenate(([0], vertices))
    if clip < 0 and slope[-1] < 0.0:  # the minorant falls to the last point: its lowest
        vertices = np.append(vertices, x.size - 1)
    return vertices


HULL_LEVELS = 64  # levels of minorant_slopes before it hands the points to scipy
PRUNING_PASSES = 1  # passes that drop the points no corner can be, before the tangents
# (one: on the channel and the patch later passes drop one point per dent and pass)
MAX_JOINS = 32  # at most this many dents left: convex runs joined by tangents, else quickhull


def minorant_slopes(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The slope of the greatest convex minorant of the points (x, y) (x increasing) over
    each step of x: the weighted isotonic regression of the steps' slopes (weights the steps
    of x) that scipy.optimize.isotonic_regression gives, found as the lower hull instead
    (:func:`_hull_corners`; importing scipy.optimize takes 0.2-0.3 s, on the first solve of
    every process that meets a passed wall)."""
    hull = _hull_corners(x, y)
    if hull is None:
        return _isotonic_slopes(x, y)
    corners, slope = hull
    return np.repeat(slope, np.diff(corners))


def _hull_corners(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The corners of the lower hull of the points (x, y) (indices, increasing, the first and
    the last among them) and the slope between each two, or None for a lopsided hull. A point
    where the slope does not rise is no corner, and dropping all such points at once leaves
    the hull as it is: one such pass leaves convex runs between a few dents (the channel,
    the flat patch), joined by their common tangents (:func:`_join_convex_runs`); many dents
    go to a quickhull (:func:`_lower_hull`)."""
    step = np.diff(y) / np.diff(x)  # the slope of every step, worked out once
    slope, kept = step, None  # every point a corner (no mask made)
    for _ in range(PRUNING_PASSES):
        rises = slope[1:] > slope[:-1]
        if rises.all():
            return (np.arange(x.size) if kept is None else np.flatnonzero(kept)), slope
        if kept is None:
            kept = np.ones(x.size, dtype=bool)
            kept[1:-1] = rises
        else:
            kept[np.flatnonzero(kept)[1:-1][~rises]] = False
        slope = _kept_slopes(x, y, step, kept)
    corners = np.arange(x.size) if kept is None else np.flatnonzero(kept)
    # what is left is convex but at a few points (each pass above dropped one point there):
    # join its convex runs by their common tangents; many such points, a quickhull
    dents = np.flatnonzero(slope[1:] <= slope[:-1]) + 1  # no corner there
    if dents.size == 0:  # the last pass left only corners
        return corners, slope
    joined = _join_convex_runs(x, y, corners, dents) if dents.size <= MAX_JOINS else None
    corners = _lower_hull(x, y, corners) if joined is None else joined
    if corners is None:
        return None
    if 2 * corners.size < x.size:  # few corners (a quickhull's): their slopes directly
        return corners, np.diff(y[corners]) / np.diff(x[corners])
    kept = np.zeros(x.size, dtype=bool)
    kept[corners] = True
    return corners, _kept_slopes(x, y, step, kept)


def _kept_slopes(x: np.ndarray, y: np.ndarray, step: np.ndarray, kept: np.ndarray
                 ) -> np.ndarray:
    """The slope between each two consecutive points ``kept`` (a mask; the first and the last
    point kept): a kept point's next point is most often kept too, and then the slope is its
    ``step`` (the slope to the next point, the same division bit for bit); only across the
    points dropped is it worked out again (no gather of every kept point)."""
    slope = step[kept[:-1]]  # each kept point but the last starts a pair
    dropped = np.flatnonzero(~kept)
    if dropped.size:  # each run of dropped points: the kept points either side of it
        first = np.flatnonzero(run_starts(dropped - np.arange(dropped.size)))
        a = dropped[first] - 1
        b = dropped[np.append(first[1:], dropped.size) - 1] + 1
        slope[a - first] = (y[b] - y[a]) / (x[b] - x[a])  # a's place among the kept
    return slope


def _isotonic_slopes(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The minorant's slope over every step of x by scipy (the weighted isotonic regression
    of the steps' slopes)."""
    from scipy.optimize import isotonic_regression

    dx = np.diff(x)
    return isotonic_regression(np.diff(y) / dx, weights=dx, increasing=True).x


def _join_convex_runs(x: np.ndarray, y: np.ndarray, corners: np.ndarray,
                      dents: np.ndarray) -> np.ndarray | None:
    """The lower hull of the points ``corners``, which are convex runs apart from the points
    at the positions ``dents`` (no vertex can be there: the slope does not rise): the runs
    joined left to right, each by the common tangent of the hull so far and the next run
    (the tangent's ends found in turn until neither moves; collinear points between them
    dropped). None if a tangent does not settle (the caller uses the quickhull)."""
    bounds = np.concatenate(([0], dents, [corners.size - 1]))
    hull = corners[: bounds[1]]
    for a, b in zip(bounds[1:-1].tolist(), bounds[2:].tolist()):
        run = corners[a + 1: b + 1] if b == corners.size - 1 else corners[a + 1: b]
        if run.size == 0:  # two dents side by side
            continue
        i, j = hull.size - 1, 0
        x_run, y_run, x_hull, y_hull = (_read(x, run), _read(y, run), _read(x, hull),
                                        _read(y, hull))  # read once a run
        to_run, across = np.empty(run.size), np.empty(run.size)
        for _ in range(HULL_LEVELS):
            with np.errstate(divide="ignore", invalid="ignore"):
                np.subtract(y_run, y_hull[i], out=to_run)
                np.divide(to_run, np.subtract(x_run, x_hull[i], out=across), out=to_run)
                j_new = run.size - 1 - int(np.argmin(to_run[::-1]))  # the last of a tie
                from_hull = (y_run[j_new] - y_hull) / (x_run[j_new] - x_hull)
                i_new = int(np.argmax(from_hull))  # the first of a tie
            if (i_new, j_new) == (i, j):
                break
            i, j = i_new, j_new
        else:
            return None
        hull = np.concatenate((hull[: i + 1], run[j:]))
    return hull


def _read(values: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``values[points]`` (``points`` increasing), as a view where they are consecutive."""
    if points.size and points[-1] - points[0] + 1 == points.size:
        return values[points[0]: points[-1] + 1]
    return values[points]


def _lower_hull(x: np.ndarray, y: np.ndarray, candidates: np.ndarray) -> np.ndarray | None:
    """The vertices of the lower hull of the points ``candidates`` (indices, increasing, the
    first and the last among them), by quickhull with every segment split at once: each level
    keeps the points below their segment's chord and makes the lowest of them a vertex. A
    smooth stretch takes about log2(points) levels; None past HULL_LEVELS."""
    vertex = np.zeros(x.size, dtype=bool)
    vertex[candidates[[0, -1]]] = True
    points = candidates[1:-1]
    left = np.full(points.size, candidates[0])
    right = np.full(points.size, candidates[-1])
    for _ in range(HULL_LEVELS):
        # how far below the chord of its segment each point lies (> 0: below)
        depth = ((y[left] - y[points]) * (x[right] - x[left])
                 + (y[right] - y[left]) * (x[points] - x[left]))
        below = depth > 0.0
        points, left, right, depth = points[below], left[below], right[below], depth[below]
        if points.size == 0:
            return np.flatnonzero(vertex)
        first = np.flatnonzero(run_starts(left))  # the segments, in order along x
        deepest = np.maximum.reduceat(depth, first)
        sizes = np.diff(np.append(first, points.size))
        lowest = np.flatnonzero(depth == np.repeat(deepest, sizes))  # the first of a tie
        split = points[lowest[run_starts(left[lowest])]]
        vertex[split] = True
        at = np.repeat(split, sizes)
        right, left = np.where(points < at, at, right), np.where(points > at, at, left)
        keep = points != at
        points, left, right = points[keep], left[keep], right[keep]
    return None


__all__ = ["minorant_slopes", "minorant_vertices"]
