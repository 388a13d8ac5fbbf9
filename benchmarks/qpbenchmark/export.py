"""contactqp's problems as a qpbenchmark test set: each scene's QP written as the parts of a
qpsolvers.Problem (.npz, P and G sparse), in SI units and scaled, with its exact contact forces
beside it.

    python benchmarks/qpbenchmark/export.py [--out DIR]     (default: benchmarks/qpbenchmark/problems)

Each QP is contactqp's (contactqp.methods.qp.problem): minimise ½ xᵀPx + qᵀx subject to
G x <= h, x the free nodes' displacements (SI: in m; scaled: in units of U), P = K, q = −P_loads,
G = C, h = g (P positive definite; only semidefinite where a bar has no support and is held by
its contacts alone: the free_bar, held_by_contact and free_bars problems, scaled from K with a
spring per free bar as the library scales them). Its duals z (qpsolvers' convention for
G x <= h) are the contact forces: λ = z (SI, N) or λ = F·z (scaled). exact.json holds, per
problem, the exact duals (from contactqp.reference: statics in extended precision or rational
arithmetic, never a solver), the scales U and F, and the scene's file so that a solution can be
checked (benchmarks/qpbenchmark/compare.py).

Two 2D problems from scikit-fem (contactqp.fem; skipped with a note when it is not installed),
each a contactqp.Problem: hertz_coarse, the Hertz cylinder at its coarse mesh (docs/hertz.md:
h = 0.05 mm along the contact strip, 7 499 free dofs, 17 rows), and block_wavy, the block on a
wavy foundation (1 640 free dofs, 41 rows). Their QP is the sparse model's
(contactqp.methods.qp.problem.qp_from_model: x the free dofs, P = K_II, q = −(f_I − K_ID u_D),
G = C_I); their exact duals are Lagrange's answer, verified, with the distance the check
measured to the exact answer on its contact set (``exact_duals_bound``, over F: about 1e-12).
Instead of a scene file, exact.json names the problem (``fem``), which compare.py builds again.
"""

from __future__ import annotations

import argparse
import json
import sys
import tomllib
from pathlib import Path

import numpy as np
import scipy.sparse as sp

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # benchmarks/cases.py

import contactqp
from cases import default_with, free_bar, tapered_scene, touching
from contactqp.methods.qp.problem import qp_from_model
from contactqp.model.sparse import build_sparse_model
from contactqp.reference import reference

EXAMPLES = HERE.parent.parent / "examples"


def scenes() -> dict[str, contactqp.Scene]:
    """The test set's scenes: the default scene and its variants (open, touching, gap 0, press
    fit), tapered bars of 10² to 10⁵ elements, a wall at every node of 10² and 10³ elements,
    several bars and bar contacts (the example scene files), and bars held only by contact
    (K singular: the default scene without its support, the example of a free bar pressed onto
    a cantilever, two free bars between two walls)."""
    out = {"default": contactqp.default_scene(), "open": default_with(load_factor=0.1),
           "touching": touching(), "gap_0": default_with(gap=0.0),
           "press_fit": default_with(gap=-1e-4)}
    for n in (100, 1000, 10_000, 100_000):
        out[f"taper_{n}"] = tapered_scene(n)
    for n in (100, 1000):
        bar = tapered_scene(n)
        out[f"walls_{n}"] = contactqp.wall_at_every_node(bar, 1e-5 * (1 + np.arange(n + 1) / n))
    for name in ("several_bars", "two_bars", "held_by_contact"):
        out[name] = contactqp.load_scene(EXAMPLES / f"{name}.toml")
    out["free_bar"] = free_bar()
    out["free_bars"] = free_bars_between_walls()
    return out


def fem_problems() -> dict[str, contactqp.Problem]:
    """The 2D problems (module docstring), built with scikit-fem; {} without it."""
    try:
        from contactqp.fem import block_on_wavy_foundation, cylinder_on_flat
        hertz = cylinder_on_flat(zone=0.5, fine=0.05).problem  # docs/hertz.md's first mesh
    except ImportError as error:
        print(f"skipped: the 2D problems need scikit-fem ({error})")
        return {}
    return {"hertz_coarse": hertz, "block_wavy": block_on_wavy_foundation()}


