"""What the user describes: elastic bars, their supports, point and distributed loads, rigid
walls and contacts between bars, in one unit system. Description and validation only: the
algebra (numbering, K, P, C, g) is contactqp.model's.

A bar's elements each have a length, an area and a modulus: given one area per element, one
area for all, or a section (:class:`Circle`, :class:`HollowCircle`, :class:`Rectangle`, each
dimension constant or tapering linearly) from which :func:`section_areas` makes them.

Each bar numbers its nodes 0..n along +x; element e joins its nodes e and e + 1; supports,
loads and walls name a bar (default 0) and a node of it. Every value is checked when the
scene is built, and an error names the field (as it is spelled in the TOML file) and the
value; a scene whose walls and contacts leave a node no position, or whose contact forces
rigid contact would leave undetermined, is refused (contactqp.feasibility).

- :mod:`~contactqp.scene.sections`: the cross-sections and the element areas they give;
- :mod:`~contactqp.scene.parts`: the value types, Bar, Support, Load, DistributedLoad, Wall,
  BarContact, Bed;
- :mod:`~contactqp.scene.walls`: :class:`Walls`, many walls as arrays;
- :mod:`~contactqp.scene.validation`: the checks of the parts together;
- :mod:`~contactqp.scene.scene`: the Scene.
"""

# WallSide, AreaRule and row_names are not public, but other modules read them here
from contactqp.scene.parts import (  # noqa: F401
    MAX_ELEMENTS,
    WALL_SIDES,
    Bar,
    BarContact,
    Bed,
    DistributedLoad,
    Load,
    Support,
    Wall,
    WallSide,
)
from contactqp.scene.scene import Scene, row_names  # noqa: F401
from contactqp.scene.sections import (  # noqa: F401
    AREA_RULES,
    SECTIONS,
    AreaRule,
    Circle,
    Dimension,
    HollowCircle,
    Rectangle,
    Section,
    section_areas,
)
from contactqp.scene.walls import Walls
from contactqp.units import UNIT_SYSTEMS, Units

__all__ = [
    "AREA_RULES", "MAX_ELEMENTS", "SECTIONS", "UNIT_SYSTEMS", "WALL_SIDES", "Bar", "BarContact", "Bed",
    "Circle", "Dimension", "DistributedLoad", "HollowCircle", "Load", "Rectangle", "Scene",
    "Section", "Support", "Units", "Wall", "Walls", "section_areas",
]
