"""Modes of the exudyn reference model (ANCF cable beams), by exudyn's own solvers.

The system is the one ``ExudynModel`` integrates (its ``assembled`` method: same mesh,
revolute joints, hinge springs, point masses and load user functions). Then:

* ``about="initial"``: the scene's initial state, without loads (``rodval.analysis.modes``
  checks before any model runs that it is at rest in equilibrium);
* ``about="equilibrium"``: exudyn's static solver (``exudyn.solver.SolveStatic``, load
  factor ramped over ``load_steps`` steps, Newton absolute tolerance scaled with EA) under the
  scene's static loads (``rodval.mechanics.modal.static_loads``, each held as a constant nodal
  force) and its hinge springs' rest angles, its result written to the initial state
  (``updateInitialValues=True``).

exudyn's static solver gives the mass matrix, the ODE2 Jacobian (so the axial force's
geometric stiffness is included), the velocity Jacobian (damping) and the constraint Jacobian
there, as ``exudyn.solver.ComputeODE2Eigenvalues`` obtains them. The joints' constraints are
eliminated on the exact 0/1 basis of ``rodval.mechanics.eigen.coordinate_null_space`` and the
pencils solved by ``rodval.mechanics.eigen`` (``_eigen``: the same digits on every BLAS kernel,
docs/modes.md); eigenvectors are mapped back to ODE2 coordinates. With hinge dampers or
bending damping (``Chain.damped``) each undamped mode is paired with the complex eigenvalue
s (Im s > 0) of nearest |s|, damping ratio -Re(s) / |s|.

The measures are taken by definition from the eigenvectors, independently of the paper's
equations: node k (k = 1..n) is the end node of rod k's beam (node 0 the pinned root), its
displacement the (x, y) part of the eigenvector there; hinge angle D_k is the change of the
angle of rod k+1's root tangent minus that of rod k's end tangent (hinge 0: rod 1's root
tangent), linearized: d atan2(s_y, s_x) = (s_x ds_y - s_y ds_x) / |s|^2 with s the slope
vector at the linearization state. Modes that stretch the beams (axial modes, absent from the
inextensible native models) are left out: a mode is axial when the largest element elongation
(the relative axial displacement of neighbouring beam nodes) exceeds ``axial_tol`` times its
largest beam-node displacement.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg

from reference_models.exudyn_beam import Array
from reference_models.exudyn_chain import ExudynModel
from rodval.core.loads import NodalForce, constant
from rodval.core.modes import ABOUT, ConstantLoads, Equilibrium, Modes
from rodval.core.scene import InitialState, Scene
from rodval.mechanics.eigen import (
    angular_frequencies,
    coordinate_null_space,
    quadratic_eigenvalues,
    symmetric_pencil,
)
from rodval.mechanics.modal import (
    check_no_mechanism,
    equilibrium_angles,
    held_hinges,
    normalize_shapes,
    split_rigid,
    static_loads,
)

#: Elongation/displacement ratio above which an exudyn mode counts as axial.
AXIAL_TOL = 1e-3
#: ExudynModel options changed for modal analysis (others: ExudynModel's DEFAULTS).
#: EA = 1e8 N instead of 1e10: exudyn's K carries round-off of eps |K| per entry, and the
#: hinge modes are where the beams' axial and bending stiffness cancels, so their digits fall
#: as EA grows: n = 8, 8 elements per rod, mode 1 = 0.078142096 (EA 1e8), 0.078142118 (1e9),
#: 0.078142313 (1e10), 0.078143951 (1e11) rad/s against 0.0781421067 natively (docs/modes.md).
#: About the straight state bending and stretching decouple, so the hinge and bending
#: frequencies do not depend on EA otherwise (mode 9: 452.44309 rad/s for EA 1e8 to 1e11);
#: under a load the static stretch is F / EA (3e-7 for 30 N).
MODES_DEFAULTS = {"EA": 1e8, "elements": 8}


def _linear_matrices(exu: Any, mbs: Any) -> tuple[Array, Array, Array, Array]:
    """(M, K, D, J) of the assembled system at its initial state, by exudyn's static solver as
    ``exudyn.solver.ComputeODE2Eigenvalues`` obtains them: mass matrix, K = -d(ODE2 rhs)/dq,
    D = -d(ODE2 rhs)/dq_t and the position-level constraint Jacobian J (rows: constraints)."""
    sim = exu.SimulationSettings()
    sim.staticSolver.verboseMode = 0
    sim.solution.file.write = False
    sim.solution.sensors.active = False
    solver = exu.MainSolverStatic()
    solver.InitializeSolver(mbs, sim)
    n2, n1 = solver.GetODE2size(), solver.GetODE1size()
    solver.ComputeMassMatrix(mbs)
    M = np.array(solver.GetSystemMassMatrix(), float)
    solver.ComputeJacobianODE2RHS(
        mbs, scalarFactor_ODE2=-1, scalarFactor_ODE2_t=0, scalarFactor_ODE1=0
    )
    solver.ComputeJacobianAE(
        mbs,
        scalarFactor_ODE2=1.0,
        scalarFactor_ODE2_t=0.0,
        scalarFactor_ODE1=0.0,
        velocityLevel=False,
    )
    jac = np.array(solver.GetSystemJacobian(), float)
    K, J = jac[:n2, :n2], jac[:n2, n2 + n1 :].T
    solver.ComputeJacobianODE2RHS(
        mbs, scalarFactor_ODE2=0, scalarFactor_ODE2_t=-1, scalarFactor_ODE1=0
    )
    D = np.array(solver.GetSystemJacobian(), float)[:n2, :n2]
    solver.FinalizeSolver(mbs, sim)
    return M, K, D, J


def _eigen(
    M: Array, K: Array, D: Array, J: Array, *, damped: bool
) -> tuple[Array, Array, Array | None, str]:
    """Undamped eigenvalues omega^2 (ascending) and eigenvectors in ODE2 coordinates of the
    constrained system, the damped eigenvalues s (or None), and the null-space kind used.

    The constraints (revolute joints: node positions equal or pinned) are eliminated with the
    exact 0/1 basis of ``rodval.mechanics.eigen.coordinate_null_space``; only if a constraint has
    another form, the SVD basis exudyn uses. The pencils are solved by
    ``rodval.mechanics.eigen`` (direct and inverted): exudyn's own ``eigh`` on an SVD basis loses
    the lowest mode's digits to the pencil's span (axial to hinge modes, 3.7e12 for the paper
    chain) and to the basis' BLAS-dependent orientation."""
    B = coordinate_null_space(J)
    kind = "coordinates"
    if B is None:
        U, sv, _ = scipy.linalg.svd(J.T)
        B = U[:, int(np.sum(sv > 1e-12)) :]
        kind = "svd"
    Mb, Kb = B.T @ M @ B, B.T @ K @ B
    lam, X = symmetric_pencil(Kb, Mb)
    s_damped = quadratic_eigenvalues(Mb, B.T @ D @ B, Kb)[0] if damped else None
    return lam, B @ X, s_damped, kind


