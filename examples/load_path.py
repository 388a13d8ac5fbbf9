"""
The force–displacement curve
============================

:func:`contactqp.load_path` scales every load from 0 to 1 and records, per method, the
displacement of the load point, the contact forces and the penetrations, every step a checked
Result. On the default scene the curve has a kink where the tip reaches the wall: at the load
factor t* = g / (F·f₂), f₂ the compliance from the support to the loaded node 2
(:func:`contactqp.first_contact_factor`).
"""

import numpy as np

import contactqp
from contactqp import plot

scene = contactqp.default_scene()
path = contactqp.load_path(scene, steps=21)
kink = contactqp.first_contact_factor(scene)

bar = scene.bars[0]
f2 = np.sum((bar.lengths / (bar.youngs_modulus * bar.areas))[:2])
print(f"t* = {kink:.6f} (closed form {scene.walls[0].gap / (scene.loads[0].force * f2):.6f})")
print("methods:", ", ".join(path.methods))

# %%
path_chart = plot.plot_load_path(path, kink=kink)
