"""One run's sway read from the answer's displacements (contactqp.runs.propagate), where few
loads act on it: no pass over the cut residuals and no running sum over the run.

In a run of elements between nodes lo and hi of one bar, element e carries the cut residual
r_e = N_e + E_e (N_e = k_e·(u_(e+1) − u_e) the element force of the answer, E_e the outside
forces on the nodes up to e), and the answer is off by the elongation errors (c − r_e)/k_e.
Their running sum from lo to node j telescopes:

    D_j = Σ (c − E_e)/k_e − (u_j − u_lo) = Σ over the stretches of constant E of
          (c − E)·(φ_q − φ_p) − (u_j − u_lo),

φ the compliance Σ 1/k from the bar's first node (:attr:`contactqp.model.Layout.compliance`,
kept per scene). Where E steps only at a few loaded nodes (one wall, a few loads), D is
α·φ_j − u_j plus a constant on each stretch, and its largest and smallest values are two
reductions over a product of model and answer, made in blocks of :data:`BLOCK` nodes into one
small buffer (numpy's running sum over 10⁶ doubles: 3.4 ms; this: about 0.5 ms, and no array
over the chain).

φ is itself a running sum: each of its additions rounds by up to ½ε·φ (ε the float epsilon),
so φ_q − φ_p is off from the sum of its elements' 1/k by up to (q − p)·½ε·φ_q, and a method that
builds u from φ (the hull) carries the same error in u, which D read through φ would not see
(measured: a uniform bar of 10⁶ elements, the hull's u 1.7e-11 U off, read as 9e-16 U). So
each stretch adds |α|·(q − p + 8)·½ε·φ_q to the sway, twice (a node's D and the run's end's),
which bounds that error and the rounding of α·φ_j − u_j; a run is read this way only where
that is at most :data:`MAX_RELATIVE` of each stretch's compliance (a stretch far stiffer than
the bar before it is read through r, whose running sum has no such error: measured on random
scenes, 6e-9 U of allowance beside a bound of 2e-22 U). c, the mean of r weighted by
1/k where the run is held at both ends, telescopes too, (Σ E·C_stretch + u_hi − u_lo)/C_run,
with C the stretches' and the run's compliance summed element by element (as the run's kept
sum is), not read from φ: a press fit's force is many times F, and φ's error in the
divisor would be that many times larger (measured: 10⁶ elements, an exact answer flagged with a
force bound of 1.4e-5 F).
"""

from __future__ import annotations

import numpy as np

BLOCK = 2**15  # nodes per block: a buffer of 256 kB, reused
FEW_STEPS = 64  # stretches of constant E in a run read this way at most (else r's own pass)
MAX_RELATIVE = 1e-9  # φ's round-off on a stretch read this way at most, of its compliance
# (a uniform bar: about n·ε/2, 1.1e-10 at 10⁶ elements; beyond it, r's own pass)
HALF_EPS = float(np.finfo(float).eps) / 2.0  # the unit round-off


def telescoped(phi: np.ndarray, compliance: np.ndarray, u: np.ndarray, steps: np.ndarray,
               levels: np.ndarray, run: tuple[int, int, int, int, float], c: float | None,
               left_held: bool) -> tuple[float, float] | None:
    """(c, the sway) of one run, or None (below): ``run`` is (its first link lo, one past its last link hi,
    its first element's index in ``compliance``, its bar's first node, its compliance summed
    element by element); links lo … hi − 1 are elements first … first + hi − lo − 1, nodes lo
    … hi. ``c`` when the run is held at one end only (the cut residual past its free end),
    None for the weighted mean; ``steps`` the loaded nodes (sorted) and ``levels`` E from each
    of them on. None where more than :data:`FEW_STEPS` stretches of constant E cross the
    run, or φ's round-off on one is more than :data:`MAX_RELATIVE` of its compliance."""
    lo, hi, first, _, run_compliance = run
    low_step = int(np.searchsorted(steps, lo, side="right"))  # steps in (lo, hi)
    high_step = int(np.searchsorted(steps, hi - 1, side="right"))
    if high_step - low_step >= FEW_STEPS:
        return None
    cuts = [lo, *steps[low_step:high_step].tolist(), hi]
    level = [float(levels[low_step - 1]) if low_step > 0 else 0.0,
             *levels[low_step:high_step].tolist()]
    p_phi = phi[cuts].tolist()
    # φ's round-off on each stretch, relative to its compliance: where a stretch is stiff
    # beside what comes before it in its bar, r's own pass is the sharper
    for p, q, phi_p, phi_q in zip(cuts, cuts[1:], p_phi, p_phi[1:]):
        if (q - p + 8) * HALF_EPS * phi_q > MAX_RELATIVE * (phi_q - phi_p):
            return None
    if c is None:
        # Σ E·C over the stretches, as E_L·C_run + Σ (E − E_L)·C over all but the longest
        # stretch L: its compliance is never summed (one wall and a load at mid-span: half a
        # pass), each other stretch's element by element
        longest = int(np.argmax(np.diff(cuts)))
        loaded = level[longest] * run_compliance + sum(
            (e - level[longest]) * float(np.add.reduce(compliance[first + p - lo:
                                                                  first + q - lo]))
            for k, (e, p, q) in enumerate(zip(level, cuts, cuts[1:])) if k != longest)
        c = (loaded + (float(u[hi]) - float(u[lo]))) / run_compliance
    top, bottom, d_p, slack = 0.0, 0.0, 0.0, 0.0  # D over the nodes after lo; D at lo is 0
    buffer = np.empty(min(BLOCK, hi - lo))
    for e, p, q, phi_p, phi_q in zip(level, cuts, cuts[1:], p_phi, p_phi[1:]):
        alpha = c - e
        u_p = float(u[p])
        shift = d_p - alpha * phi_p + u_p  # D_j = shift + α·φ_j − u_j on (p, q]
        high, low = _span(phi, u, alpha, p + 1, q + 1, buffer)
        top, bottom = max(top, shift + high), min(bottom, shift + low)
        d_p += alpha * (phi_q - phi_p) - (float(u[q]) - u_p)
        slack += abs(alpha) * (q - p + 8) * HALF_EPS * phi_q  # φ's round-off (docstring)
    if left_held:
        return c, max(abs(top), abs(bottom)) + 2.0 * slack
    return c, max(abs(d_p - top), abs(d_p - bottom), abs(d_p)) + 2.0 * slack


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


__all__ = ["BLOCK", "FEW_STEPS", "MAX_RELATIVE", "telescoped"]
