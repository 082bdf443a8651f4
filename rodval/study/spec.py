"""Study files (TOML): a base scene, the models to compare, a grid of overrides, the report.

A study file has the tables ``[study]``, ``[scene]``, ``[integrator]``, ``[models.LABEL]``,
``[grid]`` and ``[report]`` (documented with an example in ``studies/README.md``). The
rule for the grid is one: *each grid key is the dotted path of a key of this file, and each
case is the file with those keys replaced* (e.g. ``scene.n``, ``scene.t_end``,
``scene.chain.EI``, ``integrator.rtol``, ``models.full.method``, ``models.exudyn.elements``).
The cartesian product of the axes gives the cases; several ``[[grid]]`` tables give the union
of their products (for maps whose parts vary different things). A case id is built from the
axis values (``n=8,t_end=2``), so it stays the same when other axes or values are added.

This module reads the file and assembles the study; its parts are checked by
``rodval.study.model_specs`` ([integrator], [models]), ``rodval.study.grid`` ([grid],
[sample]), ``rodval.study.case`` (each case, [modes], [agreement]), ``rodval.study.report_spec``
([report]) and ``rodval.study.acceptance`` ([acceptance]); a [scene] that names a scene file
(``file = "wing.toml"`` and overrides) is resolved by ``rodval.study.scene_source``.

Every error is a ValueError naming the file and the key, raised before any work.
"""

from __future__ import annotations

import copy
import hashlib
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
from rodval.core.scene import trajectory_quantities
from rodval.core.scene_file import anchor_load_files
from rodval.core.scene_keys import scene_path, set_path
from rodval.core.settings import SETTING_NAMES
from rodval.study.acceptance import acceptance_spec
from rodval.study.case import Case, agreement_spec, build_case
from rodval.study.document import key_error, plain_document
from rodval.study.grid import Design, grid_design, sample_design, sample_meta
from rodval.study.model_specs import ModelSpec, model_specs
from rodval.study.report_spec import ReportSpec, report_spec
from rodval.study.scene_source import resolve_scene, resolved_text
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
    "agreement",
}
#: Most cases a study grid may have by default: every case is built and checked before any
#: runs (about 1-3 ms each on the 2-core machine, so ~1 min at the limit); raise it with
#: ``max_cases`` (CLI ``--max-cases N``).
MAX_CASES = 20_000
STUDY_KEYS = {"name", "description", "reference"}


@dataclass(frozen=True)
class StudySpec:
    """A study read and checked: its models, grid axes (path -> values) and their labels,
    every case built, what the report draws, and the file's text (copied beside the results)."""

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
    #: The scene file [scene] names (``rodval.study.scene_source``): its path, SHA-256 and
    #: the [scene] table it resolved to; None for a scene written in the study.
    scene_file: dict[str, Any] | None = None
    #: The checked [agreement] table with its defaults (``rodval.study.case.agreement_spec``:
    #: the tolerances of the report's answer and the reference's twin run).
    agreement: dict[str, Any] | None = None

    @classmethod
    def from_dict(
        cls, doc: dict[str, Any], *, name: str = "study", max_cases: int = MAX_CASES
    ) -> StudySpec:
        """A study built in Python: ``doc`` has the study file's tables as dicts ([scene] may
        be a ``rodval.Scene``); ``name`` is its default name. It runs, resumes and reports
        like the same study read from TOML, and ``study.toml`` beside its results is ``doc``
        as TOML (``rodval.study.toml_text``), which ``load_study`` reads back."""
        plain = plain_document(doc, name)
        plain.setdefault("study", {}).setdefault("name", name)
        return study_from_dict(plain, where=name, text=toml_text(plain), max_cases=max_cases)

    def case(self, case_id: str) -> Case:
        """The case called ``case_id`` (KeyError if the study has none)."""
        for c in self.cases:
            if c.id == case_id:
                return c
        raise KeyError(case_id)


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
    names = [t for t in types if isinstance(t, str)]
    if names and len(names) == len(v):
        kind = re.sub(r"[^A-Za-z0-9+]", "", "+".join(names))[:12]
    elif isinstance(v, list):
        kind = f"list{len(v)}"
    elif isinstance(v, dict):
        kind = re.sub(r"[^A-Za-z0-9]", "", str(v.get("type", "profile")))[:12] or "table"
    else:
        kind = text[:12]
    return f"{kind}-{digest[:8]}"


