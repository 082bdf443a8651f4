"""rodval: cross-validation of plane elastic rod-chain models.

Data flows one way: Scene -> Model -> Trajectory -> comparison -> table -> report.
"""
from .loads import NodalForce, constant, pulse
from .models import FullModel, Model, ReducedModel, get_model
from .scene import Chain, InitialState, Scene, TABLE1_TIMES, paper_scene
from .settings import IntegratorSettings
from .simulate import simulate
from .trajectory import SolverStats, Trajectory

__version__ = "0.1.0"

__all__ = ["Chain", "InitialState", "Scene", "NodalForce", "pulse", "constant", "paper_scene",
           "TABLE1_TIMES", "Model", "FullModel", "ReducedModel", "get_model",
           "IntegratorSettings", "simulate", "Trajectory", "SolverStats", "__version__"]
