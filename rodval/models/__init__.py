"""Models registered by name. Native: ``full``, ``reduced``; reference: ``exudyn``."""
from __future__ import annotations

import importlib

from .base import Model, OdeModel, OdeSystem
from .full import FullModel
from .reduced import ReducedModel

#: name -> "module:Class". Reference models are imported only when asked for.
REGISTRY: dict[str, str] = {
    "full": "rodval.models.full:FullModel",
    "reduced": "rodval.models.reduced:ReducedModel",
    "exudyn": "reference_models.exudyn_chain:ExudynModel",
}


def get_model(name: str | Model, **options) -> Model:
    """The model called ``name`` with its options (a Model instance is returned as is)."""
    if isinstance(name, Model):
        if options:
            raise ValueError("model options can only be given with a model name")
        return name
    if name not in REGISTRY:
        raise ValueError(f"model must be one of {tuple(REGISTRY)}, got {name!r}")
    module, cls = REGISTRY[name].split(":")
    try:
        mod = importlib.import_module(module)
    except ImportError as exc:
        raise ValueError(f"model {name!r} is not available: {exc}") from exc
    try:
        return getattr(mod, cls)(**options)
    except TypeError as exc:  # an unknown option name
        raise ValueError(f"model {name!r} does not accept options {sorted(options)}: {exc}") from None


__all__ = ["Model", "OdeModel", "OdeSystem", "FullModel", "ReducedModel", "REGISTRY", "get_model"]
