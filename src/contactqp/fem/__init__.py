"""2D and 3D contact models built with scikit-fem, handed over as :class:`~contactqp.Problem`.

Needs the optional extra: ``pip install "contactqp[fem]"`` (scikit-fem is imported when a
model is built, never by ``import contactqp``). Three cases:

- :func:`cylinder_on_flat`: a plane-strain cylinder pressed onto a rigid flat, to compare
  with Hertz's closed form (:func:`measure`, :mod:`contactqp.fem.hertz`);
- :func:`sphere_on_flat`: an elastic sphere pressed onto a rigid flat (linear tetrahedra), to
  compare with Hertz's point contact (:func:`measure_sphere`, :mod:`contactqp.fem.hertz3d`);
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
from contactqp.fem.hertz3d import (
    effective_modulus,
    sphere_approach,
    sphere_contact_radius,
    sphere_load,
    sphere_peak_pressure,
    sphere_pressure,
)
from contactqp.fem.sphere import HertzComparison3D, SphereModel, measure_sphere, sphere_on_flat

__all__ = [
    "CylinderModel", "HertzComparison", "HertzComparison3D", "SphereModel",
    "block_on_wavy_foundation", "cylinder_on_flat", "effective_modulus", "hertz_half_width",
    "hertz_peak_pressure", "hertz_pressure", "measure", "measure_sphere", "plane_strain_modulus",
    "sphere_approach", "sphere_contact_radius", "sphere_load", "sphere_on_flat",
    "sphere_peak_pressure", "sphere_pressure",
]
