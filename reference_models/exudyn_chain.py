"""Independent reference model: the rod chain as ANCF cable beams in exudyn.

Each rod k is meshed into ``elements`` ObjectANCFCable2D elements (cubic Hermite position
field, Euler-Bernoulli bending stiffness EI_k, mass per length m_k, axial stiffness ``EA``
standing in for inextensibility). Rods are meshed separately; at node k the end node of rod k
and the start node of rod k+1 are joined by a 2D revolute joint (position constraint) and a
torsional spring-damper (kappa_k, nu_k) on the relative rotation of the two end tangents.
Hinge 0 joins the ground frame (the x axis) to rod 1's root tangent. The torsional springs use
a NodeGenericData to keep their angle continuous beyond +-pi (hinge 0 turns past pi in the
paper's example). Point masses mu_k sit on the end node of rod k; the scene's nodal forces act
there through exudyn load user functions, exactly zero outside each force's support.

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
step (halved, down to step/64, only if Newton fails), sparse linear solver (EigenSparse), no
solution files, no graphics and no console output. Newton's absolute tolerance is ``newton_atol_per_EA * EA``
(N): the default absolute tolerance lies below the round-off of the stiff axial forces.
rodval's native integrator settings are refused unless at their defaults (``check_settings``;
``blowup_factor`` applies). Before every step ``_Guard`` checks the state: non-finite
(STATUS_DIVERGED), kinetic energy above blowup_factor x (E(0) + W+ + 1e-6 J) (STATUS_BLOWUP),
rotation per step above ``max_rotation_per_step`` (STATUS_FAILED); a verdict stops the run.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from rodval.core.contract import Model
from rodval.core.scene import QUANTITIES, Scene
from rodval.core.settings import IntegratorSettings
from rodval.core.status import (
    STATUS_DIVERGED,
    STATUS_ERROR,
    STATUS_FAILED,
    numerical_failure,
)
from rodval.core.trajectory import SolverStats, Trajectory
from rodval.core.validity import Check, step_resolution
from rodval.solvers.guard import EnergyBudget, GuardSpec, diverged_message

ELEMENTS = ("cable2d",)
SOLVERS = ("generalized-alpha", "trapezoidal")

#: Converged defaults, chosen by benchmarks/exudyn_convergence.py (docs/reference_model.md).
DEFAULTS: dict[str, Any] = {
    "elements": 2,
    "step": 2e-4,
    "EA": 1e10,
    "element": "cable2d",
    "solver": "generalized-alpha",
    "spectral_radius": 0.9,
    "newton_rtol": 1e-8,
    "newton_atol_per_EA": 1e-12,
    "max_rotation_per_step": 0.1,
}

#: IntegratorSettings fields that belong to rodval's ODE integrators: exudyn cannot honour
#: them (its integrator is set by this model's options), so any non-default value is refused.
NATIVE_INTEGRATOR_FIELDS = (
    "method",
    "rtol",
    "atol",
    "max_step",
    "first_step",
    "max_evaluations",
    "max_wall_s",
)

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(5)


def _positive(name: str, value, *, upper: float = math.inf, integer: bool = False):
    ok_type = (
        isinstance(value, (int, np.integer))
        if integer
        else isinstance(value, (int, float, np.number))
    )
    if (
        isinstance(value, bool)
        or not ok_type
        or not (0 < value <= upper)
        or not math.isfinite(value)
    ):
        kind = "an integer >= 1" if integer else f"a number in (0, {upper:g}]"
        raise ValueError(f"{name} must be {kind}, got {value!r}")
    return int(value) if integer else float(value)


def _wrap(a: np.ndarray) -> np.ndarray:
    """Angle(s) wrapped to (-pi, pi]."""
    return np.pi - np.mod(np.pi - a, 2.0 * np.pi)


def _hermite(s: np.ndarray, le: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cubic Hermite shape functions of an element of length le at local s (m):
    values, first and second s-derivatives, each (len(s), 4) for [r0, r0', r1, r1']."""
    x = s / le
    S = np.stack(
        [
            1 - 3 * x**2 + 2 * x**3,
            le * (x - 2 * x**2 + x**3),
            3 * x**2 - 2 * x**3,
            le * (-(x**2) + x**3),
        ],
        axis=-1,
    )
    dS = np.stack(
        [
            (-6 * x + 6 * x**2) / le,
            1 - 4 * x + 3 * x**2,
            (6 * x - 6 * x**2) / le,
            -2 * x + 3 * x**2,
        ],
        axis=-1,
    )
    ddS = np.stack(
        [(-6 + 12 * x) / le**2, (-4 + 6 * x) / le, (6 - 12 * x) / le**2, (-2 + 6 * x) / le], axis=-1
    )
    return S, dS, ddS


#: Composite Gauss-Legendre rule on [0, 1] for the arc-length integrals of the initial shape.
_ARC_PANELS = 8
_ARC_X, _ARC_W = np.polynomial.legendre.leggauss(16)


