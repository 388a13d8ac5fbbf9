"""The scene's numbering and what is computed from it, by their former name: they are
:mod:`contactqp.layout`'s (a :class:`~contactqp.scene.Scene` makes its own layout, so the
layout sits below the scene, not in the model)."""

from contactqp.layout import *
from contactqp.layout import __all__  # noqa: F401  (the same public names)