def exudyn_modes(
    scene: Scene,
    *,
    about: str = "initial",
    count: int | None = None,
    load_at: float | None = None,
    load_steps: int = 20,
    axial_tol: float = AXIAL_TOL,
    **options: Any,
) -> Modes:
    """Modes of the exudyn beam model about the scene's initial state or its static
    equilibrium under the static loads (``rodval.mechanics.modal.static_loads`` at ``load_at``,
    each held as a constant nodal force) and the hinge rest angles (see module docstring);
    ``options``: ExudynModel options (elements, EA; the defaults for modes are
    ``MODES_DEFAULTS``)."""
    import exudyn as exu

    if about not in ABOUT:
        raise ValueError(f"about must be one of {ABOUT}, got {about!r}")
    model = ExudynModel(**{**MODES_DEFAULTS, **options})
    n = scene.n
    loads = static_loads(scene, load_at) if about == "equilibrium" else None
    scene, mbs, nodes, (iters, residual, matrices) = _linear_system(
        exu, scene, model, loads, (about, load_steps)
    )
    lam, V, s_damped, basis = _eigen(*matrices, damped=scene.chain.damped)
    idx, state = _node_states(exu, mbs, nodes, n)
    body = _body_index(mbs) if scene.base.free else None
    free = body is not None
    lam, U, axial, theta = _bending_modes(
        lam, V, idx, state, axial_tol, None if free else count, body
    )
    ends = np.concatenate([state[:1, 0, :2], state[:, -1, :2]])
    d = np.diff(ends, axis=0)
    phi0 = np.arctan2(d[:, 1], d[:, 0])
    rigid_info: dict[str, Any] = {}
    if free:
        lam, dx, dy, hinge, rigid_info = _free_shapes(lam, U, state, theta, ends, count)
    else:
        dx, dy, hinge = _node_shapes(U, state)
    omega = angular_frequencies(lam)
    damping = _damping_ratios(omega, s_damped)
    if free:
        damping[:3] = np.nan
    eq = None
    if about == "equilibrium":
        phi0, eq = _equilibrium(scene, phi0, (iters, load_steps, residual), loads)
    return Modes(
        model="exudyn",
        about=about,
        omega=omega,
        damping=damping,
        dx=dx,
        dy=dy,
        hinge=hinge,
        phi0=phi0,
        l=np.linalg.norm(d, axis=1),
        equilibrium=eq,
        info={
            "node_positions": ends,
            "axial_modes_dropped": int(axial.sum()),
            "null_space": basis,
            "options": model.options(),
            **rigid_info,
        },
        rigid=3 if free else 0,
    )


