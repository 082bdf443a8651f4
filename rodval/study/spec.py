"""Study files (TOML): a base scene, the models to compare, a grid of overrides, the report.

A study file has the tables ``[study]``, ``[scene]``, ``[integrator]``, ``[models.LABEL]``,
``[grid]`` and ``[report]`` (documented with an example in ``studies/README.md``). The
rule for the grid is one: *each grid key is the dotted path of a key of this file, and each
case is the file with those keys replaced* (e.g. ``scene.n``, ``scene.t_end``,
``scene.chain.EI``, ``integrator.rtol``, ``models.full.method``, ``models.exudyn.elements``).
The cartesian product of the axes gives the cases; several ``[[grid]]`` tables give the union
of their products (for maps whose parts vary different things). A case id is built from the
axis values (``n=8,t_end=2``), so it stays the same when other axes or values are added.

Every error is a ValueError naming the file and the key, raised before any work.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
import re
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rodval.core.checks import as_path, check_keys
from rodval.core.resources import (
    STATE_PER_ROD,
    check_run_memory,
    check_study_memory,
    dense_path,
    output_values,
)
from rodval.core.scene import QUANTITIES, Scene, trajectory_quantities
from rodval.core.scene_file import anchor_load_files, scene_from_dict, scene_to_dict
from rodval.core.settings import SETTING_NAMES, IntegratorSettings
from rodval.models import REGISTRY, get_model
from rodval.models.registry import uses_integrator
from rodval.study.acceptance import acceptance_spec
from rodval.study.sampling import flatten_keys as _flatten_sample_keys
from rodval.study.sampling import sample_columns
from rodval.study.store import MAX_NAME, case_file_name
from rodval.study.toml_text import toml_text

TOP_KEYS = {
    "study",
    "scene",
    "integrator",
    "models",
    "grid",
    "sample",
    "report",
    "modes",
    "acceptance",
}
MODES_KEYS = {"count", "about", "load_at", "allow_unbalanced"}
#: Most cases a study grid may have by default: every case is built and checked before any
#: runs (about 1-3 ms each on the 2-core machine, so ~1 min at the limit); raise it with
#: ``max_cases`` (CLI ``--max-cases N``).
MAX_CASES = 20_000
#: Most modes a study may ask for per model.
MAX_MODES = 200
STUDY_KEYS = {"name", "description", "reference"}
INTEGRATOR_KEYS = set(SETTING_NAMES)
REPORT_KEYS = {"cases", "rods", "quantities", "times"}
GRID_ROOTS = ("scene", "integrator", "models")


@dataclass(frozen=True)
class ModelSpec:
    """One model of a study: its label (column in the tables), registry name, options
    (passed to ``get_model``) and integrator settings."""

    label: str
    model: str
    options: dict[str, Any]
    settings: IntegratorSettings

    def as_dict(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "model": self.model,
            "options": self.options,
            "settings": self.settings.as_dict(),
        }


@dataclass(frozen=True)
class Case:
    """One scene (the base scene after the grid's overrides) run by every model of the study."""

    id: str
    params: dict[str, Any]  # axis label -> value
    scene_dict: dict[str, Any]  # the [scene] table of this case (scene_file format)
    scene: Scene
    models: tuple[ModelSpec, ...]
    reference: str
    where: str
    #: ``{"count": k, "about": "initial" | "equilibrium"}`` when the study asks for modes.
    modes: dict[str, Any] | None = None

    @property
    def fingerprint(self) -> str:
        """Hash of everything that determines the case's results (scene, models, reference,
        modes asked for)."""
        text = json.dumps(
            {
                "scene": self.scene_dict,
                "reference": self.reference,
                "models": [m.as_dict() for m in self.models],
                **({"modes": self.modes} if self.modes else {}),
            },
            sort_keys=True,
            default=repr,
        )
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def payload(self) -> dict[str, Any]:
        """What a worker needs to run the case (plain JSON)."""
        return {
            "case": self.id,
            "where": self.where,
            "scene": self.scene_dict,
            "models": [m.as_dict() for m in self.models],
            "modes": self.modes,
        }


def _modes_spec(table: Any, where: str) -> dict[str, Any] | None:
    """The study's [modes] table: the first ``count`` modes (1..MAX_MODES, default 10) of
    every model about ``about`` ("initial" or "equilibrium"), with ``load_at`` (s) and
    ``allow_unbalanced`` as in ``rodval.modes``; None without the table."""
    if table is None:
        return None
    check_keys(table, MODES_KEYS, f"{where}:", path="modes")
    count = table.get("count", 10)
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_MODES:
        raise _err(where, "modes.count", f"must be an integer in 1..{MAX_MODES}, got {count!r}")
    about = table.get("about", "initial")
    if about not in ("initial", "equilibrium"):
        raise _err(where, "modes.about", f"must be 'initial' or 'equilibrium', got {about!r}")
    load_at = table.get("load_at")
    if load_at is not None and (
        isinstance(load_at, bool)
        or not isinstance(load_at, (int, float))
        or not 0 <= load_at < math.inf
    ):
        raise _err(where, "modes.load_at", f"must be a finite time >= 0 s, got {load_at!r}")
    unbalanced = table.get("allow_unbalanced", False)
    if not isinstance(unbalanced, bool):
        raise _err(where, "modes.allow_unbalanced", f"must be true or false, got {unbalanced!r}")
    return {"count": count, "about": about, "load_at": load_at, "allow_unbalanced": unbalanced}


#: The quantities the report draws when [report] does not say (those the cases output).
DEFAULT_REPORT_QUANTITIES = ("phi", "dphi", "alpha", "beta")


@dataclass(frozen=True)
class ReportSpec:
    """What the report draws. ``rods``: rod numbers >= 1 or "last"; ``times``: configuration
    times (s), None for quarters of each case's horizon."""

    cases: tuple[str, ...]
    rods: tuple[int | str, ...] = (1, "last")
    quantities: tuple[str, ...] = DEFAULT_REPORT_QUANTITIES
    times: tuple[float, ...] | None = None

    def as_dict(self) -> dict[str, Any]:
        return {
            "cases": list(self.cases),
            "rods": list(self.rods),
            "quantities": list(self.quantities),
            "times": None if self.times is None else list(self.times),
        }


def _plain_document(doc: Any, where: str) -> dict[str, Any]:
    """A deep copy of a study document (never changing the caller's dict), with a
    ``rodval.Scene`` given as [scene] turned into its scene-file table (``scene_to_dict``)."""
    if not isinstance(doc, dict):
        raise ValueError(f"{where}: a study document must be a dict, got {type(doc).__name__}")
    doc = copy.deepcopy(doc)
    if isinstance(doc.get("scene"), Scene):
        doc["scene"] = scene_to_dict(doc["scene"])
    return doc


@dataclass(frozen=True)
class StudySpec:
    name: str
    description: str
    source: str  # file name used in messages
    text: str  # the TOML text, copied beside the results
    reference: str
    models: tuple[ModelSpec, ...]
    axes: dict[str, list[Any]]  # grid path -> values
    labels: dict[str, str]  # grid path -> short label used in case ids and tables
    cases: tuple[Case, ...]
    report: ReportSpec
    #: The [sample] table as drawn (design, count, seed, keys: path -> distribution), or
    #: None for a grid study.
    sample: dict[str, Any] | None = None
    #: The checked [acceptance] table (``rodval.study.acceptance``), or None.
    acceptance: dict[str, Any] | None = None

    @classmethod
    def from_dict(
        cls, doc: dict[str, Any], *, name: str = "study", max_cases: int = MAX_CASES
    ) -> StudySpec:
        """A study built in Python: ``doc`` has the study file's tables as dicts ([scene] may
        be a ``rodval.Scene``); ``name`` is its default name. It runs, resumes and reports
        like the same study read from TOML, and ``study.toml`` beside its results is ``doc``
        as TOML (``rodval.study.toml_text``), which ``load_study`` reads back."""
        plain = _plain_document(doc, name)
        plain.setdefault("study", {}).setdefault("name", name)
        return study_from_dict(plain, where=name, text=toml_text(plain), max_cases=max_cases)

    def case(self, case_id: str) -> Case:
        for c in self.cases:
            if c.id == case_id:
                return c
        raise KeyError(case_id)


def _err(where: str, key: str, msg: str) -> ValueError:
    return ValueError(f"{where}: key '{key}': {msg}")


def _flatten(d: dict, prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in d.items():
        path = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, dict):
            out.update(_flatten(v, path))
        else:
            out[path] = v
    return out


def _set_path(doc: dict, path: str, value: Any) -> None:
    """Set ``value`` at the dotted ``path`` of ``doc``, creating tables on the way; in a list
    a segment is an index or ``*`` (every element: every latch). ValueError when the path
    runs into a value that is neither a table nor a list."""
    _set_parts(doc, path.split("."), value, path)


def _set_parts(node: Any, parts: list[str], value: Any, path: str) -> None:
    head, rest = parts[0], parts[1:]
    if isinstance(node, list):
        if head == "*":
            index = range(len(node))
        elif head.isdigit() and int(head) < len(node):
            index = range(int(head), int(head) + 1)
        else:
            raise ValueError(f"{path}: {head!r} is not '*' or an index of a list of {len(node)}")
        for i in index:
            if rest:
                _set_parts(node[i], rest, value, path)
            else:
                node[i] = value
        return
    if not isinstance(node, dict):
        raise ValueError(f"{path}: {head!r} goes into {node!r:.40}, which is not a table or list")
    if not rest:
        node[head] = value
        return
    if node.get(head) is None:
        node[head] = {}
    _set_parts(node[head], rest, value, path)


#: Longest text of one grid value in a case id; a longer one (a list of per-rod values, a load
#: table) is written as a label and a short hash of the value (its full value is in cases.csv).
MAX_VALUE_TEXT = 24


def case_value_text(v: Any) -> str:
    """Compact text of a grid value for case ids and table columns: 8, 1e-06, inf,
    pulse(node=last,Xbar=-1500); a text longer than ``MAX_VALUE_TEXT`` becomes a label and 8
    hex digits of the value's SHA-256 (``list8-3fa2c1d0``, ``profile-...``, ``pulse-...``):
    short, stable, and different for different values."""
    text = _value_text(v)
    if len(text) <= MAX_VALUE_TEXT:
        return text
    digest = hashlib.sha256(json.dumps(v, sort_keys=True, default=repr).encode()).hexdigest()
    types = [x.get("type") for x in v if isinstance(x, dict)] if isinstance(v, list) else []
    if types and all(isinstance(t, str) for t in types) and len(types) == len(v):
        kind = re.sub(r"[^A-Za-z0-9+]", "", "+".join(types))[:12]
    elif isinstance(v, list):
        kind = f"list{len(v)}"
    elif isinstance(v, dict):
        kind = re.sub(r"[^A-Za-z0-9]", "", str(v.get("type", "profile")))[:12] or "table"
    else:
        kind = text[:12]
    return f"{kind}-{digest[:8]}"


def _value_text(v: Any) -> str:
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, float):
        return "inf" if math.isinf(v) else f"{v:.12g}"
    if isinstance(v, dict):
        kind = v.get("type", "")
        return (
            f"{kind}("
            + ",".join(f"{k}={_value_text(x)}" for k, x in v.items() if k != "type")
            + ")"
        )
    if isinstance(v, list):
        return "+".join(_value_text(x) for x in v)
    return re.sub(r"[^A-Za-z0-9._+-]", "-", str(v))


