"""Argument checks shared by every entry point: one definition of "a table with known keys"
and of "an argument of the right type", each raising a one-line ValueError that names the
argument and what is allowed (rodval's rule: bad input is refused before any work)."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any


def check_keys(
    d: Any, allowed: Iterable[str], where: str, *, noun: str = "key", table: str = "a table"
) -> None:
    """ValueError naming ``where`` unless ``d`` is a dict whose keys are all in ``allowed``;
    the message names the first unknown ``noun`` and lists the allowed ones."""
    allowed = set(allowed)
    if not isinstance(d, dict):
        raise ValueError(f"{where}: expected {table}, got {type(d).__name__}")
    unknown = sorted(set(d) - allowed)
    if unknown:
        raise ValueError(
            f"{where}: unknown {noun} {unknown[0]!r} (allowed: {', '.join(sorted(allowed))})"
        )


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
