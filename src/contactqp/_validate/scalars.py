"""One number or one value a user gives (a scene's fields, a method's options): each function
returns it checked, or raises the given error in one line naming the field and the value as
the user wrote it."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from contactqp.errors import ContactqpError, SceneError

# Every number of a scene is 0 or between 1/MAGNITUDE and MAGNITUDE in size: then every
# product the model and the check form (stiffness E·A/L, displacement load/stiffness, energy,
# a penalty 1e8 times a stiffness) stays far inside double precision, with no overflow.
MAGNITUDE = 1e30


def is_number(value: Any) -> bool:
    """A real number (int or float, numpy's too), not a boolean and not text."""
    return not isinstance(value, (bool, np.bool_)) and isinstance(
        value, (int, float, np.integer, np.floating))


def shown(value: Any) -> str:
    """The value as the user wrote it (numpy scalars as plain Python)."""
    return repr(value.item() if isinstance(value, np.generic) else value)


def in_range(name: str, number: float, tiny: bool = False,
             error: type[ContactqpError] = SceneError) -> float:
    """``number`` if it is finite and 0 or within MAGNITUDE's range. ``tiny``: any small size
    will do (a gap, a load: no product of the model grows from it)."""
    if not math.isfinite(number):
        raise error(f"{name} must be finite, got {number!r}")
    if abs(number) > MAGNITUDE or (not tiny and number != 0.0 and abs(number) < 1 / MAGNITUDE):
        raise error(f"{name} = {number!r} is outside the range contactqp computes in (0, or "
                    f"{1 / MAGNITUDE:.0e} to {MAGNITUDE:.0e} in size; choose other units)")
    return number


def number(name: str, value: Any, *, minimum: float | None = None, strict: bool = False,
           tiny: bool = False, error: type[ContactqpError] = SceneError) -> float:
    """``value`` as a finite float within range (optionally >= or > ``minimum``)."""
    if not is_number(value):
        raise error(f"{name} must be a number, got {shown(value)}")
    result = float(value)
    if not math.isfinite(result):
        raise error(f"{name} must be finite, got {result!r}")
    if minimum is not None and (result <= minimum if strict else result < minimum):
        raise error(f"{name} must be {'>' if strict else '>='} {minimum:g}, got {result!r}")
    return in_range(name, result, tiny, error)


def positive_number(name: str, value: Any, unit: str = "",
                    error: type[ContactqpError] = SceneError) -> float:
    """``value`` as a positive finite float (``unit`` named in the message) within
    MAGNITUDE's range, as a scene's numbers are: a penalty of 1e300 overflows what it
    multiplies."""
    what = f" ({unit})" if unit else ""
    if not is_number(value) or not (math.isfinite(value) and value > 0.0):
        raise error(f"{name} must be a positive finite number{what}, got {shown(value)}")
    if not 1 / MAGNITUDE <= value <= MAGNITUDE:
        unit = f", {unit}" if unit else ""
        raise error(f"{name} = {shown(value)} is outside the range contactqp computes in "
                    f"({1 / MAGNITUDE:.0e} to {MAGNITUDE:.0e}{unit})")
    return float(value)


def positive_values(name: str, values: Any, unit: str = "",
                    error: type[ContactqpError] = SceneError) -> tuple[float, ...]:
    """``values``, a non-empty sequence, each a :func:`positive_number` (named ``name[i]``)."""
    if isinstance(values, (str, bytes, dict)) or not hasattr(values, "__iter__"):
        raise error(f"{name} must be a sequence of numbers, got {shown(values)}")
    checked = tuple(positive_number(f"{name}[{i}]", v, unit, error) for i, v in enumerate(values))
    if not checked:
        raise error(f"{name} must hold at least one number, got {shown(values)}")
    return checked


def one_of(name: str, value: Any, choices: Any,
           error: type[ContactqpError] = SceneError) -> str:
    """``value`` if it is one of the names ``choices`` (a list or a dict of them): text only,
    so that a list or a table given for a name is refused, not hashed."""
    if not isinstance(value, str) or value not in choices:
        raise error(f"{name} must be one of {', '.join(map(repr, choices))}, got {shown(value)}")
    return value


def text(name: str, value: Any, error: type[ContactqpError] = SceneError) -> str:
    """``value`` if it is text that UTF-8 can hold (a lone surrogate cannot be written to a
    scene file)."""
    if not isinstance(value, str):
        raise error(f"{name} must be text, got {shown(value)}")
    try:
        value.encode("utf-8")
    except UnicodeEncodeError:
        raise error(f"{name} must be text UTF-8 can hold, got {value!r}") from None
    return value


def whole_number(name: str, value: Any, minimum: int | None = None, what: str = "number",
                 error: type[ContactqpError] = SceneError, note: str = "") -> int:
    """``value`` as an int (not a boolean, not a float), at least ``minimum``; ``note`` is
    added to the message."""
    if not isinstance(value, (int, np.integer)) or isinstance(value, (bool, np.bool_)) or (
            minimum is not None and value < minimum):
        at_least = "" if minimum is None else f" >= {minimum}"
        raise error(f"{name} must be a whole {what}{at_least}{note}, got {shown(value)}")
    return int(value)


def flag(name: str, value: Any, error: type[ContactqpError] = SceneError) -> bool:
    """``value`` if it is True or False."""
    if not isinstance(value, (bool, np.bool_)):
        raise error(f"{name} must be True or False, got {shown(value)}")
    return bool(value)


def positive_numbers(name: str, values: Any, limit: int) -> np.ndarray:
    """``values`` (one or more) as a read-only float array, every one a positive finite
    number within range; at most ``limit`` of them."""
    if isinstance(values, (str, bytes)):
        raise SceneError(f"{name} must be numbers, got {values!r}")
    try:
        raw = np.asarray(values)
    except (TypeError, ValueError):
        raise SceneError(f"{name} must be numbers, got {values!r}") from None
    if raw.dtype.kind not in "iuf":  # strings, booleans, objects: name the first non-number
        items = values if isinstance(values, (list, tuple)) else raw.reshape(-1)
        for i, value in enumerate(items):
            if not is_number(value):
                raise SceneError(f"{name}[{i}] must be a number, got {shown(value)}")
    if raw.ndim > 1:  # a table of numbers is not one per element: flattening would guess
        raise SceneError(f"{name} must be a flat list of numbers (one per element), got an "
                         f"array of shape {raw.shape}")
    if raw.size > limit:
        raise SceneError(f"{name} has {raw.size} values; contactqp takes at most {limit} "
                         "elements in a scene")
    array = raw.astype(float).reshape(-1)
    bad = np.flatnonzero(~np.isfinite(array) | (array <= 0.0))
    if bad.size:
        i = int(bad[0])
        raise SceneError(f"{name}[{i}] must be a positive finite number, got {float(array[i])!r}")
    for i in (int(array.argmin()), int(array.argmax())) if array.size else ():
        in_range(f"{name}[{i}]", float(array[i]))
    array.flags.writeable = False
    return array


def _not_a_number(name: str, raw: np.ndarray) -> str:
    """What of ``raw`` (an array whose dtype is not a number's) is not a number, in one line:
    its first entry that is not, with where it is, or its dtype (an array's repr spans lines
    and holds every entry)."""
    if raw.dtype.kind == "c":
        return f"complex values (dtype {raw.dtype})"
    for index in np.ndindex(raw.shape):
        if not is_number(raw[index]):
            return f"{shown(raw[index])} at {name}[{', '.join(map(str, index))}]"
    return f"an array of dtype {raw.dtype}"


def value_array(name: str, values: Any, shape: tuple[int, ...], what: str,
                error: type[ContactqpError]) -> np.ndarray:
    """``values`` as a float array of ``shape`` (a leading -1: any number of cases), every
    entry a finite number within range; else ``error`` naming ``name`` and what it holds
    (``what``: "one per point load, ..."), with the first bad entry."""
    try:
        raw = np.asarray(values)
    except (TypeError, ValueError):
        raise error(f"{name} must be numbers ({what}), got {values!r}") from None
    if raw.dtype.kind not in "iuf":  # text, booleans, objects: not numbers, as in a Scene
        raise error(f"{name} must be numbers ({what}), got {_not_a_number(name, raw)}")
    array = raw.astype(float)
    expected = tuple(array.shape[0] if n == -1 and array.ndim else n for n in shape)
    if array.shape != expected:
        parts = ["cases" if n == -1 else str(n) for n in shape]
        wanted = "(" + ", ".join(parts) + ("," if len(parts) == 1 else "") + ")"
        raise error(f"{name} must have shape {wanted} ({what}), got shape {array.shape}")
    bad = np.argwhere(~np.isfinite(array))
    if bad.size:
        where = ", ".join(map(str, bad[0]))
        raise error(f"{name}[{where}] must be finite, got {float(array[tuple(bad[0])])!r}")
    if array.size:
        for index in (np.unravel_index(np.abs(array).argmax(), array.shape),):
            in_range(f"{name}[{', '.join(map(str, index))}]", float(array[index]), True, error)
    return array
