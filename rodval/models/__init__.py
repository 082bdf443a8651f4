"""The paper's models (``full``, ``reduced``) and the registry of every model by name."""

from rodval.models.full import FullModel
from rodval.models.reduced import ReducedModel
from rodval.models.registry import REGISTRY, get_model, model_class, simulate

__all__ = ["FullModel", "ReducedModel", "REGISTRY", "get_model", "model_class", "simulate"]