#: exudyn's modes exist on a free base (its three rigid modes separated, ``split_rigid``).
exudyn_modes.FREE_BASE = True  # type: ignore[attr-defined]


def _linear_system(
    exu: Any, scene: Scene, model: ExudynModel, loads: ConstantLoads | None, about: tuple[str, int]
) -> tuple[Scene, Any, list[list[int]], tuple[int, float, tuple[Array, ...]]]:
    """The system the modes are about: (the scene as assembled, exudyn's mbs, its beam nodes,
    ``_linearized``), the static ``loads`` held as constant nodal forces; ``about`` = (about,
    load_steps): about "equilibrium" a loaded or pre-stressed scene is solved statically in
    load_steps steps, starting from the hinges' rest angles when pre-stressed. Motors and rate
    dampers are left out, as the native models' modes leave them (``damping_matrix``: nu)."""
    (about_what, load_steps), held = about, _held_forces(loads)
    equilibrium = about_what == "equilibrium"
    if scene.base.free:
        _check_free(scene, held)
    prestressed = _springs_loaded(scene)
    if equilibrium and prestressed:
        scene = _at_rest_angles(scene)  # the static solve starts where the springs relax
    _, mbs, nodes = model.assembled(scene.with_(loads=held, motors=(), rate_dampers=()))
    _check_nodes(mbs, nodes)
    # on a free base without loads the start at the rest angles is the equilibrium (a static
    # solve of the unsupported body would be singular)
    solved = equilibrium and (bool(held) or prestressed) and not scene.base.free
    return scene, mbs, nodes, _linearized(exu, mbs, model, load_steps if solved else None)


def _check_free(scene: Scene, held: tuple[NodalForce, ...]) -> None:
    """ValueError before any work on a free base: a hinge without a spring
    (``check_no_mechanism``), or static loads (a loaded free body has no equilibrium)."""
    check_no_mechanism(scene)
    if held:
        raise ValueError(
            "a free base under static loads has no static equilibrium (the body accelerates); "
            "use about='initial' (free vibration, loads left out)"
        )


