"""Does ``verified`` mean right? Every method and solver on many random scenes, against the exact
reference.

    python benchmarks/run.py --cases guarantee [--scenes N] [--seed S] [--floating P] [--out DIR]

Scenes come from contactqp.random_scenes (one to three bars, areas over five decades, zero
gaps, press fits, walls on both sides, bar contacts, distributed loads; with --floating P each
bar loses its support with chance P, held by its walls and bar contacts alone). Each is solved by
every method in every formulation it takes (lagrange full/condensed/strain, penalty at its
default ε and at the textbook 1e14 N/m, augmented full/condensed, lemke, pgs at ω = 1 and
1.5, semismooth_newton on min and Fischer–Burmeister) and by every installed QP
backend and solver (formulation, accuracy and scaling drawn per scene). Each run is compared
with contactqp.reference and classed:

    verified, within bound   the check accepts it and the error is within force_error_bound
                             and displacement_error_bound (the guarantee)
    verified, beyond bound   the check accepts it and the error exceeds its bound (by more
                             than the reference's round-off, 1e-12 of F and U): must be 0
    verified, wrong          the error exceeds 1e-5·F or 1e-5·U: must be 0
    flagged, right           the check rejects an answer within 1e-5 of the exact one
    flagged, wrong           the check rejects a wrong answer (as it should)
    failed                   the method raised (an active-set cycle, a refused formulation)

The force error is each row's, or Cᵀλ's where rows repeat a constraint (:func:`classify`);
the verified runs whose rows share a force otherwise than the reference does are counted
apart as well ("split").

The counts go to stdout and, with --out, to guarantee.json with every run beyond its bound.
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

import contactqp
from contactqp.model import contact_forces_on_nodes
from contactqp.random_scenes import random_scene
from contactqp.reference import reference

ROUND_OFF = 1e-12  # the reference's own accuracy, relative to F and U
RIGHT = 1e-5  # the guarantee: contactqp.GUARANTEE


def runs(rng: np.random.Generator) -> list[tuple[str, dict, str]]:
    out = [("lagrange", {}, f) for f in ("full", "condensed", "strain")]
    out += [("penalty", {}, f) for f in ("full", "condensed")]
    out += [("penalty", {"penalty": 1e14}, "full"), ("augmented", {}, "full"),
            ("augmented", {}, "condensed"), ("lemke", {}, "full"), ("pgs", {}, "full"),
            ("pgs", {"relaxation": 1.5}, "full"), ("semismooth_newton", {}, "full"),
            ("semismooth_newton", {"ncp": "fischer-burmeister"}, "full"),
            ("nitsche", {}, "full")]
    for info in contactqp.available_qp_solvers():
        if info.available:
            out.append(("qp", {"backend": info.backend, "solver": info.solver,
                               "accuracy": str(rng.choice(["default", "high"])),
                               "scale": bool(rng.random() < 0.8)},
                        str(rng.choice(["full", "condensed", "strain"]))))
    return out


def classify(result: contactqp.Result, exact) -> tuple[str, float, float]:
    """The run's class (module docstring), its force and displacement errors over F and U.
    The force error is each row's, or where rows repeat a constraint (walls on both sides of
    a node at one position, a loop of rows with zero gaps) what the rows put on each node,
    Cᵀλ, whichever is smaller: there the exact answer fixes no row's own share, and the check
    promises Cᵀλ (docs/howto/check.md; tests/test_guarantee.py holds the same)."""
    F, U = result.force_scale, result.displacement_scale
    error = result.contact_force - exact.contact_force
    force = min(float(np.abs(error).max(initial=0.0)),
                float(np.abs(contact_forces_on_nodes(result.layout, error)).max(initial=0.0)))
    displacement = float(np.abs(result.u - exact.displacement).max())
    right = force <= RIGHT * F and displacement <= RIGHT * U
    if not result.verified:
        return ("flagged, right" if right else "flagged, wrong"), force / F, displacement / U
    if not right:
        return "verified, wrong", force / F, displacement / U
    within = (force <= result.force_error_bound + ROUND_OFF * F
              and displacement <= result.displacement_error_bound + ROUND_OFF * U)
    return ("verified, within bound" if within else "verified, beyond bound"), force / F, \
        displacement / U


def main(scenes: int, seed: int, out: Path | None = None, floating: float = 0.0) -> int:
    """Run the family, print the counts, write guarantee.json into ``out``; 1 when a verified
    answer was beyond its bound or the guarantee. ``floating``: the chance that a bar loses
    its support and is held by its contacts alone (:func:`random_scene`)."""
    rng = np.random.default_rng(seed)
    counts: Counter[str] = Counter()
    by_run: dict[str, Counter[str]] = {}
    beyond, failures = [], []
    start = time.perf_counter()
    for index in range(scenes):
        scene = random_scene(rng, floating=floating)
        try:
            exact = reference(scene)
        except contactqp.SceneError:  # beyond the exact path's last resort (rows x nodes)
            counts["no reference"] += 1
            continue
        for method, options, formulation in runs(rng):
            label = "/".join([method, *(str(options[k]) for k in ("backend", "solver",
                                                                  "relaxation", "ncp")
                                        if k in options)])
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    result = contactqp.solve(scene, method, "inequality", formulation, **options)
            except contactqp.ContactqpError as error:
                counts["failed"] += 1
                by_run.setdefault(label, Counter())["failed"] += 1
                failures.append({"scene": index, "run": label, "options": options,
                                 "formulation": formulation, "error": str(error)})
                continue
            kind, force, displacement = classify(result, exact)
            counts[kind] += 1
            if kind.startswith("verified") and np.abs(result.contact_force - exact.contact_force
                                                      ).max(initial=0.0) > RIGHT * result.force_scale:
                counts["verified, split"] += 1  # right on Cᵀλ, its rows' shares not the reference's
            by_run.setdefault(label, Counter())[kind] += 1
            if kind in ("verified, beyond bound", "verified, wrong"):
                beyond.append({"scene": index, "run": label, "options": options,
                               "formulation": formulation, "kind": kind,
                               "force_error": force, "displacement_error": displacement,
                               "force_bound": result.force_error_bound / result.force_scale,
                               "displacement_bound": result.displacement_error_bound
                               / result.displacement_scale})
        if (index + 1) % 100 == 0:
            print(f"{index + 1} scenes, {sum(counts.values())} runs, "
                  f"{time.perf_counter() - start:.0f} s", file=sys.stderr)
    total = sum(counts.values())
    print(f"{scenes} random scenes (seed {seed}), {total} runs, "
          f"{time.perf_counter() - start:.0f} s")
    total -= counts["verified, split"]  # counted within the verified ones too
    for kind in ("verified, within bound", "verified, beyond bound", "verified, wrong",
                 "flagged, right", "flagged, wrong", "failed"):
        print(f"  {kind:<24} {counts[kind]:>7}  ({100 * counts[kind] / max(total, 1):.1f} %)")
    print(f"  (of the verified, {counts['verified, split']} split a force between rows that "
          "repeat a constraint otherwise than the reference: right on Cᵀλ)")
    print("\nper method / solver: verified (within bound), flagged right, flagged wrong, failed")
    for label, c in sorted(by_run.items()):
        print(f"  {label:<28} {c['verified, within bound']:>5} {c['flagged, right']:>5} "
              f"{c['flagged, wrong']:>5} {c['failed']:>5}")
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        with open(out / "guarantee.json", "w", encoding="utf-8") as handle:
            json.dump({"scenes": scenes, "seed": seed, "counts": dict(counts),
                       "by_run": {k: dict(v) for k, v in by_run.items()},
                       "beyond_bound": beyond, "failed": failures}, handle, indent=1)
    return 1 if counts["verified, beyond bound"] or counts["verified, wrong"] else 0

