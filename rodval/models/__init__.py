"""The paper's models (``full``, ``reduced``) and the registry of every model by name.

``FullModel`` and ``ReducedModel`` are imported on first use (PEP 562), so that a run of one
model loads that model's modules and compiled kernels only."""

from typing import TYPE_CHECKING, Any

from rodval.models.registry import REGISTRY, get_model, model_class, simulate

if TYPE_CHECKING:
    from rodval.models.full import FullModel
    from rodval.models.reduced import ReducedModel

__all__ = ["FullModel", "ReducedModel", "REGISTRY", "get_model", "model_class", "simulate"]


def __getattr__(name: str) -> Any:
    if name in ("FullModel", "ReducedModel"):
        return model_class("full" if name == "FullModel" else "reduced")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
