"""A case of a study: the study document with one combination of grid or sample values set,
its scene, models, [modes] and [agreement] built and checked (``build_case``), what a worker
needs to run it (``Case.payloads``: the case, and the reference's twin when [agreement.twin]
asks for one) and the fingerprint that decides whether a saved record is reused."""

from __future__ import annotations

import copy
import hashlib
import json
import math
from dataclasses import dataclass
from typing import Any

from rodval.analysis.agreement import DEFAULT_QUANTITIES, DEFAULT_TOL, twin_label
from rodval.analysis.events import COMPARABLE_DT_S
from rodval.core.checks import check_keys, check_number
from rodval.core.scene import Scene, trajectory_quantities
from rodval.core.scene_file import scene_from_dict, scene_to_dict
from rodval.core.scene_keys import set_path
from rodval.models.registry import check_scene, get_model
from rodval.study.document import key_error
from rodval.study.model_specs import ModelSpec, model_specs

MODES_KEYS = {"count", "about", "load_at", "allow_unbalanced"}
AGREEMENT_KEYS = {"tol", "quantities", "lock_dt", "reference_error", "twin"}
REFERENCE_ERROR_KEYS = {"rel", "lock_dt", "impulse_rel", "attitude"}
TWIN_KEYS = {"rod", "angle"}
#: Largest twin perturbation (rad): far below any tolerance of the agreement horizon.
MAX_TWIN_ANGLE = 1e-3
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
    #: The twin's perturbation ``{"rod": k, "angle": rad}`` ([agreement.twin]) or None.
    twin: dict[str, Any] | None = None
    #: label -> the options each model runs this scene with, its scene-dependent defaults
    #: resolved (``Model.for_scene``: the full model's kinematics = "auto"), in the
    #: fingerprint, so a record made under another default is not reused.
    ran_options: dict[str, dict[str, Any]] | None = None

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
                **({"twin": self.twin} if self.twin else {}),
                **({"ran_options": self.ran_options} if self.ran_options else {}),
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

    @property
    def labels(self) -> list[str]:
        """The labels of the case's runs: its models', then the reference's twin if any."""
        return [m.label for m in self.models] + ([twin_label(self.reference)] if self.twin else [])

    def payloads(self) -> list[dict[str, Any]]:
        """What workers run for the case: ``payload``, and the twin's (``twin_payload``)."""
        return [self.payload(), *([self.twin_payload()] if self.twin else [])]

    def twin_payload(self) -> dict[str, Any]:
        """The reference's twin run: the reference model, labelled ``twin_label``, on the
        case's scene with the initial chord angle of rod ``twin["rod"]`` moved by
        ``twin["angle"]`` rad (one extra run; ``"part": "twin"``)."""
        assert self.twin is not None
        scene = scene_to_dict(self.scene)
        phi = list(scene["initial"]["phi"])
        phi[int(self.twin["rod"]) - 1] += float(self.twin["angle"])
        scene["initial"] = {**scene["initial"], "phi": phi}
        ref = next(m for m in self.models if m.label == self.reference)
        return {
            "case": self.id,
            "part": "twin",
            "where": f"{self.where} (twin)",
            "scene": scene,
            "models": [{**ref.as_dict(), "label": twin_label(self.reference)}],
            "modes": None,
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
    ran_options = check_refusals(scene, models, where, cid)
    return Case(
        id=cid,
        params={labels[p]: v for p, v in combo.items()},
        scene_dict=scene_dict,
        scene=scene,
        models=models,
        reference=case_doc["study"]["reference"],
        where=case_where,
        modes=modes_spec(case_doc.get("modes"), where),
        twin=case_twin(
            case_doc.get("agreement"), scene, models, case_doc["study"]["reference"], case_where
        ),
        ran_options=ran_options,
    )


def check_refusals(
    scene: Scene, models: tuple[ModelSpec, ...], where: str, cid: str
) -> dict[str, dict[str, Any]]:
    """Each model of a case against what it refuses for the case's scene before any work
    (``rodval.models.registry.check_scene``, the check ``simulate`` makes): a
    ValueError naming the study file ``where``, the case ``cid``, the model and the reason,
    when the study is read, so no case runs a model that would refuse it. A model that cannot
    be imported here (exudyn not installed) is not an error of the file: its runs fail and
    say why. Returns label -> the options each model runs the scene with (its "auto"
    defaults resolved, ``Model.for_scene``)."""
    ran: dict[str, dict[str, Any]] = {}
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
        ran[spec.label] = model.for_scene(scene)[0].options()
    return ran


def _bound(where: str, key: str, value: Any, **limits: Any) -> float:
    """``check_number`` on a study key, the error naming the file and the key."""
    try:
        return check_number(key, value, **limits)
    except ValueError as exc:
        raise key_error(where, key, str(exc).removeprefix(f"{key} ")) from None


def agreement_spec(table: Any, where: str) -> dict[str, Any]:
    """The study's [agreement] table checked, with its defaults (``rodval.analysis.agreement``,
    docs/deployment.md): ``tol`` in (0, 1) (fraction of each watched quantity's scale,
    default DEFAULT_TOL), ``quantities`` (non-empty list of output quantities, default
    DEFAULT_QUANTITIES), ``lock_dt`` > 0 s (default COMPARABLE_DT_S), ``reference_error``
    (the reference's own error bars, each >= 0: ``rel``, ``lock_dt`` s, ``impulse_rel``,
    ``attitude`` rad: a free base's attitude) and
    ``twin`` ({rod, angle}: the reference's twin run; none by default)."""
    table = {} if table is None else table
    if not isinstance(table, dict):
        raise key_error(where, "agreement", "must be a table")
    check_keys(table, AGREEMENT_KEYS, f"{where}:", path="agreement")
    out: dict[str, Any] = {
        "tol": _bound(
            where,
            "agreement.tol",
            table.get("tol", DEFAULT_TOL),
            low=0,
            high=1,
            low_open=True,
            high_open=True,
        ),
        "quantities": _quantities(table.get("quantities", list(DEFAULT_QUANTITIES)), where),
        "lock_dt": _bound(
            where,
            "agreement.lock_dt",
            table.get("lock_dt", COMPARABLE_DT_S),
            unit="s",
            low=0,
            low_open=True,
            finite=True,
        ),
    }
    ref = table.get("reference_error", {})
    if not isinstance(ref, dict):
        raise key_error(where, "agreement.reference_error", "must be a table")
    check_keys(ref, REFERENCE_ERROR_KEYS, f"{where}:", path="agreement.reference_error")
    out["reference_error"] = {
        k: _bound(where, f"agreement.reference_error.{k}", v, low=0, finite=True)
        for k, v in ref.items()
    }
    if "twin" in table:
        out["twin"] = _twin(table["twin"], where)
    return out


def _quantities(value: Any, where: str) -> list[str]:
    """[agreement] quantities: a non-empty list of quantity names."""
    if not isinstance(value, list) or not value or not all(isinstance(q, str) for q in value):
        raise key_error(
            where,
            "agreement.quantities",
            f"must be a non-empty list of quantity names, got {value!r}",
        )
    return list(value)


def _twin(value: Any, where: str) -> dict[str, Any]:
    """[agreement.twin]: the rod (integer >= 1) whose initial chord angle moves, by ``angle``
    rad (0 < |angle| <= MAX_TWIN_ANGLE)."""
    if not isinstance(value, dict):
        raise key_error(where, "agreement.twin", "must be a table {rod = k, angle = rad}")
    check_keys(value, TWIN_KEYS, f"{where}:", path="agreement.twin")
    for key in TWIN_KEYS:
        if key not in value:
            raise key_error(where, f"agreement.twin.{key}", "is missing")
    rod = int(_bound(where, "agreement.twin.rod", value["rod"], low=1, integer=True))
    angle = _bound(
        where,
        "agreement.twin.angle",
        value["angle"],
        unit="rad",
        low=-MAX_TWIN_ANGLE,
        high=MAX_TWIN_ANGLE,
    )
    if angle == 0:
        raise key_error(
            where,
            "agreement.twin.angle",
            f"must be a nonzero angle within +-{MAX_TWIN_ANGLE:g} rad, got 0",
        )
    return {"rod": rod, "angle": angle}


def case_twin(
    table: Any, scene: Scene, models: tuple[ModelSpec, ...], reference: str, where: str
) -> dict[str, Any] | None:
    """The case's twin perturbation ([agreement.twin], checked against the case: rod <= n,
    the twin's label not a model's, the watched quantities output by the scene), or None
    (``reference``: the study's reference label)."""
    spec = agreement_spec(table, where)
    outputs = set(trajectory_quantities(scene.outputs))
    missing = [q for q in spec["quantities"] if q not in outputs]
    if table is not None and "quantities" in table and missing:
        raise key_error(
            where,
            "agreement.quantities",
            f"{missing[0]!r} is not an output of the scene ({sorted(outputs)})",
        )
    twin: dict[str, Any] | None = spec.get("twin")
    if twin is None:
        return None
    if any(m.label == twin_label(reference) for m in models):
        raise key_error(
            where,
            f"models.{twin_label(reference)}",
            "is the label of the reference's twin run ([agreement.twin]); rename that model",
        )
    if twin["rod"] > scene.n:
        raise key_error(
            where, "agreement.twin.rod", f"must be in 1..{scene.n} (n), got {twin['rod']}"
        )
    return twin
