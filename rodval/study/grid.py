"""The cases a study asks for, as combinations of values before any case is built: the
cartesian product of each ``[[grid]]`` table's axes (the union over several tables), or the
draws of the ``[sample]`` table (``rodval.study.sampling``). Their number is known, and
refused over the limit, before they are expanded.

Each key of a grid or a sample is the dotted path of a key of the study file, into
``scene``, ``integrator`` or a model's table (``models.LABEL.KEY``); its label in case ids
and tables is its shortest unambiguous tail (``scene.t_end`` -> ``t_end``).
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from rodval.study.document import flatten, key_error
from rodval.study.model_specs import INTEGRATOR_KEYS
from rodval.study.sampling import sample_columns

GRID_ROOTS = ("scene", "integrator", "models")


@dataclass(frozen=True)
class Design:
    """The cases of a study before they are built: the varied keys' values (``axes``: path
    -> values), their labels (path -> short label), one combination of values per case
    (path -> value) and the cases' ids when the design names them (a sample's
    ``sample=0001``), else None (the id is made from the values)."""

    axes: dict[str, list[Any]]
    labels: dict[str, str]
    combos: list[dict[str, Any]]
    ids: list[str] | None = None


def check_axis_path(path: str, key: str, doc: dict[str, Any], where: str) -> None:
    """A grid or sample key is a path into the scene, the integrator or a model's table."""
    root, *rest = path.split(".")
    if root not in GRID_ROOTS or not rest:
        raise key_error(
            where,
            key,
            f"must be a path into {', '.join(GRID_ROOTS)} "
            "(e.g. scene.n, scene.chain.EI, integrator.rtol, models.full.method)",
        )
    if path == "scene.file":
        raise key_error(
            where,
            key,
            "the scene file is read once for the whole study; vary its keys "
            "(scene.t_end, scene.chain.EI, ...) or write one study per file",
        )
    if root == "integrator" and (len(rest) != 1 or rest[0] not in INTEGRATOR_KEYS):
        raise key_error(where, key, f"integrator keys are {', '.join(sorted(INTEGRATOR_KEYS))}")
    if root == "models" and (len(rest) != 2 or rest[0] not in doc.get("models", {})):
        raise key_error(
            where,
            key,
            f"must be models.LABEL.KEY with LABEL one of {', '.join(doc.get('models', {}))}",
        )


def axis_labels(paths: list[str]) -> dict[str, str]:
    """Shortest unambiguous label of each path: its last segment(s); scene.t_end -> t_end."""
    labels = {}
    for p in paths:
        parts = p.split(".")
        for depth in range(1, len(parts) + 1):
            cand = ".".join(parts[-depth:])
            if sum(1 for q in paths if q == cand or q.endswith("." + cand)) == 1:
                labels[p] = cand
                break
    return labels


def grid_axes(grid: Any, doc: dict[str, Any], where: str) -> dict[str, list[Any]]:
    """The axes (path -> distinct values) of one ``[grid]`` table, checked; {} without one."""
    if grid is None:
        return {}
    if not isinstance(grid, dict):
        raise key_error(
            where,
            "grid",
            "must be a table of dotted keys -> lists of values, "
            "or an array of such tables ([[grid]])",
        )
    axes = flatten(grid)
    for path, values in axes.items():
        key = f"grid.{path}"
        check_axis_path(path, key, doc, where)
        if not isinstance(values, list) or not values:
            raise key_error(where, key, f"must be a non-empty list of values, got {values!r}")
        if len({json.dumps(v, sort_keys=True) for v in values}) != len(values):
            raise key_error(where, key, f"values must be distinct, got {values!r}")
    return axes


def grid_size(grids: list[dict[str, list[Any]]]) -> int:
    """Number of cases of a grid: the sum over its ``[[grid]]`` tables of the product of
    their axes' lengths (one case for a study without a grid), without expanding it."""
    return sum(math.prod(len(values) for values in sub.values()) for sub in grids)


def check_size(
    size: int, key: str, where: str, max_cases: int, announce: Callable[[int], None] | None
) -> None:
    """ValueError naming ``key`` when ``size`` cases are more than ``max_cases``; else
    ``announce(size)`` (when given)."""
    if size > max_cases:
        raise key_error(
            where,
            key,
            f"{size} cases, more than the limit of {max_cases} (every case is built and "
            "checked before any runs); split the study, or raise the limit with "
            "--max-cases N (Python: max_cases=N)",
        )
    if announce is not None:
        announce(size)


def grid_design(
    doc: dict[str, Any], where: str, max_cases: int, announce: Callable[[int], None] | None
) -> Design:
    """The cases of the grid: the cartesian product of each [[grid]] table's axes, the union
    over the tables; its size checked before it is expanded."""
    grid = doc.get("grid")
    grids = [grid_axes(g, doc, where) for g in (grid if isinstance(grid, list) else [grid])]
    check_size(grid_size(grids), "grid", where, max_cases, announce)
    axes: dict[str, list[Any]] = {}
    for sub in grids:  # [[grid]]: the union of several grids' cartesian products
        for path, values in sub.items():
            axes.setdefault(path, [])
            axes[path] += [v for v in values if v not in axes[path]]
    combos = [dict(zip(sub, combo)) for sub in grids for combo in itertools.product(*sub.values())]
    return Design(axes=axes, labels=axis_labels(list(axes)), combos=combos)


def sample_design(
    doc: dict[str, Any], where: str, max_cases: int, announce: Callable[[int], None] | None
) -> Design:
    """The cases of the [sample] table (``rodval.study.sampling``): one case per sample, id
    ``sample=0001`` ..., the sampled values as its parameters (columns of cases.csv and
    every table)."""
    if "grid" in doc:
        raise key_error(where, "sample", "a study has a [grid] or a [sample], not both")
    count = doc["sample"].get("count") if isinstance(doc["sample"], dict) else None
    if isinstance(count, int) and not isinstance(count, bool):
        check_size(count, "sample.count", where, max_cases, announce)
    columns = sample_columns(doc["sample"], where)
    for path in columns:
        check_axis_path(path, f"sample.keys.{path}", doc, where)
    width = len(str(count))
    samples = range(len(next(iter(columns.values()))))
    return Design(
        axes=columns,
        labels=axis_labels(list(columns)),
        combos=[{p: v[i] for p, v in columns.items()} for i in samples],
        ids=[f"sample={i + 1:0{width}d}" for i in samples],
    )


def sample_meta(table: Any) -> dict[str, Any] | None:
    """The [sample] table (already checked by ``sample_columns``) for study.json."""
    if table is None:
        return None
    return {
        "design": table.get("design", "sobol"),
        "count": table["count"],
        "seed": table["seed"],
        "keys": {p: dict(v) for p, v in flatten(table["keys"], leaf="dist").items()},
    }