def _value_text(v: Any) -> str:
    """The full text of a grid value (``case_value_text`` before it is shortened)."""
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


def _check_max_cases(max_cases: Any) -> int:
    """``max_cases`` when it is an integer >= 1, else ValueError."""
    if isinstance(max_cases, bool) or not isinstance(max_cases, int) or max_cases < 1:
        raise ValueError(f"max_cases must be an integer >= 1, got {max_cases!r}")
    return max_cases


def study_from_dict(
    doc: dict[str, Any],
    where: str = "study",
    text: str = "",
    *,
    max_cases: int = MAX_CASES,
    announce: Callable[[int], None] | None = None,
    folder: str | Path | None = None,
) -> StudySpec:
    """Parse and validate a study document (the TOML as a dict); see the module docstring.

    max_cases: most cases the grid may have (``MAX_CASES`` by default); its size is computed
    before it is expanded, and a larger grid is refused at once.
    announce: called with the number of cases once it is known, before the cases are built
    and checked (which takes about 1-3 ms per case).
    folder: where a relative ``[scene] file`` is (the study file's folder; default: the
    current folder); the resolved [scene] replaces it (``rodval.study.scene_source``), and
    ``text`` becomes the resolved document's TOML.
    """
    doc = plain_document(doc, where)
    max_cases = _check_max_cases(max_cases)
    check_keys(doc, TOP_KEYS, f"{where}:", path="")
    study = doc.setdefault("study", {})
    check_keys(study, STUDY_KEYS, f"{where}:", path="study")
    models = model_specs(doc, where)
    reference = _reference(study, models, where)
    study["reference"] = reference
    scene_file, text = _resolve_scene(doc, Path(folder or "."), where, text)
    expand = sample_design if "sample" in doc else grid_design
    design = expand(doc, where, max_cases, announce)
    try:
        cases = _build_cases(doc, design, where)
    except ValueError as exc:  # a case's scene, from the file [scene] names: name the file
        if scene_file is None or scene_file["path"] in str(exc):
            raise
        raise ValueError(f"{exc} (its [scene]: file {scene_file['path']!r})") from None
    _check_file_names([c.id for c in cases], where)
    _check_resources(cases, where)
    return StudySpec(
        name=str(study.get("name", Path(where).stem)),
        description=str(study.get("description", "")),
        source=where,
        text=text,
        reference=reference,
        models=models,
        axes=design.axes,
        labels=design.labels,
        cases=cases,
        report=report_spec(doc.get("report"), cases, where),
        sample=sample_meta(doc.get("sample")),
        acceptance=acceptance_spec(
            doc.get("acceptance"),
            [m.label for m in models],
            reference,
            {q for c in cases for q in trajectory_quantities(c.scene.outputs)},
            where,
            scenes=[c.scene for c in cases],
        ),
        scene_file=scene_file,
        agreement=agreement_spec(doc.get("agreement"), where),
    )


def _resolve_scene(
    doc: dict[str, Any], folder: Path, where: str, text: str
) -> tuple[dict[str, Any] | None, str]:
    """Check that [scene] is a table and, when it names a scene file (relative to
    ``folder``), replace it in ``doc`` by the table it resolves to (``resolve_scene``).
    Returns the file's record for study.json (path, SHA-256, the resolved table; None
    without a file) and the study's text: ``text``, or the resolved document's TOML."""
    if "scene" not in doc:
        return None, text
    if not isinstance(doc["scene"], dict):
        raise key_error(where, "scene", "must be a table")
    doc["scene"], scene_file = resolve_scene(doc["scene"], folder, where, TOP_KEYS)
    if scene_file is None:
        return None, text
    named = {**doc, "study": {"name": Path(where).stem, **doc["study"]}}
    return {**scene_file.as_dict(), "scene": doc["scene"]}, resolved_text(named, where, scene_file)


