"""What a scene-file key is: its type (``Kind``: words and test) and its unit, allowed values
and nested keys (``Key``). The scene's keys are declared with them: ``rodval.core.scene_keys``
(``SCENE_KEYS``) and each hinge item's ``KEYS`` (``rodval.core.hinges``)."""

from __future__ import annotations

import numbers
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class Kind:
    """A type of scene-file value: its words in messages and docs, and its test."""

    words: str
    accepts: Callable[[Any], bool]


def _real(v: Any) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def _integer(v: Any) -> bool:
    return isinstance(v, numbers.Integral) and not isinstance(v, bool)


def _reals(v: Any) -> bool:
    return isinstance(v, list) and all(_real(x) for x in v)


TABLE = Kind("a table", lambda v: isinstance(v, dict))
TABLES = Kind("an array of tables", lambda v: isinstance(v, list))
INTEGER = Kind("an integer", _integer)
NUMBER = Kind("a number", _real)
STRING = Kind("a string", lambda v: isinstance(v, str))
BOOLEAN = Kind("true or false", lambda v: isinstance(v, bool))
PAIR = Kind("a pair [x, y] of numbers", lambda v: _reals(v) and len(v) == 2)
NUMBERS = Kind("a list of numbers", _reals)
STRINGS = Kind(
    "a list of strings", lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v)
)
NUMBER_OR_NUMBERS = Kind("a number or a list of numbers", lambda v: _real(v) or _reals(v))
ROD = Kind(
    "a number, a list of n numbers or a profile table",
    lambda v: _real(v) or _reals(v) or isinstance(v, dict),
)
TIMES = Kind(
    "a list of numbers or a table {start, stop, num}", lambda v: _reals(v) or isinstance(v, dict)
)
NODE = Kind('an integer or "last"', lambda v: _integer(v) or v == "last")


@dataclass(frozen=True)
class Key:
    """One key of a scene file: its type, unit and allowed values (words), and for a table
    its keys (``keys``: checked when the value is a table; for an array of tables, each
    element's). ``section``: a table that ``merge_documents`` merges key by key, unless the
    later table names another ``variant`` (a key of the table and its default: [base]'s
    ``kind``), which replaces the earlier table whole; ``required``: a key every table of its
    array must hold; ``none``: the dict form (a run record) may hold None for "omitted"."""

    kind: Kind
    unit: str = ""
    allowed: str = ""
    keys: dict[str, Key] = field(default_factory=dict)
    section: bool = False
    required: bool = False
    none: bool = False
    variant: tuple[str, str] | None = None