def _axis_labels(paths: list[str]) -> dict[str, str]:
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


def _model_specs(doc: dict, where: str) -> tuple[ModelSpec, ...]:
    integ = doc.get("integrator", {})
    check_keys(integ, INTEGRATOR_KEYS, f"{where}:", path="integrator")
    models = doc.get("models")
    if not isinstance(models, dict) or not models:
        raise _err(
            where,
            "models",
            f"at least one [models.LABEL] table is required (model names: {', '.join(REGISTRY)})",
        )
    specs = []
    for label, table in models.items():
        key = f"models.{label}"
        if not isinstance(table, dict):
            raise _err(where, key, "must be a table")
        name = table.get("model", label)
        if not isinstance(name, str) or name not in REGISTRY:
            raise _err(
                where,
                f"{key}.model" if "model" in table else key,
                f"model must be one of {', '.join(REGISTRY)}, got {name!r}",
            )
        own = {k: v for k, v in table.items() if k in INTEGRATOR_KEYS}
        if not _uses_rodval_integrator(name):
            if own:
                raise _err(
                    where,
                    f"{key}.{sorted(own)[0]}",
                    f"model {name!r} integrates with its own options, not rodval's "
                    "integrator settings (see its options, e.g. step, solver)",
                )
            settings_kw = {}  # [integrator] applies to the models rodval integrates
        else:
            settings_kw = {**integ, **own}
        try:
            settings = IntegratorSettings(**settings_kw)
        except (TypeError, ValueError) as exc:
            bad = next((k for k in INTEGRATOR_KEYS if k in str(exc)), "method")
            src = f"{key}.{bad}" if bad in table else f"integrator.{bad}"
            raise _err(where, src, str(exc)) from None
        options = {k: v for k, v in table.items() if k not in INTEGRATOR_KEYS | {"model"}}
        _check_model_options(name, options, where, key)
        specs.append(ModelSpec(label=str(label), model=name, options=options, settings=settings))
    return tuple(specs)


