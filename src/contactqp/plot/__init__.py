"""Charts (matplotlib only, never pyplot; never imported by ``contactqp/__init__``).

Each function draws what it is given on a Figure of its own (no global state, no GUI backend)
and returns its Axes or Figure. Every chart states its scene, its units and its methods, and
marks what failed: a red × where a solve raised or failed its check, open markers where an
answer was flagged. Artists a reader's script (or a test) may look for carry a ``gid``, e.g.
``"undeformed bar 1 element 0"``, ``"wall 0"``, ``"contact 0 deformed"``.

- :mod:`~contactqp.plot.common`: what every chart shares, and :func:`save`;
- :mod:`~contactqp.plot.bars`: the scene, undeformed and deformed (:func:`plot_bar`);
- :mod:`~contactqp.plot.studies`: the penalty and Nitsche sweeps, mesh convergence;
- :mod:`~contactqp.plot.load_path`: the force-displacement curve;
- :mod:`~contactqp.plot.friction`: the traction along a frictional contact.
"""

from contactqp.plot.bars import bar_magnification, bar_positions, plot_bar
from contactqp.plot.common import FAILED, FLOOR, engineering, round_125, save
from contactqp.plot.friction import plot_traction
from contactqp.plot.load_path import plot_load_path
from contactqp.plot.studies import plot_mesh_convergence, plot_nitsche_sweep, plot_penalty_sweep

__all__ = ["FAILED", "FLOOR", "bar_magnification", "bar_positions", "engineering",
           "plot_bar", "plot_load_path", "plot_mesh_convergence", "plot_nitsche_sweep",
           "plot_penalty_sweep", "plot_traction", "round_125", "save"]
