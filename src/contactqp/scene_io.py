"""Scene files: TOML in (:func:`load_scene`, :func:`scene_from_dict`) and out
(:func:`scene_to_toml`); the format is in docs/scene_files.md. Unknown keys are errors, and every error
names the field as the file spells it."""

from __future__ import annotations

import tomllib
from dataclasses import fields
from pathlib import Path
from typing import Any

import numpy as np

from contactqp._validate import number
from contactqp.builders import wall_at_every_node
from contactqp.errors import SceneError
from contactqp.scene import (
    SECTIONS,
    Bar,
    BarContact,
    Bed,
    DistributedLoad,
    Load,
    Scene,
    Section,
    Support,
    Wall,
    Walls,
)

_TOP_KEYS = {"name", "units", "material", "bar", "support", "load", "wall", "walls",
             "distributed_load", "contact", "obstacle", "bed"}
_WALLS_KEYS = {"nodes", "gaps", "sides", "bars"}
_MATERIAL_KEYS = {"youngs_modulus", "yield_stress"}
_BAR_KEYS = {"length", "lengths", "elements", "section", "areas", "area", "material"}
_AREA_KEYS = ("areas", "area", "section")  # exactly one says what each element's area is
_ENDS = ("_start", "_end")


def _table(data: Any, name: str, allowed: set[str], required: set[str] = frozenset()) -> dict:
    if not isinstance(data, dict):
        raise SceneError(f"{name} must be a table, got {data!r}")
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise SceneError(f"{name}.{unknown[0]}: unknown key (allowed: {', '.join(sorted(allowed))})")
    missing = sorted(required - set(data))
    if missing:
        raise SceneError(f"{name}.{missing[0]} is missing")
    return data


def _array_of_tables(data: dict, key: str, allowed: set[str], required: set[str]) -> list[dict]:
    items = data.get(key, [])
    if not isinstance(items, list):
        raise SceneError(f"{key} must be an array of tables ([[{key}]]), got {items!r}")
    return [_table(item, f"{key}[{i}]", allowed, required) for i, item in enumerate(items)]


def _bar_from_dict(bar_data: Any, name: str, material: dict | None) -> Bar:
    """One bar from its TOML table; its own ``material`` table, else the scene's."""
    bar_data = _table(bar_data, name, _BAR_KEYS)
    if "material" in bar_data:
        material = _table(bar_data["material"], f"{name}.material", _MATERIAL_KEYS,
                          {"youngs_modulus"})
        where = f"{name}.material"
    else:
        where = "material"
    if material is None:
        raise SceneError(f"{name}: no material; give [material] or {name}.material")
    modulus = number(f"{where}.youngs_modulus", material["youngs_modulus"], minimum=0.0,
                     strict=True)
    yield_stress = material.get("yield_stress")
    if yield_stress is not None:
        yield_stress = number(f"{where}.yield_stress", yield_stress, minimum=0.0, strict=True)
    given = [key for key in _AREA_KEYS if key in bar_data]
    if len(given) != 1:
        raise SceneError(f"{name}: give one of areas = [...] (m², one per element), area = A "
                         "(m², every element) or section = {...}, got "
                         f"{' and '.join(given) if given else 'none'}")
    common = {"yield_stress": yield_stress, "name": name}
    if "areas" in bar_data:
        if "elements" in bar_data:
            raise SceneError(f"{name}.elements goes with {name}.area or {name}.section; with "
                             f"{name}.areas there is one element per area")
        if not isinstance(bar_data["areas"], list):
            raise SceneError(f"{name}.areas must be a list of numbers, got {bar_data['areas']!r}")
        return Bar.from_areas(bar_data["areas"], modulus, length=bar_data.get("length"),
                              lengths=bar_data.get("lengths"), **common)
    if "area" in bar_data:
        if isinstance(bar_data["area"], list):
            raise SceneError(f"{name}.area must be one number (m², every element), got "
                             f"{bar_data['area']!r}; one per element is {name}.areas = [...]")
        if "lengths" in bar_data and ("length" in bar_data or "elements" in bar_data):
            raise SceneError(f"{name}: give length and elements, or lengths, not both")
        return Bar.uniform(bar_data["area"], modulus, length=bar_data.get("length"),
                           elements=bar_data.get("elements"), lengths=bar_data.get("lengths"),
                           **common)
    for key in ("length", "elements"):
        if key not in bar_data:
            raise SceneError(f"{name}.{key} is missing (a section needs length and elements)")
    if "lengths" in bar_data:
        raise SceneError(f"{name}.lengths goes with {name}.areas or {name}.area; with "
                         f"{name}.section the elements are equal ({name}.length / "
                         f"{name}.elements)")
    section, rule = _section_from_dict(bar_data["section"], f"{name}.section")
    return Bar.from_section(section, modulus, length=bar_data["length"],
                            elements=bar_data["elements"], area_rule=rule, **common)


