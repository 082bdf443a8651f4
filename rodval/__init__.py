"""rodval: cross-validation of plane elastic rod-chain models.

Data flows one way: Scene -> Model -> Trajectory -> comparison -> table -> report, and so do
the imports: core <- solvers <- models, reference_models <- analysis <- report <- study, bench
<- cli (see docs/architecture.md).
"""

# First, before any kernel is decorated: a change of rodval's sources recompiles its cached
# kernels (rodval/core/jit_cache.py).
import rodval.core.jit_cache  # noqa: F401

# isort: split
from rodval.analysis.metrics import discrepancies as compare
from rodval.analysis.modes import model_modes as modes
from rodval.core.base import Base
from rodval.core.contract import Model
from rodval.core.loads import NodalForce, constant, harmonic, pulse, ramp, tabulated
from rodval.core.scene import TABLE1_TIMES, Chain, InitialState, Latch, Scene, Stop, paper_scene
from rodval.core.scene_file import load_scene
from rodval.core.settings import IntegratorSettings
from rodval.core.status import Status
from rodval.core.trajectory import SolverStats, Trajectory
from rodval.models import FullModel, ReducedModel, get_model, simulate
from rodval.report.tables import read_tables as read_study_tables
from rodval.study import load_study, run_study
from rodval.study.spec import StudySpec as Study

__version__ = "0.2.0"

__all__ = [
    "Chain",
    "InitialState",
    "Scene",
    "Latch",
    "Stop",
    "Base",
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
