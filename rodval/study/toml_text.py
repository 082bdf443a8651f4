"""A study document (plain dicts, lists and scalars) as TOML text: what a study built in Python
writes beside its results as ``study.toml``, so that it can be read back (``load_study``),
rerun from the command line and resumed like a study written by hand.

Every table is written inline (``key = {a = 1, b = [2, 3]}``), which TOML 1.0 allows at any
depth; keys that are not bare (e.g. grid paths ``"scene.n"``) are quoted. Floats keep every
digit (``repr``), including ``inf`` and ``nan``.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any

import numpy as np

_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def _text(v: str, where: str) -> str:
    """A TOML string of ``v``; ValueError naming ``where`` for text that is not Unicode
    scalars (a lone surrogate: JSON escapes it as \\udXXX, which TOML readers refuse)."""
    try:
        v.encode("utf-8")
    except UnicodeEncodeError:
        raise ValueError(
            f"{where}: text {v!r:.40} holds a lone surrogate, which a study file cannot hold"
        ) from None
    return json.dumps(v, ensure_ascii=False)


def _key(k: Any, where: str) -> str:
    if not isinstance(k, str):
        raise ValueError(f"{where}: keys must be strings, got {k!r}")
    return k if _BARE.match(k) else _text(k, where)


def toml_value(v: Any, where: str = "study") -> str:
    """One TOML value (inline); ValueError naming ``where`` for what TOML cannot hold."""
    if isinstance(v, np.generic):
        v = v.item()
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return _text(v, where)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x, f"{where}[{i}]") for i, x in enumerate(v)) + "]"
    if isinstance(v, dict):
        items = (f"{_key(k, where)} = {toml_value(x, f'{where}.{k}')}" for k, x in v.items())
        return "{" + ", ".join(items) + "}"
    raise ValueError(
        f"{where}: {type(v).__name__} {v!r} cannot be written to a study file (numbers, "
        "strings, booleans, lists and tables only)"
    )


def toml_text(doc: dict[str, Any]) -> str:
    """The TOML text of ``doc``, one top-level key per line; ``tomllib.loads`` of it gives
    ``doc`` back (tuples as lists, numpy values as Python ones)."""
    return "".join(f"{_key(k, 'study')} = {toml_value(v, str(k))}\n" for k, v in doc.items())