def _arc_rule(upper: float) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights integrating over [0, upper] (composite Gauss, exact to round-off for
    the smooth integrands of ``_bent_rod``)."""
    edges = np.linspace(0.0, upper, _ARC_PANELS + 1)
    half = 0.5 * np.diff(edges)[:, None]
    x = (edges[:-1, None] + half * (_ARC_X + 1.0)).ravel()
    return x, (half * _ARC_W).ravel()


def _bent_rod(alpha: float, beta: float, l: float, elements: int):
    """One rod bent into the assumed shape with end tangent angles alpha, beta (rad) to its
    chord and arc length exactly l, in its chord frame (x along the chord from the root).

    The curve is y = eta(x) = X (ta sig(xi) + tb tau(xi)), xi = x / X, sig = xi (1 - xi)^2,
    tau = -xi^2 (1 - xi), ta = tan(alpha), tb = tan(beta): the paper's shape functions on a
    chord of length X, with end slopes whose angles are alpha and beta exactly. X = l / c with
    c = int_0^1 sqrt(1 + g^2) dxi, g = eta'(x) (g depends on xi only), so the arc length is l.
    Beam node j (of elements + 1) sits at arc length j l / elements.

    Returns positions p (E+1, 2), unit tangents t (E+1, 2), and their derivatives with
    respect to alpha and beta: dp (2, E+1, 2), dt (2, E+1, 2)."""
    if not (abs(alpha) < 0.5 * math.pi and abs(beta) < 0.5 * math.pi):
        raise ValueError(
            f"initial alpha and beta must lie in (-pi/2, pi/2), got {alpha!r}, {beta!r}"
        )
    ta, tb = math.tan(alpha), math.tan(beta)

    def g(xi):
        return ta * (1 - xi) * (1 - 3 * xi) - tb * xi * (2 - 3 * xi)

    def gp(xi):  # dg/dta, dg/dtb
        return np.stack([(1 - xi) * (1 - 3 * xi), -xi * (2 - 3 * xi)])

    def w(xi):
        return np.sqrt(1.0 + g(xi) ** 2)

    x1, w1 = _arc_rule(1.0)
    c = float(np.sum(w1 * w(x1)))
    dc = np.sum(w1 * g(x1) * gp(x1) / w(x1), axis=-1)  # (2,)
    X = l / c
    dX = -l / c**2 * dc
    # arc-length positions of the beam nodes: int_0^xi w = (j / E) c, by Newton
    frac = np.arange(elements + 1) / elements
    xi = frac.copy()
    for _ in range(50):
        A = np.array([np.sum(wq * w(xq)) for xq, wq in map(_arc_rule, xi)])
        step = (A - frac * c) / w(xi)
        xi = np.clip(xi - step, 0.0, 1.0)
        if np.max(np.abs(step)) < 1e-15:
            break
    xi[0], xi[-1] = 0.0, 1.0
    dA = np.stack(
        [np.sum(wq * g(xq) * gp(xq) / w(xq), axis=-1) for xq, wq in map(_arc_rule, xi)], -1
    )
    dxi = (frac * dc[:, None] - dA) / w(xi)  # (2, E+1)
    dxi[:, 0] = dxi[:, -1] = 0.0
    sig, tau = xi * (1 - xi) ** 2, -(xi**2) * (1 - xi)
    eta_hat = ta * sig + tb * tau
    gj, wj = g(xi), w(xi)
    dg_dxi = ta * (-4 + 6 * xi) + tb * (-2 + 6 * xi)
    p = np.stack([X * xi, X * eta_hat], -1)
    t = np.stack([1.0 / wj, gj / wj], -1)
    dp = np.empty((2, elements + 1, 2))
    dt = np.empty((2, elements + 1, 2))
    for i, (shape, dtan) in enumerate(((sig, 1.0 + ta**2), (tau, 1.0 + tb**2))):
        dp_i = dX[i] * np.stack([xi, eta_hat], -1) + X * np.stack(
            [dxi[i], gj * dxi[i] + shape], -1
        )  # per unit d(tan)
        dgj = gp(xi)[i] + dg_dxi * dxi[i]
        dt_i = np.stack([-gj / wj**3, 1.0 / wj**3], -1) * dgj[:, None]
        dp[i], dt[i] = dp_i * dtan, dt_i * dtan  # per unit angle
    return p, t, dp, dt


def _initial_node_states(scene: Scene, elements: int):
    """Reference coordinates (straight rods along the initial chords) and initial coordinate
    offsets and velocities of every beam node, per rod: arrays (n, elements+1, 4) with
    [x, y, slope_x, slope_y] (m, m, -, -) and their rates.

    Each rod starts on the bent curve of ``_bent_rod``: arc length exactly l, nodes at equal
    arc-length spacing and slopes equal to the unit tangents, so the axial strain is zero at
    the nodes (the Hermite interpolation between them departs from it at the order of the
    fourth power of curvature x element length); the chord points along phi_k, the end
    tangents at phi_k + alpha_k and phi_k + beta_k. The velocities are those of the same
    curve moving with dphi (rigid rotation about the rod's root), dalpha and dbeta (shape
    rates, with the chord length following the constant arc length)."""
    chain, ini = scene.chain, scene.initial.resolve(scene.n)
    n, l = chain.n, chain.l
    phi, dphi = ini["phi"], ini["dphi"]
    J = np.array([[0.0, -1.0], [1.0, 0.0]])
    root, root_vel = np.zeros(2), np.zeros(2)
    s = np.linspace(0.0, 1.0, elements + 1)
    ref = np.empty((n, elements + 1, 4))
    cur = np.empty((n, elements + 1, 4))
    vel = np.empty((n, elements + 1, 4))
    for k in range(n):
        p, t, dp, dt = _bent_rod(
            float(ini["alpha"][k]), float(ini["beta"][k]), float(l[k]), elements
        )
        c, sn = math.cos(phi[k]), math.sin(phi[k])
        R = np.array([[c, -sn], [sn, c]])
        e = R[:, 0]
        ref[k, :, :2] = root + s[:, None] * l[k] * e
        ref[k, :, 2:] = e
        cur[k, :, :2] = root + p @ R.T
        cur[k, :, 2:] = t @ R.T
        dp_rate = ini["dalpha"][k] * dp[0] + ini["dbeta"][k] * dp[1]
        dt_rate = ini["dalpha"][k] * dt[0] + ini["dbeta"][k] * dt[1]
        vel[k, :, :2] = root_vel + dphi[k] * p @ (R @ J).T + dp_rate @ R.T
        vel[k, :, 2:] = dphi[k] * t @ (R @ J).T + dt_rate @ R.T
        root, root_vel = cur[k, -1, :2].copy(), vel[k, -1, :2].copy()
    return ref, cur - ref, vel


@dataclass
class _Built:
    """An assembled exudyn system and the sensor ids needed for the scene's outputs."""

    SC: Any
    mbs: Any
    node_sensors: dict[tuple[int, int], tuple[int, int, int]]  # (rod, local node) -> (q, v, a)
    load_errors: list
    nodes: list | None = None  # beam node numbers per rod
    initial: tuple | None = None  # _initial_node_states: ref, offsets, velocities
    latch_joints: dict | None = None  # hinge -> exudyn object number of its locking joint


