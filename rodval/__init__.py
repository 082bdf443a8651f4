"""rodval: cross-validation of plane elastic rod-chain models.

Data flows one way: Scene -> Model -> Trajectory -> comparison -> table -> report, and so do
the imports: core <- solvers <- models, reference_models <- analysis <- report <- study, bench
<- cli (see docs/architecture.md).
"""

from rodval.core.contract import Model
from rodval.core.loads import NodalForce, constant, harmonic, pulse, ramp, tabulated
from rodval.core.scene import TABLE1_TIMES, Chain, InitialState, Scene, paper_scene
from rodval.core.settings import IntegratorSettings
from rodval.core.trajectory import SolverStats, Trajectory
from rodval.models import FullModel, ReducedModel, get_model, simulate

__version__ = "0.2.0"

__all__ = [
    "Chain",
    "InitialState",
    "Scene",
    "NodalForce",
    "pulse",
    "constant",
    "ramp",
    "harmonic",
    "tabulated",
    "paper_scene",
    "TABLE1_TIMES",
    "Model",
    "FullModel",
    "ReducedModel",
    "get_model",
    "IntegratorSettings",
    "simulate",
    "Trajectory",
    "SolverStats",
    "__version__",
]
