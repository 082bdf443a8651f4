"""Argument checks shared by every entry point: one definition of "a table with known keys",
of "an argument of the right type" and of "a number in a range", each raising a one-line
ValueError that names the argument and what is allowed (rodval's rule: bad input is refused
before any work)."""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from pathlib import Path
from typing import Any, TypedDict, Unpack, cast


def check_keys(
    d: Any,
    allowed: Iterable[str],
    where: str,
    *,
    noun: str = "key",
    table: str = "a table",
    path: str | None = None,
) -> None:
    """ValueError naming ``where`` unless ``d`` is a dict whose keys are all in ``allowed``;
    the message names the first unknown ``noun`` and lists the allowed ones.

    ``path``: the table's dotted path in a document ("" for the document itself, as in study
    files); the messages then name the key by its full path after ``where``:
    ``<where> key 'report.foo': unknown key (allowed: ...)`` and
    ``<where> 'report' must be a table, got list``."""
    allowed = set(allowed)
    if not isinstance(d, dict):
        if path is not None:
            raise ValueError(f"{where} '{path}' must be a table, got {type(d).__name__}")
        raise ValueError(f"{where}: expected {table}, got {type(d).__name__}")
    unknown = sorted(set(d) - allowed)
    if unknown:
        listed = ", ".join(sorted(allowed))
        if path is not None:
            key = f"{path}.{unknown[0]}" if path else unknown[0]
            raise ValueError(f"{where} key '{key}': unknown key (allowed: {listed})")
        raise ValueError(f"{where}: unknown {noun} {unknown[0]!r} (allowed: {listed})")


def check_type(name: str, value: Any, kind: type | tuple[type, ...], expected: str) -> None:
    """ValueError unless ``value`` is an instance of ``kind``: "``name`` must be ``expected``,
    got <its type>" (checked up front, so that a wrong argument never fails deep inside)."""
    if not isinstance(value, kind):
        raise ValueError(f"{name} must be {expected}, got {type(value).__name__} {value!r:.60}")


def as_path(name: str, value: Any) -> Path:
    """A str or os.PathLike argument as a Path (ValueError naming ``name`` otherwise)."""
    check_type(name, value, (str, Path), "a path (str or pathlib.Path)")
    return Path(value)


def check_choice(name: str, value: Any, choices: Iterable[str]) -> str:
    """``value`` when it is one of the strings ``choices``, else ValueError naming ``name`` and
    the choices (an array, a number or None never reaches an ``in`` test that fails deep
    inside with numpy's "truth value of an array is ambiguous")."""
    choices = tuple(choices)
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name} must be one of {choices}, got {value!r:.60}")
    return value


class Bounds(TypedDict, total=False):
    """The range ``check_number`` accepts and ``describe_range`` words: ``low``..``high``
    (defaults -inf..inf; each end open when ``low_open``, ``high_open``), ``finite``,
    ``integer``; ``unit`` for the words only."""

    unit: str
    low: float
    high: float
    low_open: bool
    high_open: bool
    finite: bool
    integer: bool


def describe_range(**bounds: Unpack[Bounds]) -> str:
    """The range of ``check_number`` in words, e.g. "a finite real number > 0 (m)",
    "an integer in [1, 1000]"."""
    low, high = bounds.get("low", -math.inf), bounds.get("high", math.inf)
    low_open, high_open = bounds.get("low_open", False), bounds.get("high_open", False)
    finite, unit = bounds.get("finite", False), bounds.get("unit", "")
    kind = "a finite real number" if finite else "a real number"
    kind = "an integer" if bounds.get("integer", False) else kind
    if math.isfinite(low) and math.isfinite(high):
        ends = f" in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
    elif math.isfinite(low):
        ends = f" {'>' if low_open else '>='} {low:g}"
    elif math.isfinite(high):
        ends = f" {'<' if high_open else '<='} {high:g}"
    else:
        ends = ""
    return f"{kind}{ends}{f' ({unit})' if unit else ''}"


def check_number(
    name: str, value: Any, *, allowed: str | None = None, **bounds: Unpack[Bounds]
) -> float:
    """``value`` as a float (an int when ``integer``) when it is a real number (an integral
    one when ``integer``; never a bool, string, complex or NaN), finite when ``finite``, and
    within ``low``..``high`` (each end open or closed; ``Bounds``); else the one-line
    ValueError "<name> must be <allowed>, got <value>", ``allowed`` defaulting to
    ``describe_range``. The one number validator of rodval: types before values, the unit in
    the message."""
    integer = bounds.get("integer", False)
    low, high = bounds.get("low", -math.inf), bounds.get("high", math.inf)
    low_open, high_open = bounds.get("low_open", False), bounds.get("high_open", False)
    kind = numbers.Integral if integer else numbers.Real
    if isinstance(value, kind) and not isinstance(value, bool):
        v = int(cast(int, value)) if integer else float(value)
        if (
            not math.isnan(v)
            and (math.isfinite(v) or not bounds.get("finite", False))
            and (v > low if low_open else v >= low)
            and (v < high if high_open else v <= high)
        ):
            return v
    words = describe_range(**bounds) if allowed is None else allowed
    raise ValueError(f"{name} must be {words}, got {value!r}")


def check_reals(name: str, values: Iterable[Any], allowed: str) -> tuple[float, ...]:
    """``values`` as floats when each is a real number (inf allowed; never a bool, string,
    complex or NaN), in one call; else the one-line ValueError "<name>[i] must be <allowed>,
    got <value>" of ``check_number`` for the first that is not."""
    out = []
    for i, value in enumerate(values):
        if isinstance(value, numbers.Real) and not isinstance(value, bool) and value == value:
            out.append(float(value))
        else:
            check_number(f"{name}[{i}]", value, allowed=allowed)
    return tuple(out)