class ExudynModel(Model):
    """The chain as ANCF cable beams in exudyn (independent of the paper's equations).

    Options (validated on construction; defaults in ``DEFAULTS``):

    elements : int >= 1
        ANCF cable elements per rod.
    step : float in (0, 0.1] s
        Fixed time step (the run uses ceil(t_end / step) equal steps).
    EA : float in (0, 1e14] N
        Axial stiffness standing in for inextensibility.
    element : "cable2d"
        ObjectANCFCable2D (the geometrically exact 2D beam did not earn its place: see
        docs/reference_model.md).
    solver : "generalized-alpha" or "trapezoidal"
        exudyn's implicit integrator (trapezoidal = Newmark beta 1/4, index-2 constraints).
    spectral_radius : float in [0, 1]
        Generalized-alpha numerical damping at infinite frequency (1 = none).
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
    Divergence is detected during the run (``_Guard``): a non-finite state ends it as
    STATUS_DIVERGED, kinetic energy above ``settings.blowup_factor`` x (E(0) + W+(t) + 1e-6 J)
    as STATUS_BLOWUP, both at the time of detection with the output times before it kept.
    """

    name = "exudyn"
    OPTIONS = tuple(DEFAULTS)
    #: exudyn integrates with its own options: rodval's integrator settings do not apply.
    USES_INTEGRATOR_SETTINGS = False

    def __init__(
        self,
        *,
        elements: int = DEFAULTS["elements"],
        step: float = DEFAULTS["step"],
        EA: float = DEFAULTS["EA"],
        element: str = DEFAULTS["element"],
        solver: str = DEFAULTS["solver"],
        spectral_radius: float = DEFAULTS["spectral_radius"],
        newton_rtol: float = DEFAULTS["newton_rtol"],
        newton_atol_per_EA: float = DEFAULTS["newton_atol_per_EA"],
        max_rotation_per_step: float = DEFAULTS["max_rotation_per_step"],
        **unknown,
    ):
        if unknown:
            raise ValueError(_unknown_options_message(unknown))
        self.elements = _positive("elements", elements, integer=True)
        self.step = _positive("step", step, upper=0.1)
        self.EA = _positive("EA", EA, upper=1e14)
        if element not in ELEMENTS:
            raise ValueError(f"element must be one of {ELEMENTS}, got {element!r}")
        self.element = element
        if solver not in SOLVERS:
            raise ValueError(f"solver must be one of {SOLVERS}, got {solver!r}")
        self.solver = solver
        if (
            isinstance(spectral_radius, bool)
            or not isinstance(spectral_radius, (int, float))
            or not 0 <= spectral_radius <= 1
        ):
            raise ValueError(f"spectral_radius must be a number in [0, 1], got {spectral_radius!r}")
        self.spectral_radius = float(spectral_radius)
        self.newton_rtol = _positive("newton_rtol", newton_rtol, upper=1e-2)
        self.newton_atol_per_EA = _positive("newton_atol_per_EA", newton_atol_per_EA, upper=1e-6)
        self.max_rotation_per_step = _positive(
            "max_rotation_per_step", max_rotation_per_step, upper=math.pi
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
    def _build(self, scene: Scene) -> _Built:
        import exudyn as exu
        from exudyn.itemInterface import (
            LoadForceVector,
            MarkerBodyPosition,
            MarkerBodyRigid,
            MarkerNodePosition,
            NodeGenericData,
            NodePoint2DSlope1,
            ObjectANCFCable2D,
            ObjectConnectorTorsionalSpringDamper,
            ObjectGround,
            ObjectJointGeneric,
            ObjectJointRevolute2D,
            ObjectMassPoint2D,
            SensorNode,
        )

        chain, E = scene.chain, self.elements
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        ground = mbs.AddObject(ObjectGround())
        ref, q0, v0 = _initial_node_states(scene, E)
        nodes, elems = [], []
        for k in range(chain.n):
            nodes.append(
                [
                    mbs.AddNode(
                        NodePoint2DSlope1(
                            referenceCoordinates=ref[k, j].tolist(),
                            initialCoordinates=q0[k, j].tolist(),
                            initialVelocities=v0[k, j].tolist(),
                        )
                    )
                    for j in range(E + 1)
                ]
            )
            le = float(chain.l[k]) / E
            elems.append(
                [
                    mbs.AddObject(
                        ObjectANCFCable2D(
                            nodeNumbers=[nodes[k][j], nodes[k][j + 1]],
                            length=le,
                            massPerLength=float(chain.m[k]),
                            bendingStiffness=float(chain.EI[k]),
                            axialStiffness=self.EA,
                        )
                    )
                    for j in range(E)
                ]
            )
        # hinges: position joint + torsional spring-damper on the end tangents (relaxed at the
        # rest angle: exudyn's ``offset``); limit stops: a second torsional spring-damper with a
        # one-sided user law; latches: a rotation-locking ObjectJointGeneric, inactive until
        # the pre-step function (``_Latches``) switches it on
        ini = scene.initial.resolve(chain.n)
        tangent_left = ini["phi"] + ini["alpha"]
        tangent_right = ini["phi"] + ini["beta"]
        latch_of = {latch.hinge: latch for latch in scene.latches}
        stops_of: dict[int, list] = {}
        for stop in scene.stops:
            stops_of.setdefault(stop.hinge, []).append(stop)
        latch_joints: dict[int, int] = {}
        for k in range(chain.n):
            if k == 0:
                pos0 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground))
                rot0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground))
                angle0 = tangent_left[0]
            else:
                pos0 = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[k - 1][-1]))
                rot0 = mbs.AddMarker(
                    MarkerBodyRigid(
                        bodyNumber=elems[k - 1][-1], localPosition=[chain.l[k - 1] / E, 0, 0]
                    )
                )
                angle0 = tangent_left[k] - tangent_right[k - 1]
            pos1 = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[k][0]))
            mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[pos0, pos1]))
            rot1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=elems[k][0], localPosition=[0, 0, 0]))
            springs = [(float(chain.kappa[k]), float(chain.nu[k]), float(chain.rest_angle[k]), 0)]
            springs += [
                (stop.stiffness, stop.damping, stop.angle, _stop_law(stop.side))
                for stop in stops_of.get(k, [])
            ]
            for stiffness, damping, offset, law in springs:
                if stiffness == 0 and damping == 0:
                    continue
                turns = mbs.AddNode(
                    NodeGenericData(
                        numberOfDataCoordinates=1, initialCoordinates=[_revolutions(angle0)]
                    )
                )
                mbs.AddObject(
                    ObjectConnectorTorsionalSpringDamper(
                        markerNumbers=[rot0, rot1],
                        nodeNumber=turns,
                        stiffness=stiffness,
                        damping=damping,
                        offset=offset,
                        springTorqueUserFunction=law,
                    )
                )
            if k in latch_of:
                # joint frame 1 = marker 1 turned back by the latch angle: the joint's locked
                # relative rotation is D_k = angle (locally unique)
                a = float(latch_of[k].angle)
                c, sn = math.cos(-a), math.sin(-a)
                latch_joints[k] = mbs.AddObject(
                    ObjectJointGeneric(
                        markerNumbers=[rot0, rot1],
                        constrainedAxes=[0, 0, 0, 0, 0, 1],
                        rotationMarker1=[[c, -sn, 0.0], [sn, c, 0.0], [0.0, 0.0, 1.0]],
                        activeConnector=False,
                    )
                )
        for k in range(chain.n):
            if chain.mu[k] > 0:
                mbs.AddObject(ObjectMassPoint2D(nodeNumber=nodes[k][-1], mass=float(chain.mu[k])))
        load_errors: list = []
        for f in scene.loads:
            marker = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[f.node - 1][-1]))
            mbs.AddLoad(
                LoadForceVector(
                    markerNumber=marker,
                    loadVector=[0, 0, 0],
                    loadVectorUserFunction=_load_function(f, load_errors),
                )
            )
        # sensors on the beam nodes the outputs need
        wanted = set()
        if scene.wants("phi", "dphi", "alpha", "beta", "x", "y", "hinge_angle", "hinge_moment"):
            wanted |= {(k, 0) for k in range(chain.n)} | {(k, E) for k in range(chain.n)}
        if scene.wants("energy", "angular_momentum") or scene.latches:
            wanted |= {(k, j) for k in range(chain.n) for j in range(E + 1)}
        ovt = exu.OutputVariableType
        node_sensors = {
            key: tuple(
                mbs.AddSensor(
                    SensorNode(
                        nodeNumber=nodes[key[0]][key[1]],
                        storeInternal=True,
                        writeToFile=False,
                        outputVariableType=v,
                    )
                )
                for v in (ovt.CoordinatesTotal, ovt.Coordinates_t, ovt.Coordinates_tt)
            )
            for key in sorted(wanted)
        }
        mbs.Assemble()
        return _Built(SC, mbs, node_sensors, load_errors, nodes, (ref, q0, v0), latch_joints)

    def _settings(self, t_end: float):
        import exudyn as exu

        s = exu.SimulationSettings()
        ti = s.timeIntegration
        nsteps = max(1, math.ceil(t_end / self.step - 1e-9))
        ti.endTime = t_end
        ti.numberOfSteps = nsteps
        ti.initialStepSize = t_end / nsteps
        ti.automaticStepSize = False
        ti.adaptiveStep = True
        ti.minimumStepSize = ti.initialStepSize / 64.0  # fail fast instead of crawling
        ti.verboseMode = 0
        ti.verboseModeFile = 0
        ti.newton.relativeTolerance = self.newton_rtol
        ti.newton.absoluteTolerance = self.newton_atol_per_EA * self.EA
        ti.generalizedAlpha.spectralRadius = self.spectral_radius
        s.solution.file.write = False
        s.solution.sensors.writePeriod = 0.25 * t_end / nsteps
        s.show.statistics = False
        s.show.computationTime = False
        s.show.globalTimers = False
        s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
        return s

    # -- run -----------------------------------------------------------------------------------
    @staticmethod
    def check_settings(settings: IntegratorSettings | None) -> None:
        """Refuse native integrator settings exudyn cannot honour: ValueError naming the first
        field of ``NATIVE_INTEGRATOR_FIELDS`` that differs from ``IntegratorSettings()``.
        (``blowup_factor`` is honoured: it sets the blow-up check.)"""
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
        if self.spectral_radius > self.LATCH_MAX_SPECTRAL_RADIUS:
            raise ValueError(
                f"scenes with latches need spectral_radius <= {self.LATCH_MAX_SPECTRAL_RADIUS} "
                f"(0 recommended), got {self.spectral_radius}: with less numerical damping the "
                "locked hinge's relative rate oscillates from step to step after the lock"
            )

    def run(self, scene: Scene, settings: IntegratorSettings | None = None) -> Trajectory:
        """Run the scene. Of the native integrator ``settings`` only ``blowup_factor`` applies;
        any other non-default field raises ValueError before any work (``check_settings``): the
        exudyn integrator is set by this model's options, recorded in ``trajectory.settings``
        with the steps actually taken."""
        import exudyn as exu

        self.check_settings(settings)
        self.check_scene(scene)
        factor = (settings or IntegratorSettings()).blowup_factor
        stats = SolverStats()
        run_info: dict[str, Any] = {"blowup_factor": factor}
        try:
            built = self._build(scene)
            sim = self._settings(scene.t_end)
            guard = _Guard(built, scene, self.elements, self.EA, factor, self.max_rotation_per_step)
        except Exception as exc:  # noqa: BLE001 - a failed build is data
            status, message = numerical_failure(exc, 0.0) or (
                STATUS_ERROR,
                f"{type(exc).__name__}: {exc}",
            )
            stats.status, stats.message = status, f"build failed: {message}"
            return self._trajectory(scene, np.empty(0), {}, stats, run_info)
        ti = sim.timeIntegration
        run_info.update(steps_planned=int(ti.numberOfSteps), step_used=float(ti.initialStepSize))
        solver = exu.MainSolverImplicitSecondOrder()
        guard.solver = solver
        latches = _Latches(built, guard, scene, self.elements) if scene.latches else None

        def pre_step(mbs, t):
            go = guard.pre_step(mbs, t)
            if latches is not None and go:
                try:
                    latches.pre_step(t, float(solver.it.currentStepSize))
                except Exception as exc:  # noqa: BLE001 - reported as data, the run stops
                    guard.verdict = (
                        STATUS_ERROR,
                        f"latch handling failed at t = {t:.6g} s: {type(exc).__name__}: {exc}",
                        t,
                        True,
                    )
                    return False
            return go

        built.mbs.SetPreStepUserFunction(pre_step)
        if self.solver == "trapezoidal":
            sim.timeIntegration.generalizedAlpha.useNewmark = True
            sim.timeIntegration.generalizedAlpha.useIndex2Constraints = True
        console = exu.config.printToConsole
        exu.config.printToConsole = False
        start = time.perf_counter()
        try:
            ok = solver.SolveSystem(built.mbs, sim)
            if not ok:
                stats.status, stats.message = (
                    STATUS_FAILED,
                    _solver_message(solver, "solver failed"),
                )
            elif guard.verdict is None:  # the last step's end state has had no pre-step check
                guard.check(scene.t_end)
        except Exception as exc:  # noqa: BLE001 - exudyn errors come back as data
            stats.status = STATUS_ERROR
            cause = built.load_errors[0] if built.load_errors else exc
            stats.message = f"{type(cause).__name__}: {cause}"
        finally:
            stats.wall_s = time.perf_counter() - start
            exu.config.printToConsole = console
        stats.nsteps = max(int(solver.it.currentStepIndex) - 1, 0)  # the index ends one past
        stats.njev = int(solver.it.newtonJacobiCount)
        stats.nfev = int(solver.it.newtonStepsCount)
        run_info.update(
            steps=stats.nsteps,
            min_step_used=guard.min_step if math.isfinite(guard.min_step) else None,
            max_rotation_per_step_seen=guard.max_rotation_seen,
        )
        try:
            t_rec, records, diverged = self._records(built)
        except Exception as exc:  # noqa: BLE001
            stats.status, stats.message = STATUS_ERROR, f"reading sensors failed: {exc}"
            return self._trajectory(scene, np.empty(0), {}, stats, run_info)
        stats.t_reached = float(t_rec[-1]) if t_rec.size else 0.0
        keep_detected = True
        if guard.verdict is not None and stats.status != STATUS_ERROR:
            # the guard's verdict explains a solver failure that may follow it
            stats.status, stats.message, t_detected, keep_detected = guard.verdict
            stats.t_reached = min(stats.t_reached, t_detected) if t_rec.size else 0.0
        if stats.status == 0 and stats.t_reached < scene.t_end * (1 - 1e-9):
            stats.status, stats.message = STATUS_FAILED, "solver stopped before t_end"
        if stats.status == STATUS_FAILED and diverged and guard.verdict is None:
            stats.status = STATUS_DIVERGED
            stats.message = f"non-finite state after t = {stats.t_reached:.6g} s"
        if stats.status == 0:
            stats.message = "reached t_end"
        times = np.asarray(scene.times)
        tol = 1e-9 * max(1.0, scene.t_end)
        if not t_rec.size:
            times = t_rec
        elif keep_detected:
            times = times[times <= stats.t_reached + tol]
        else:  # the state at the detection time is the bad one: keep the times before it
            times = times[times < stats.t_reached - tol]
        if latches is not None:
            try:
                latches.close()
            except Exception:  # noqa: BLE001 - the pending locks stay unrecorded
                pass
        events = sorted(latches.events, key=lambda ev: ev["t"]) if latches is not None else []
        lock_steps = {}
        if latches is not None:
            lock_steps = {k: t for k, t in latches.lock_times.items()}
        try:
            observed = (
                _observe(scene, self.elements, self.EA, times, t_rec, records, lock_steps)
                if times.size
                else {}
            )
        except Exception as exc:  # noqa: BLE001
            stats.status, stats.message = (
                STATUS_ERROR,
                f"observation failed: {type(exc).__name__}: {exc}",
            )
            return self._trajectory(scene, np.empty(0), {}, stats, run_info)
        return self._trajectory(scene, times, observed, stats, run_info, events)

    def validity_checks(self, scene: Scene, trajectory: Trajectory) -> list[Check]:
        """The energy balance (where audited) and the time-step resolution: the largest rod
        rotation per step seen against ``max_rotation_per_step`` (the beam itself is
        geometrically exact: no small-bending assumption)."""
        seen = trajectory.settings.get("max_rotation_per_step_seen")
        return super().validity_checks(scene, trajectory) + step_resolution(
            seen, self.max_rotation_per_step
        )

    def _records(self, built: _Built):
        """Recorded times (s); per (rod, local node), arrays q, v, a (nt, 4) up to the first
        non-finite record; whether a non-finite record was cut off."""
        mbs = built.mbs
        data = {
            key: tuple(mbs.GetSensorStoredData(s) for s in ids)
            for key, ids in built.node_sensors.items()
        }
        first = next(iter(data.values()))[0]
        if first.ndim != 2 or first.shape[0] == 0:
            return np.empty(0), {}, False
        t = first[:, 0]
        # keep one record per time (the solver may write the last step twice)
        keep = np.concatenate([np.diff(t) > 0, [True]])
        finite = np.ones(keep.sum(), bool)
        out = {}
        for key, arrs in data.items():
            q, v, a = (arr[keep, 1:] for arr in arrs)
            finite &= np.isfinite(q).all(1) & np.isfinite(v).all(1) & np.isfinite(a).all(1)
            out[key] = (q, v, a)
        bad = np.flatnonzero(~finite)
        end = bad[0] if bad.size else finite.size
        t = t[keep][:end]
        return t, {key: tuple(x[:end] for x in arrs) for key, arrs in out.items()}, bool(bad.size)

    def _trajectory(self, scene, times, observed, stats, run_info=None, events=()) -> Trajectory:
        """``settings``: the integrator, every option, and what the run used (``run_info``:
        steps_planned, step_used (s, the fixed step), steps (taken), min_step_used (s, smaller
        than step_used only if Newton failures halved it), max_rotation_per_step_seen (rad),
        blowup_factor)."""
        return Trajectory(
            model=self.name,
            scene_name=scene.name,
            times=times,
            values={q: v for q, (v, _) in observed.items()},
            k_index={q: k for q, (_, k) in observed.items()},
            stats=stats,
            settings={"method": f"exudyn {self.solver}", "step": self.step, **(run_info or {})},
            options=self.options(),
            events=[dict(ev) for ev in events],
        )