def _uses_rodval_integrator(name: str) -> bool:
    """Whether model ``name`` is integrated by rodval's driver (its IntegratorSettings apply);
    a model that cannot be imported here is taken to be (its runs fail and say why)."""
    try:
        return uses_integrator(name)
    except ValueError:
        return True


def _check_model_options(name: str, options: dict, where: str, key: str) -> None:
    """Reject bad options of an importable model now; a model that cannot be imported here
    (e.g. exudyn not installed) is not an error of the file: its runs fail and say why."""
    try:
        get_model(name, **options)
    except ValueError as exc:
        if isinstance(exc.__cause__, ImportError):
            return
        raise _err(where, key, str(exc)) from None
    except TypeError as exc:
        raise _err(where, key, f"bad model option: {exc}") from None


def _report_spec(table: Any, cases: tuple[Case, ...], where: str) -> ReportSpec:
    """The [report] table, checked against the cases it draws (``report.cases``, by default
    the study's most demanding case, most rods x longest horizon, then its first): every rod
    number within every report case's chain, every quantity among every report case's outputs,
    every time within every report case's horizon (s)."""
    table = {} if table is None else table
    check_keys(table, REPORT_KEYS, f"{where}:", path="report")
    by_id = {c.id: c for c in cases}
    demanding = max(cases, key=lambda c: c.scene.n * c.scene.t_end).id
    ids = table.get("cases", list(dict.fromkeys([demanding, cases[0].id])))
    if not isinstance(ids, list) or any(c not in by_id for c in ids):
        raise _err(
            where, "report.cases", f"must be a list of case ids from {list(by_id)}, got {ids!r}"
        )
    drawn = [by_id[c] for c in ids]
    rods = table.get("rods", [1, "last"])
    if (
        not isinstance(rods, list)
        or not rods
        or any(
            not (r == "last" or (isinstance(r, int) and not isinstance(r, bool) and r >= 1))
            for r in rods
        )
    ):
        raise _err(
            where, "report.rods", f'must be a list of rod numbers >= 1 or "last", got {rods!r}'
        )
    shortest = min(drawn, key=lambda c: c.scene.n)
    beyond = [r for r in rods if r != "last" and r > shortest.scene.n]
    if beyond:
        raise _err(
            where,
            "report.rods",
            f"rod {beyond[0]} is beyond the chain of report case {shortest.id!r} "
            f'(n = {shortest.scene.n}); allowed: 1..{shortest.scene.n} or "last"',
        )
    outputs = [
        q for q in QUANTITIES if all(q in trajectory_quantities(c.scene.outputs) for c in drawn)
    ]
    quantities = table.get(
        "quantities", [q for q in DEFAULT_REPORT_QUANTITIES if q in outputs] or outputs
    )
    if (
        not isinstance(quantities, list)
        or not quantities
        or any(q not in outputs for q in quantities)
    ):
        raise _err(
            where,
            "report.quantities",
            f"must be a list of quantities every report case outputs ({', '.join(outputs)}), "
            f"got {quantities!r}",
        )
    times = table.get("times")
    horizon = min(c.scene.t_end for c in drawn)
    if times is not None and (
        not isinstance(times, list)
        or not times
        or any(
            isinstance(t, bool)
            or not isinstance(t, (int, float))
            or not math.isfinite(t)
            or not 0 <= t <= horizon
            for t in times
        )
    ):
        raise _err(
            where,
            "report.times",
            f"must be a list of times in 0..{horizon:g} s (the shortest horizon of the report "
            f"cases), got {times!r}",
        )
    return ReportSpec(
        cases=tuple(ids),
        rods=tuple(rods),
        quantities=tuple(quantities),
        times=None if times is None else tuple(float(t) for t in times),
    )


