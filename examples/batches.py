"""
Many load cases: prepare once, solve many
=========================================

:func:`contactqp.prepare` checks the method and its options and builds the model once;
:meth:`~contactqp.Prepared.solve_many` then solves the scene for many values of its loads (one
per point load, then one per distributed load) and gaps (one per wall, then one per bar
contact), every case checked. Here the default scene's load runs from 0 to 1 MN in 101 steps.

The closed form: the tip reaches the wall when F·f₂ = g (f₂ the compliance from the support
to node 2); beyond it λ = (F·f₂ − g)/f₄, linear in F; below it λ = 0.
"""

import numpy as np
from matplotlib.figure import Figure

import contactqp

scene = contactqp.default_scene()
prepared = contactqp.prepare(scene, "lagrange")
loads = np.linspace(0.0, 1e6, 101)
batch = prepared.solve_many(loads=loads[:, None])  # cases × point loads
print(f"{len(loads)} cases, all verified: {bool(np.all(batch.verified))}")

bar = scene.bars[0]
compliance = np.cumsum(bar.lengths / (bar.youngs_modulus * bar.areas))
closed_form = np.maximum(loads * compliance[1] - scene.walls[0].gap, 0.0) / compliance[3]
error = np.max(np.abs(batch.contact_force[:, 0] - closed_form))
print(f"largest difference to the closed form over the cases: {error:.2e} N")
for i in (0, 10, 50, 100):
    print(f"F = {loads[i]:9.0f} N: λ = {batch.contact_force[i, 0]:12.4f} N")

# %%
# The contact force of every case against the closed form: zero until the tip reaches the
# wall, then linear in the load (a matplotlib Figure drawn from the batch's arrays):
figure = Figure(figsize=(6.0, 3.6), layout="constrained")
axes = figure.subplots()
axes.plot(loads / 1e3, closed_form / 1e3, "-", color="0.6", lw=3, label="closed form")
axes.plot(loads / 1e3, batch.contact_force[:, 0] / 1e3, "o", ms=3, label="solve_many")
axes.set(xlabel="load F (kN)", ylabel="contact force λ (kN)",
         title="101 load cases, one prepared model")
axes.legend()

# %%
# One case alone, with a new load and a new gap, is a checked Result as :func:`contactqp.solve`
# gives:
print(prepared.solve(loads=[4.0e5], gaps=[2e-4]))