class _Guard:
    """Divergence and resolution checks of one run, on every accepted step (exudyn's
    PreStepUserFunction: called before each step with t = the end of the coming step, on the
    state of the last accepted step, at t - step). A verdict stops the solver after the coming
    step; ``verdict`` is then (status, message, time of the checked state, whether output times
    at that time are kept).

    * non-finite coordinates or velocities: STATUS_DIVERGED;
    * kinetic energy T = v^T M v / 2 (consistent mass of the cubic elements plus the point
      masses; the hinge data nodes carry no mass) above ``factor`` x the budget of
      ``rodval.solvers.guard`` (``GuardSpec``, ``EnergyBudget``: W+ on the load power at the
      checked states), E(0) the initial T + Pi (``_energies``): STATUS_BLOWUP;
    * max_k |dphi_k| x step above ``max_rotation``: STATUS_FAILED (under-resolved)."""

    def __init__(
        self, built: _Built, scene: Scene, E: int, EA: float, factor: float, max_rotation: float
    ):
        mbs, chain = built.mbs, scene.chain
        ref, q0, v0 = built.initial
        self.mbs, self.solver = mbs, None
        self.max_rotation = float(max_rotation)
        size = mbs.systemData.ODE2Size()
        ltg = [
            [np.asarray(mbs.systemData.GetNodeLTGODE2(nd), int) for nd in rod]
            for rod in built.nodes
        ]
        self.ref = np.zeros(size)
        for k, rod in enumerate(ltg):
            for j, idx in enumerate(rod):
                self.ref[idx] = ref[k, j]
        self.M = np.zeros((size, size))  # dense: a 4 us product at n = 8, 2 elements/rod
        for k in range(chain.n):
            le = chain.l[k] / E
            s = 0.5 * le * (_GAUSS_X + 1.0)
            S = _hermite(s, le)[0]
            Me = chain.m[k] * np.einsum("g,gi,gj->ij", 0.5 * le * _GAUSS_W, S, S)  # (4, 4)
            for j in range(E):
                a, b = ltg[k][j], ltg[k][j + 1]
                dofs = np.array([a[:2], a[2:], b[:2], b[2:]])  # (4, 2)
                for c in range(2):
                    self.M[np.ix_(dofs[:, c], dofs[:, c])] += Me
            if chain.mu[k] > 0:
                tip = ltg[k][E][:2]
                self.M[tip, tip] += chain.mu[k]
        # chord vectors d = A q + d_ref (rows: x, y of rod 1, 2, ...)
        self.A = np.zeros((2 * chain.n, size))
        for k in range(chain.n):
            for c in range(2):
                self.A[2 * k + c, ltg[k][E][c]] += 1.0
                self.A[2 * k + c, ltg[k][0][c]] -= 1.0
        self.d_ref = self.A @ self.ref
        self.loads = [(f, ltg[f.node - 1][E][:2]) for f in scene.loads]
        ini = scene.initial.resolve(chain.n)
        at0 = {
            (k, j): ((ref + q0)[k, j][None], v0[k, j][None])
            for k in range(chain.n)
            for j in range(E + 1)
        }
        kin0, pot0 = _energies(
            scene, E, EA, at0, ini["phi"][None], ini["alpha"][None], ini["beta"][None]
        )
        self.spec = GuardSpec(blowup_factor=float(factor), energy0_J=float(kin0[0] + pot0[0]))
        self.energy = EnergyBudget(self.spec)
        self.verdict: tuple | None = None
        self.min_step, self.max_rotation_seen = math.inf, 0.0

    def _power(self, t: float, v: np.ndarray) -> float:
        p = 0.0
        for f, idx in self.loads:
            if f.active(t):
                fx = f.fx(t) if f.fx is not None else 0.0
                fy = f.fy(t) if f.fy is not None else 0.0
                p += fx * v[idx[0]] + fy * v[idx[1]]
        return p

    def pre_step(self, mbs, t: float) -> bool:
        h = float(self.solver.it.currentStepSize) if self.solver is not None else 0.0
        if h > 0:
            self.min_step = min(self.min_step, h)
        return self.check(t - h, h)

    def check(self, t: float, h: float = 0.0) -> bool:
        """Check the current state, at time t (s), before a step h (s); False stops the run."""
        if self.verdict is not None:
            return False
        try:
            sd = self.mbs.systemData
            q, v = sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t()
            if not math.isfinite(float(q @ q) + float(v @ v)):
                self.verdict = (STATUS_DIVERGED, diverged_message(t), t, False)
                return False
            if self.spec.checks_energy:
                p = self._power(t, v)
                if not math.isfinite(p):
                    self.verdict = (
                        STATUS_ERROR,
                        (f"a load is not finite at t = {t:.6g} s (load power {p!r} W)"),
                        t,
                        False,
                    )
                    return False
                blown = self.energy.check(t, p, 0.5 * float(v @ self.M @ v))
                if blown is not None:
                    self.verdict = (*blown, t, False)
                    return False
            if h > 0:
                d, dd = self.A @ q + self.d_ref, self.A @ v
                dx, dy, ddx, ddy = d[0::2], d[1::2], dd[0::2], dd[1::2]
                rate = np.abs(dx * ddy - dy * ddx) / (dx * dx + dy * dy)
                rot = float(rate.max()) * h
                self.max_rotation_seen = max(self.max_rotation_seen, rot)
                if rot > self.max_rotation:
                    k = int(rate.argmax()) + 1
                    self.verdict = (
                        STATUS_FAILED,
                        (
                            f"under-resolved: rod {k} turns by {rot:.3g} rad in one step of {h:.3g} s "
                            f"(|dphi| = {rate.max():.4g} rad/s) at t = {t:.6g} s, above "
                            f"max_rotation_per_step = {self.max_rotation:g} rad; reduce step"
                        ),
                        t,
                        True,
                    )
                    return False
        except Exception as exc:  # noqa: BLE001 - reported as data, the run stops
            status, message = numerical_failure(exc, t) or (
                STATUS_ERROR,
                f"divergence check failed at t = {t:.6g} s: {type(exc).__name__}: {exc}",
            )
            self.verdict = (status, message, t, True)
            return False
        return True


