"""Scene files: TOML in (:func:`load_scene`, :func:`scene_from_dict`) and out
(:func:`scene_to_toml`); the format is in the README. Unknown keys are errors, and every error
names the field as the file spells it."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from contactqp.builders import wall_at_every_node
from contactqp.errors import SceneError
from contactqp.scene import Bar, BarContact, DistributedLoad, Load, Scene, Support, Wall
from contactqp.values import number

_TOP_KEYS = {"name", "units", "material", "bar", "support", "load", "wall", "distributed_load",
             "contact",
             "obstacle"}
_MATERIAL_KEYS = {"youngs_modulus", "yield_stress"}
_BAR_KEYS = {"length", "lengths", "elements", "section", "areas", "material"}
_SECTION_KEYS = {"shape", "diameter_start", "diameter_end", "area_rule"}


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
    if "areas" in bar_data:
        if "section" in bar_data or "elements" in bar_data:
            raise SceneError(f"{name}: give either areas or elements + section, not both")
        if not isinstance(bar_data["areas"], list):
            raise SceneError(f"{name}.areas must be a list of numbers, got {bar_data['areas']!r}")
        return Bar.from_areas(
            bar_data["areas"], modulus, length=bar_data.get("length"),
            lengths=bar_data.get("lengths"), yield_stress=yield_stress,
        )
    for key in ("length", "elements", "section"):
        if key not in bar_data:
            raise SceneError(f"{name}.{key} is missing (or give {name}.areas)")
    if "lengths" in bar_data:
        raise SceneError(f"{name}.lengths goes with {name}.areas; with {name}.section the "
                         f"elements are equal ({name}.length / {name}.elements)")
    section = _table(bar_data["section"], f"{name}.section", _SECTION_KEYS,
                     {"shape", "diameter_start", "diameter_end"})
    if section["shape"] != "circle":
        raise SceneError(f"{name}.section.shape must be 'circle', got {section['shape']!r}")
    return Bar.tapered_circle(
        bar_data["length"], bar_data["elements"], section["diameter_start"],
        section["diameter_end"], modulus, area_rule=section.get("area_rule", "midpoint"),
        yield_stress=yield_stress,
    )


def scene_from_dict(data: dict, name: str = "scene") -> Scene:
    """Build a scene from the parsed TOML structure documented in the README: one ``[bar]``
    or several ``[[bar]]`` (each may have its own ``material`` table)."""
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
    scene = Scene(bars, supports, loads, walls, name=str(data.get("name", name)),
                  units=data.get("units", "SI"),
                  distributed=distributed, contacts=contacts)
    for i, o in enumerate(_array_of_tables(data, "obstacle", {"gap", "side", "bar"}, {"gap"})):
        gap = o["gap"]
        if isinstance(gap, list):
            gap = [number(f"obstacle[{i}].gap[{j}]", g, tiny=True) for j, g in enumerate(gap)]
        else:
            gap = number(f"obstacle[{i}].gap", gap, tiny=True)
        scene = wall_at_every_node(scene, gap, o.get("side", "+"), o.get("bar", 0))
    return scene


def load_scene(path: str | Path) -> Scene:
    """Read a scene from a TOML file (format in the README)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SceneError(f"scene file {str(path)!r} does not exist") from None
    except (OSError, UnicodeDecodeError) as error:
        raise SceneError(f"scene file {str(path)!r} cannot be read: {error}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise SceneError(f"scene file {str(path)!r} is not valid TOML: {error}") from None
    return scene_from_dict(data, name=path.stem)


def scene_to_toml(scene: Scene) -> str:
    """The scene as TOML text that :func:`load_scene` reads back (explicit areas and lengths;
    an obstacle as its walls)."""
    lines = [f"name = {json.dumps(scene.name)}",  # JSON strings are TOML
             f"units = {json.dumps(scene.units)}"]
    several = len(scene.bars) > 1
    for i, bar in enumerate(scene.bars):
        moduli = np.unique(bar.youngs_modulus)
        if moduli.size != 1:
            raise SceneError(f"scene_to_toml: bar[{i}] has several moduli, which have no TOML form")
        lines += ["", "[[bar]]" if several else "[bar]", f"areas = {[float(a) for a in bar.areas]!r}",
                  f"lengths = {[float(v) for v in bar.lengths]!r}",
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
    for w in scene.walls:
        lines += ["", "[[wall]]", f"bar = {w.bar}", f"node = {w.node}", f"gap = {float(w.gap)!r}",
                  f'side = "{w.side}"']
    for c in scene.contacts:
        lines += ["", "[[contact]]", f"bar_a = {c.bar_a}", f"node_a = {c.node_a}",
                  f"bar_b = {c.bar_b}", f"node_b = {c.node_b}", f"gap = {float(c.gap)!r}"]
    return "\n".join(lines) + "\n"


__all__ = ["load_scene", "scene_from_dict", "scene_to_toml"]