def _section_from_dict(data: Any, name: str) -> tuple[Section, Any]:
    """A section and its area rule from its TOML table: ``shape``, each dimension as one
    number (``width``) or its two ends (``width_start``, ``width_end``), ``area_rule``."""
    shapes = ", ".join(map(repr, SECTIONS))
    if not isinstance(data, dict):
        raise SceneError(f"{name} must be a table, got {data!r}")
    if "shape" not in data:
        raise SceneError(f"{name}.shape is missing (one of {shapes})")
    shape = data["shape"]
    kind = SECTIONS.get(shape) if isinstance(shape, str) else None
    if kind is None:
        raise SceneError(f"{name}.shape must be one of {shapes}, got {shape!r}")
    dimensions = [f.name for f in fields(kind)]
    _table(data, name, {"shape", "area_rule"} | {d + end for d in dimensions
                                                  for end in ("", *_ENDS)})
    values = {}
    for d in dimensions:
        ends = [d + end for end in _ENDS if d + end in data]
        if d in data and ends:
            raise SceneError(f"{name}.{d} and {name}.{ends[0]} are both given: give {d} (the "
                             f"same along the bar) or {d}_start and {d}_end (a taper)")
        if d in data:
            if isinstance(data[d], list):
                raise SceneError(f"{name}.{d} must be one number, got {data[d]!r}; a taper "
                                 f"is {d}_start and {d}_end")
            values[d] = data[d]
        elif len(ends) == 2:
            values[d] = (data[d + _ENDS[0]], data[d + _ENDS[1]])
        else:
            missing = d if not ends else d + _ENDS[ends[0] == d + _ENDS[0]]
            raise SceneError(f"{name}.{missing} is missing ({d} for a {kind.shape} the same "
                             f"along the bar, {d}_start and {d}_end for a taper)")
    return kind(**values), data.get("area_rule", "midpoint")