def _unknown_options_message(unknown: dict) -> str:
    names = ", ".join(repr(k) for k in sorted(unknown))
    return (
        f"unknown exudyn model option(s) {names}; allowed options: {', '.join(DEFAULTS)} "
        f"(defaults {DEFAULTS})"
    )


def _revolutions(angle: float) -> float:
    """Initial value of a torsional spring's revolution counter for a relative angle (rad)."""
    return float(round(angle / (2.0 * math.pi)))


def _stop_law(side: str):
    """springTorqueUserFunction of a one-sided limit stop (exudyn's sign: the returned torque
    is the spring's restoring torque, k (rotation - offset) for a plain spring): stiffness x
    penetration + damping x rate beyond the stop angle (``offset``), zero on the free side."""
    upper = side == "upper"

    def law(mbs, t, item, rotation, omega, stiffness, damping, offset):
        pen = rotation - offset
        if (pen > 0.0) if upper else (pen < 0.0):
            return stiffness * pen + damping * omega
        return 0.0

    return law


def stop_moment(stop, D, dD):
    """The moment (N m, same sign as a hinge spring's kappa (D - rest)) of a limit stop at
    hinge angle(s) D (rad) and rate(s) dD (rad/s): zero on the free side."""
    pen = np.asarray(D, float) - stop.angle
    inside = pen > 0 if stop.side == "upper" else pen < 0
    return np.where(inside, stop.stiffness * pen + stop.damping * np.asarray(dD, float), 0.0)


def _solver_message(solver, default: str) -> str:
    try:
        msg = solver.GetErrorString()
    except Exception:  # noqa: BLE001
        msg = ""
    return msg.strip() or default


def _load_function(f, errors: list):
    """exudyn load user function of a NodalForce: [X, Y, 0] (N) inside its support, zero
    (and not evaluated) outside; exceptions are recorded and re-raised."""
    fx, fy = f.fx, f.fy

    def user_function(mbs, t, load):
        if not f.active(t):
            return [0.0, 0.0, 0.0]
        try:
            return [fx(t) if fx is not None else 0.0, fy(t) if fy is not None else 0.0, 0.0]
        except Exception as exc:
            errors.append(exc)
            raise

    return user_function


def _interpolate(times: np.ndarray, t_rec: np.ndarray, y: np.ndarray, dy: np.ndarray) -> np.ndarray:
    """Cubic Hermite interpolation of records y (nt, m) with derivatives dy at ``times``;
    exact at recorded times."""
    i = np.clip(np.searchsorted(t_rec, times, side="right") - 1, 0, max(t_rec.size - 2, 0))
    if t_rec.size < 2:
        return np.repeat(y[:1], times.size, axis=0)
    h = (t_rec[i + 1] - t_rec[i])[:, None]
    th = ((times - t_rec[i])[:, None] / h).clip(0.0, 1.0)
    h00, h10 = 2 * th**3 - 3 * th**2 + 1, th**3 - 2 * th**2 + th
    h01, h11 = -2 * th**3 + 3 * th**2, th**3 - th**2
    return h00 * y[i] + h10 * h * dy[i] + h01 * y[i + 1] + h11 * h * dy[i + 1]


