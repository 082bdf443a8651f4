"""Independent reference model: the rod chain as ANCF cable beams in exudyn.

Each rod k is meshed into ``elements`` ObjectANCFCable2D elements (cubic Hermite position
field, Euler-Bernoulli bending stiffness EI_k, mass per length m_k, axial stiffness ``EA``
standing in for inextensibility). Rods are meshed separately; at node k the end node of rod k
and the start node of rod k+1 are joined by a 2D revolute joint (position constraint) and a
torsional spring-damper (kappa_k, nu_k) on the relative rotation of the two end tangents.
Hinge 0 joins the ground frame (the x axis) to rod 1's root tangent, or on a free base
(``Scene.base``) a rigid body (NodeRigidBody2D and ObjectRigidBody2D: the body's mass and
inertia, free in the plane) at its hinge offset, the hinge angle measured from the body's
attitude; the body's motion is then part of the outputs ("base", "momentum",
"angular_momentum", the kinetic energy). A prescribed base is the same body (of a nominal
mass) with its three coordinates imposed by CoordinateConstraints following the laws; the
outputs treat it as massless, as the native models do, and its run has no energy audit (the
drive's work is not measured). The torsional springs use a NodeGenericData to keep their
angle continuous beyond +-pi (hinge 0 turns past pi in the paper's example). Point masses
mu_k sit on the end node of rod k; the scene's nodal forces act there through exudyn load
user functions, exactly zero outside each force's support; motors, rate dampers through
torque user laws across their hinges (``exudyn_beam.torque_law``).

Nothing of the paper's equations is used: the quantities are measured on the beam solution by
their definitions (see ``rodval.core.scene``):

* phi_k: angle of the chord node k-1 -> node k, unwrapped continuously in time (every solver
  step is recorded), starting from the scene's initial phi;
* dphi_k: its rate, (d x d') / |d|^2 with d the chord vector;
* alpha_k, beta_k: angle of the beam tangent at node k-1 (resp. node k) minus phi_k,
  wrapped to (-pi, pi];
* x, y: node positions; kinetic/potential/energy: beam, axial, hinge and point-mass energies
  evaluated on the element fields by Gauss quadrature.

Values between solver steps come from cubic Hermite interpolation of the recorded node
coordinates (with their velocities) and velocities (with their accelerations); output times on
the step grid are taken as recorded.

Initial state: every rod starts on the assumed-mode curve with end tangent angles phi + alpha,
phi + beta and arc length exactly l (its chord slightly shorter than l), beam nodes at equal arc
length with unit slopes: unstretched at the nodes (``_bent_rod``). Velocities follow the same
curve (dphi, dalpha, dbeta).

Solver: exudyn's implicit generalized-alpha (or trapezoidal index-2) integrator with a fixed
step (halved, down to step/64, only if Newton fails): the option ``step``'s, or by default
(``step = "auto"``) the one the run needs (``exudyn_step``), sparse linear solver
(EigenSparse), no files, graphics or console output. Newton's absolute tolerance is
``newton_atol_per_EA * EA`` (N): the default lies below the round-off of the stiff axial
forces. With latches the Newton Jacobian is renewed every step (``JAC_PER_STEP``; why:
docs/reference_model.md, "Speed"). rodval's native integrator settings are refused unless at
their defaults (``check_settings``; ``blowup_factor`` and ``max_wall_s`` apply). Before every
step ``Guard`` checks the state: non-finite (STATUS_DIVERGED), kinetic energy above
blowup_factor x (E(0) + W+ + 1e-6 J) (STATUS_BLOWUP), rotation per step above
``max_rotation_per_step`` (STATUS_FAILED); a verdict stops the run. Then ``RunBudget``
(``exudyn_budget``) reads the clock (the run's wall-clock budget, set-up included:
STATUS_WALL) and counts the recorded steps against the memory bound; a run without a
wall-clock budget is refused before any work when it plans more than ``MAX_STEPS_UNBOUNDED``
steps or more than its records fit in memory (``check_plan``).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Iterable
from typing import Any

import numpy as np

from reference_models import exudyn_step
from reference_models.exudyn_audit import account
from reference_models.exudyn_beam import Array, Nodes, positive
from reference_models.exudyn_budget import RunBudget, check_plan, refinement_refusal
from reference_models.exudyn_build import BuiltSystem, build, read_records, recorded_doubles
from reference_models.exudyn_ending import (
    ended,
    lock_records,
    run_guard,
    solver_message,
    unaudited_drive,
)
from reference_models.exudyn_guard import Guard
from reference_models.exudyn_latches import Latches
from reference_models.exudyn_observe import (
    Observed,
    body_view,
    momentum_audit,
    observe,
    recorded_peaks,
    stop_events,
)
from reference_models.exudyn_settings import (
    newton_record,
    simulation_settings,
)
from reference_models.exudyn_step import AUTO, check_step, run_auto
from rodval.core.contract import Model
from rodval.core.scene import Scene
from rodval.core.settings import IntegratorSettings
from rodval.core.status import (
    STATUS_ERROR,
    STATUS_FAILED,
    numerical_failure,
    update_status,
)
from rodval.core.trajectory import SolverStats, Trajectory, finish
from rodval.core.validity import Check, momentum_point, step_resolution
from rodval.solvers.audit import momentum_residual

ELEMENTS = ("cable2d",)
SOLVERS = ("generalized-alpha", "trapezoidal")

#: Converged defaults, chosen by benchmarks/exudyn_convergence.py (docs/reference_model.md);
#: the step by the run's needs ("auto": ``exudyn_step``, from at most 2e-4 s, the converged
#: fixed default before it).
DEFAULTS: dict[str, Any] = {
    "elements": 2,
    "step": AUTO,
    "EA": 1e10,
    "element": "cable2d",
    "solver": "generalized-alpha",
    "spectral_radius": "auto",
    "newton_rtol": 1e-8,
    "newton_atol_per_EA": 1e-12,
    "max_rotation_per_step": 0.1,
}

#: IntegratorSettings fields exudyn honours (``exudyn_budget``, ``exudyn_guard``); every other
#: field belongs to rodval's ODE integrators, and a non-default value of it is refused.
HONOURED_SETTINGS = ("max_wall_s", "blowup_factor")
NATIVE_INTEGRATOR_FIELDS = tuple(
    f.name for f in dataclasses.fields(IntegratorSettings) if f.name not in HONOURED_SETTINGS
)


class ExudynModel(Model):
    """The chain as ANCF cable beams in exudyn (independent of the paper's equations).

    Options (validated on construction; defaults in ``DEFAULTS``):

    elements : int >= 1
        ANCF cable elements per rod.
    step : "auto" or float in (0, 0.1] s
        The time step. A float: the fixed step (the run uses ceil(t_end / step) equal
        steps). "auto" (the default): the fixed step the run needs, by attempts
        (``exudyn_step``): an a-priori step (the shortest lock window over 20 steps, at most
        2e-4 s), halved (at most 4 times) while a lock window holds fewer than 20 steps, the
        energy residual exceeds its bound or a rod turns by more than
        ``max_rotation_per_step`` in a step; the last attempt is the run, its settings record
        every attempt (``step_auto``) and its notes why that step was chosen, or that none
        within the limits met the checks. ``max_wall_s`` covers every attempt together.
    EA : float in (0, 1e14] N
        Axial stiffness standing in for inextensibility.
    element : "cable2d"
        ObjectANCFCable2D (the geometrically exact 2D beam did not earn its place: see
        docs/reference_model.md).
    solver : "generalized-alpha" or "trapezoidal"
        exudyn's implicit integrator (trapezoidal = Newmark beta 1/4, index-2 constraints).
    spectral_radius : float in [0, 1] or "auto"
        Generalized-alpha numerical damping at infinite frequency (1 = none). "auto" (the
        default): ``SPECTRAL_RADIUS_FREE`` = 0.9, or ``SPECTRAL_RADIUS_LATCHES`` = 0 for a
        scene with latches (``spectral_radius_for``; the run records the value it used).
    newton_rtol : float in (0, 1e-2]
        Newton relative tolerance.
    newton_atol_per_EA : float in (0, 1e-6]
        Newton absolute tolerance per unit EA (absolute tolerance = this * EA, in N).
    max_rotation_per_step : float in (0, pi] rad
        Resolution bound: a run whose chords turn by more than this in one step (max |dphi_k|
        x step) ends as STATUS_FAILED. Default 0.1 rad: 10 steps per radian, where a
        second-order integrator's phase error on a rotation is about (|dphi| h)^2 / 12 = 1e-3
        rad per radian turned; the paper example turns by < 1e-3 rad per step at the default
        step. Beyond it the trajectory is not a resolved solution.

    Any other keyword is refused with a ValueError listing these (``check_options``).
    Divergence is detected during the run (``Guard``): a non-finite state ends it as
    STATUS_DIVERGED, kinetic energy above ``settings.blowup_factor`` x (E(0) + W+(t) + 1e-6 J)
    as STATUS_BLOWUP, both at the time of detection with the output times before it kept.
    ``settings.max_wall_s`` (s, from the start of the run) ends it as STATUS_WALL with the
    outputs up to the time reached; without it a run of more than ``MAX_STEPS_UNBOUNDED``
    steps is refused (``exudyn_budget``).
    """

    name = "exudyn"
    OPTIONS = tuple(DEFAULTS)
    MODAL_ANALYSIS = "reference_models.exudyn_modes:exudyn_modes"
    #: a modal analysis takes the model's options and its own (``exudyn_modes``)
    MODES_OPTIONS = (*OPTIONS, "load_steps", "axial_tol")
    #: exudyn integrates with its own options: rodval's integrator settings do not apply.
    USES_INTEGRATOR_SETTINGS = False

    def __init__(self, **options: Any) -> None:
        """The model with ``options`` (keywords of ``DEFAULTS``, the rest at their defaults)."""
        unknown = sorted(set(options) - set(DEFAULTS))
        if unknown:
            raise ValueError(_unknown_options_message(unknown))
        o = {**DEFAULTS, **options}
        self.elements: int = positive("elements", o["elements"], integer=True)
        self.step: float | str = check_step(o["step"])
        self.EA: float = positive("EA", o["EA"], upper=1e14)
        element, solver, spectral_radius = o["element"], o["solver"], o["spectral_radius"]
        if element not in ELEMENTS:
            raise ValueError(f"element must be one of {ELEMENTS}, got {element!r}")
        self.element: str = element
        if solver not in SOLVERS:
            raise ValueError(f"solver must be one of {SOLVERS}, got {solver!r}")
        self.solver: str = solver
        if spectral_radius != "auto" and (
            isinstance(spectral_radius, bool)
            or not isinstance(spectral_radius, (int, float))
            or not 0 <= spectral_radius <= 1
        ):
            raise ValueError(
                f"spectral_radius must be a number in [0, 1] or 'auto', got {spectral_radius!r}"
            )
        self.spectral_radius: float | str = (
            "auto" if spectral_radius == "auto" else float(spectral_radius)
        )
        self.newton_rtol: float = positive("newton_rtol", o["newton_rtol"], upper=1e-2)
        self.newton_atol_per_EA: float = positive(
            "newton_atol_per_EA", o["newton_atol_per_EA"], upper=1e-6
        )
        self.max_rotation_per_step: float = positive(
            "max_rotation_per_step", o["max_rotation_per_step"], upper=math.pi
        )

    def check_base(self, scene: Scene) -> None:
        """Every kind of base is modelled: a pinned base as the ground, a free one as a rigid
        body, a prescribed one as a rigid body whose coordinates are imposed by constraints
        (``exudyn_build``). The output "drive" (a prescribed base's force and moment on the
        chain) is refused: the constraints' reactions are not measured."""
        if scene.wants("drive"):
            raise ValueError(
                "exudyn model: output 'drive' (a prescribed base's force and moment on the chain) "
                "is not measured by the exudyn model; drop it from outputs, or run the full model"
            )

    @classmethod
    def check_options(cls, options: dict[str, Any]) -> dict[str, Any]:
        """Validate a dict of model options without running anything: the complete options
        (defaults filled in), or ValueError naming an unknown key (and listing the allowed
        ones) or a bad value."""
        if not isinstance(options, dict):
            raise ValueError(  # noqa: TRY004 - rodval reports every bad input as ValueError
                f"exudyn model options must be a dict, got {type(options).__name__}"
            )
        return cls(**options).options()

    def options(self) -> dict[str, Any]:
        return {k: getattr(self, k) for k in DEFAULTS}

    def assembled(self, scene: Scene) -> tuple[Any, Any, list[list[int]]]:
        """(SC, mbs, nodes) of ``scene``, assembled as for a run (for analyses other than time
        integration, e.g. reference_models.exudyn_modes): nodes[k][j] is the exudyn node
        number of beam node j = 0..elements of rod k (0-based); the scene's loads are attached."""
        built = self._build(scene)
        E = self.elements
        nodes = [[k * (E + 1) + j for j in range(E + 1)] for k in range(scene.n)]
        return built.SC, built.mbs, nodes

    # -- system ------------------------------------------------------------------------------
    def _build(self, scene: Scene) -> BuiltSystem:
        """The beam model of ``scene`` with this model's discretization (``build``)."""
        return build(scene, self.elements, self.EA)

    def _settings(self, scene: Scene) -> Any:
        """exudyn's simulation settings of a run of ``scene`` (``simulation_settings``) at the
        fixed step (a float: ``_run_at``)."""
        return simulation_settings(
            scene,
            float(self.step),
            (self.newton_rtol, self.newton_atol_per_EA * self.EA),
            self.spectral_radius_for(scene),
        )

    # -- run -----------------------------------------------------------------------------------
    @staticmethod
    def check_settings(settings: IntegratorSettings | None) -> None:
        """Refuse native integrator settings exudyn cannot honour: ValueError naming the first
        field of ``NATIVE_INTEGRATOR_FIELDS`` that differs from ``IntegratorSettings()``."""
        if settings is None:
            return
        default = IntegratorSettings()
        for name in NATIVE_INTEGRATOR_FIELDS:
            value = getattr(settings, name)
            if value != getattr(default, name):
                raise ValueError(
                    f"the exudyn model cannot honour integrator setting {name}={value!r} "
                    f"(default {getattr(default, name)!r}): exudyn's integrator is set by its own "
                    f"options ({', '.join(DEFAULTS)}); leave {', '.join(NATIVE_INTEGRATOR_FIELDS)} "
                    "at their defaults"
                )

    #: Largest generalized-alpha spectral radius accepted with latches: above it the index-3
    #: lock leaves a slowly decaying step-to-step oscillation of the relative rate
    #: (docs/deployment.md); 0 damps it within two steps.
    LATCH_MAX_SPECTRAL_RADIUS = 0.5
    #: The spectral radius "auto" gives: 0.9 (little numerical damping) for free motion, 0
    #: with latches (docs/reference_model.md, docs/deployment.md).
    SPECTRAL_RADIUS_FREE = 0.9
    SPECTRAL_RADIUS_LATCHES = 0.0

    def spectral_radius_for(self, scene: Scene) -> float:
        """The generalized-alpha spectral radius a run of ``scene`` uses: the option's value,
        or for "auto" ``SPECTRAL_RADIUS_LATCHES`` when the scene has latches and
        ``SPECTRAL_RADIUS_FREE`` otherwise."""
        if self.spectral_radius != "auto":
            return float(self.spectral_radius)
        return self.SPECTRAL_RADIUS_LATCHES if scene.latches else self.SPECTRAL_RADIUS_FREE

    def check_scene(self, scene: Scene) -> None:
        """Refuse, before any work, what this model cannot honour in ``scene``: latches with the
        trapezoidal (index-2) solver, which would hold a latched hinge at the angle where its
        joint was switched on instead of the latch angle, or with a spectral radius above
        ``LATCH_MAX_SPECTRAL_RADIUS``."""
        if not scene.latches:
            return
        if self.solver == "trapezoidal":
            raise ValueError(
                "the exudyn model locks latches with an index-3 rotation constraint: use "
                "solver='generalized-alpha' (the trapezoidal solver's index-2 constraints would "
                "hold the hinge at the angle of activation, not at the latch angle)"
            )
        if self.spectral_radius_for(scene) > self.LATCH_MAX_SPECTRAL_RADIUS:
            raise ValueError(
                f"scenes with latches need spectral_radius <= {self.LATCH_MAX_SPECTRAL_RADIUS} "
                f"(0 recommended, or 'auto'), got {self.spectral_radius}: with less numerical "
                "damping the locked hinge's relative rate oscillates from step to step after "
                "the lock"
            )

    def first_step(self, scene: Scene) -> float:
        """The step (s) of the first run of ``scene``: the option's, or for "auto" the
        a-priori step (``exudyn_step.a_priori_step``)."""
        return self.step if isinstance(self.step, float) else exudyn_step.a_priori_step(scene)[0]

    def check_plan(self, scene: Scene, settings: IntegratorSettings) -> int:
        """The (first) run's planned steps, or ValueError before any work when a run without
        a wall-clock budget plans too many steps or records (``exudyn_budget.check_plan``)."""
        doubles = recorded_doubles(scene, self.elements)
        return check_plan(scene.t_end, self.first_step(scene), doubles, settings.max_wall_s)

    def simulate(self, scene: Scene, settings: IntegratorSettings | None = None) -> Trajectory:
        """``Model.simulate``, with the note of a ``step = "auto"`` run (why its step was
        chosen, or that none met the checks) first in ``stats.notes``."""
        trajectory = super().simulate(scene, settings)
        auto = trajectory.settings.get("step_auto")
        if auto is not None:
            trajectory.stats.notes = [auto["note"], *trajectory.stats.notes]
        return trajectory

    def run(self, scene: Scene, settings: IntegratorSettings | None = None) -> Trajectory:
        """Run the scene. Of the native integrator ``settings`` ``blowup_factor`` and
        ``max_wall_s`` (s, from this call: the set-up counts, and with ``step = "auto"`` every
        attempt) apply; any other non-default field raises ValueError before any work
        (``check_settings``), as does a run without a wall-clock budget that plans too many
        steps (``check_plan``): the exudyn integrator is set by this model's options, recorded
        in ``trajectory.settings`` with the steps actually taken."""
        start = time.perf_counter()
        settings = settings or IntegratorSettings()
        self.check_settings(settings)
        self.check_scene(scene)
        planned = self.check_plan(scene, settings)
        if isinstance(self.step, float):
            return self._run_at(scene, settings, (planned, start))
        return self._run_auto(scene, settings, start)

    def with_step(self, step: float) -> ExudynModel:
        """This model with the fixed ``step`` (s), every other option the same."""
        return ExudynModel(**{**self.options(), "step": step})

    def _run_auto(self, scene: Scene, settings: IntegratorSettings, start: float) -> Trajectory:
        """The ``step = "auto"`` run (``exudyn_step.run_auto``): fixed-step attempts from
        ``start`` (``time.perf_counter()`` s, the run's start: one wall-clock budget for them
        all), each further one refused before it starts when it would not fit
        (``refinement_refusal``). The last attempt's trajectory, its settings recording
        ``requested_step`` "auto" and ``step_auto`` (the attempts), its stats' wall time and
        counters summed over the attempts, its options this model's."""
        doubles = recorded_doubles(scene, self.elements)
        totals = {"wall_s": 0.0, "nsteps": 0, "nfev": 0, "njev": 0}

        def run_at(step: float) -> Trajectory:
            planned = check_plan(scene.t_end, step, doubles, settings.max_wall_s)
            trajectory = self.with_step(step)._run_at(scene, settings, (planned, start))
            for key in totals:
                totals[key] += getattr(trajectory.stats, key)
            return trajectory

        def refusal(step: float, predicted_s: float) -> str | None:
            left = settings.max_wall_s - (time.perf_counter() - start)
            return refinement_refusal(
                scene.t_end, step, doubles, settings.max_wall_s, left, predicted_s
            )

        bounds = (self.energy_residual_bound, self.max_rotation_per_step)
        trajectory, auto = run_auto(scene, run_at, refusal, bounds)
        for key, value in totals.items():
            setattr(trajectory.stats, key, value)
        trajectory.settings.update(requested_step=AUTO, step_auto=auto.record())
        trajectory.options = self.options()
        return trajectory

    def _run_at(
        self, scene: Scene, settings: IntegratorSettings, plan: tuple[int, float]
    ) -> Trajectory:
        """One run of ``scene`` at this model's fixed step (a float); ``plan`` = (its planned
        steps, the run's start in ``time.perf_counter()`` s, from which ``max_wall_s``
        counts)."""
        planned, start = plan
        budget = RunBudget(settings, start, recorded_doubles(scene, self.elements))
        factor = settings.blowup_factor
        stats = SolverStats()
        run_info: dict[str, Any] = {
            "blowup_factor": factor,
            "max_wall_s": settings.max_wall_s,
            "steps_planned": planned,
        }
        try:
            built = self._build(scene)
            sim = self._settings(scene)
            guard = run_guard(
                built, scene, self.elements, self.EA, factor, self.max_rotation_per_step
            )
        except Exception as exc:  # noqa: BLE001 - a failed build is data
            status, message = numerical_failure(exc, 0.0) or (
                STATUS_ERROR,
                f"{type(exc).__name__}: {exc}",
            )
            update_status(stats, status, f"build failed: {message}")
            return self._trajectory(scene, np.empty(0), {}, stats, run_info)
        run_info.update(
            step_used=float(sim.timeIntegration.initialStepSize),
            **newton_record(sim, bool(scene.latches)),
        )
        latches = Latches.of(built, guard, scene, self.elements)
        self._solve(scene, built, sim, (guard, latches, budget), stats)
        run_info.update(
            steps=stats.nsteps,
            min_step_used=guard.min_step if math.isfinite(guard.min_step) else None,
            max_rotation_per_step_seen=guard.max_rotation_seen,
        )
        try:
            t_rec, records, diverged = read_records(built)
        except Exception as exc:  # noqa: BLE001
            update_status(stats, STATUS_ERROR, f"reading sensors failed: {exc}")
            return self._trajectory(scene, np.empty(0), {}, stats, run_info)
        times = ended(scene, stats, (guard, budget), t_rec, diverged)
        events, switched = lock_records(latches)
        reached = t_rec[t_rec <= times[-1]] if times.size else t_rec[:0]
        stops = stop_events(scene, self.elements, reached, records, switched[0])
        events = sorted(events + stops, key=lambda ev: ev["t"])
        try:
            observed, audit = self._observe(
                scene, (times, reached, t_rec, records), switched, events, stats
            )
        except Exception as exc:  # noqa: BLE001
            message = f"observation failed: {type(exc).__name__}: {exc}"
            update_status(stats, STATUS_ERROR, message)
            return self._trajectory(scene, np.empty(0), {}, stats, run_info)
        run_info.update(audit)
        return self._trajectory(scene, times, observed, stats, run_info, events)

    def _observe(
        self,
        scene: Scene,
        recorded: tuple[Array, Array, Array, Nodes],
        switched: tuple[dict[int, float], dict[int, float]],
        events: list[dict[str, Any]],
        stats: SolverStats,
    ) -> tuple[Observed, dict[str, float]]:
        """The outputs at the kept output times and the audit's settings entry of a run,
        ``recorded`` = (the kept output times, the recorded times reached, all recorded times,
        the node records), ``switched`` (``lock_records``); its peaks and energy and momentum
        residuals into ``stats``, the lock records in ``events`` completed (``account``)."""
        times, reached, t_rec, records = recorded
        E, EA = self.elements, self.EA
        observed = observe(scene, E, EA, times, t_rec, records, *switched) if times.size else {}
        stats.peaks = recorded_peaks(scene, E, EA, reached, t_rec, records, *switched)
        stats.energy_residual, audit = account(
            body_view(scene), E, EA, times, t_rec, records, events, observed, switched[1]
        )
        if scene.base.prescribed:
            stats.energy_residual, audit = unaudited_drive(observed, events)
        if times.size and momentum_point(scene) is not None:
            stats.momentum_residual = momentum_residual(
                *momentum_audit(scene, E, times[-1], t_rec, records)
            )
        return observed, audit

    def _solve(
        self,
        scene: Scene,
        built: BuiltSystem,
        sim: Any,
        checks: tuple[Guard, Latches | None, RunBudget],
        stats: SolverStats,
    ) -> None:
        """exudyn's implicit solver over the scene, ``checks`` = (guard, latches or None,
        budget) in its pre-step function; the outcome and counters into ``stats`` (the guard
        keeps its verdict, the budget its stop)."""
        import exudyn as exu

        guard, latches, budget = checks
        solver: Any = exu.MainSolverImplicitSecondOrder()
        guard.solver = solver
        jac_on_switch = not sim.timeIntegration.newton.modifiedNewtonJacUpdatePerStep

        def pre_step(mbs: Any, t: float) -> bool:
            go = guard.pre_step(mbs, t)
            if latches is not None and go:
                try:
                    latches.pre_step(t, guard.h, solver if jac_on_switch else None)
                except Exception as exc:  # noqa: BLE001 - reported as data, the run stops
                    guard.verdict = (
                        STATUS_ERROR,
                        f"latch handling failed at t = {t:.6g} s: {type(exc).__name__}: {exc}",
                        t,
                        True,
                    )
                    return False
            return go and budget.pre_step()

        built.mbs.SetPreStepUserFunction(pre_step)
        if self.solver == "trapezoidal":
            sim.timeIntegration.generalizedAlpha.useNewmark = True
            sim.timeIntegration.generalizedAlpha.useIndex2Constraints = True
        console = exu.config.printToConsole
        exu.config.printToConsole = False
        start = time.perf_counter()
        try:
            ok = solver.SolveSystem(built.mbs, sim)
            if not ok and guard.verdict is None:  # a verdict says why it stopped (``ended``)
                update_status(stats, STATUS_FAILED, solver_message(solver, "solver failed"))
            elif guard.verdict is None:  # the last step's end state has had no pre-step check
                guard.check(scene.t_end if budget.stop is None else built.mbs.systemData.GetTime())
        except Exception as exc:  # noqa: BLE001 - exudyn errors come back as data
            cause = built.load_errors[0] if built.load_errors else exc
            update_status(stats, STATUS_ERROR, f"{type(cause).__name__}: {cause}")
        finally:
            stats.wall_s = time.perf_counter() - start
            exu.config.printToConsole = console
        stats.nsteps = max(int(solver.it.currentStepIndex) - 1, 0)  # the index ends one past
        stats.njev = int(solver.it.newtonJacobiCount)
        stats.nfev = int(solver.it.newtonStepsCount)

    def validity_checks(self, scene: Scene, trajectory: Trajectory) -> list[Check]:
        """The energy balance (where audited) and the time-step resolution: the largest rod
        rotation per step seen against ``max_rotation_per_step`` (the beam itself is
        geometrically exact: no small-bending assumption). A ``step = "auto"`` run whose
        energy residual did not fall with the step names more elements as the energy fix."""
        seen = trajectory.settings.get("max_rotation_per_step_seen")
        checks = super().validity_checks(scene, trajectory)
        fix = trajectory.settings.get("step_auto", {}).get("energy_fix")
        if fix:  # "auto" found the residual does not fall with the step: not the step's fix
            checks = [
                dataclasses.replace(c, fix=fix) if c.assumption == "energy balance" else c
                for c in checks
            ]
        return checks + step_resolution(
            seen, self.max_rotation_per_step, trajectory.settings.get("step_used")
        )

    def energy_fix(self) -> str:
        """exudyn's residual is generalized-alpha's numerical dissipation, which falls with
        the step (docs/deployment.md, "Where the lock energy goes")."""
        return "a smaller step (exudyn option step; its numerical dissipation falls with it)"

    def _trajectory(
        self,
        scene: Scene,
        times: Array,
        observed: Observed,
        stats: SolverStats,
        run_info: dict[str, Any] | None = None,
        events: Iterable[dict[str, Any]] = (),
    ) -> Trajectory:
        """``settings``: the integrator, every option, and what the run used (``run_info``:
        steps_planned, step_used (s, the fixed step), steps (taken), min_step_used (s, smaller
        than step_used only if Newton failures halved it), max_rotation_per_step_seen (rad),
        blowup_factor) and ``spectral_radius`` (the value used, ``spectral_radius_for``)."""
        return finish(
            stats,
            model=self.name,
            scene_name=scene.name,
            times=times,
            observed=observed,
            settings={
                "method": f"exudyn {self.solver}",
                "step": self.step,
                "spectral_radius": self.spectral_radius_for(scene),
                **(run_info or {}),
            },
            options=self.options(),
            events=[dict(ev) for ev in events],
        )


def _unknown_options_message(unknown: list[str]) -> str:
    names = ", ".join(repr(k) for k in unknown)
    return (
        f"unknown exudyn model option(s) {names}; allowed options: {', '.join(DEFAULTS)} "
        f"(defaults {DEFAULTS})"
    )
