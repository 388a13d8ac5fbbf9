"""contactqp's problems as a qpbenchmark test set: each scene's QP written as the parts of a
qpsolvers.Problem (.npz, P and G sparse), in SI units and scaled, with its exact contact forces
beside it.

    python benchmarks/qpbenchmark/export.py [--out DIR]     (default: benchmarks/qpbenchmark/problems)

Each QP is contactqp's (contactqp.methods.qp.problem): minimise ½ xᵀPx + qᵀx subject to
G x <= h, x the free nodes' displacements (SI: in m; scaled: in units of U), P = K, q = −P_loads,
G = C, h = g. Its duals z (qpsolvers' convention for G x <= h) are the contact forces: λ = z
(SI, N) or λ = F·z (scaled). exact.json holds, per problem, the exact duals (from
contactqp.reference: statics in extended precision or rational arithmetic, never a solver),
the scales U and F, and the scene's file so that a solution can be checked
(benchmarks/qpbenchmark/compare.py).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # benchmarks/cases.py

import contactqp
from cases import default_with, tapered_scene, touching
from contactqp.methods.qp.problem import qp_from_model
from contactqp.reference import reference

EXAMPLES = HERE.parent.parent / "examples"


def scenes() -> dict[str, contactqp.Scene]:
    """The test set's scenes: the default scene and its variants (open, touching, gap 0, press
    fit), tapered bars of 10² to 10⁴ elements, a wall at every node of 10² and 10³ elements,
    several bars and bar contacts (the example scene files)."""
    out = {"default": contactqp.default_scene(), "open": default_with(load_factor=0.1),
           "touching": touching(), "gap_0": default_with(gap=0.0),
           "press_fit": default_with(gap=-1e-4)}
    for n in (100, 1000, 10_000):
        out[f"taper_{n}"] = tapered_scene(n)
    for n in (100, 1000):
        bar = tapered_scene(n)
        out[f"walls_{n}"] = contactqp.wall_at_every_node(bar, 1e-5 * (1 + np.arange(n + 1) / n))
    for name in ("several_bars", "two_bars"):
        out[name] = contactqp.load_scene(EXAMPLES / f"{name}.toml")
    return out


def save(path: Path, P, q: np.ndarray, G, h: np.ndarray) -> None:
    """The QP as sparse arrays (qpsolvers.Problem.save writes P and G dense: 800 MB for the
    10⁴-element bar): P and G in CSC parts, q and h as they are (:func:`load` reads it)."""
    parts = {}
    for name, matrix in (("P", sp.csc_array(P)), ("G", sp.csc_array(G))):
        parts.update({f"{name}_data": matrix.data, f"{name}_indices": matrix.indices,
                      f"{name}_indptr": matrix.indptr, f"{name}_shape": np.array(matrix.shape)})
    np.savez_compressed(path, q=q, h=h, **parts)  # read by contactqp_test_set.load


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    exact_answers = {}
    for name, scene in scenes().items():
        model = contactqp.build_model(scene)
        exact = reference(scene)
        for scaled in (False, True):
            qp = qp_from_model(model, "inequality", scale=scaled)
            problem_name = f"{name}_{'scaled' if scaled else 'SI'}"
            save(out / f"{problem_name}.npz", qp.K, qp.q, qp.C, qp.g)
            exact_answers[problem_name] = {
                "scene": name, "scaled": scaled,
                "displacement_scale": qp.displacement_scale, "force_scale": qp.force_scale,
                "exact_duals": (exact.contact_force / qp.force_scale).tolist()}
        (out / f"{name}.toml").write_text(contactqp.scene_to_toml(scene))
    (out / "exact.json").write_text(json.dumps(exact_answers, indent=1))
    print(f"{len(exact_answers)} problems written to {out}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(HERE / "problems"), help="output folder")
    main(Path(parser.parse_args().out))