def scene_from_dict(data: dict, name: str = "scene") -> Scene:
    """Build a scene from the parsed TOML structure (docs/scene_files.md): one ``[bar]``
    or several ``[[bar]]`` (each may have its own ``material`` table).

    Parameters
    ----------
    data : dict
        The parsed TOML, as :func:`tomllib.loads` gives it.
    name : str
        The scene's name where ``data`` has no ``name`` key.

    Returns
    -------
    Scene
        The scene, validated.

    Raises
    ------
    SceneError
        An unknown key, a missing one, or a bad value (naming the field).
    """
    data = _table(data, "scene", _TOP_KEYS, {"bar"})
    material = None
    if "material" in data:
        material = _table(data["material"], "material", _MATERIAL_KEYS, {"youngs_modulus"})
    if isinstance(data["bar"], list):
        if not data["bar"]:
            raise SceneError("bar: [[bar]] is empty; give at least one bar")
        bars = tuple(_bar_from_dict(b, f"bar[{i}]", material) for i, b in enumerate(data["bar"]))
    else:
        bars = (_bar_from_dict(data["bar"], "bar", material),)
    supports = tuple(Support(s["node"], s.get("bar", 0))
                     for s in _array_of_tables(data, "support", {"node", "bar"}, {"node"}))
    loads = tuple(
        Load(s["node"], s["force"], s.get("bar", 0))
        for s in _array_of_tables(data, "load", {"node", "force", "bar"}, {"node", "force"})
    )
    walls = tuple(
        Wall(s["node"], s["gap"], s.get("side", "+"), s.get("bar", 0))
        for s in _array_of_tables(data, "wall", {"node", "gap", "side", "bar"}, {"node", "gap"})
    )
    sets = [Walls(w["nodes"], w["gaps"], w.get("sides", "+"), w.get("bars", 0), name=f"walls[{i}]")
            for i, w in enumerate(_array_of_tables(data, "walls", _WALLS_KEYS, {"nodes", "gaps"}))]
    if sets:  # the [[wall]] tables' rows first, then each [[walls]] in order
        walls = [*walls, *sets]
    distributed = tuple(
        DistributedLoad(q["intensity"], q.get("bar", 0), q.get("start", 0), q.get("stop"))
        for q in _array_of_tables(data, "distributed_load", {"intensity", "bar", "start", "stop"},
                                  {"intensity"})
    )
    contacts = tuple(
        BarContact(c["bar_a"], c["node_a"], c["bar_b"], c["node_b"], c["gap"])
        for c in _array_of_tables(data, "contact", {"bar_a", "node_a", "bar_b", "node_b", "gap"},
                                  {"bar_a", "node_a", "bar_b", "node_b", "gap"})
    )
    beds = tuple(Bed(b["tau"], b.get("bar", 0))
                 for b in _array_of_tables(data, "bed", {"tau", "bar"}, {"tau"}))
    scene = Scene(bars, supports, loads, walls, name=data.get("name", name),
                  units=data.get("units", "SI"),
                  distributed=distributed, contacts=contacts, beds=beds)
    for i, o in enumerate(_array_of_tables(data, "obstacle", {"gap", "side", "bar"}, {"gap"})):
        gap = o["gap"]
        if isinstance(gap, list):
            gap = [number(f"obstacle[{i}].gap[{j}]", g, tiny=True) for j, g in enumerate(gap)]
        else:
            gap = number(f"obstacle[{i}].gap", gap, tiny=True)
        scene = wall_at_every_node(scene, gap, o.get("side", "+"), o.get("bar", 0))
    return scene


