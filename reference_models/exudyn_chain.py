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
their definitions (see ``rodval.scene``):

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

Solver: exudyn's implicit generalized-alpha (or trapezoidal index-2) integrator with a fixed
step (halved, down to step/64, only if Newton fails), sparse linear solver (EigenSparse), no solution files, no
graphics and no console output. Newton's absolute tolerance is ``newton_atol_per_EA * EA``
(N): the default absolute tolerance lies below the round-off of the stiff axial forces.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from rodval.models.base import Model
from rodval.scene import Scene
from rodval.settings import IntegratorSettings
from rodval.trajectory import (STATUS_DIVERGED, STATUS_ERROR, STATUS_FAILED, SolverStats,
                               Trajectory)

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
}

_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(5)


def _positive(name: str, value, *, upper: float = math.inf, integer: bool = False):
    ok_type = isinstance(value, (int, np.integer)) if integer else isinstance(value, (int, float, np.number))
    if isinstance(value, bool) or not ok_type or not (0 < value <= upper) or not math.isfinite(value):
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
    S = np.stack([1 - 3 * x**2 + 2 * x**3, le * (x - 2 * x**2 + x**3),
                  3 * x**2 - 2 * x**3, le * (-x**2 + x**3)], axis=-1)
    dS = np.stack([(-6 * x + 6 * x**2) / le, 1 - 4 * x + 3 * x**2,
                   (6 * x - 6 * x**2) / le, -2 * x + 3 * x**2], axis=-1)
    ddS = np.stack([(-6 + 12 * x) / le**2, (-4 + 6 * x) / le,
                    (6 - 12 * x) / le**2, (-2 + 6 * x) / le], axis=-1)
    return S, dS, ddS


def _initial_node_states(scene: Scene, elements: int):
    """Reference coordinates (straight rods along the initial chords) and initial coordinate
    offsets and velocities of every beam node, per rod: arrays (n, elements+1, 4) with
    [x, y, slope_x, slope_y] (m, m, -, -) and their rates. The bent shape is the scene's
    assumed mode eta = alpha sigma + beta tau (its definition of alpha, beta)."""
    chain, ini = scene.chain, scene.initial.resolve(scene.n)
    n, l = chain.n, chain.l
    phi, dphi = ini["phi"], ini["dphi"]
    e = np.stack([np.cos(phi), np.sin(phi)], -1)
    nrm = np.stack([-np.sin(phi), np.cos(phi)], -1)
    roots = np.vstack([np.zeros(2), np.cumsum(l[:, None] * e, axis=0)])[:-1]
    root_vel = np.vstack([np.zeros(2), np.cumsum((l * dphi)[:, None] * nrm, axis=0)])[:-1]
    s = np.linspace(0.0, 1.0, elements + 1)[None, :] * l[:, None]           # (n, E+1)
    lk = l[:, None]
    sig, tau = s * (lk - s) ** 2 / lk**2, -s**2 * (lk - s) / lk**2
    dsig, dtau = (lk - s) * (lk - 3 * s) / lk**2, -s * (2 * lk - 3 * s) / lk**2
    a, b = ini["alpha"][:, None], ini["beta"][:, None]
    da, db, w = ini["dalpha"][:, None], ini["dbeta"][:, None], dphi[:, None, None]
    eta, deta = a * sig + b * tau, a * dsig + b * dtau
    eta_t, deta_t = da * sig + db * tau, da * dsig + db * dtau
    E, N = e[:, None, :], nrm[:, None, :]
    ref = np.concatenate([roots[:, None, :] + s[..., None] * E, np.broadcast_to(E, s.shape + (2,))], -1)
    pos = roots[:, None, :] + s[..., None] * E + eta[..., None] * N
    slope = E + deta[..., None] * N
    vel = (root_vel[:, None, :] + w * (s[..., None] * N - eta[..., None] * E)
           + eta_t[..., None] * N)
    slope_t = w * (N - deta[..., None] * E) + deta_t[..., None] * N
    return ref, np.concatenate([pos, slope], -1) - ref, np.concatenate([vel, slope_t], -1)