def _observe(
    scene: Scene,
    E: int,
    EA: float,
    times: np.ndarray,
    t_rec: np.ndarray,
    records: dict,
    lock_steps: dict | None = None,
):
    """The scene's quantities at ``times`` from recorded node states (see module docstring).

    "hinge_angle": D_k (k = 0..n-1) from the continuous tangent angles; "hinge_moment" (N m):
    the moment of hinge k, in the sense of its spring's kappa (D - rest): the spring, damper
    and stop laws at the measured D and dD while the hinge is free, and from the state
    where its latch was switched on (``lock_steps``: hinge -> time, s) the beam's own bending
    moment EI kappa_b at the root of rod k+1 (the hinge has no inertia: it transmits that
    moment), kappa_b the curvature of the cable's field there."""
    n = scene.n
    rods = np.arange(1, n + 1)
    at = {
        key: (_interpolate(times, t_rec, q, v), _interpolate(times, t_rec, v, a))
        for key, (q, v, a) in records.items()
    }
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    if not scene.wants(*QUANTITIES):
        return out
    left = [records[(k, 0)] for k in range(n)]
    right = [records[(k, E)] for k in range(n)]
    # chord angles on every recorded step, unwrapped in time from the initial phi
    chord_rec = np.stack([r[0][:, :2] - lft[0][:, :2] for lft, r in zip(left, right)], 1)
    raw_rec = np.arctan2(chord_rec[..., 1], chord_rec[..., 0])
    phi_rec = np.unwrap(raw_rec, axis=0)
    phi0 = scene.initial.resolve(n)["phi"]
    phi_rec += 2 * np.pi * np.round((phi0 - phi_rec[0]) / (2 * np.pi))
    i = np.clip(np.searchsorted(t_rec, times, side="right") - 1, 0, t_rec.size - 1)
    qL = np.stack([at[(k, 0)][0] for k in range(n)], 1)  # (nt, n, 4)
    qR = np.stack([at[(k, E)][0] for k in range(n)], 1)
    vL = np.stack([at[(k, 0)][1] for k in range(n)], 1)
    vR = np.stack([at[(k, E)][1] for k in range(n)], 1)
    d, dd = qR[..., :2] - qL[..., :2], vR[..., :2] - vL[..., :2]
    phi = phi_rec[i] + _wrap(np.arctan2(d[..., 1], d[..., 0]) - phi_rec[i])
    dphi = (d[..., 0] * dd[..., 1] - d[..., 1] * dd[..., 0]) / np.sum(d**2, -1)
    alpha = _wrap(np.arctan2(qL[..., 3], qL[..., 2]) - phi)
    beta = _wrap(np.arctan2(qR[..., 3], qR[..., 2]) - phi)
    for name, val in (("phi", phi), ("dphi", dphi), ("alpha", alpha), ("beta", beta)):
        if scene.wants(name):
            out[name] = (val, rods)
    if scene.wants("x", "y"):
        nodes = np.arange(0, n + 1)
        x = np.concatenate([qL[:, :1, 0], qR[..., 0]], 1)
        y = np.concatenate([qL[:, :1, 1], qR[..., 1]], 1)
        if scene.wants("x"):
            out["x"] = (x, nodes)
        if scene.wants("y"):
            out["y"] = (y, nodes)
    if scene.wants("hinge_angle", "hinge_moment"):
        hinges = np.arange(n)
        left = np.concatenate([np.zeros((phi.shape[0], 1)), (phi + beta)[:, :-1]], 1)
        D = (phi + alpha) - left

        def rate(q, v):
            return (q[..., 2] * v[..., 3] - q[..., 3] * v[..., 2]) / (
                q[..., 2] ** 2 + q[..., 3] ** 2
            )

        rate_left = rate(qL, vL)
        rate_right = np.concatenate([np.zeros((phi.shape[0], 1)), rate(qR, vR)[:, :-1]], 1)
        dD = rate_left - rate_right
        if scene.wants("hinge_angle"):
            out["hinge_angle"] = (D, hinges)
        if scene.wants("hinge_moment"):
            chain = scene.chain
            M = chain.kappa * (D - chain.rest_angle) + chain.nu * dD
            for stop in scene.stops:
                M[:, stop.hinge] += stop_moment(stop, D[:, stop.hinge], dD[:, stop.hinge])
            for k, t_on in (lock_steps or {}).items():
                after = times >= t_on - 1e-12
                if not after.any():
                    continue
                le = chain.l[k] / E
                ddS = _hermite(np.zeros(1), le)[2][0]  # (4,) at s = 0
                dS = _hermite(np.zeros(1), le)[1][0]
                qa, qb = at[(k, 0)][0], at[(k, 1)][0]
                Q = np.stack([qa[:, :2], qa[:, 2:], qb[:, :2], qb[:, 2:]], 1)  # (nt, 4, 2)
                r1 = np.einsum("i,tic->tc", dS, Q)
                r2 = np.einsum("i,tic->tc", ddS, Q)
                curv = (r1[:, 0] * r2[:, 1] - r1[:, 1] * r2[:, 0]) / np.sum(r1**2, -1)
                M[after, k] = chain.EI[k] * curv[after]
            out["hinge_moment"] = (M, hinges)
    if scene.wants("energy"):
        kin, pot = _energies(scene, E, EA, at, phi, alpha, beta)
        zero = np.zeros(1, dtype=int)
        out["kinetic"] = (kin[:, None], zero)
        out["potential"] = (pot[:, None], zero)
        out["energy"] = ((kin + pot)[:, None], zero)
    if scene.wants("angular_momentum"):
        out["angular_momentum"] = (_angular_momentum(scene.chain, E, at), np.arange(2))
    return out


def _elements(chain, E: int, at: dict):
    """Per element j of every rod k, with the Gauss points of ``_GAUSS_X`` on it: (k, weights
    (g,) (m), shape functions S, dS, ddS (g, 4), nodal positions/slopes Q and their rates V
    (nt, 4, 2)) from the node states ``at`` at the output times."""
    for k in range(chain.n):
        le = chain.l[k] / E
        w = 0.5 * le * _GAUSS_W
        S, dS, ddS = _hermite(0.5 * le * (_GAUSS_X + 1.0), le)
        for j in range(E):
            qa, va = at[(k, j)]
            qb, vb = at[(k, j + 1)]
            Q = np.stack([qa[:, :2], qa[:, 2:], qb[:, :2], qb[:, 2:]], 1)
            V = np.stack([va[:, :2], va[:, 2:], vb[:, :2], vb[:, 2:]], 1)
            yield k, w, S, dS, ddS, Q, V


def _energies(
    scene: Scene, E: int, EA: float, at: dict, phi, alpha, beta
) -> tuple[np.ndarray, np.ndarray]:
    """Kinetic and potential energy (J) per output time: beam kinetic, bending (EI kappa^2/2),
    axial (EA eps^2/2, EA of the run), point masses and hinge springs (kappa D^2/2 with the
    continuous tangent angles phi + alpha, phi + beta)."""
    chain = scene.chain
    kin = np.zeros(phi.shape[0])
    pot = np.zeros(phi.shape[0])
    for k, w, S, dS, ddS, Q, V in _elements(chain, E, at):
        r_t = np.einsum("gi,tic->tgc", S, V)
        r1 = np.einsum("gi,tic->tgc", dS, Q)
        r2 = np.einsum("gi,tic->tgc", ddS, Q)
        norm2 = np.sum(r1**2, -1)
        curv = (r1[..., 0] * r2[..., 1] - r1[..., 1] * r2[..., 0]) / norm2
        strain = np.sqrt(norm2) - 1.0
        kin += 0.5 * chain.m[k] * np.sum(w * np.sum(r_t**2, -1), -1)
        pot += 0.5 * np.sum(w * (chain.EI[k] * curv**2 + EA * strain**2), -1)
    for k in range(chain.n):
        vt = at[(k, E)][1][:, :2]
        kin += 0.5 * chain.mu[k] * np.sum(vt**2, -1)
    left = np.concatenate([np.zeros((phi.shape[0], 1)), (phi + beta)[:, :-1]], 1)
    D = (phi + alpha) - left
    pot += 0.5 * np.sum(chain.kappa * (D - chain.rest_angle) ** 2, -1)
    for stop in scene.stops:
        pen = D[:, stop.hinge] - stop.angle
        inside = pen > 0 if stop.side == "upper" else pen < 0
        pot += np.where(inside, 0.5 * stop.stiffness * pen**2, 0.0)
    return kin, pot


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _angular_momentum(chain, E: int, at: dict) -> np.ndarray:
    """The ``angular_momentum`` rows (nt, 2) (N m s, counter-clockwise positive) of the beam
    field (see rodval.core.scene.QUANTITIES): k = 0 about the root node,
    H_0 = sum int (r - r_0) x r_t dm (the rods' mass on the beam's reference arc length, the
    node masses at the rod ends; 5 Gauss points per element integrate the degree-6 integrand
    exactly), k = 1 about the centre of mass, H_0 - (S x P) / M."""
    root = at[(0, 0)][0][:, None, :2]  # (nt, 1, 2)
    H0 = np.zeros(root.shape[0])
    P = np.zeros((root.shape[0], 2))
    first = np.zeros((root.shape[0], 2))
    for k, w, S, _, _, Q, V in _elements(chain, E, at):
        r = np.einsum("gi,tic->tgc", S, Q) - root
        v = np.einsum("gi,tic->tgc", S, V)
        H0 += chain.m[k] * np.sum(w * _cross(r, v), -1)
        P += chain.m[k] * np.einsum("g,tgc->tc", w, v)
        first += chain.m[k] * np.einsum("g,tgc->tc", w, r)
    for k in range(chain.n):
        r = at[(k, E)][0][:, :2] - root[:, 0]
        v = at[(k, E)][1][:, :2]
        H0 += chain.mu[k] * _cross(r, v)
        P += chain.mu[k] * v
        first += chain.mu[k] * r
    total = float(np.sum(chain.m * chain.l + chain.mu))
    return np.stack([H0, H0 - _cross(first, P) / total], -1)


