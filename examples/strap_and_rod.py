"""
A tapered strap against a rod: sections and materials
=====================================================

A steel strap with a rectangular section tapering in width (40 mm to 20 mm, 10 mm thick, the
``exact`` area rule) pushed with 60 kN across a 0.2 mm gap into an aluminium rod of 250 mm²
(``examples/strap_and_rod.toml``). With the exact area rule the strap's four elements have the
compliance of the continuous taper, k₀ = E h (w₁ − w₀) / (L ln(w₁/w₀)), and the rod's is
k₁ = EA/L; the contact force is that of two springs across a gap,
λ = (F − k₀ g) k₁ / (k₀ + k₁) = 9486.20 N.
"""

import math
import sys
from pathlib import Path

import contactqp
from contactqp import plot

scene = contactqp.load_scene(Path(sys.argv[0]).parent / "strap_and_rod.toml")
result = contactqp.solve(scene)
print(result.summary())

k0 = 210e9 * 0.010 * (0.020 - 0.040) / (0.5 * math.log(0.020 / 0.040))
k1 = 70e9 * 250e-6 / 0.4
force, gap = 60e3, 2e-4
print(f"k0 = {k0:.5e} N/m, k1 = {k1:.5e} N/m")
print(f"closed form: {(force - k0 * gap) * k1 / (k0 + k1):.4f} N")

# %%
# The strap and the rod before and after loading, the gap between them and the contact
# force:
bar_chart = plot.plot_bar(result)
