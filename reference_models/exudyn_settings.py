"""exudyn's simulation settings of a run (``simulation_settings``), what the run records of
them (``newton_record``) and the start-up rule for rods with bending damping
(``initial_kick``); the model itself is ``reference_models.exudyn_chain``."""

from __future__ import annotations

from typing import Any

from reference_models.exudyn_budget import EXUDYN_MAX_STEPS, planned_steps
from rodval.core.scene import Scene

#: renew the Newton Jacobian every step of a scene with latches (True: the old way) instead of
#: only in the step a latch's joint is switched on (``Latches.pre_step``)
JAC_PER_STEP = True


def initial_kick(scene: Scene) -> bool:
    """Whether generalized-alpha's first step from computed initial accelerations would kick
    the element-scale modes: any rod with bending damping (docs/deployment.md, "exudyn's
    start-up with bending damping"), or a torque item (motor, rate damper) with a moment at
    rest at t = 0 on a hinge between two rods (k >= 1): that step moment on two beam ends
    gives element-scale initial accelerations (on hinge 0 it does not; docs/reference_model.md,
    "Motors and rate dampers"). Such a run starts from a = 0."""
    return bool(scene.chain.bending_damping.any()) or any(
        item.hinge > 0 and item.moment(0.0, 0.0) != 0.0 for item in scene.torques
    )


def simulation_settings(
    scene: Scene, step: float, newton: tuple[float, float], spectral_radius: float
) -> Any:
    """exudyn's simulation settings of a run of ``scene``: ``planned_steps`` equal steps of
    ``step`` (s) over t_end, or only the first ``EXUDYN_MAX_STEPS`` of them (exudyn's largest
    count; a budgeted run stops before it); ``newton`` = (relative tolerance, absolute
    tolerance in N); generalized-alpha's ``spectral_radius``."""
    import exudyn as exu

    t_end = scene.t_end
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    planned = planned_steps(t_end, step)
    nsteps = min(planned, EXUDYN_MAX_STEPS)
    ti.endTime = t_end * nsteps / planned if nsteps < planned else t_end
    ti.numberOfSteps = nsteps
    ti.initialStepSize = t_end / planned
    ti.automaticStepSize = False
    ti.adaptiveStep = True
    ti.minimumStepSize = ti.initialStepSize / 64.0  # fail fast instead of crawling
    ti.verboseMode = 0
    ti.verboseModeFile = 0
    ti.newton.relativeTolerance, ti.newton.absoluteTolerance = newton
    ti.newton.modifiedNewtonJacUpdatePerStep = bool(scene.latches) and JAC_PER_STEP
    ti.generalizedAlpha.spectralRadius = spectral_radius
    # with bending damping (or a step moment across a hinge at t = 0), generalized-alpha's
    # step from computed initial accelerations kicks the element-scale modes (by 5-45 J on
    # a stowed wing); start from a = 0
    ti.generalizedAlpha.computeInitialAccelerations = not initial_kick(scene)
    s.solution.file.write = False
    s.solution.sensors.writePeriod = 0.25 * t_end / planned
    s.show.statistics = False
    s.show.computationTime = False
    s.show.globalTimers = False
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    return s


def newton_record(sim: Any, latches: bool) -> dict[str, Any]:
    """The Newton and linear-solver choices of a run, for ``trajectory.settings`` (chosen by
    benchmarks/exudyn_speed.py and the measurements in docs/reference_model.md, "Speed"), and
    whether it started from computed initial accelerations."""
    newton = sim.timeIntegration.newton
    per_step = bool(newton.modifiedNewtonJacUpdatePerStep)
    return {
        "initial_accelerations": bool(
            sim.timeIntegration.generalizedAlpha.computeInitialAccelerations
        ),
        "linear_solver": str(sim.linearSolver.solverType).split(".")[-1],
        "newton": "modified" if newton.useModifiedNewton else "full",
        "newton_atol": float(newton.absoluteTolerance),
        "newton_rtol": float(newton.relativeTolerance),
        "jacobian_update": (
            "every step"
            if per_step
            else f"when the contraction exceeds {newton.modifiedNewtonContractivity:g}"
            + (" and in the step a latch switches on" if latches else "")
        ),
    }