def load_scene(path: str | Path) -> Scene:
    """Read a scene from a TOML file (format in docs/scene_files.md).

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML file.

    Returns
    -------
    Scene
        The scene, validated.

    Raises
    ------
    SceneError
        The file does not exist, cannot be read, is not TOML, or holds a bad key or value (one
        line naming the field as the file spells it).
    """
    if str(path) == "":  # Path("") is ".", the working folder: say what was given
        raise SceneError("scene file path is empty ('')")
    path = Path(path)
    try:  # utf-8-sig: a byte-order mark, which some editors write, is read past
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise SceneError(f"scene file {str(path)!r} does not exist") from None
    except (OSError, UnicodeDecodeError) as error:
        raise SceneError(f"scene file {str(path)!r} cannot be read: {error}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise SceneError(f"scene file {str(path)!r} is not valid TOML: {error}") from None
    return scene_from_dict(data, name=path.stem)


def _bar_geometry(bar: Bar) -> list[str]:
    """A bar's TOML lines that give back its lengths and areas bit for bit: ``area`` where
    every element has one area, ``length`` where the elements are equal and length / elements
    gives their length again, else one value per element."""
    n, first = bar.n_elements, float(bar.lengths[0])
    equal = bool(np.all(bar.lengths == first)) and (first * n) / n == first
    lines = [f"length = {first * n!r}"] if equal else [
        f"lengths = {[float(v) for v in bar.lengths]!r}"]
    if np.all(bar.areas == bar.areas[0]):
        return [*lines, f"area = {float(bar.areas[0])!r}"] + ([f"elements = {n}"] if equal else [])
    return [*lines, f"areas = {[float(a) for a in bar.areas]!r}"]


def toml_string(value: str) -> str:
    """``value`` as a TOML basic string: every character as it is but the quotation mark, the
    backslash and the control characters, which are escaped (JSON's escapes of characters
    beyond U+FFFF are surrogate pairs, which TOML refuses)."""
    def escaped(char: str) -> str:
        if char in '"\\':
            return "\\" + char
        return f"\\u{ord(char):04X}" if ord(char) < 0x20 or ord(char) == 0x7F else char

    return '"' + "".join(map(escaped, value)) + '"'


def _wall_set_lines(walls: Walls) -> list[str]:
    """A :class:`Walls` as one ``[[walls]]`` table: its arrays as TOML arrays (gaps bit for
    bit, as repr gives them), ``sides`` and ``bars`` as one value where every wall shares it."""
    sides, bars = walls.sides.tolist(), walls.bars.tolist()
    side = f'"{sides[0]}"' if len(set(sides)) == 1 else (
        "[" + ", ".join(f'"{x}"' for x in sides) + "]")
    bar = str(bars[0]) if len(set(bars)) == 1 else repr(bars)
    lines = ["", "[[walls]]", f"nodes = {walls.nodes.tolist()!r}",
             f"gaps = {walls.gaps.tolist()!r}"]
    return lines + ([f"sides = {side}", f"bars = {bar}"] if len(walls) else [])


def scene_to_toml(scene: Scene) -> str:
    """The scene as TOML text that :func:`load_scene` reads back to the same scene: each
    bar's areas and lengths (a section as the areas it gave, one ``area`` for a uniform
    bar), an obstacle as its walls.

    Parameters
    ----------
    scene : Scene
        Any scene.

    Returns
    -------
    str
        The TOML text.
    """
    lines = [f"name = {toml_string(scene.name)}", f"units = {toml_string(scene.units)}"]
    several = len(scene.bars) > 1
    for i, bar in enumerate(scene.bars):
        moduli = np.unique(bar.youngs_modulus)
        if moduli.size != 1:
            raise SceneError(f"scene_to_toml: bar[{i}] has several moduli, which have no TOML form")
        lines += ["", "[[bar]]" if several else "[bar]", *_bar_geometry(bar),
                  "", "[bar.material]", f"youngs_modulus = {float(moduli[0])!r}"]
        if bar.yield_stress is not None:
            lines.append(f"yield_stress = {bar.yield_stress!r}")
    for s in scene.supports:
        lines += ["", "[[support]]", f"bar = {s.bar}", f"node = {s.node}"]
    for p in scene.loads:
        lines += ["", "[[load]]", f"bar = {p.bar}", f"node = {p.node}", f"force = {float(p.force)!r}"]
    for q in scene.distributed:
        lines += ["", "[[distributed_load]]", f"bar = {q.bar}", f"intensity = {float(q.intensity)!r}",
                  f"start = {q.start}"] + ([] if q.stop is None else [f"stop = {q.stop}"])
    if isinstance(scene.walls, Walls):
        lines += _wall_set_lines(scene.walls)
    else:
        for w in scene.walls:
            lines += ["", "[[wall]]", f"bar = {w.bar}", f"node = {w.node}",
                      f"gap = {float(w.gap)!r}", f'side = "{w.side}"']
    for c in scene.contacts:
        lines += ["", "[[contact]]", f"bar_a = {c.bar_a}", f"node_a = {c.node_a}",
                  f"bar_b = {c.bar_b}", f"node_b = {c.node_b}", f"gap = {float(c.gap)!r}"]
    for b in scene.beds:
        lines += ["", "[[bed]]", f"bar = {b.bar}", f"tau = {float(b.tau)!r}"]
    return "\n".join(lines) + "\n"


__all__ = ["load_scene", "scene_from_dict", "scene_to_toml", "toml_string"]
