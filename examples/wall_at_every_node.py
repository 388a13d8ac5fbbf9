"""
A wall beside every node
========================

The discrete obstacle problem (``examples/wall_at_every_node.toml``): the default scene's
tapered bar and load beside an obstacle, a wall at each of its 8 free nodes with gaps growing
along the bar. Lagrange's hull active set adds whole contact patches in one step; the exact
answer (:func:`contactqp.reference.reference`, statics in extended precision) is computed
independently of every method.
"""

import sys
from pathlib import Path

import numpy as np

import contactqp
from contactqp import plot
from contactqp.reference import reference

scene = contactqp.load_scene(Path(sys.argv[0]).parent / "wall_at_every_node.toml")
result = contactqp.solve(scene)
print(result.summary())
exact = np.asarray(reference(scene).contact_force, dtype=float)
print("exact contact forces (N):", np.array2string(exact, precision=4))

# %%
bar_chart = plot.plot_bar(result)