def _grid_axes(grid: Any, doc: dict, where: str) -> dict[str, list[Any]]:
    if grid is None:
        return {}
    if not isinstance(grid, dict):
        raise _err(
            where,
            "grid",
            "must be a table of dotted keys -> lists of values, "
            "or an array of such tables ([[grid]])",
        )
    axes = _flatten(grid)
    for path, values in axes.items():
        key = f"grid.{path}"
        _check_axis_path(path, key, doc, where)
        if not isinstance(values, list) or not values:
            raise _err(where, key, f"must be a non-empty list of values, got {values!r}")
        if len({json.dumps(v, sort_keys=True) for v in values}) != len(values):
            raise _err(where, key, f"values must be distinct, got {values!r}")
    return axes


def _check_axis_path(path: str, key: str, doc: dict, where: str) -> None:
    """A grid or sample key is a path into the scene, the integrator or a model's table."""
    root, *rest = path.split(".")
    if root not in GRID_ROOTS or not rest:
        raise _err(
            where,
            key,
            f"must be a path into {', '.join(GRID_ROOTS)} "
            "(e.g. scene.n, scene.chain.EI, integrator.rtol, models.full.method)",
        )
    if root == "integrator" and (len(rest) != 1 or rest[0] not in INTEGRATOR_KEYS):
        raise _err(where, key, f"integrator keys are {', '.join(sorted(INTEGRATOR_KEYS))}")
    if root == "models" and (len(rest) != 2 or rest[0] not in doc.get("models", {})):
        raise _err(
            where,
            key,
            f"must be models.LABEL.KEY with LABEL one of {', '.join(doc.get('models', {}))}",
        )


