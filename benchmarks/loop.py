"""The library call inside a user's loop: contactqp against hand-written numpy doing the same
job on the default scene, measured in the same run (issue 15's yardsticks).

    hand script      the course's Algorithm 1 as a user writes it: K (5 x 5) and the wall row
                     assembled from the geometry, the bordered system [[K, Cᵀ], [C, 0]] solved
                     by numpy.linalg.solve, the wall dropped and K solved alone if it pulls
    hand loop        the hand script once per load case, in a Python loop
    hand vectorised  every case at once: K factored once, the free displacements of all cases
                     by one solve with many right-hand sides, the wall force per case in closed
                     form (one wall: λ = max(0, (u_free,tip − g) / (K⁻¹)_tip,tip))

contactqp is timed as a user calls it: ``solve(scene, method)`` for one answer (each a checked
Result); per case ``solve(scene.scaled_loads(f))`` in a loop; ``prepare(scene)`` once, then
``prepared.solve(loads)`` for one case and ``prepared.solve_many(loads)`` for all (lagrange
and the penalty solve the cases together; augmented case by case). Every
contactqp answer is compared with the hand version's; a mismatch stops the run. Writes
loop.json.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

import contactqp
from cases import machine, median_time

E, LENGTH, D0, D1 = 210e9, 1.0, 0.040, 0.020  # the course problem (contactqp.default_scene)
ELEMENTS, LOAD_NODE, FORCE, GAP = 4, 2, 565486.67, 1e-4
METHODS = [("lagrange", {}), ("penalty", {}), ("augmented", {}), ("qp", {"backend": "clarabel"}),
           ("qp", {"backend": "osqp"}), ("qp", {"backend": "cvxpy"})]


def hand_stiffness() -> np.ndarray:
    """K of the free nodes 1..4 from the geometry (areas at the elements' mid-length)."""
    h = LENGTH / ELEMENTS
    d = D0 + (D1 - D0) * (np.arange(ELEMENTS) + 0.5) * h / LENGTH
    k = E * math.pi * d**2 / 4 / h
    K = np.diag(k + np.r_[k[1:], 0.0]) - np.diag(k[1:], 1) - np.diag(k[1:], -1)
    return K


def hand_script(force: float = FORCE) -> tuple[np.ndarray, float]:
    """Algorithm 1: (u at nodes 1..4, wall force)."""
    K = hand_stiffness()
    P = np.zeros(ELEMENTS)
    P[LOAD_NODE - 1] = force
    C = np.zeros(ELEMENTS)
    C[-1] = 1.0
    kkt = np.block([[K, C[:, None]], [C[None, :], np.zeros((1, 1))]])
    x = np.linalg.solve(kkt, np.r_[P, GAP])
    if x[-1] < 0.0:  # the wall would pull: no contact
        return np.linalg.solve(K, P), 0.0
    return x[:-1], float(x[-1])


def hand_loop(forces: np.ndarray) -> np.ndarray:
    return np.array([hand_script(f)[1] for f in forces])


def hand_vectorised(forces: np.ndarray) -> np.ndarray:
    """Every case at once (one wall: the closed form)."""
    K = hand_stiffness()
    P = np.zeros((ELEMENTS, forces.size))
    P[LOAD_NODE - 1] = forces
    u_free = np.linalg.solve(K, P)
    flexibility = np.linalg.solve(K, np.eye(ELEMENTS)[:, -1])[-1]
    return np.maximum(0.0, (u_free[-1] - GAP) / flexibility)


def label(method: str, options: dict) -> str:
    return "/".join([method, *map(str, options.values())])


def main(quick: bool, out: Path) -> None:
    repeats, cases = (20, 1000) if quick else (200, 10_000)
    scene = contactqp.default_scene()
    factors = np.linspace(0.5, 1.5, cases)
    forces = FORCE * factors
    exact = hand_vectorised(forces)
    if not np.allclose(hand_loop(forces), exact, rtol=1e-12, atol=0.0):
        raise SystemExit("hand loop and hand vectorised disagree")
    one = median_time(hand_script, repeats)
    loop = median_time(lambda: hand_loop(forces), max(3, repeats // 50))
    vectorised = median_time(lambda: hand_vectorised(forces), repeats)
    rows = [{"run": "hand script", "seconds": one, "ratio": 1.0},
            {"run": f"hand loop, {cases} cases", "seconds": loop, "ratio": 1.0},
            {"run": f"hand vectorised, {cases} cases", "seconds": vectorised, "ratio": 1.0}]
    for method, options in METHODS:
        result = contactqp.solve(scene, method, **options)
        if not math.isclose(result.contact_force[0], hand_script()[1], rel_tol=1e-5):
            raise SystemExit(f"{label(method, options)}: {result.contact_force[0]} N against "
                             f"the hand script's {hand_script()[1]} N")
        seconds = median_time(lambda m=method, o=options: contactqp.solve(scene, m, **o), repeats)
        rows.append({"run": f"solve {label(method, options)}", "seconds": seconds,
                     "ratio": seconds / one, "against": "hand script", "goal": "<= 5"})
    sample = min(cases, 1000)  # the per-case loop is timed on this many cases, then scaled

    def library_loop() -> np.ndarray:  # as a user writes it: a scene per case, then solve
        return np.array([contactqp.solve(scene.scaled_loads(float(f))).contact_force[0]
                         for f in factors[:sample]])

    found = library_loop()
    if not np.allclose(found, exact[:sample], rtol=1e-9, atol=1e-9 * FORCE):
        raise SystemExit("the library loop disagrees with the hand version")
    seconds = median_time(library_loop, 1) * cases / sample
    rows.append({"run": f"solve per case, {cases} cases", "seconds": seconds,
                 "ratio": seconds / vectorised, "against": "hand vectorised", "goal": "<= 2",
                 "ratio_to_hand_loop": seconds / loop})
    prepared = contactqp.prepare(scene)
    one_case = np.array([1.1 * FORCE])
    seconds = median_time(lambda: prepared.solve(one_case), repeats)
    rows.append({"run": "prepared.solve, one case", "seconds": seconds, "ratio": seconds / one,
                 "against": "hand script", "goal": "<= 3"})
    load_cases = forces[:, None]
    for method, options in METHODS[:2]:  # augmented and qp: case by case, as the loop above
        prepared = contactqp.prepare(scene, method, **options)
        batch = prepared.solve_many(load_cases)
        tolerance = 1e-9 if method == "lagrange" else 1e-5  # the penalty: its λ/ε
        if not np.allclose(batch.contact_force[:, 0], exact, rtol=tolerance,
                           atol=tolerance * FORCE) or not batch.verified.all():
            raise SystemExit(f"solve_many {method} disagrees with the hand version")
        seconds = median_time(lambda p=prepared: p.solve_many(load_cases), 3)
        together = "every case at once" if not batch.alone else (
            f"{len(batch.alone)} of {cases} cases alone")
        rows.append({"run": f"solve_many {method}, {cases} cases", "seconds": seconds,
                     "ratio": seconds / vectorised, "against": "hand vectorised",
                     "goal": "<= 2", "ratio_to_hand_loop": seconds / loop,
                     "solved": together})
    print(f"{'run':36} {'ms':>10} {'ratio':>8}  against")
    for r in rows:
        print(f"{r['run']:36} {1e3 * r['seconds']:10.3f} {r['ratio']:8.1f}  "
              f"{r.get('against', '')} {r.get('goal', '')} {r.get('solved', '')}")
    out.mkdir(parents=True, exist_ok=True)
    (out / "loop.json").write_text(json.dumps({"machine": machine(), "rows": rows}, indent=1))
