"""
A cylinder on a rigid flat against Hertz, built with scikit-fem
===============================================================

A user's own finite-element model handed to contactqp as K, f, C, g
(:class:`contactqp.Problem`). A long steel roller of radius R = 10 mm (E = 210 GPa, ν = 0.3)
is pushed down by δ = 10 µm onto a rigid flat. :func:`contactqp.fem.cylinder_on_flat` builds
the quarter of its cross-section (plane strain, P1 triangles from scikit-fem, refined towards
the contact with every boundary node on the circle): the symmetry line x = 0 slides
vertically, the cut through the centre moves down by δ, and each node of the arc within
0.05 R of the lowest point is a row −u_y ≤ y of C u ≤ g (it may not pass the flat). The load
per unit thickness is P = 2 Σλ; Hertz gives, for that P, the half-width
a = √(4PR/(πE*)) and the peak pressure p₀ = 2P/(πa), E* = E/(1 − ν²), and the pressure
p₀√(1 − (x/a)²). The :doc:`refinement study </hertz>` shows how the errors fall with the mesh.

Needs the optional extra: ``pip install "contactqp[fem]"``.
"""

import numpy as np
from matplotlib.figure import Figure

import contactqp
from contactqp.fem import block_on_wavy_foundation, cylinder_on_flat, hertz_pressure, measure

model = cylinder_on_flat(radius=10.0, young=210e3, poisson=0.3, approach=0.01, fine=0.00625)
result = contactqp.solve(model.problem, "lagrange")
comparison = measure(model, result.contact_force)

print(model.problem)
print(f"verified: {result.verified}; {result.iterations} iterations")
print(f"P  = {comparison.load:.2f} N/mm")
print(f"a  = {comparison.half_width:.5f} mm, Hertz {comparison.hertz_half_width:.5f} mm "
      f"({comparison.half_width_error:+.2%})")
print(f"p0 = {comparison.peak_pressure:.1f} MPa, Hertz {comparison.hertz_peak_pressure:.1f} MPa "
      f"({comparison.peak_pressure_error:+.2%})")

# %%
# The pressure of each row (its contact force over the length of flat it carries) on Hertz's
# ellipse for the same load.
pressure_chart = Figure(figsize=(6.4, 3.6), layout="constrained")
ax = pressure_chart.add_subplot()
x = np.linspace(0.0, 1.2 * comparison.hertz_half_width, 400)
ax.plot(x, hertz_pressure(x, comparison.hertz_half_width, comparison.hertz_peak_pressure),
        color="0.3", label="Hertz")
ax.plot(comparison.x, comparison.pressure, "o", markersize=3, label="contactqp, lagrange")
ax.set_xlim(0.0, 1.5 * comparison.hertz_half_width)
ax.set_xlabel("x (mm)")
ax.set_ylabel("contact pressure (MPa)")
ax.set_title(f"cylinder on a flat, {model.problem.n} dofs, {model.problem.m} contact rows")
ax.legend()

# %%
# Where Hertz does not apply: an elastic block (20 x 10 mm) pressed by 4 µm onto a rigid
# foundation with two waves of 5 µm depth. It touches in patches around the crests, whose
# widths no formula gives for a finite block; every method solves it, each answer is checked,
# and each is compared with the exact method's.
block = block_on_wavy_foundation()
exact = contactqp.solve(block, "lagrange")
runs = {"lagrange": exact}
for method in ("penalty", "augmented", "lemke", "pgs", "semismooth_newton"):
    runs[method] = contactqp.solve(block, method)
for backend in ("clarabel", "osqp"):
    runs[f"qp ({backend})"] = contactqp.solve(block, "qp", backend=backend)

largest = np.abs(exact.contact_force).max()
print(f"{block}; {np.count_nonzero(exact.contact_force > 0)} rows push")
print(f"{'method':18s} {'verified':8s} {'max |λ − λ_lagrange| / max λ':>30s}")
for label, run in runs.items():
    difference = np.abs(run.contact_force - exact.contact_force).max() / largest
    print(f"{label:18s} {run.verified!s:8s} {difference:30.1e}")

# %%
# The contact forces along the block's bottom, by method: the patches around the three crests
# (x = 0, 10 and 20 mm).
block_chart = Figure(figsize=(6.4, 3.6), layout="constrained")
ax = block_chart.add_subplot()
bottom_x = block.coordinates[block.C.indices, 0]  # one entry a row: its node's u_y
for label, run in runs.items():
    ax.plot(bottom_x, run.contact_force, "o-" if label == "lagrange" else ".",
            label=label, markersize=6 if label == "lagrange" else 4)
ax.set_xlabel("x (mm)")
ax.set_ylabel("contact force (N/mm)")
ax.set_title("block on a wavy foundation, every method")
ax.legend(fontsize="small", ncols=2, loc="upper center", bbox_to_anchor=(0.5, -0.2))
