"""One run's sway read from the answer's displacements (contactqp.runs.propagate), where few
loads act on it: no pass over the cut residuals and no running sum over the run.

In a run of elements between nodes lo and hi of one bar, element e carries the cut residual
r_e = N_e + E_e (N_e = k_e·(u_(e+1) − u_e) the element force of the answer, E_e the outside
forces on the nodes up to e), and the answer is off by the elongation errors (c − r_e)/k_e.
Their running sum from lo to node j telescopes:

    D_j = Σ (c − E_e)/k_e − (u_j − u_lo) = Σ over the stretches of constant E of
          (c − E)·(φ_q − φ_p) − (u_j − u_lo),

φ the compliance Σ L/(EA) from the bar's first node (:attr:`contactqp.model.Layout.compliance`,
kept per scene). Where E steps only at a few loaded nodes (one wall, a few loads), D is
α·φ_j − u_j plus a constant on each stretch, and its largest and smallest values are two
reductions over a product of model and answer, made in blocks of :data:`BLOCK` nodes into one
small buffer (numpy's running sum over 10⁶ doubles: 3.4 ms; this: about 0.5 ms, and no array
over the chain). c, the mean of r weighted by 1/k where the run is held at both ends,
telescopes the same way: (Σ E·(φ_q − φ_p) + u_hi − u_lo)/(φ_hi − φ_lo).
"""

from __future__ import annotations

import numpy as np

BLOCK = 2**15  # nodes per block: a buffer of 256 kB, reused
FEW_STEPS = 64  # stretches of constant E in a run read this way at most (else r's own pass)


def telescoped(phi: np.ndarray, u: np.ndarray, steps: np.ndarray, levels: np.ndarray,
               lo: int, hi: int, c: float | None, left_held: bool
               ) -> tuple[float, float] | None:
    """(c, the sway) of the run over the links lo … hi − 1 (nodes lo … hi): ``c`` when the
    run is held at one end only (the cut residual past its free end), None for the weighted
    mean; ``steps`` the loaded nodes (sorted) and ``levels`` E from each of them on. None
    where more than :data:`FEW_STEPS` stretches of constant E cross the run."""
    first = int(np.searchsorted(steps, lo, side="right"))  # steps in (lo, hi)
    last = int(np.searchsorted(steps, hi - 1, side="right"))
    if last - first >= FEW_STEPS:
        return None
    cuts = [lo, *steps[first:last].tolist(), hi]
    level = [float(levels[first - 1]) if first > 0 else 0.0, *levels[first:last].tolist()]
    p_phi = phi[cuts].tolist()
    if c is None:
        loaded = sum(e * (b - a) for e, a, b in zip(level, p_phi, p_phi[1:]))
        c = (loaded + (float(u[hi]) - float(u[lo]))) / (p_phi[-1] - p_phi[0])
    top, bottom, d_p = 0.0, 0.0, 0.0  # D over the nodes after lo; D at lo is 0
    buffer = np.empty(min(BLOCK, hi - lo))
    for e, p, q, phi_p, phi_q in zip(level, cuts, cuts[1:], p_phi, p_phi[1:]):
        alpha = c - e
        u_p = float(u[p])
        shift = d_p - alpha * phi_p + u_p  # D_j = shift + α·φ_j − u_j on (p, q]
        high, low = _span(phi, u, alpha, p + 1, q + 1, buffer)
        top, bottom = max(top, shift + high), min(bottom, shift + low)
        d_p += alpha * (phi_q - phi_p) - (float(u[q]) - u_p)
    if left_held:
        return c, max(abs(top), abs(bottom))
    return c, max(abs(d_p - top), abs(d_p - bottom), abs(d_p))


def _span(phi: np.ndarray, u: np.ndarray, alpha: float, a: int, b: int,
          buffer: np.ndarray) -> tuple[float, float]:
    """The largest and smallest α·φ_j − u_j over the nodes a … b − 1, block by block."""
    high, low = -np.inf, np.inf
    for start in range(a, b, buffer.size):
        stop = min(start + buffer.size, b)
        part = np.multiply(phi[start:stop], alpha, out=buffer[: stop - start])
        part -= u[start:stop]
        high = max(high, float(part.max()))
        low = min(low, float(part.min()))
    return high, low


__all__ = ["BLOCK", "FEW_STEPS", "telescoped"]
