"""
Tutorial: the course problem, end to end
========================================

The standard course problem is contactqp's default scene (:func:`contactqp.default_scene`): a
1 m cantilever bar fixed at x = 0, a circular section tapering linearly from 40 mm to 20 mm
in diameter, E = 210 GPa, cut into four equal elements (nodes 0 to 4), each with the area of
the circle at its mid-length diameter. A point load F = 565 486.67 N acts in +x at node 2, and
a rigid wall stands 0.1 mm beyond node 4. This page solves it as the course does: with
Lagrange multipliers, then with the penalty method over a range of ε, and looks at the
deformed bar and at how far each answer lets the tip pass the wall.

Every number below is printed by the library when this documentation was built.
"""

# %%
# The scene
# ---------
# A :class:`~contactqp.Scene` holds the bars, supports, loads and walls. The default scene is
# built in Python; ``contactqp.load_scene("scene.toml")`` reads the same from a file.
import numpy as np

import contactqp

scene = contactqp.default_scene()
bar = scene.bars[0]
print(scene.name)
print("element areas (mm²):", np.round(bar.areas * 1e6, 2))
print("element stiffnesses E·A/L (N/m):", [f"{k:.4e}" for k in bar.youngs_modulus * bar.areas
                                         / bar.lengths])

# %%
# Lagrange multipliers
# --------------------
# :func:`contactqp.solve` with its defaults solves the saddle-point system
# ``[[K, Cᵀ], [C, 0]] [u; λ] = [P; g]`` and, for unilateral contact, keeps only the walls that
# push. The multiplier λ is the contact force: the force with which the wall pushes the bar.
# The Result is checked independently of the method (``verified``).
result = contactqp.solve(scene)
print(result.summary())

# %%
# The hand calculation agrees. Without the wall, node 4 moves as node 2 does, F times the
# compliance Σ L/(EA) of elements 0 and 1; the wall takes what closes the rest of the gap back
# through the compliance of the whole bar:
compliance = np.cumsum(bar.lengths / (bar.youngs_modulus * bar.areas))  # m/N, nodes 1..4
force, gap = scene.loads[0].force, scene.walls[0].gap
by_hand = (force * compliance[1] - gap) / compliance[3]
print(f"λ by hand: {by_hand:.4f} N; by contactqp: {result.contact_force[0]:.4f} N")
print(f"tip displacement u4 = {result.u[4] * 1e3:.4f} mm (the gap is {gap * 1e3:.4f} mm)")
print(f"support reaction: {result.reactions[0]:.4f} N "
      f"(balance: {result.reactions[0] + force - result.contact_force[0]:.2e} N)")

# %%
# The deformed shape
# ------------------
# :func:`contactqp.plot.plot_bar` draws the bar before and after loading (displacements
# magnified), the support, the load, the wall and the contact force.
from contactqp import plot  # matplotlib is imported only here

bar_chart = plot.plot_bar(result)

# %%
# The penalty method against ε
# ----------------------------
# The penalty method replaces the wall by a spring of stiffness ε: the contact force is
# ε × penetration, so the tip must pass the wall to be pushed back. Too soft a spring lets it
# through; too stiff a spring drowns K in round-off. :func:`contactqp.penalty_sweep` solves the
# scene for ε from 1 to 1e20 N/m, by the penalty method and by the augmented Lagrangian (a
# moderate ε, plus multiplier updates), and compares each with Lagrange.
sweep = contactqp.penalty_sweep(scene)
print(f"{'ε (N/m)':>8}  {'force (N)':>14}  {'penetration (m)':>15}  {'rel. error':>10}  verified")
for eps, run, error, depth in zip(sweep.penalties, sweep.runs, sweep.force_error,
                                  sweep.penetration):
    verdict = "failed" if run.result is None else ("yes" if run.result.verified else "NO")
    contact_force = np.nan if run.result is None else run.result.contact_force[0]
    print(f"{eps:8.0e}  {contact_force:14.4f}  {depth:15.3e}  {error:10.2e}  {verdict}")
print()
print(sweep.summary())

# %%
# The force error falls as s/ε, s the stiffness the wall sees, until round-off in K + εCᵀC
# takes over; the augmented Lagrangian reaches the Lagrange force at moderate ε.
sweep_chart = plot.plot_penalty_sweep(sweep)

# %%
# The penetration
# ---------------
# An exact method puts the tip on the wall; the penalty method leaves it λ/ε past it. The
# textbook ε = 1e14 N/m:
textbook = contactqp.solve(scene, "penalty", penalty=1e14)
print(f"penetration at ε = 1e14 N/m: {textbook.penetration[0]:.3e} m "
      f"(λ/ε = {textbook.contact_force[0] / 1e14:.3e} m)")
print(f"penetration by Lagrange: {result.penetration[0]:.1e} m")

# %%
# Every method at once
# --------------------
# :func:`contactqp.compare` runs every method and every installed QP solver on the scene, and
# :func:`contactqp.table` prints one row each, with the error against the exact reference.
runs = contactqp.compare(scene)
print(contactqp.table(runs))
