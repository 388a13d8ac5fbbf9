"""2D contact models built with scikit-fem, handed to contactqp as :class:`~contactqp.Problem`.

Needs the optional extra: ``pip install "contactqp[fem]"`` (scikit-fem is imported when a
model is built, never by ``import contactqp``). Two cases:

- :func:`cylinder_on_flat`: a plane-strain cylinder pressed onto a rigid flat, to compare
  with Hertz's closed form (:func:`measure`, :mod:`contactqp.fem.hertz`);
- :func:`block_on_wavy_foundation`: an elastic block pressed onto a wavy rigid foundation,
  where no closed form applies and the methods are compared with each other.
"""

from contactqp.fem.block import block_on_wavy_foundation
from contactqp.fem.cylinder import CylinderModel, HertzComparison, cylinder_on_flat, measure
from contactqp.fem.hertz import (
    hertz_half_width,
    hertz_peak_pressure,
    hertz_pressure,
    plane_strain_modulus,
)

__all__ = [
    "CylinderModel", "HertzComparison", "block_on_wavy_foundation", "cylinder_on_flat",
    "hertz_half_width", "hertz_peak_pressure", "hertz_pressure", "measure",
    "plane_strain_modulus",
]
