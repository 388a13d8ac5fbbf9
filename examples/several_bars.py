"""
Three bars, two contacts and a wall
===================================

Three bars in a row (``examples/several_bars.toml``): bar 0 (steel, fixed at its left end,
loaded at its right end) is pushed into bar 1 (aluminium, its own material, fixed at its right
end), whose middle node is 0.02 mm from bar 2 (steel, fixed at its right end); a wall on the
− side of bar 1's node 2 can only push that node in +x. The nodes of all bars are numbered in
one sequence, bar after bar; contact rows are the walls, then the bar contacts.

The exact answer comes from :func:`contactqp.reference.reference` (exact rational arithmetic
for a scene of several bars), independently of every method.
"""

import sys
from pathlib import Path

import numpy as np

import contactqp
from contactqp import plot
from contactqp.reference import reference

scene = contactqp.load_scene(Path(sys.argv[0]).parent / "several_bars.toml")
result = contactqp.solve(scene)
print(result.summary())

exact = reference(scene)
print("exact contact forces (N):", np.array2string(np.asarray(exact.contact_force, float),
                                                   precision=4))

# %%
# The global numbering: bar 1's node 2 is this entry of ``result.u``:
print("bar 1, node 2 -> global node", result.layout.node(1, 2))

# %%
bar_chart = plot.plot_bar(result)
