"""Cross-sections of a bar and the element areas they give: :class:`Circle`,
:class:`HollowCircle` and :class:`Rectangle`, each dimension constant or tapering linearly, and
:func:`section_areas`, which makes the areas of equal elements along one (by the section at
mid-element, or exactly: the area with the element's own axial compliance).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from contactqp._validate import number
from contactqp.errors import SceneError

AreaRule = Literal["midpoint", "exact"]
AREA_RULES = ("midpoint", "exact")
Ends = tuple[float, float]  # a dimension at x = 0 and at x = L (m)
Dimension = float | Ends
"""A section's dimension (m): one number along the whole bar, or a pair (at x = 0, at x = L)
between which it tapers linearly."""
_PAIRS = (tuple, list, np.ndarray)  # what a tapered dimension may be given as


def _dimension(name: str, value: Any, zero_allowed: bool = False) -> tuple[float, float]:
    """``value`` (a number, or a pair (start, end)) as its two ends, each a number > 0 (>= 0
    where ``zero_allowed``); a pair's ends are named ``name_start`` and ``name_end``,
    as a scene file spells them."""
    strict = not zero_allowed
    if isinstance(value, _PAIRS):
        if len(value) != 2:
            raise SceneError(f"{name} must be one number or a pair (start, end), got {value!r}")
        return (number(f"{name}_start", value[0], minimum=0.0, strict=strict),
                number(f"{name}_end", value[1], minimum=0.0, strict=strict))
    one = number(name, value, minimum=0.0, strict=strict)
    return one, one


def _key(name: str, value: Any, end: int) -> str:
    """How a scene file spells end ``end`` (0 or 1) of dimension ``name`` given as ``value``."""
    return f"{name}{('_start', '_end')[end]}" if isinstance(value, _PAIRS) else name


@dataclass(frozen=True)
class Circle:
    """A solid circular section of ``diameter`` (m): one number, or (at x = 0, at x = L)."""

    diameter: Dimension
    shape: ClassVar[str] = "circle"

    def _factors(self, name: str) -> tuple[float, Ends, Ends]:
        d = _dimension(f"{name}.diameter", self.diameter)
        return math.pi / 4.0, d, d  # A = π/4 · d · d


@dataclass(frozen=True)
class HollowCircle:
    """A tube: a circle of ``outer_diameter`` with a concentric hole of ``inner_diameter``
    (m; 0: no hole), each one number or (at x = 0, at x = L); inner < outer at both ends."""

    outer_diameter: Dimension
    inner_diameter: Dimension
    shape: ClassVar[str] = "hollow_circle"

    def _factors(self, name: str) -> tuple[float, Ends, Ends]:
        outer = _dimension(f"{name}.outer_diameter", self.outer_diameter)
        inner = _dimension(f"{name}.inner_diameter", self.inner_diameter, True)
        for end in (0, 1):
            if not inner[end] < outer[end]:
                raise SceneError(
                    f"{name}.{_key('inner_diameter', self.inner_diameter, end)} = "
                    f"{inner[end]!r} is not less than "
                    f"{_key('outer_diameter', self.outer_diameter, end)} = {outer[end]!r}")
        # A = π/4 · (D − d)(D + d): a product of two linear factors, as a rectangle's is
        return (math.pi / 4.0, (outer[0] - inner[0], outer[1] - inner[1]),
                (outer[0] + inner[0], outer[1] + inner[1]))


@dataclass(frozen=True)
class Rectangle:
    """A solid rectangular section ``width`` × ``height`` (m), each one number or
    (at x = 0, at x = L)."""

    width: Dimension
    height: Dimension
    shape: ClassVar[str] = "rectangle"

    def _factors(self, name: str) -> tuple[float, Ends, Ends]:
        return (1.0, _dimension(f"{name}.width", self.width),
                _dimension(f"{name}.height", self.height))


Section = Circle | HollowCircle | Rectangle
SECTIONS: dict[str, type[Section]] = {kind.shape: kind for kind in (Circle, HollowCircle, Rectangle)}


def section_areas(section: Section, elements: int, rule: str,
                  name: str = "bar.section") -> np.ndarray:
    """Element areas (m²) of ``elements`` equal elements along ``section``; ``name``: how
    messages name the section (as a scene file spells it).

    Every section's area is c·p(x)·q(x) with p and q linear in x (a circle d·d, a tube
    (D − d)(D + d), a rectangle w·h). ``rule``:

    ``"midpoint"``: the section at each element's mid-length, c·p_m·q_m.
    ``"exact"``: the constant area with the element's own axial compliance,
    L / ∫₀ᴸ dx/A(x) = c·M(p_b·q_a, p_a·q_b), M the logarithmic mean (x − y)/ln(x/y), since
    ∫₀¹ dt/(p(t)q(t)) = ln(p_b q_a/(p_a q_b))/(p_b q_a − p_a q_b). A circle: π·d_a·d_b/4; a
    rectangle tapered in width only: h·(w_b − w_a)/ln(w_b/w_a). A bar of exact elements has
    the compliance of the continuous taper, whatever the mesh.
    """
    if rule not in AREA_RULES:
        raise SceneError(f"{name}.area_rule must be one of {AREA_RULES}, got {rule!r}")
    if not isinstance(section, tuple(SECTIONS.values())):
        raise SceneError(f"{name} must be a contactqp.scene.Circle, HollowCircle or Rectangle, "
                         f"got {section!r}")
    scale, p_ends, q_ends = section._factors(name)
    p = np.linspace(*p_ends, elements + 1)
    q = np.linspace(*q_ends, elements + 1)
    if rule == "midpoint":
        return scale * (0.5 * (p[:-1] + p[1:]) * (0.5 * (q[:-1] + q[1:])))
    return scale * _log_mean(p[1:] * q[:-1], p[:-1] * q[1:])


def _log_mean(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(x − y)/ln(x/y) of positive x, y, and y where x = y: written y·u/log1p(u) with
    u = x/y − 1, which stays accurate as x → y, where the quotient itself is 0/0."""
    u = (x - y) / y
    with np.errstate(divide="ignore", invalid="ignore"):
        mean = y * u / np.log1p(u)
    return np.where(u == 0.0, y, mean)