def export_problem(name: str, problem: contactqp.Problem, out: Path) -> dict[str, dict]:
    """A 2D problem's QP (SI and scaled) written to ``out``; its exact.json entries."""
    model = build_sparse_model(problem)
    exact = contactqp.solve(problem, "lagrange")
    if not exact.verified:  # the reference must be the exact answer, not a solver's word
        raise RuntimeError(f"{name}: Lagrange's answer is not verified ({exact.message})")
    entries = {}
    for scaled in (False, True):
        qp = qp_from_model(model, "inequality", scale=scaled)
        problem_name = f"{name}_{'scaled' if scaled else 'SI'}"
        save(out / f"{problem_name}.npz", qp.K, qp.q, qp.C, qp.g)
        entries[problem_name] = {
            "fem": name, "scaled": scaled, "displacement_scale": qp.displacement_scale,
            "force_scale": qp.force_scale,
            "exact_duals": (exact.contact_force / qp.force_scale).tolist(),
            "exact_duals_bound": exact.force_error_bound / exact.force_scale}
    return entries


def free_bars_between_walls() -> contactqp.Scene:
    """Two bars with no support (tests/test_floating.py::test_two_bars_between_walls): bar 0,
    1 kN at its node 1, between a "−" wall 0.2 mm before its node 0 and a contact 0.05 mm from
    its node 4 to bar 1's node 0; bar 1, −300 N at its node 2, against a "+" wall 0.1 mm beyond
    its node 4. Both are pushed to the "+" wall: it carries 700 N, the contact 1 kN, the "−"
    wall nothing."""
    bar = contactqp.Bar.from_areas([1e-3, 5e-4, 2e-4, 1e-4], 200e9, length=1.0)
    return contactqp.Scene(
        (bar, bar), (), (contactqp.Load(1, 1e3, 0), contactqp.Load(2, -3e2, 1)),
        (contactqp.Wall(0, 2e-4, "-", 0), contactqp.Wall(4, 1e-4, "+", 1)),
        contacts=(contactqp.BarContact(0, 4, 1, 0, 5e-5),), name="two free bars")


TAPER_FILE = """# the default scene's bar with {n} exact-area elements, its load at mid-length
name = "taper-{n}"

[material]
youngs_modulus = 210e9

[[bar]]
length = 1.0
elements = {n}
section = {{ shape = "circle", diameter_start = 0.040, diameter_end = 0.020, area_rule = "exact" }}

[[support]]
node = 0

[[load]]
node = {mid}
force = 565486.67

[[wall]]
node = {n}
gap = 1e-4
"""


def scene_file(name: str, scene: contactqp.Scene) -> str:
    """The scene as a scene file: a tapered bar as its section (a few lines; its areas
    written out took 2.3 MB at 10⁵ elements), checked to load back to the same areas bit for
    bit; any other scene by :func:`contactqp.scene_to_toml`."""
    if name.startswith("taper_"):
        n = scene.n_elements
        text = TAPER_FILE.format(n=n, mid=n // 2)
        again = contactqp.scene_from_dict(tomllib.loads(text))
        if np.array_equal(again.bars[0].areas, scene.bars[0].areas) and np.array_equal(
                again.bars[0].lengths, scene.bars[0].lengths):
            return text
    return contactqp.scene_to_toml(scene)


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
        (out / f"{name}.toml").write_text(scene_file(name, scene))
    for name, problem in fem_problems().items():
        exact_answers.update(export_problem(name, problem, out))
    (out / "exact.json").write_text(json.dumps(exact_answers, indent=1))
    print(f"{len(exact_answers)} problems written to {out}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(HERE / "problems"), help="output folder")
    main(Path(parser.parse_args().out))
