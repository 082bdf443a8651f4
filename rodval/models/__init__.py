"""The chain engine and the paper's models as its presets (``full``, ``reduced``), with the
registry of every model by name, laid out by concept: ``assembly`` (the assembled chain
system, its matrices and O(n) kernels), ``kinematics`` (the model ladder: shapes p and exact
kinematics), ``bending`` (quasi-static bending: the reduced model's kernels), ``base`` (a free
body and a prescribed motion on every rung), ``hinge_items`` (latches and their locks),
``presets`` (``full``, ``reduced``, the registry) and ``observation`` (modes, statics).

``FullModel`` and ``ReducedModel`` are imported on first use (PEP 562), so that a run of one
model loads that model's modules and compiled kernels only."""

from typing import TYPE_CHECKING, Any

from rodval.models.registry import REGISTRY, get_model, model_class, simulate

if TYPE_CHECKING:
    from rodval.models.presets.full import FullModel
    from rodval.models.presets.reduced import ReducedModel

__all__ = ["FullModel", "ReducedModel", "REGISTRY", "get_model", "model_class", "simulate"]


def __getattr__(name: str) -> Any:
    if name in ("FullModel", "ReducedModel"):
        return model_class("full" if name == "FullModel" else "reduced")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
