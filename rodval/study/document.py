"""A study document: the study file's tables as plain dicts (``rodval.study.spec`` reads it).

One form for the errors of a study file, a ValueError naming the file and the dotted key
(``key_error``), and dotted paths into the document: a grid's or a sample's keys, set in each
case's copy of it (``rodval.core.scene_keys.set_path``, the one definition that `--set`
uses too; in a list, ``*`` is every element and an integer one).
"""

from __future__ import annotations

import copy
from typing import Any

from rodval.core.scene import Scene
from rodval.core.scene_file import scene_to_file_table


def key_error(where: str, key: str, msg: str) -> ValueError:
    """The error of the study file ``where`` at its dotted ``key``: "where: key 'key': msg"."""
    return ValueError(f"{where}: key '{key}': {msg}")


def plain_document(doc: Any, where: str) -> dict[str, Any]:
    """A deep copy of a study document (never changing the caller's dict), with a
    ``rodval.Scene`` given as [scene] turned into its scene-file table
    (``scene_to_file_table``: ValueError naming ``scene.loads[i]`` for a callable load)."""
    if not isinstance(doc, dict):
        raise ValueError(f"{where}: a study document must be a dict, got {type(doc).__name__}")
    plain: dict[str, Any] = copy.deepcopy(doc)
    if isinstance(plain.get("scene"), Scene):
        plain["scene"] = scene_to_file_table(plain["scene"], where="scene")
    return plain


def flatten(d: dict[str, Any], prefix: str = "", leaf: str = "") -> dict[str, Any]:
    """The leaves of nested tables by their dotted paths: {"scene": {"n": v}} -> {"scene.n": v};
    a table holding the key ``leaf`` (e.g. a sample's "dist") is a leaf too."""
    out: dict[str, Any] = {}
    for k, v in d.items():
        path = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, dict) and not (leaf and leaf in v):
            out.update(flatten(v, path, leaf))
        else:
            out[path] = v
    return out
