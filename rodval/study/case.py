"""A case of a study: the study document with one combination of grid or sample values set,
its scene, models and [modes] built and checked (``build_case``), what a worker needs to run
it (``Case.payload``) and the fingerprint that decides whether a saved record is reused."""

from __future__ import annotations

import copy
import hashlib
import json
import math
from dataclasses import dataclass
from typing import Any

from rodval.core.checks import check_keys
from rodval.core.scene import Scene
from rodval.core.scene_file import scene_from_dict
from rodval.core.scene_keys import set_path
from rodval.models.presets.registry import check_scene, get_model
from rodval.study.document import key_error
from rodval.study.model_specs import ModelSpec, model_specs

MODES_KEYS = {"count", "about", "load_at", "allow_unbalanced"}
#: Most modes a study may ask for per model.
MAX_MODES = 200


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


def modes_spec(table: Any, where: str) -> dict[str, Any] | None:
    """The study's [modes] table: the first ``count`` modes (1..MAX_MODES, default 10) of
    every model about ``about`` ("initial" or "equilibrium"), with ``load_at`` (s) and
    ``allow_unbalanced`` as in ``rodval.modes``; None without the table."""
    if table is None:
        return None
    check_keys(table, MODES_KEYS, f"{where}:", path="modes")
    count = table.get("count", 10)
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_MODES:
        raise key_error(
            where, "modes.count", f"must be an integer in 1..{MAX_MODES}, got {count!r}"
        )
    about = table.get("about", "initial")
    if about not in ("initial", "equilibrium"):
        raise key_error(where, "modes.about", f"must be 'initial' or 'equilibrium', got {about!r}")
    load_at = table.get("load_at")
    if load_at is not None and (
        isinstance(load_at, bool)
        or not isinstance(load_at, (int, float))
        or not 0 <= load_at < math.inf
    ):
        raise key_error(where, "modes.load_at", f"must be a finite time >= 0 s, got {load_at!r}")
    unbalanced = table.get("allow_unbalanced", False)
    if not isinstance(unbalanced, bool):
        raise key_error(
            where, "modes.allow_unbalanced", f"must be true or false, got {unbalanced!r}"
        )
    return {"count": count, "about": about, "load_at": load_at, "allow_unbalanced": unbalanced}


def build_case(
    doc: dict[str, Any], combo: dict[str, Any], labels: dict[str, str], where: str, cid: str
) -> Case:
    """The case ``cid`` of the study document ``doc`` (file ``where``, its reference already
    set) with the grid or sample values ``combo`` (path -> value) set, its scene, models and
    modes built and checked; ``labels``: each path's short label (the case's parameters)."""
    case_doc = copy.deepcopy(doc)
    for path, value in combo.items():
        try:
            set_path(case_doc, path, value)
        except ValueError as exc:
            raise ValueError(f"{where} (case {cid}): {exc}") from None
    case_where = where if not combo else f"{where} (case {cid})"
    scene_dict = case_doc.get("scene", {})
    scene_dict.setdefault("name", cid)
    scene = scene_from_dict(scene_dict, where=f"{case_where} [scene]")
    models = model_specs(case_doc, case_where)
    check_refusals(scene, models, where, cid)
    return Case(
        id=cid,
        params={labels[p]: v for p, v in combo.items()},
        scene_dict=scene_dict,
        scene=scene,
        models=models,
        reference=case_doc["study"]["reference"],
        where=case_where,
        modes=modes_spec(case_doc.get("modes"), where),
    )


def check_refusals(scene: Scene, models: tuple[ModelSpec, ...], where: str, cid: str) -> None:
    """Each model of a case against what it refuses for the case's scene before any work
    (``rodval.models.presets.registry.check_scene``, the check ``simulate`` makes): a
    ValueError naming the study file ``where``, the case ``cid``, the model and the reason,
    when the study is read, so no case runs a model that would refuse it. A model that cannot
    be imported here (exudyn not installed) is not an error of the file: its runs fail and
    say why."""
    for spec in models:
        try:
            model = get_model(spec.model, **spec.options)
        except ValueError as exc:
            if isinstance(exc.__cause__, ImportError):
                continue
            raise
        try:
            check_scene(model, scene, spec.settings)
        except ValueError as exc:
            raise ValueError(
                f"{where}: case {cid!r}: model {spec.label!r} ({spec.model}) refuses it "
                f"before any work: {exc}"
            ) from None
