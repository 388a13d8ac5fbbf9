"""
A bar held only by contact
==========================

Bar 1 has no support (``examples/held_by_contact.toml``): its load of 20 kN in −x presses it
across a 0.05 mm gap onto the tip of bar 0, a cantilever. The stiffness matrix is singular
(bar 1 can move as a whole) and the contact holds that mode, so the contact carries the whole
load: λ = 20 kN. Lagrange multipliers, the penalty, the augmented Lagrangian, every QP
backend and Nitsche solve such scenes; the methods that need K⁻¹ refuse with that reason.
"""

import sys
from pathlib import Path

import contactqp
from contactqp import plot

scene = contactqp.load_scene(Path(sys.argv[0]).parent / "held_by_contact.toml")
result = contactqp.solve(scene)
print(result.summary())
print(f"closed form: {-scene.loads[0].force:.4f} N (the whole load)")

# %%
# Lemke's method works with K⁻¹, which this scene does not have:
try:
    contactqp.solve(scene, "lemke")
except contactqp.ContactqpError as error:
    print(f"{type(error).__name__}: {error}")

# %%
bar_chart = plot.plot_bar(result)