def _check_nodes(mbs: Any, nodes: list[list[int]]) -> None:
    """RuntimeError unless every beam node of ``nodes`` (rows of exudyn node numbers) is a
    Point2DSlope1 (position x, y in m and slope vector, dimensionless)."""
    for row in nodes:
        for nd in row:
            if mbs.GetNode(nd)["nodeType"] != "Point2DSlope1":
                raise RuntimeError("unexpected exudyn node numbering")


def _linearized(
    exu: Any, mbs: Any, model: ExudynModel, load_steps: int | None
) -> tuple[int, float, tuple[Array, Array, Array, Array]]:
    """(Newton iterations, exudyn's last Newton residual (N), (M, K, D, J)): exudyn's static
    solve in ``load_steps`` load steps first (None: no solve, (0, 0.0)), then the linear
    matrices there (``_linear_matrices``: kg, N/m, N s/m and the constraint Jacobian),
    exudyn's console output silenced meanwhile."""
    console = exu.config.printToConsole
    exu.config.printToConsole = False
    try:
        iters, residual = (
            _static_solve(exu, mbs, model, load_steps) if load_steps is not None else (0, 0.0)
        )
        matrices = _linear_matrices(exu, mbs)
    finally:
        exu.config.printToConsole = console
    return iters, residual, matrices


def _free_shapes(
    lam: Array, U: Array, state: Array, theta: Array | None, ends: Array, count: int | None
) -> tuple[Array, Array, Array, Array, dict[str, Any]]:
    """A free base's modes: node shapes with hinge 0 measured from the body (rod 1's root
    tangent less the body's theta, rad), the three rigid modes separated (``split_rigid``;
    ``ends`` (n+1, 2) the nodes' positions, m), then the first ``count`` flexible ones
    (default all), normalized. Returns (lam (1/s^2), dx, dy (m per unit), hinge (rad per the
    same unit), the rigid modes' record)."""
    d = np.diff(ends, axis=0)
    dx, dy, hinge = _node_shapes(U, state, theta, normalize=False)
    lam, dx, dy, hinge, rigid_info = split_rigid(
        lam, dx, dy, hinge, ends[:, 0], ends[:, 1], float(np.mean(np.linalg.norm(d, axis=1)))
    )
    keep = lam.size if count is None else min(lam.size, 3 + int(count))
    lam, dx, dy, hinge = lam[:keep], dx[:keep], dy[:keep], hinge[:keep]
    dx, dy, hinge = normalize_shapes(dx, dy, hinge)
    return lam, dx, dy, hinge, rigid_info


def _equilibrium(
    scene: Scene, phi0: Array, solve: tuple[int, int, float], loads: ConstantLoads | None
) -> tuple[Array, Equilibrium]:
    """The chord angles phi0 (rad) of the equilibrium, unwrapped to within pi of the scene's
    initial ones, and its record (``Equilibrium``: the static solve's ``solve`` = (Newton
    iterations, load steps, exudyn's last Newton residual in N), the static loads held)."""
    (iters, load_steps, residual), n = solve, scene.n
    ini = scene.initial.resolve(n)
    phi0 = ini["phi"] + (phi0 - ini["phi"] + np.pi) % (2 * np.pi) - np.pi
    eq = Equilibrium(
        q=np.concatenate([phi0, np.zeros(2 * n)]),
        iterations=iters,
        load_steps=int(load_steps),
        residual=residual,
        converged=True,
        loads=loads,
    )
    return phi0, eq


def _springs_loaded(scene: Scene) -> bool:
    """Whether the initial state loads the structure without any load: a hinge spring away
    from its rest angle (a stowed wing, a rest angle; not on a held latch's hinge, whose joint
    takes the spring's moment), an acting stop, or bent rods. Such a
    state is no equilibrium, so modes "about equilibrium" need the static solve (before, only
    rest angles counted, and a folded wing relaxed at 0 was reported balanced as it was)."""
    ini = scene.initial.resolve(scene.n)
    D = scene.initial_hinge_angles()
    chain = scene.chain
    stops = any(st.acts(D[st.hinge]) for st in scene.stops)
    bent = np.any(ini["alpha"] != 0) or np.any(ini["beta"] != 0)
    # a held latch carries its hinge spring's moment (its joint is active): no load
    moment = chain.kappa * (D - chain.rest_angle)
    moment[held_hinges(scene)] = 0.0
    return bool(np.any(moment != 0) or stops or bent)