def _build_case(
    doc: dict, combo: dict[str, Any], labels: dict[str, str], where: str, cid: str | None = None
) -> Case:
    """The case of ``doc`` with the grid or sample values ``combo`` (path -> value) set; its id
    ``cid`` (default: the values' short texts)."""
    case_doc = copy.deepcopy(doc)
    cid = cid or ",".join(f"{labels[p]}={case_value_text(v)}" for p, v in combo.items()) or "base"
    for path, value in combo.items():
        try:
            _set_path(case_doc, path, value)
        except ValueError as exc:
            raise ValueError(f"{where} (case {cid}): {exc}") from None
    case_where = where if not combo else f"{where} (case {cid})"
    scene_dict = case_doc.get("scene", {})
    scene_dict.setdefault("name", cid)
    scene = scene_from_dict(scene_dict, where=f"{case_where} [scene]")
    models = _model_specs(case_doc, case_where)
    return Case(
        id=cid,
        params={labels[p]: v for p, v in combo.items()},
        scene_dict=scene_dict,
        scene=scene,
        models=models,
        reference=case_doc["study"]["reference"],
        where=case_where,
        modes=_modes_spec(case_doc.get("modes"), where),
    )


def grid_size(grids: list[dict[str, list[Any]]]) -> int:
    """Number of cases of a grid: the sum over its ``[[grid]]`` tables of the product of
    their axes' lengths (one case for a study without a grid), without expanding it."""
    return sum(math.prod(len(values) for values in sub.values()) for sub in grids)