#: Steps after the activation step at which a lock's "after" state is taken (the index-3
#: constraint brings the relative rate to zero within the activation step; the extra steps let
#: the generalized-alpha velocity transient settle; see docs/deployment.md).
LOCK_SETTLE_STEPS = 2


class _Latches:
    """The latches of one run, driven from exudyn's PreStepUserFunction (state of the last
    accepted step, at t - h, before the step to t).

    Each latch's hinge angle D = (tangent angle of rod k+1's root) - (tangent angle of rod k's
    end) is measured on the beam nodes' slopes, continuous in time from the scene's initial D,
    with its rate and acceleration. The latch's ObjectJointGeneric (relative rotation locked
    at the latch angle) is switched on before the step in which D reaches the angle: when D
    is already past it, or its second-order Taylor extrapolation D + dD h + ddD h^2 / 2 passes
    it within the coming step. The lock time is where D crosses the angle: the root of that
    extrapolation within the coming step, or of the cubic Hermite interpolant between the last
    two states when D is already past (bracketed between steps either way).

    Measures of each lock, on the beam solution: the kinetic energy v^T M v / 2 of the whole
    chain (consistent mass), the angular momentum about the root (node 0) and the angular
    momentum H_k of the outboard part (rods k+1..n and their node masses) about the hinge node
    k, just before the activation step and ``LOCK_SETTLE_STEPS`` steps after it. The angular
    impulse of the latch on the outboard part is
    S = H_k(after) - H_k(before) - int M_k dt, with M_k the finite moments on the outboard part
    about the moving hinge node (hinge k's spring, damper and stops, the outboard loads, and
    -v_P x p of the moving reference point), integrated by the trapezoid rule: the jump of the
    relative angular momentum (N m s, counter-clockwise positive on rod k+1)."""

    def __init__(self, built: _Built, guard: _Guard, scene: Scene, E: int):
        self.mbs, self.guard, self.scene, self.E = built.mbs, guard, scene, E
        chain, n = scene.chain, scene.n
        sd = built.mbs.systemData
        ltg = [[np.asarray(sd.GetNodeLTGODE2(nd), int) for nd in rod] for rod in built.nodes]
        self.ltg = ltg
        size = guard.ref.size
        D0 = scene.initial_hinge_angles()
        self.items = []
        for latch in scene.latches:
            k = latch.hinge
            direction = latch.direction or int(np.sign(latch.angle - D0[k]))
            self.items.append(
                {
                    "latch": latch,
                    "k": k,
                    "dir": direction,
                    "joint": built.latch_joints[latch.hinge],
                    "left": None if k == 0 else ltg[k - 1][E][2:],
                    "right": ltg[k][0][2:],
                    "D": float(D0[k]),
                    "state": "armed",
                }
            )
        # quadrature points of every rod (5 Gauss points per element) and the node masses:
        # position rows Gx, Gy (points x size), weights (kg), rod of each point
        rows_x, rows_y, wts, rod_of = [], [], [], []
        for k in range(n):
            le = chain.l[k] / E
            sg = 0.5 * le * (_GAUSS_X + 1.0)
            S = _hermite(sg, le)[0]
            for j in range(E):
                a, b = ltg[k][j], ltg[k][j + 1]
                dofs = np.array([a[:2], a[2:], b[:2], b[2:]])  # (4, 2)
                for g in range(sg.size):
                    for rows, c in ((rows_x, 0), (rows_y, 1)):
                        r = np.zeros(size)
                        r[dofs[:, c]] = S[g]
                        rows.append(r)
                    wts.append(chain.m[k] * 0.5 * le * _GAUSS_W[g])
                    rod_of.append(k)
            if chain.mu[k] > 0:
                for rows, c in ((rows_x, 0), (rows_y, 1)):
                    r = np.zeros(size)
                    r[ltg[k][E][c]] = 1.0
                    rows.append(r)
                wts.append(chain.mu[k])
                rod_of.append(k)
        self.Gx, self.Gy = np.array(rows_x), np.array(rows_y)
        self.w, self.rod_of = np.array(wts), np.array(rod_of)
        self.loads = [(f, ltg[f.node - 1][E][:2], f.node) for f in scene.loads]
        self.stops = {}
        for stop in scene.stops:
            self.stops.setdefault(stop.hinge, []).append(stop)
        self.root = {"left": None, "right": ltg[0][0][2:], "D": float(D0[0])}
        self.prev: dict | None = None
        self.pending: list[dict] = []
        self.events: list[dict] = []
        self.lock_times: dict[int, float] = {}
        self.step_count = 0
        self._cfg = None  # exudyn's configuration of the last accepted state (StartOfStep)

    # -- measures --------------------------------------------------------------------------
    def _state(self):
        import exudyn as exu

        sd, cfg = self.mbs.systemData, self._cfg
        if cfg is None:
            cfg = exu.ConfigurationType.StartOfStep
        q = np.asarray(sd.GetODE2Coordinates(cfg)) + self.guard.ref
        return (
            q,
            np.asarray(sd.GetODE2Coordinates_t(cfg)),
            np.asarray(sd.GetODE2Coordinates_tt(cfg)),
        )

    @staticmethod
    def _angle(q, v, a, idx):
        """Tangent angle (wrapped), its rate and acceleration of slope dofs ``idx`` (None: the
        x axis)."""
        if idx is None:
            return 0.0, 0.0, 0.0
        sx, sy = q[idx]
        vx, vy = v[idx]
        ax, ay = a[idx]
        r2 = sx * sx + sy * sy
        cross = sx * vy - sy * vx
        rate = cross / r2
        acc = (sx * ay - sy * ax) / r2 - 2.0 * (sx * vx + sy * vy) * cross / r2**2
        return math.atan2(sy, sx), rate, acc

    def _hinge(self, item, q, v, a):
        tl, rl, al = self._angle(q, v, a, item["left"])
        tr, rr, ar = self._angle(q, v, a, item["right"])
        D = item["D"] + float(_wrap(np.array((tr - tl) - item["D"])))
        return D, rr - rl, ar - al

    def _momenta(self, q, v):
        """Per rod: linear momentum (n, 2) and angular momentum about the origin (n,)."""
        x, y, vx, vy = self.Gx @ q, self.Gy @ q, self.Gx @ v, self.Gy @ v
        n = self.scene.n
        px = np.bincount(self.rod_of, self.w * vx, n)
        py = np.bincount(self.rod_of, self.w * vy, n)
        h = np.bincount(self.rod_of, self.w * (x * vy - y * vx), n)
        return np.stack([px, py], -1), h

    def _chord_rate(self, j: int, q, v) -> float:
        """d(phi)/dt of rod j (0-based): (d x d') / |d|^2, d the chord vector."""
        a, b = self.ltg[j][0][:2], self.ltg[j][self.E][:2]
        d, dd = q[b] - q[a], v[b] - v[a]
        return float((d[0] * dd[1] - d[1] * dd[0]) / (d @ d))

    def _root_moment(self, j: int, q) -> float:
        """EI kappa_b (N m) at the root of rod j (0-based): the moment the hinge there
        transmits, in the sense of its spring's kappa (D - rest)."""
        E, le = self.E, self.scene.chain.l[j] / self.E
        _, dS, ddS = _hermite(np.zeros(1), le)
        a, b = self.ltg[j][0], self.ltg[j][1 if E >= 1 else 0]
        Q = np.stack([q[a[:2]], q[a[2:]], q[b[:2]], q[b[2:]]])  # (4, 2)
        r1, r2 = dS[0] @ Q, ddS[0] @ Q
        return float(self.scene.chain.EI[j] * (r1[0] * r2[1] - r1[1] * r2[0]) / (r1 @ r1))

    def _measures(self, t: float, item, q, v, a) -> dict:
        k, chain = item["k"], self.scene.chain
        p, h = self._momenta(q, v)
        P = q[self.ltg[k][0][:2]]
        vP = v[self.ltg[k][0][:2]]
        p_out = p[k:].sum(0)
        H_out = float(h[k:].sum() - (P[0] * p_out[1] - P[1] * p_out[0]))
        D, dD, _ = self._hinge(item, q, v, a)
        moment = chain.kappa[k] * (D - chain.rest_angle[k]) + chain.nu[k] * dD
        moment += sum(float(stop_moment(st, D, dD)) for st in self.stops.get(k, []))
        finite = -moment - (vP[0] * p_out[1] - vP[1] * p_out[0])
        for f, idx, node in self.loads:
            if node > k and f.active(t):
                fx = f.fx(t) if f.fx is not None else 0.0
                fy = f.fy(t) if f.fy is not None else 0.0
                r = q[idx] - P
                finite += r[0] * fy - r[1] * fx
        # about the origin: hinge 0's spring, damper and stops on rod 1, and all loads
        D0, dD0, _ = self._hinge(self.root, q, v, a)
        root_moment = -(chain.kappa[0] * (D0 - chain.rest_angle[0]) + chain.nu[0] * dD0)
        root_moment -= sum(float(stop_moment(st, D0, dD0)) for st in self.stops.get(0, []))
        for f, idx, _ in self.loads:
            if f.active(t):
                fx = f.fx(t) if f.fx is not None else 0.0
                fy = f.fy(t) if f.fy is not None else 0.0
                root_moment += q[idx][0] * fy - q[idx][1] * fx
        rel = self._chord_rate(k, q, v) - (self._chord_rate(k - 1, q, v) if k > 0 else 0.0)
        return {
            "t": t,
            "rel": rel,
            "M_beam": self._root_moment(k, q),
            "H_out": H_out,
            "finite": finite,
            "H_root": float(h.sum()),
            "root_moment": root_moment,
            "T": 0.5 * float(v @ self.guard.M @ v),
            "D": D,
            "dD": dD,
        }

    # -- per step --------------------------------------------------------------------------
    def pre_step(self, t: float, h: float) -> None:
        """Called before the step to t, on the state at t - h (the last accepted step)."""
        if h <= 0:
            return
        t0 = t - h
        q, v, a = self._state()
        self.root["D"] = self._hinge(self.root, q, v, a)[0]
        now = {}
        for item in self.items:
            if item["state"] != "armed":
                continue
            D, dD, ddD = self._hinge(item, q, v, a)
            item["D"] = D
            now[item["k"]] = (D, dD, ddD)
        for ev in list(self.pending):
            ev["steps"] += 1
            now_m = self._measures(t0, ev["item"], q, v, a)
            last = ev["last"]
            ev["integral"] += 0.5 * (now_m["t"] - last["t"]) * (last["finite"] + now_m["finite"])
            ev["root_integral"] += (
                0.5 * (now_m["t"] - last["t"]) * (last["root_moment"] + now_m["root_moment"])
            )
            ev["peak"] = max(ev["peak"], abs(now_m["M_beam"]))
            s0 = np.sign(ev["before"]["rel"])
            if ev["steps"] > LOCK_SETTLE_STEPS and np.sign(now_m["rel"]) != s0:
                self._finish(ev, last, now_m)
            else:
                ev["last"] = now_m
        for item in self.items:
            if item["state"] != "armed":
                continue
            D, dD, ddD = now[item["k"]]
            angle, s = item["latch"].angle, item["dir"]
            t_lock = None
            if s * (D - angle) >= 0:  # already at or past: Hermite root in the last step
                if self.prev is not None and item["k"] in self.prev["D"]:
                    Dp, dDp, _ = self.prev["D"][item["k"]]
                    t_lock = _hermite_root(self.prev["t"], t0, Dp - angle, dDp, D - angle, dD)
                else:
                    t_lock = t0
            else:
                tau = _taylor_root(D - angle, dD, ddD, h)
                if tau is not None:
                    t_lock = t0 + tau
            if t_lock is None:
                continue
            self.mbs.SetObjectParameter(item["joint"], "activeConnector", True)
            item["state"] = "locking"
            self.lock_times[item["k"]] = t0
            before = self._measures(t0, item, q, v, a)
            self.pending.append(
                {
                    "item": item,
                    "t_lock": t_lock,
                    "steps": 0,
                    "before": before,
                    "last": before,
                    "integral": 0.0,
                    "root_integral": 0.0,
                    "peak": abs(before["M_beam"]),
                    "step": h,
                }
            )
        self.prev = {"t": t0, "D": now}

    def close(self) -> None:
        """At the end of the run: locks whose window has not closed are recorded with the
        last state (``window_closed`` False)."""
        for ev in list(self.pending):
            self._finish(ev, ev["last"], None)

    def _finish(self, ev: dict, last: dict, now: dict | None) -> None:
        """Record a lock. The lock window ends where the relative chord rate of the two rods
        (d phi_{k+1}/dt - d phi_k/dt) first reaches zero after the activation (linear
        interpolation between ``last`` and ``now``; the last state if it never does)."""
        item, before = ev["item"], ev["before"]
        if now is None:
            after, frac, closed = last, 0.0, False
        else:
            frac = last["rel"] / (last["rel"] - now["rel"]) if last["rel"] != now["rel"] else 1.0
            frac = min(max(frac, 0.0), 1.0)
            after = {key: last[key] + frac * (now[key] - last[key]) for key in last}
            closed = True
            # the integral holds the whole last step: take back the part beyond the crossing
            h = now["t"] - last["t"]
            ev["integral"] -= 0.5 * (1 - frac) * h * (after["finite"] + now["finite"])
            ev["root_integral"] -= (
                0.5 * (1 - frac) * h * (after["root_moment"] + now["root_moment"])
            )
        impulse = after["H_out"] - before["H_out"] - ev["integral"]
        root_jump = after["H_root"] - before["H_root"] - ev["root_integral"]
        latch = item["latch"]
        self.events.append(
            {
                "t": float(ev["t_lock"]),
                "label": f"latch hinge {latch.hinge}",
                "hinge": int(latch.hinge),
                "angle": float(latch.angle),
                "angular_impulse": float(impulse),
                "kinetic_before": float(before["T"]),
                "kinetic_after": float(after["T"]),
                "rate_before": float(before["dD"]),
                "chord_rate_before": float(before["rel"]),
                "angular_momentum_root_before": float(before["H_root"]),
                "angular_momentum_root_after": float(after["H_root"]),
                "angular_momentum_root_jump": float(root_jump),
                "peak_moment": float(ev["peak"]),
                "t_activated": float(before["t"]),
                "lock_duration": float(after["t"] - before["t"]),
                "window_closed": closed,
                "step": float(ev["step"]),
            }
        )
        item["state"] = "locked"
        self.pending.remove(ev)