def _at_rest_angles(scene: Scene) -> Scene:
    """``scene`` started from straight rods with every hinge at its rest angle, a held latch's
    hinge at the latch's angle (chord angles phi_k = theta + D_0 + ... + D_{k-1},
    ``equilibrium_angles``, at rest): without loads or acting stops the
    equilibrium itself, otherwise the start of the static solve. From a stowed wing exudyn's
    Newton does not reach it (its load steps scale loads, not the springs' pre-stress)."""
    theta = scene.base.attitude if scene.base.free else 0.0
    phi = theta + np.cumsum(equilibrium_angles(scene))
    # held latches are held (their hinges start at their angles, ``equilibrium_angles``); the
    # others play no part in modes (in every model), and one at its angle would refuse the start
    return scene.with_(
        initial=InitialState(phi=phi), latches=tuple(la for la in scene.latches if la.held)
    )


def _held_forces(loads: ConstantLoads | None) -> tuple[NodalForce, ...]:
    """The static loads (``static_loads``; None: none) as constant nodal forces (N)."""
    if loads is None or loads.X is None or loads.Y is None:
        return ()
    X, Y = loads.X, loads.Y
    return tuple(
        constant(int(k) + 1, X=float(X[k]), Y=float(Y[k]))
        for k in np.flatnonzero((X != 0) | (Y != 0))
    )


def _static_solve(exu: Any, mbs: Any, model: ExudynModel, load_steps: int) -> tuple[int, float]:
    """exudyn's static solve in ``load_steps`` load steps (the state becomes the
    configuration the modes are about): (Newton iterations, exudyn's last Newton residual in
    its own norm, N). ValueError if it fails."""
    sim = exu.SimulationSettings()
    st = sim.staticSolver
    st.numberOfLoadSteps = int(load_steps)
    st.useLoadFactor = True
    st.verboseMode = 0
    st.newton.relativeTolerance = 1e-10
    st.newton.absoluteTolerance = model.newton_atol_per_EA * model.EA
    st.newton.maxIterations = 50
    sim.solution.file.write = False
    sim.show.computationTime = False
    ok = exu.solver.SolveStatic(mbs, sim, updateInitialValues=True)
    solver = mbs.sys.get("staticSolver")
    iters = int(solver.it.newtonStepsCount) if solver is not None else -1
    residual = float(solver.conv.residual) if solver is not None else float("nan")
    if not ok:
        raise ValueError("exudyn static solve failed")
    return iters, residual


def _node_states(exu: Any, mbs: Any, nodes: list[list[int]], n: int) -> tuple[Array, Array]:
    """Each beam node's first ODE2 index (n, E+1) and its position and slope at the
    configuration (n, E+1, 4)."""
    q_all = np.asarray(
        mbs.systemData.GetODE2Coordinates(configuration=exu.ConfigurationType.Initial)
    )

    def node_state(nd: int) -> tuple[int, Array]:
        i = mbs.GetNodeODE2Index(nd)
        ref = np.asarray(mbs.GetNodeParameter(nd, "referenceCoordinates"), float)
        return i, ref + q_all[i : i + 4]

    idx, state = zip(*(node_state(nd) for row in nodes for nd in row), strict=True)
    first = np.array(idx).reshape(n, -1)
    return first, np.array(state).reshape(n, first.shape[1], 4)


def _body_index(mbs: Any) -> int:
    """The first ODE2 index of a free base's rigid body node (NodeRigidBody2D: x_c, y_c,
    theta)."""
    for nd in range(mbs.systemData.NumberOfNodes()):
        if "RigidBody2D" in str(mbs.GetNode(nd)["nodeType"]):
            return int(mbs.GetNodeODE2Index(nd))
    raise RuntimeError("free base: no NodeRigidBody2D in the exudyn system")