def _check_max_cases(max_cases: Any) -> int:
    if isinstance(max_cases, bool) or not isinstance(max_cases, int) or max_cases < 1:
        raise ValueError(f"max_cases must be an integer >= 1, got {max_cases!r}")
    return max_cases


def _grid_cases(
    doc: dict, where: str, max_cases: int, announce: Callable[[int], None] | None
) -> tuple[dict[str, list[Any]], dict[str, str], tuple[Case, ...]]:
    """(axes, labels, cases) of the grid: the cartesian product of each [[grid]] table's
    axes, the union over the tables; its size checked before it is expanded."""
    grid = doc.get("grid")
    grids = [_grid_axes(g, doc, where) for g in (grid if isinstance(grid, list) else [grid])]
    size = grid_size(grids)
    _check_size(size, "grid", where, max_cases, announce)
    axes: dict[str, list[Any]] = {}
    for sub in grids:  # [[grid]]: the union of several grids' cartesian products
        for path, values in sub.items():
            axes.setdefault(path, [])
            axes[path] += [v for v in values if v not in axes[path]]
    labels = _axis_labels(list(axes))
    cases = tuple(
        _build_case(doc, dict(zip(sub, combo)), labels, where)
        for sub in grids
        for combo in itertools.product(*sub.values())
    )
    return axes, labels, cases


def _sample_cases(
    doc: dict, where: str, max_cases: int, announce: Callable[[int], None] | None
) -> tuple[dict[str, list[Any]], dict[str, str], tuple[Case, ...]]:
    """(axes, labels, cases) of the [sample] table (``rodval.study.sampling``): one case per
    sample, id ``sample=0001`` ..., the sampled values as its parameters (columns of
    cases.csv and every table)."""
    if "grid" in doc:
        raise _err(where, "sample", "a study has a [grid] or a [sample], not both")
    count = doc["sample"].get("count") if isinstance(doc["sample"], dict) else None
    if isinstance(count, int) and not isinstance(count, bool):
        _check_size(count, "sample.count", where, max_cases, announce)
    columns = sample_columns(doc["sample"], where)
    for path in columns:
        _check_axis_path(path, f"sample.keys.{path}", doc, where)
    labels = _axis_labels(list(columns))
    width = len(str(count))
    cases = tuple(
        _build_case(
            doc, {p: v[i] for p, v in columns.items()}, labels, where, f"sample={i + 1:0{width}d}"
        )
        for i in range(len(next(iter(columns.values()))))
    )
    return columns, labels, cases


def _sample_meta(table: Any) -> dict[str, Any] | None:
    """The [sample] table (already checked by ``sample_columns``) for study.json."""
    if table is None:
        return None
    return {
        "design": table.get("design", "sobol"),
        "count": table["count"],
        "seed": table["seed"],
        "keys": {p: dict(v) for p, v in _flatten_sample_keys(table["keys"]).items()},
    }


def _check_size(
    size: int, key: str, where: str, max_cases: int, announce: Callable[[int], None] | None
) -> None:
    if size > max_cases:
        raise _err(
            where,
            key,
            f"{size} cases, more than the limit of {max_cases} (every case is built and "
            "checked before any runs); split the study, or raise the limit with "
            "--max-cases N (Python: max_cases=N)",
        )
    if announce is not None:
        announce(size)


