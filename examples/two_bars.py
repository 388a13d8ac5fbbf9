"""
Two bars across a gap
=====================

Contact between two bars (``examples/two_bars.toml``): bar 0 is fixed at its left end and
pushed in +x with P = 50 kN at its right end; bar 1 is fixed at its right end. Their facing
ends are 0.1 mm apart, the row u_a − u_b <= gap. As two springs k₀ = 2e8 N/m and k₁ = 5e7 N/m
across a gap g, the contact force is λ = (P − k₀ g) k₁ / (k₀ + k₁) = 6000 N.
"""

import sys
from pathlib import Path

import contactqp
from contactqp import plot

scene = contactqp.load_scene(Path(sys.argv[0]).parent / "two_bars.toml")  # beside this script
result = contactqp.solve(scene)
print(result.summary())

k0, k1, load, gap = 2e8, 5e7, 50e3, 1e-4
print(f"closed form: {(load - k0 * gap) * k1 / (k0 + k1):.4f} N")

# %%
# The two bars before and after loading, the gap between them and the contact force:
bar_chart = plot.plot_bar(result)