def _bending_modes(
    lam: Array,
    V: Array,
    idx: Array,
    state: Array,
    axial_tol: float,
    count: int | None,
    body: int | None = None,
) -> tuple[Array, Array, Array, Array | None]:
    """The modes without axial content (element elongation along the tangent below
    ``axial_tol`` x the largest node displacement), ascending, the first ``count``:
    (eigenvalues, beam-node shapes (modes, n, E+1, 4), which modes were axial, and the
    body's theta in each mode (None without a free base: ``body`` its first ODE2 index))."""
    U = np.stack([V[idx + c] for c in range(4)], axis=-1)  # (n, E+1, modes, 4)
    U = np.moveaxis(U, 2, 0)  # (modes, n, E+1, 4)
    disp = U[..., :2]
    chord = state[:, 1:, :2] - state[:, :-1, :2]
    t_hat = chord / np.linalg.norm(chord, axis=-1, keepdims=True)
    elong = np.abs(np.sum((disp[:, :, 1:] - disp[:, :, :-1]) * t_hat, -1))
    dmax = np.max(np.linalg.norm(disp, axis=-1), axis=(1, 2))
    axial = np.max(elong, axis=(1, 2)) > axial_tol * np.maximum(dmax, 1e-300)
    keep = ~axial
    theta = None if body is None else V[body + 2][keep]
    lam, U = lam[keep], U[keep]
    order = np.argsort(lam)
    lam, U = lam[order], U[order]
    theta = None if theta is None else theta[order]
    if count is not None:
        lam, U = lam[: int(count)], U[: int(count)]
        theta = None if theta is None else theta[: int(count)]
    return lam, U, axial, theta


def _node_shapes(
    U: Array, state: Array, theta: Array | None = None, normalize: bool = True
) -> tuple[Array, Array, Array]:
    """Node displacements dx, dy (node 0 = rod 1's root, node k = rod k's end) and
    hinge-angle changes of each mode (normalized unless ``normalize`` is False); ``theta``:
    a free body's attitude change per mode, which hinge 0 is measured from."""
    dx = np.concatenate([U[:, :1, 0, 0], U[:, :, -1, 0]], axis=1)
    dy = np.concatenate([U[:, :1, 0, 1], U[:, :, -1, 1]], axis=1)

    def dtheta(s: Array, ds: Array) -> Any:
        return (s[..., 0] * ds[..., 1] - s[..., 1] * ds[..., 0]) / np.sum(s * s, -1)

    root = dtheta(state[None, :, 0, 2:], U[:, :, 0, 2:])  # (modes, n) rod k root tangent
    end = dtheta(state[None, :, -1, 2:], U[:, :, -1, 2:])  # rod k end tangent
    hinge = root.copy()
    hinge[:, 1:] -= end[:, :-1]
    if theta is not None:
        hinge[:, 0] -= theta
    return normalize_shapes(dx, dy, hinge) if normalize else (dx, dy, hinge)


def _damping_ratios(omega: Array, s_damped: Array | None) -> Array:
    """Each undamped mode's damping ratio from the damped eigenvalue (Im > 0) of nearest |s|
    (Hungarian pairing); 0 without dampers, NaN where undefined."""
    zeta = np.full(omega.size, np.nan)
    if s_damped is None:
        zeta[omega > 0] = 0.0
        return zeta
    from scipy.optimize import linear_sum_assignment

    s_up = np.asarray(s_damped)[np.asarray(s_damped).imag > 0]
    pos = np.flatnonzero(omega > 0)
    if pos.size and s_up.size:
        cost = np.abs(np.abs(s_up)[None, :] - omega[pos, None]) / omega[pos, None]
        r, c = linear_sum_assignment(cost)
        zeta[pos[r]] = -s_up[c].real / np.abs(s_up[c])
    return zeta
