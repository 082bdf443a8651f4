"""The models of a study: its ``[models.LABEL]`` tables (registry name, options) with the
integrator settings that apply to each (``[integrator]``, overridden by the model's own keys,
for the models rodval integrates), checked when the study file is read."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rodval.core.checks import check_keys
from rodval.core.settings import SETTING_NAMES, IntegratorSettings
from rodval.models import REGISTRY, get_model
from rodval.models.registry import uses_integrator
from rodval.study.document import key_error

#: The keys of ``[integrator]`` (and the integrator keys of a model's table).
INTEGRATOR_KEYS = set(SETTING_NAMES)


@dataclass(frozen=True)
class ModelSpec:
    """One model of a study: its label (column in the tables), registry name, options
    (passed to ``get_model``) and integrator settings."""

    label: str
    model: str
    options: dict[str, Any]
    settings: IntegratorSettings

    def as_dict(self) -> dict[str, Any]:
        """The model as plain JSON (case payloads, fingerprints, study.json)."""
        return {
            "label": self.label,
            "model": self.model,
            "options": self.options,
            "settings": self.settings.as_dict(),
        }


def model_specs(doc: dict[str, Any], where: str) -> tuple[ModelSpec, ...]:
    """Every ``[models.LABEL]`` table of the study document ``doc`` (file ``where``), in file
    order; ValueError naming the key for anything wrong."""
    integ = doc.get("integrator", {})
    check_keys(integ, INTEGRATOR_KEYS, f"{where}:", path="integrator")
    models = doc.get("models")
    if not isinstance(models, dict) or not models:
        raise key_error(
            where,
            "models",
            f"at least one [models.LABEL] table is required (model names: {', '.join(REGISTRY)})",
        )
    return tuple(_model_spec(str(label), table, integ, where) for label, table in models.items())


def _model_spec(label: str, table: Any, integ: dict[str, Any], where: str) -> ModelSpec:
    """The model of the table ``[models.LABEL]`` (``table``), with ``[integrator]`` (``integ``)."""
    key = f"models.{label}"
    if not isinstance(table, dict):
        raise key_error(where, key, "must be a table")
    name = table.get("model", label)
    if not isinstance(name, str) or name not in REGISTRY:
        raise key_error(
            where,
            f"{key}.model" if "model" in table else key,
            f"model must be one of {', '.join(REGISTRY)}, got {name!r}",
        )
    settings = _settings(name, table, integ, key, where)
    options = {k: v for k, v in table.items() if k not in INTEGRATOR_KEYS | {"model"}}
    _check_model_options(name, options, where, key)
    return ModelSpec(label=label, model=name, options=options, settings=settings)


def _settings(
    name: str, table: dict[str, Any], integ: dict[str, Any], key: str, where: str
) -> IntegratorSettings:
    """The integrator settings of model ``name``: ``[integrator]`` overridden by its table's
    own integrator keys, for a model rodval integrates; the defaults for a model that
    integrates itself (which may not have integrator keys of its own)."""
    own = {k: v for k, v in table.items() if k in INTEGRATOR_KEYS}
    if not _uses_rodval_integrator(name):
        if own:
            raise key_error(
                where,
                f"{key}.{sorted(own)[0]}",
                f"model {name!r} integrates with its own options, not rodval's "
                "integrator settings (see its options, e.g. step, solver)",
            )
        settings_kw = {}  # [integrator] applies to the models rodval integrates
    else:
        settings_kw = {**integ, **own}
    try:
        return IntegratorSettings(**settings_kw)
    except (TypeError, ValueError) as exc:
        bad = next((k for k in INTEGRATOR_KEYS if k in str(exc)), "method")
        src = f"{key}.{bad}" if bad in table else f"integrator.{bad}"
        raise key_error(where, src, str(exc)) from None


def _uses_rodval_integrator(name: str) -> bool:
    """Whether model ``name`` is integrated by rodval's driver (its IntegratorSettings apply);
    a model that cannot be imported here is taken to be (its runs fail and say why)."""
    try:
        return uses_integrator(name)
    except ValueError:
        return True


def _check_model_options(name: str, options: dict[str, Any], where: str, key: str) -> None:
    """Reject bad options of an importable model now; a model that cannot be imported here
    (e.g. exudyn not installed) is not an error of the file: its runs fail and say why."""
    try:
        get_model(name, **options)
    except ValueError as exc:
        if isinstance(exc.__cause__, ImportError):
            return
        raise key_error(where, key, str(exc)) from None
    except TypeError as exc:
        raise key_error(where, key, f"bad model option: {exc}") from None
