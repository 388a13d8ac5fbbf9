"""Numbers written for people: the comparison table, the penalty sweep's table, a Result's
summary and repr show a force, a length and a set of contact forces one way.

A force is shown to ten significant digits of the scene's force scale F: what lies below F's
tenth digit is round-off of the answer (an open wall's 1e-11 N), and shows as 0. No number is
ever written "-0".
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence

import numpy as np

from contactqp.check import TOLERANCES
from contactqp.scene import Scene, row_names  # noqa: F401  (row_names: re-exported)

FORCE_DIGITS = 10  # significant digits of F a force is shown to
WIDTH = 110  # lines of prose (notes, summaries) are wrapped to this many characters


def number(value: float, spec: str = ".3g") -> str:
    """``value`` formatted by ``spec``; zero as '0', and a value that shows as zero without a
    sign."""
    if float(value) == 0.0:
        return "0"
    text = format(float(value), spec)
    try:
        return text.lstrip("-") if float(text) == 0.0 else text
    except ValueError:  # a spec with text around the number
        return text


def force(value: float, scale: float) -> str:
    """A force to :data:`FORCE_DIGITS` significant digits of ``scale`` (F, the scene's force
    scale): 175870.4536 for F = 5.7e5 N; 1.7e-11 N there shows as 0."""
    value = float(value)
    if not (math.isfinite(value) and math.isfinite(scale) and scale > 0.0):
        return number(value, f".{FORCE_DIGITS}g")
    decimals = FORCE_DIGITS - 1 - math.floor(math.log10(scale))
    return number(round(value, decimals), f".{FORCE_DIGITS}g")


def largest_entry(values: np.ndarray) -> int:
    """The index of the entry of largest magnitude (a NaN counts as the largest)."""
    size = np.abs(np.asarray(values, dtype=float))
    return int(np.argmax(np.where(np.isnan(size), np.inf, size)))


def carrying(forces: np.ndarray, scale: float) -> np.ndarray:
    """Which contact forces are more than the check's force tolerance of F (1e-5·F): the
    contacts that carry force, as far as a verified answer can tell."""
    return ~(np.abs(np.asarray(forces, dtype=float)) <= TOLERANCES.force * scale)


def forces_summary(forces: np.ndarray, scale: float) -> str:
    """One contact's force; of several, the largest and (k/n) how many of the n carry force
    (:func:`carrying`): '486212.7847 (1/8)'. '-' for no contacts."""
    forces = np.asarray(forces, dtype=float)
    if forces.size <= 1:
        return force(forces[0], scale) if forces.size else "-"
    top = force(forces[largest_entry(forces)], scale)
    return f"{top} ({int(np.count_nonzero(carrying(forces, scale)))}/{forces.size})"


def carrying_forces(forces: np.ndarray, names: Sequence[str], scale: float,
                    most: int = 8) -> str:
    """The forces that carry force (:func:`carrying`), the largest first, at most ``most``
    of them, each after its row's name; then how many carry none: 'wall[0] 175870.4536;
    2 of 3 carry none'."""
    shown = [i for i in np.argsort(-np.abs(forces), kind="stable") if carrying(forces[i], scale)]
    text = ", ".join(f"{names[i]} {force(forces[i], scale)}" for i in shown[:most])
    if len(shown) > most:
        text += f", … ({len(shown) - most} more)"
    rest = forces.size - len(shown)
    if rest:
        text += f"{'; ' if shown else ''}{rest} of {forces.size} carry none"
    return text


def text_table(header: Sequence[tuple[str, str]], rows: Sequence[Sequence[str]]) -> str:
    """Columns padded to their widest cell, two spaces apart, under a two-line header (each
    column's name, then its unit or ''), and a rule."""
    names, units = [h[0] for h in header], [h[1] for h in header]
    widths = [max(len(str(row[i])) for row in (names, units, *rows)) for i in range(len(header))]

    def line(cells: Sequence[str]) -> str:
        return "  ".join(str(c).ljust(w) for c, w in zip(cells, widths)).rstrip()

    head = [line(names)] + ([line(units)] if any(units) else [])
    return "\n".join([*head, "  ".join("-" * w for w in widths), *map(line, rows)])


def wrap(text: str, width: int = WIDTH) -> str:
    """Each line of ``text`` wrapped to ``width`` characters, continued with an indent."""
    return "\n".join(textwrap.fill(line, width, subsequent_indent="    ",
                                    break_on_hyphens=False) if len(line) > width else line
                      for line in text.splitlines())


__all__ = ["FORCE_DIGITS", "WIDTH", "carrying", "force", "forces_summary", "largest_entry",
           "number", "row_names", "text_table", "wrap"]