def _taylor_root(g: float, dg: float, ddg: float, h: float) -> float | None:
    """Smallest tau in (0, h] where g + dg tau + ddg tau^2 / 2 changes sign from that of g
    (None if it does not within the step)."""
    tau = np.array([h])
    coeffs = [0.5 * ddg, dg, g]
    roots = np.roots(coeffs) if abs(ddg) > 0 or abs(dg) > 0 else np.array([])
    real = sorted(
        float(r.real) for r in np.atleast_1d(roots) if abs(r.imag) < 1e-12 and 0 < r.real <= tau[0]
    )
    return real[0] if real else None


def _hermite_root(t0: float, t1: float, g0: float, dg0: float, g1: float, dg1: float) -> float:
    """Where the cubic Hermite interpolant of g between (t0, g0, dg0) and (t1, g1, dg1) crosses
    zero (g0 and g1 of opposite sign or g1 = 0), by bisection; t1 when not bracketed."""
    h = t1 - t0
    if h <= 0 or g0 * g1 > 0:
        return t1

    def g(th):
        h00, h10 = 2 * th**3 - 3 * th**2 + 1, th**3 - 2 * th**2 + th
        h01, h11 = -2 * th**3 + 3 * th**2, th**3 - th**2
        return h00 * g0 + h10 * h * dg0 + h01 * g1 + h11 * h * dg1

    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if (g(mid) > 0) == (g0 > 0) and g(mid) != 0:
            lo = mid
        else:
            hi = mid
    return t0 + hi * h