def _reference(study: dict[str, Any], models: tuple[ModelSpec, ...], where: str) -> str:
    """``study.reference``: one of the model labels (default: the first model's)."""
    labels = [m.label for m in models]
    reference: str = study.get("reference", labels[0])
    if reference not in labels:
        raise key_error(
            where,
            "study.reference",
            f"must be one of the model labels {labels}, got {reference!r}",
        )
    return reference


def _build_cases(doc: dict[str, Any], design: Design, where: str) -> tuple[Case, ...]:
    """Every case of ``design``, built and checked; the id of a case the design does not name
    is made of its values' short texts (``case_value_text``: ``n=8,t_end=2``; "base" without
    a grid). ValueError when two cases get the same id."""
    ids = design.ids
    if ids is None:
        ids = [
            ",".join(f"{design.labels[p]}={case_value_text(v)}" for p, v in combo.items()) or "base"
            for combo in design.combos
        ]
    cases = tuple(
        build_case(doc, combo, design.labels, where, cid) for combo, cid in zip(design.combos, ids)
    )
    if len(set(ids)) != len(ids):
        raise key_error(
            where,
            "grid",
            "two cases format to the same id; use values that differ "
            "in their first 12 significant digits",
        )
    return cases


def _check_file_names(ids: list[str], where: str) -> None:
    """Every case's record file name is distinct and bounded (before any case runs)."""
    names: dict[str, str] = {}
    for cid in ids:
        name = case_file_name(cid)
        if len(name) > MAX_NAME:  # pragma: no cover - case_file_name bounds it
            raise key_error(where, "grid", f"case {cid!r}: file name longer than {MAX_NAME}")
        if name in names:
            raise key_error(
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


def study_path(key: str) -> str:
    """The dotted path of the study file that ``rodval study --set KEY=VALUE`` names: KEY
    itself when it starts with a table of the study file (``scene.chain.EI``,
    ``integrator.rtol``, ``models.full.shapes``: a grid key's form), or a scene key without
    its ``scene.`` (``chain.EI``, as ``rodval simulate --set`` takes it). A bare integrator
    setting or model option is refused (ValueError naming its paths: a study's [integrator]
    holds every model's settings, a [models.LABEL] one model's)."""
    if key.split(".")[0] in TOP_KEYS:
        return key
    path = scene_path(key)
    if path is not None:
        return f"scene.{path}"
    if key in SETTING_NAMES:
        raise ValueError(
            f"--set {key}: a study's integrator setting goes by its path: --set "
            f"integrator.{key}=... (every model) or --set models.LABEL.{key}=... (one model)"
        )
    raise ValueError(
        f"--set {key}: not a key of the study file; give its dotted path as a [grid] key does "
        f"(scene.chain.EI, integrator.rtol; a model option: models.LABEL.{key})"
    )


def with_set_values(doc: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """A copy of the study document ``doc`` with each value of ``overrides`` (``--set KEY`` ->
    value) set at its ``study_path`` (``set_path``, as a grid sets a case's), checked when
    the study is; a path given twice (``chain.EI`` and ``scene.chain.EI``) is refused."""
    out = copy.deepcopy(doc)
    given: dict[str, str] = {}
    for key, value in overrides.items():
        path = study_path(key)
        if path in given:
            raise ValueError(f"--set {path} given twice (as {given[path]} and {key}); give it once")
        given[path] = key
        try:
            set_path(out, path, value)
        except ValueError as exc:
            raise ValueError(f"--set {key}: {exc}") from None
    return out


def load_study(
    path: str | Path,
    *,
    max_cases: int = MAX_CASES,
    announce: Callable[[int], None] | None = None,
    overrides: dict[str, Any] | None = None,
) -> StudySpec:
    """Read and validate a study file (``path``: str or Path; ``max_cases``, ``announce``: see
    study_from_dict) with the values of ``overrides`` (``rodval study --set``: key -> value,
    ``with_set_values``) set; the study's text is then the file's with them set."""
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
    if overrides:
        doc = with_set_values(doc, overrides)
        text = f"# {path} with --set {', '.join(overrides)}\n{toml_text(doc)}"
    return study_from_dict(
        doc,
        where=str(path),
        text=text,
        max_cases=max_cases,
        announce=announce,
        folder=path.parent,
    )