@dataclass
class _Built:
    """An assembled exudyn system and the sensor ids needed for the scene's outputs."""

    SC: Any
    mbs: Any
    node_sensors: dict[tuple[int, int], tuple[int, int, int]]   # (rod, local node) -> (q, v, a)
    load_errors: list


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
    """

    name = "exudyn"

    def __init__(self, *, elements: int = DEFAULTS["elements"], step: float = DEFAULTS["step"],
                 EA: float = DEFAULTS["EA"], element: str = DEFAULTS["element"],
                 solver: str = DEFAULTS["solver"],
                 spectral_radius: float = DEFAULTS["spectral_radius"],
                 newton_rtol: float = DEFAULTS["newton_rtol"],
                 newton_atol_per_EA: float = DEFAULTS["newton_atol_per_EA"]):
        self.elements = _positive("elements", elements, integer=True)
        self.step = _positive("step", step, upper=0.1)
        self.EA = _positive("EA", EA, upper=1e14)
        if element not in ELEMENTS:
            raise ValueError(f"element must be one of {ELEMENTS}, got {element!r}")
        self.element = element
        if solver not in SOLVERS:
            raise ValueError(f"solver must be one of {SOLVERS}, got {solver!r}")
        self.solver = solver
        if (isinstance(spectral_radius, bool) or not isinstance(spectral_radius, (int, float))
                or not 0 <= spectral_radius <= 1):
            raise ValueError(f"spectral_radius must be a number in [0, 1], got {spectral_radius!r}")
        self.spectral_radius = float(spectral_radius)
        self.newton_rtol = _positive("newton_rtol", newton_rtol, upper=1e-2)
        self.newton_atol_per_EA = _positive("newton_atol_per_EA", newton_atol_per_EA, upper=1e-6)

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
        from exudyn.itemInterface import (LoadForceVector, MarkerBodyPosition, MarkerBodyRigid,
                                          MarkerNodePosition, NodeGenericData, NodePoint2DSlope1,
                                          ObjectANCFCable2D, ObjectConnectorTorsionalSpringDamper,
                                          ObjectGround, ObjectJointRevolute2D, ObjectMassPoint2D,
                                          SensorNode)

        chain, E = scene.chain, self.elements
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        ground = mbs.AddObject(ObjectGround())
        ref, q0, v0 = _initial_node_states(scene, E)
        nodes, elems = [], []
        for k in range(chain.n):
            nodes.append([mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=ref[k, j].tolist(),
                                                        initialCoordinates=q0[k, j].tolist(),
                                                        initialVelocities=v0[k, j].tolist()))
                          for j in range(E + 1)])
            le = float(chain.l[k]) / E
            elems.append([mbs.AddObject(ObjectANCFCable2D(
                nodeNumbers=[nodes[k][j], nodes[k][j + 1]], length=le,
                massPerLength=float(chain.m[k]), bendingStiffness=float(chain.EI[k]),
                axialStiffness=self.EA)) for j in range(E)])
        # hinges: position joint + torsional spring-damper on the end tangents
        ini = scene.initial.resolve(chain.n)
        tangent_left = ini["phi"] + ini["alpha"]
        tangent_right = ini["phi"] + ini["beta"]
        for k in range(chain.n):
            if k == 0:
                pos0 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground))
                rot0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground))
                angle0 = tangent_left[0]
            else:
                pos0 = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[k - 1][-1]))
                rot0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=elems[k - 1][-1],
                                                     localPosition=[chain.l[k - 1] / E, 0, 0]))
                angle0 = tangent_left[k] - tangent_right[k - 1]
            pos1 = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[k][0]))
            mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[pos0, pos1]))
            if chain.kappa[k] > 0 or chain.nu[k] > 0:
                rot1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=elems[k][0], localPosition=[0, 0, 0]))
                turns = mbs.AddNode(NodeGenericData(numberOfDataCoordinates=1,
                                                    initialCoordinates=[_revolutions(angle0)]))
                mbs.AddObject(ObjectConnectorTorsionalSpringDamper(
                    markerNumbers=[rot0, rot1], nodeNumber=turns,
                    stiffness=float(chain.kappa[k]), damping=float(chain.nu[k])))
        for k in range(chain.n):
            if chain.mu[k] > 0:
                mbs.AddObject(ObjectMassPoint2D(nodeNumber=nodes[k][-1], mass=float(chain.mu[k])))
        load_errors: list = []
        for f in scene.loads:
            marker = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[f.node - 1][-1]))
            mbs.AddLoad(LoadForceVector(markerNumber=marker, loadVector=[0, 0, 0],
                                        loadVectorUserFunction=_load_function(f, load_errors)))
        # sensors on the beam nodes the outputs need
        wanted = set()
        if scene.wants("phi", "dphi", "alpha", "beta", "x", "y"):
            wanted |= {(k, 0) for k in range(chain.n)} | {(k, E) for k in range(chain.n)}
        if scene.wants("energy"):
            wanted |= {(k, j) for k in range(chain.n) for j in range(E + 1)}
        ovt = exu.OutputVariableType
        node_sensors = {
            key: tuple(mbs.AddSensor(SensorNode(nodeNumber=nodes[key[0]][key[1]], storeInternal=True,
                                                writeToFile=False, outputVariableType=v))
                       for v in (ovt.CoordinatesTotal, ovt.Coordinates_t, ovt.Coordinates_tt))
            for key in sorted(wanted)}
        mbs.Assemble()
        return _Built(SC, mbs, node_sensors, load_errors)

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
        ti.minimumStepSize = ti.initialStepSize / 64.0   # fail fast instead of crawling
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
    def simulate(self, scene: Scene, settings: IntegratorSettings | None = None) -> Trajectory:
        """Run the scene. ``settings`` (the native integrator settings) do not apply: the
        exudyn integrator is set by this model's options, recorded in ``trajectory.settings``."""
        import exudyn as exu

        stats = SolverStats()
        try:
            built = self._build(scene)
            sim = self._settings(scene.t_end)
        except Exception as exc:  # noqa: BLE001 - a failed build is data
            stats.status, stats.message = STATUS_ERROR, f"build failed: {type(exc).__name__}: {exc}"
            return self._trajectory(scene, np.empty(0), {}, stats)
        solver = exu.MainSolverImplicitSecondOrder()
        if self.solver == "trapezoidal":
            sim.timeIntegration.generalizedAlpha.useNewmark = True
            sim.timeIntegration.generalizedAlpha.useIndex2Constraints = True
        console = exu.config.printToConsole
        exu.config.printToConsole = False
        start = time.perf_counter()
        try:
            ok = solver.SolveSystem(built.mbs, sim)
            if not ok:
                stats.status, stats.message = STATUS_FAILED, _solver_message(solver, "solver failed")
        except Exception as exc:  # noqa: BLE001 - exudyn errors come back as data
            stats.status = STATUS_ERROR
            cause = built.load_errors[0] if built.load_errors else exc
            stats.message = f"{type(cause).__name__}: {cause}"
        finally:
            stats.wall_s = time.perf_counter() - start
            exu.config.printToConsole = console
        stats.nsteps = int(solver.it.currentStepIndex)
        stats.njev = int(solver.it.newtonJacobiCount)
        stats.nfev = int(solver.it.newtonStepsCount)
        try:
            t_rec, records, diverged = self._records(built)
        except Exception as exc:  # noqa: BLE001
            stats.status, stats.message = STATUS_ERROR, f"reading sensors failed: {exc}"
            return self._trajectory(scene, np.empty(0), {}, stats)
        stats.t_reached = float(t_rec[-1]) if t_rec.size else 0.0
        if stats.status == 0 and stats.t_reached < scene.t_end * (1 - 1e-9):
            stats.status, stats.message = STATUS_FAILED, "solver stopped before t_end"
        if stats.status == STATUS_FAILED and diverged:
            stats.status = STATUS_DIVERGED
            stats.message = f"non-finite state after t = {stats.t_reached:.6g} s"
        if stats.status == 0:
            stats.message = "reached t_end"
        times = np.asarray(scene.times)
        times = times[times <= stats.t_reached + 1e-9 * max(1.0, scene.t_end)] if t_rec.size else t_rec
        try:
            observed = _observe(scene, self.elements, self.EA, times, t_rec, records) if times.size else {}
        except Exception as exc:  # noqa: BLE001
            stats.status, stats.message = STATUS_ERROR, f"observation failed: {type(exc).__name__}: {exc}"
            return self._trajectory(scene, np.empty(0), {}, stats)
        return self._trajectory(scene, times, observed, stats)

    def _records(self, built: _Built):
        """Recorded times (s); per (rod, local node), arrays q, v, a (nt, 4) up to the first
        non-finite record; whether a non-finite record was cut off."""
        mbs = built.mbs
        data = {key: tuple(mbs.GetSensorStoredData(s) for s in ids)
                for key, ids in built.node_sensors.items()}
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

    def _trajectory(self, scene, times, observed, stats) -> Trajectory:
        return Trajectory(model=self.name, scene_name=scene.name, times=times,
                          values={q: v for q, (v, _) in observed.items()},
                          k_index={q: k for q, (_, k) in observed.items()},
                          stats=stats, settings={"integrator": f"exudyn {self.solver}",
                                                 **self.options()})


