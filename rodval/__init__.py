"""rodval: cross-validation of plane elastic rod-chain models.

Data flows one way: Scene -> Model -> Trajectory -> comparison -> table -> report, and so do
the imports: core <- solvers <- models, reference_models <- analysis <- report <- study, bench
<- cli (see docs/architecture.md).

``import rodval`` is light (the standard library only): the public API below is imported on
first use (PEP 562), so ``rodval --help``, ``rodval --version`` and a module that needs one
name do not pay for numba, scipy and pandas (docs/performance.md, "Start-up").
"""

from __future__ import annotations

import importlib
import sys
from importlib.abc import MetaPathFinder
from typing import TYPE_CHECKING, Any

__version__ = "0.2.0"

#: Each public name -> (the module defining it, its name there), imported on first use.
_LAZY: dict[str, tuple[str, str]] = {
    "Chain": ("rodval.core.scene", "Chain"),
    "InitialState": ("rodval.core.scene", "InitialState"),
    "Scene": ("rodval.core.scene", "Scene"),
    "Latch": ("rodval.core.scene", "Latch"),
    "Stop": ("rodval.core.scene", "Stop"),
    "Motor": ("rodval.core.scene", "Motor"),
    "RateDamper": ("rodval.core.scene", "RateDamper"),
    "CompliantLatch": ("rodval.core.scene", "CompliantLatch"),
    "Base": ("rodval.core.base", "Base"),
    "Motion": ("rodval.core.motion", "Motion"),
    "NodalForce": ("rodval.core.loads", "NodalForce"),
    "pulse": ("rodval.core.loads", "pulse"),
    "constant": ("rodval.core.loads", "constant"),
    "ramp": ("rodval.core.loads", "ramp"),
    "harmonic": ("rodval.core.loads", "harmonic"),
    "tabulated": ("rodval.core.loads", "tabulated"),
    "paper_scene": ("rodval.core.scene", "paper_scene"),
    "load_scene": ("rodval.core.scene_file", "load_scene"),
    "Status": ("rodval.core.status", "Status"),
    "TABLE1_TIMES": ("rodval.core.scene", "TABLE1_TIMES"),
    "Model": ("rodval.core.contract", "Model"),
    "FullModel": ("rodval.models", "FullModel"),
    "ReducedModel": ("rodval.models", "ReducedModel"),
    "get_model": ("rodval.models", "get_model"),
    "IntegratorSettings": ("rodval.core.settings", "IntegratorSettings"),
    "simulate": ("rodval.models", "simulate"),
    "Trajectory": ("rodval.core.trajectory", "Trajectory"),
    "SolverStats": ("rodval.core.trajectory", "SolverStats"),
    "compare": ("rodval.analysis.metrics", "discrepancies"),
    "modes": ("rodval.analysis.modes", "model_modes"),
    "load_study": ("rodval.study", "load_study"),
    "Study": ("rodval.study.spec", "StudySpec"),
    "run_study": ("rodval.study", "run_study"),
    "read_study_tables": ("rodval.report.tables", "read_tables"),
}

__all__ = [
    "Chain",
    "InitialState",
    "Scene",
    "Latch",
    "Stop",
    "Motor",
    "RateDamper",
    "CompliantLatch",
    "Base",
    "Motion",
    "NodalForce",
    "pulse",
    "constant",
    "ramp",
    "harmonic",
    "tabulated",
    "paper_scene",
    "load_scene",
    "Status",
    "TABLE1_TIMES",
    "Model",
    "FullModel",
    "ReducedModel",
    "get_model",
    "IntegratorSettings",
    "simulate",
    "Trajectory",
    "SolverStats",
    "compare",
    "modes",
    "load_study",
    "Study",
    "run_study",
    "read_study_tables",
    "__version__",
]

if TYPE_CHECKING:  # the names as mypy and editors see them; at run time ``__getattr__``
    from rodval.analysis.metrics import discrepancies as compare
    from rodval.analysis.modes import model_modes as modes
    from rodval.core.base import Base
    from rodval.core.contract import Model
    from rodval.core.loads import NodalForce, constant, harmonic, pulse, ramp, tabulated
    from rodval.core.motion import Motion
    from rodval.core.scene import (
        TABLE1_TIMES,
        Chain,
        CompliantLatch,
        InitialState,
        Latch,
        Motor,
        RateDamper,
        Scene,
        Stop,
        paper_scene,
    )
    from rodval.core.scene_file import load_scene
    from rodval.core.settings import IntegratorSettings
    from rodval.core.status import Status
    from rodval.core.trajectory import SolverStats, Trajectory
    from rodval.models import FullModel, ReducedModel, get_model, simulate
    from rodval.report.tables import read_tables as read_study_tables
    from rodval.study import load_study, run_study
    from rodval.study.spec import StudySpec as Study


if not TYPE_CHECKING:  # hidden from mypy, which would otherwise accept any rodval.NAME

    def __getattr__(name: str) -> Any:
        """A public name, imported from its module on first use (and kept here after)."""
        try:
            module, attr = _LAZY[name]
        except KeyError:
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
        value = getattr(importlib.import_module(module), attr)
        globals()[name] = value
        return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


# numba's cache of rodval's kernels is keyed by all of rodval's sources
# (rodval/core/jit_cache.py), which must patch numba before any kernel is decorated: numba
# reads a kernel's source stamp when ``@njit(cache=True)`` decorates it. Importing
# jit_cache imports numba, so ``import rodval`` no longer does; instead the first import of
# numba in a process that imported rodval installs it, whichever module imports numba first
# (a kernel module, a subcommand, a study worker, a test importing a submodule directly).
class _KeyNumbaCache(MetaPathFinder):
    """Runs ``import rodval.core.jit_cache`` right after numba's own ``__init__``: numba is
    then complete, and no module has decorated a kernel yet (each imports numba first)."""

    keys_rodval_kernels = True

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> Any:
        if fullname != "numba":
            return None
        for finder in sys.meta_path:  # the spec the other finders give, its loader wrapped
            if finder is self or not hasattr(finder, "find_spec"):
                continue
            spec = finder.find_spec(fullname, path, target)
            if spec is not None:
                break
        else:
            return None
        loader = spec.loader
        if loader is None or not hasattr(loader, "exec_module"):
            return spec
        exec_module = loader.exec_module

        def exec_then_key(module: Any) -> None:
            exec_module(module)
            if self in sys.meta_path:
                sys.meta_path.remove(self)
            importlib.import_module("rodval.core.jit_cache")

        # the loader is this spec's own instance (a new one per find_spec): patch it only
        loader.exec_module = exec_then_key  # type: ignore[method-assign]
        return spec


if "numba" in sys.modules:  # numba was imported before rodval: key the cache now
    importlib.import_module("rodval.core.jit_cache")
elif not any(getattr(f, "keys_rodval_kernels", False) for f in sys.meta_path):
    sys.meta_path.insert(0, _KeyNumbaCache())
