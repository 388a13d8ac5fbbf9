"""
A distributed load against a wall
=================================

A bar fixed at x = 0 under a uniform axial load q = 50 kN/m, with a wall 0.05 mm beyond its
free end (``examples/distributed_load.toml``). Without the wall the tip would move
qL²/(2EA); the wall pushes back with what closes the rest, through the bar's stiffness EA/L:
λ = (qL²/(2EA) − g)·EA/L = 14 500 N. The consistent nodal loads (q·h/2 to each end of an
element) make the nodal displacements exact, so the discrete answer is the closed form.
"""

import sys
from pathlib import Path

import contactqp
from contactqp import plot

scene = contactqp.load_scene(Path(sys.argv[0]).parent / "distributed_load.toml")
result = contactqp.solve(scene)
print(result.summary())

E, A, L, q, g = 210e9, 1e-3, 1.0, 50e3, 5e-5
print(f"closed form: {(q * L**2 / (2 * E * A) - g) * E * A / L:.4f} N")

# %%
# The bar before and after loading, the wall and the force it takes:
bar_chart = plot.plot_bar(result)

# %%
# Every method on the same scene, one row each:
print(contactqp.table(contactqp.compare(scene)))