def _revolutions(angle: float) -> float:
    """Initial value of a torsional spring's revolution counter for a relative angle (rad)."""
    return float(round(angle / (2.0 * math.pi)))


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


def _observe(scene: Scene, E: int, EA: float, times: np.ndarray, t_rec: np.ndarray, records: dict):
    """The scene's quantities at ``times`` from recorded node states (see module docstring)."""
    n = scene.n
    rods = np.arange(1, n + 1)
    at = {key: (_interpolate(times, t_rec, q, v), _interpolate(times, t_rec, v, a))
          for key, (q, v, a) in records.items()}
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    if not scene.wants("phi", "dphi", "alpha", "beta", "x", "y", "energy"):
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
    qL = np.stack([at[(k, 0)][0] for k in range(n)], 1)       # (nt, n, 4)
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
    if scene.wants("energy"):
        kin, pot = _energies(scene, E, EA, at, phi, alpha, beta)
        zero = np.zeros(1, dtype=int)
        out["kinetic"] = (kin[:, None], zero)
        out["potential"] = (pot[:, None], zero)
        out["energy"] = ((kin + pot)[:, None], zero)
    return out


def _energies(scene: Scene, E: int, EA: float, at: dict, phi, alpha, beta) -> tuple[np.ndarray, np.ndarray]:
    """Kinetic and potential energy (J) per output time: beam kinetic, bending (EI kappa^2/2),
    axial (EA eps^2/2, EA of the run), point masses and hinge springs (kappa D^2/2 with the
    continuous tangent angles phi + alpha, phi + beta)."""
    chain = scene.chain
    kin = np.zeros(phi.shape[0])
    pot = np.zeros(phi.shape[0])
    for k in range(chain.n):
        le = chain.l[k] / E
        s = 0.5 * le * (_GAUSS_X + 1.0)
        w = 0.5 * le * _GAUSS_W
        S, dS, ddS = _hermite(s, le)
        for j in range(E):
            qa, va = at[(k, j)]
            qb, vb = at[(k, j + 1)]
            Q = np.stack([qa[:, :2], qa[:, 2:], qb[:, :2], qb[:, 2:]], 1)     # (nt, 4, 2)
            V = np.stack([va[:, :2], va[:, 2:], vb[:, :2], vb[:, 2:]], 1)
            r_t = np.einsum("gi,tic->tgc", S, V)
            r1 = np.einsum("gi,tic->tgc", dS, Q)
            r2 = np.einsum("gi,tic->tgc", ddS, Q)
            norm2 = np.sum(r1**2, -1)
            curv = (r1[..., 0] * r2[..., 1] - r1[..., 1] * r2[..., 0]) / norm2
            strain = np.sqrt(norm2) - 1.0
            kin += 0.5 * chain.m[k] * np.sum(w * np.sum(r_t**2, -1), -1)
            pot += 0.5 * np.sum(w * (chain.EI[k] * curv**2 + EA * strain**2), -1)
        vt = at[(k, E)][1][:, :2]
        kin += 0.5 * chain.mu[k] * np.sum(vt**2, -1)
    left = np.concatenate([np.zeros((phi.shape[0], 1)), (phi + beta)[:, :-1]], 1)
    D = (phi + alpha) - left
    pot += 0.5 * np.sum(chain.kappa * D**2, -1)
    return kin, pot