def study_from_dict(
    doc: dict,
    where: str = "study",
    text: str = "",
    *,
    max_cases: int = MAX_CASES,
    announce: Callable[[int], None] | None = None,
) -> StudySpec:
    """Parse and validate a study document (the TOML as a dict); see the module docstring.

    max_cases: most cases the grid may have (``MAX_CASES`` by default); its size is computed
    before it is expanded, and a larger grid is refused at once.
    announce: called with the number of cases once it is known, before the cases are built
    and checked (which takes about 1-3 ms per case).
    """
    doc = _plain_document(doc, where)
    max_cases = _check_max_cases(max_cases)
    check_keys(doc, TOP_KEYS, f"{where}:", path="")
    study = doc.setdefault("study", {})
    check_keys(study, STUDY_KEYS, f"{where}:", path="study")
    models = _model_specs(doc, where)
    labels_m = [m.label for m in models]
    reference = study.get("reference", labels_m[0])
    if reference not in labels_m:
        raise _err(
            where,
            "study.reference",
            f"must be one of the model labels {labels_m}, got {reference!r}",
        )
    study["reference"] = reference
    if "scene" in doc and not isinstance(doc["scene"], dict):
        raise _err(where, "scene", "must be a table")
    if "sample" in doc:
        axes, labels, cases = _sample_cases(doc, where, max_cases, announce)
    else:
        axes, labels, cases = _grid_cases(doc, where, max_cases, announce)
    ids = [c.id for c in cases]
    if len(set(ids)) != len(ids):
        raise _err(
            where,
            "grid",
            "two cases format to the same id; use values that differ "
            "in their first 12 significant digits",
        )
    _check_file_names(ids, where)
    _check_resources(cases, where)
    report = _report_spec(doc.get("report"), cases, where)
    return StudySpec(
        name=str(study.get("name", Path(where).stem)),
        description=str(study.get("description", "")),
        source=where,
        text=text,
        reference=reference,
        models=models,
        axes=axes,
        labels=labels,
        cases=cases,
        report=report,
        sample=_sample_meta(doc.get("sample")),
        acceptance=acceptance_spec(
            doc.get("acceptance"),
            [m.label for m in models],
            reference,
            {q for c in cases for q in trajectory_quantities(c.scene.outputs)},
            where,
        ),
    )


def _check_file_names(ids: list[str], where: str) -> None:
    """Every case's record file name is distinct and bounded (before any case runs)."""
    names: dict[str, str] = {}
    for cid in ids:
        name = case_file_name(cid)
        if len(name) > MAX_NAME:  # pragma: no cover - case_file_name bounds it
            raise _err(where, "grid", f"case {cid!r}: file name longer than {MAX_NAME}")
        if name in names:
            raise _err(
                where,
                "grid",
                f"cases {names[name]!r} and {cid!r} would share the record file {name!r}",
            )
        names[name] = cid


def _check_resources(cases: tuple[Case, ...], where: str) -> None:
    """The memory of every case's runs (model by model: the full model's state is 6 n, an
    implicit method or the numpy kernel builds dense matrices) and of the study's tables,
    refused above the limit (``rodval.core.resources``) before any case runs."""
    values = 0
    for case in cases:
        scene = case.scene
        quantities = trajectory_quantities(scene.outputs)
        for m in case.models:
            dense = m.model in STATE_PER_ROD and dense_path(m.model, m.options, m.settings.method)
            try:
                check_run_memory(
                    scene.n,
                    scene.times.size,
                    quantities,
                    model=m.model,
                    dense=dense,
                    what=f"case {case.id!r}, model {m.label!r} (n = {scene.n})",
                )
            except ValueError as exc:
                raise ValueError(f"{case.where}: {exc}") from None
            values += output_values(scene.n, scene.times.size, quantities)
    try:
        check_study_memory(values, len(cases))
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def load_study(
    path: str | Path,
    *,
    max_cases: int = MAX_CASES,
    announce: Callable[[int], None] | None = None,
) -> StudySpec:
    """Read and validate a study file (``path``: str or Path; ``max_cases``, ``announce``: see
    study_from_dict)."""
    path = as_path("path", path)
    max_cases = _check_max_cases(max_cases)
    if not path.is_file():
        raise ValueError(f"study file {str(path)!r} does not exist")
    try:
        text = path.read_text()
        doc = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: malformed TOML: {exc}") from None
    if isinstance(doc.get("scene"), dict):
        doc["scene"] = anchor_load_files(doc["scene"], path.parent)
    return study_from_dict(doc, where=str(path), text=text, max_cases=max_cases, announce=announce)
