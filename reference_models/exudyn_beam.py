"""The exudyn beam model's kinematics, shared by its build, guard, latches and observation:
the cubic Hermite shape functions, the initial bent-rod node states, the stop, torque (motor,
rate damper) and load laws as exudyn user functions, and the beam-field quadratures of energy
and angular momentum (see ``reference_models.exudyn_chain``'s module docstring for the model)."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from typing import Any

import numpy as np

from rodval.core.hinges import HingeTorque, Stop
from rodval.core.loads import LoadSet, NodalForce
from rodval.core.scene import Chain, Scene, hinge_angles

#: 5-point Gauss-Legendre points on [-1, 1] and their weights, (5,) each (exact to degree 9).
GAUSS_X, GAUSS_W = np.polynomial.legendre.leggauss(5)

#: The records' key of a free base's body node (its states [x_c, y_c, theta] (m, m, rad) and
#: their rates), beside the beam nodes' (rod, local node) keys.
BODY = (-1, -1)
#: A numpy array (floats unless said otherwise).
Array = np.ndarray
#: Node arrays by node key ((rod, local node) or ``BODY``): recorded (q, v, a) (nt, 4) or, at
#: given times, (state, rate).
Nodes = Mapping[tuple[int, int], tuple[Array, ...]]


def body_attitude(at: Nodes) -> tuple[Array | None, Array | None]:
    """The free base's attitude theta (rad) and rate (rad/s), (nt,) each, from the node states
    ``at`` (None, None on a pinned base: no body record)."""
    if BODY not in at:
        return None, None
    q, v = at[BODY][:2]
    return q[:, 2], v[:, 2]


def positive(name: str, value: Any, *, upper: float = math.inf, integer: bool = False) -> Any:
    """``value`` as a float in (0, upper] (an int >= 1 if ``integer``); ValueError naming
    ``name`` otherwise (bools, non-numbers, non-finite values)."""
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


def wrap_angle(a: Array) -> Array:
    """Angle(s) wrapped to (-pi, pi]."""
    return np.asarray(np.pi - np.mod(np.pi - a, 2.0 * np.pi))


def hermite_shapes(s: Array, le: float) -> tuple[Array, Array, Array]:
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


def _arc_rule(upper: float) -> tuple[Array, Array]:
    """Nodes and weights integrating over [0, upper] (composite Gauss, exact to round-off for
    the smooth integrands of ``_bent_rod``)."""
    edges = np.linspace(0.0, upper, _ARC_PANELS + 1)
    half = 0.5 * np.diff(edges)[:, None]
    x = (edges[:-1, None] + half * (_ARC_X + 1.0)).ravel()
    return x, (half * _ARC_W).ravel()


def _bent_rod(alpha: float, beta: float, l: float, elements: int) -> tuple[Array, ...]:
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

    def g(xi: Array) -> Array:
        return np.asarray(ta * (1 - xi) * (1 - 3 * xi) - tb * xi * (2 - 3 * xi))

    def gp(xi: Array) -> Array:  # dg/dta, dg/dtb
        return np.stack([(1 - xi) * (1 - 3 * xi), -xi * (2 - 3 * xi)])

    def w(xi: Array) -> Array:
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


def initial_node_states(scene: Scene, elements: int) -> tuple[Array, ...]:
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
    root, root_vel = scene.base.initial_root()
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


def revolutions(angle: float) -> float:
    """Initial value of a torsional spring's revolution counter for a relative angle (rad)."""
    return float(round(angle / (2.0 * math.pi)))


def stop_law(side: str) -> Callable[..., float]:
    """springTorqueUserFunction of a one-sided limit stop (exudyn's sign: the returned torque
    is the spring's restoring torque, k (rotation - offset) for a plain spring): stiffness x
    penetration + damping x rate beyond the stop angle (``offset``), zero on the free side."""
    upper = side == "upper"

    def law(mbs: Any, t: float, item: int, *spring: float) -> float:
        rotation, omega, stiffness, damping, offset = spring
        pen = rotation - offset
        if (pen > 0.0) if upper else (pen < 0.0):
            return stiffness * pen + damping * omega
        return 0.0

    return law


def engaged_law(law: Callable[..., float], switch: list[bool]) -> Callable[..., float]:
    """springTorqueUserFunction ``law`` once ``switch[0]`` is True (a compliant latch's stop
    law from its engagement on, set by ``Latches``), zero before: O(1) a call."""

    def gated(mbs: Any, t: float, item: int, *spring: float) -> float:
        return law(mbs, t, item, *spring) if switch[0] else 0.0

    return gated


def timed_stops(scene: Scene, engaged: dict[int, float] | None) -> list[tuple[Stop, float]]:
    """Every stop acting on the run with the time (s) it acts after: the scene's stops from
    the start (-inf) and each engaged compliant latch's two stops (``engaged_stops``) after
    its engagement (``engaged``: hinge -> that time, ``Latches.engaged``)."""
    stops, on = [(stop, -math.inf) for stop in scene.stops], engaged or {}
    for latch in scene.compliant_latches:
        if latch.hinge in on:
            stops += [(stop, on[latch.hinge]) for stop in latch.engaged_stops()]
    return stops


def torque_law(item: HingeTorque, errors: list[Exception]) -> Callable[..., float]:
    """springTorqueUserFunction of a torque item (motor, rate damper) on a zero-stiffness,
    zero-damping torsional connector across its hinge: exudyn's restoring torque is -M, M =
    ``item.moment(t, dD/dt)`` (N m, positive driving the hinge angle up) at the connector's
    relative rate (rad/s: the rate the hinge dampers see); exceptions are recorded in
    ``errors`` and re-raised."""

    def law(mbs: Any, t: float, index: int, *spring: float) -> float:
        try:
            return -item.moment(t, spring[1])
        except Exception as exc:
            errors.append(exc)
            raise

    return law


def torque_moments(scene: Scene, times: Array, dD: Array) -> Array | None:
    """The torque items' moments (N m, (nt, n), positive driving D_k up; ``HingeTorque.moment``
    through ``LoadSet.hinge_moments``) at ``times`` (s) and hinge rates ``dD`` (rad/s, (nt,
    n)); None without torque items. O(nt x (items + n))."""
    if not scene.torques:
        return None
    loads = LoadSet((), scene.n, torques=scene.torques)
    return np.array(
        [loads.hinge_moments(float(t), rates) for t, rates in zip(times, dD, strict=True)]
    ).reshape(len(times), scene.n)


def stop_moment(stop: Stop, D: Any, dD: Any) -> Array:
    """The moment (N m, same sign as a hinge spring's kappa (D - rest)) of a limit stop at
    hinge angle(s) D (rad) and rate(s) dD (rad/s): zero on the free side."""
    D = np.asarray(D, float)
    pen, inside = D - stop.angle, stop.acts(D)
    return np.where(inside, stop.stiffness * pen + stop.damping * np.asarray(dD, float), 0.0)


def load_function(f: NodalForce, errors: list[Exception]) -> Callable[..., list[float]]:
    """exudyn load user function of a NodalForce: [X, Y, 0] (N) inside its support, zero
    (and not evaluated) outside; exceptions are recorded and re-raised."""

    def user_function(mbs: Any, t: float, load: Any) -> list[float]:
        if not f.active(t):
            return [0.0, 0.0, 0.0]
        try:
            return [*force_at(f, t), 0.0]
        except Exception as exc:
            errors.append(exc)
            raise

    return user_function


def force_at(f: NodalForce, t: float) -> tuple[float, float]:
    """The components (X, Y) (N) of nodal force ``f`` at t (s), 0.0 for a component it has
    none of (its support is not checked: ``f.active``)."""
    return (f.fx(t) if f.fx is not None else 0.0, f.fy(t) if f.fy is not None else 0.0)


def hermite_interpolate(times: Array, t_rec: Array, y: Array, dy: Array) -> Array:
    """Cubic Hermite interpolation of records y (nt, m) with derivatives dy at ``times``;
    exact at recorded times."""
    i = np.clip(np.searchsorted(t_rec, times, side="right") - 1, 0, max(t_rec.size - 2, 0))
    if t_rec.size < 2:
        return np.repeat(y[:1], times.size, axis=0)
    h = (t_rec[i + 1] - t_rec[i])[:, None]
    th = ((times - t_rec[i])[:, None] / h).clip(0.0, 1.0)
    h00, h10 = 2 * th**3 - 3 * th**2 + 1, th**3 - 2 * th**2 + th
    h01, h11 = -2 * th**3 + 3 * th**2, th**3 - th**2
    return np.asarray(h00 * y[i] + h10 * h * dy[i] + h01 * y[i + 1] + h11 * h * dy[i + 1])


def beam_elements(chain: Chain, E: int, at: Nodes) -> Iterator[tuple[Any, ...]]:
    """Per element j of every rod k, with the Gauss points of ``GAUSS_X`` on it: (k, weights
    (g,) (m), shape functions S, dS, ddS (g, 4), nodal positions/slopes Q and their rates V
    (nt, 4, 2)) from the node states ``at`` at the output times."""
    for k in range(chain.n):
        le = chain.l[k] / E
        w = 0.5 * le * GAUSS_W
        S, dS, ddS = hermite_shapes(0.5 * le * (GAUSS_X + 1.0), le)
        for j in range(E):
            qa, va = at[(k, j)]
            qb, vb = at[(k, j + 1)]
            Q = np.stack([qa[:, :2], qa[:, 2:], qb[:, :2], qb[:, 2:]], 1)
            V = np.stack([va[:, :2], va[:, 2:], vb[:, :2], vb[:, 2:]], 1)
            yield k, w, S, dS, ddS, Q, V


def system_energies(
    scene: Scene,
    E: int,
    EA: float,
    at: Nodes,
    angles: tuple[Array, Array, Array],
    engaged: tuple[Array, dict[int, float] | None] | None = None,
) -> tuple[Array, Array, Array]:
    """Kinetic, rod strain and hinge energy (J) per output time: beam and point-mass kinetic
    (and a free base's body, m |v_c|^2 / 2 + J theta'^2 / 2, from ``at[BODY]``); the rods'
    bending (EI kappa^2/2) and axial (EA eps^2/2, EA of the run) strain; the hinge springs
    (kappa D^2/2 with the continuous tangent angles phi + alpha, phi + beta, ``angles`` =
    (phi, alpha, beta), hinge 0 from the body's attitude) and the acting stops, an engaged
    compliant latch's after its engagement (``engaged`` = (the output times, s; hinge -> the
    time it acts after), ``timed_stops``). The potential energy is strain +
    hinge."""
    phi, alpha, beta = angles
    chain = scene.chain
    kin = np.zeros(phi.shape[0])
    pot = np.zeros(phi.shape[0])
    for k, w, S, dS, ddS, Q, V in beam_elements(chain, E, at):
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
    attitude, rate = body_attitude(at)
    if rate is not None:
        v_c = at[BODY][1][:, :2]
        mass, inertia = scene.base.inertial()
        kin += 0.5 * (mass * np.sum(v_c**2, -1) + inertia * rate**2)
    D = hinge_angles(phi, alpha, beta, attitude)
    hinge = 0.5 * np.sum(chain.kappa * (D - chain.rest_angle) ** 2, -1)
    times, on = engaged if engaged is not None else (np.zeros(phi.shape[0]), None)
    for stop, t_on in timed_stops(scene, on):
        pen = D[:, stop.hinge] - stop.angle
        acting = stop.acts(D[:, stop.hinge]) & (times > t_on)
        hinge += np.where(acting, 0.5 * stop.stiffness * pen**2, 0.0)
    return kin, pot, hinge


def cross2d(a: Array, b: Array) -> Array:
    """The planar cross product a_x b_y - a_y b_x of 2-vectors along the last axis: shape
    a.shape[:-1] (broadcast), units the product of a's and b's."""
    return np.asarray(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])


def _momentum_parts(scene: Scene, E: int, at: Nodes) -> tuple[Array, Array, Array, Array]:
    """Per part of the system, about node 0 (the root, moving with a free base): the angular
    momenta h (nt, parts) (N m s), linear momenta p (nt, parts, 2) (N s), first mass moments
    (nt, parts, 2) (kg m) and masses (parts,) (kg). The parts are each rod's beam field with
    its far node's point mass (the rods' mass on the beam's reference arc length; 5 Gauss
    points per element integrate the degree-6 integrand r x v exactly) and a free base's body
    (``at[BODY]``: J theta' + m (r_c - r_0) x v_c, m v_c, m (r_c - r_0)), the last part."""
    chain = scene.chain
    root = at[(0, 0)][0][:, None, :2]  # (nt, 1, 2)
    parts = chain.n + (1 if BODY in at else 0)
    h = np.zeros((root.shape[0], parts))
    p = np.zeros((root.shape[0], parts, 2))
    first = np.zeros((root.shape[0], parts, 2))
    mass = np.append(chain.m * chain.l + chain.mu, scene.base.inertial()[0] if BODY in at else [])
    for k, w, S, _, _, Q, V in beam_elements(chain, E, at):
        r = np.einsum("gi,tic->tgc", S, Q) - root
        v = np.einsum("gi,tic->tgc", S, V)
        h[:, k] += chain.m[k] * np.sum(w * cross2d(r, v), -1)
        p[:, k] += chain.m[k] * np.einsum("g,tgc->tc", w, v)
        first[:, k] += chain.m[k] * np.einsum("g,tgc->tc", w, r)
    for k in range(chain.n):
        r = at[(k, E)][0][:, :2] - root[:, 0]
        v = at[(k, E)][1][:, :2]
        h[:, k] += chain.mu[k] * cross2d(r, v)
        p[:, k] += chain.mu[k] * v
        first[:, k] += chain.mu[k] * r
    if BODY in at:
        body_mass, inertia = scene.base.inertial()
        q_b, v_b = at[BODY][:2]
        r_c = q_b[:, :2] - root[:, 0]
        h[:, -1] = inertia * v_b[:, 2] + body_mass * cross2d(r_c, v_b[:, :2])
        p[:, -1] = body_mass * v_b[:, :2]
        first[:, -1] = body_mass * r_c
    return h, p, first, mass


def system_momenta(scene: Scene, E: int, at: Nodes) -> tuple[Array, Array]:
    """The ``angular_momentum`` rows (nt, 2) (N m s, counter-clockwise positive) and the
    ``momentum`` rows P (nt, 2) (N s) of the whole system (see rodval.core.scene.QUANTITIES),
    summed over ``_momentum_parts``: k = 0 about node 0, H_0 = sum int (r - r_0) x r_t dm;
    k = 1 about the system's centre of mass, H_0 - (S x P) / M (S the first mass moment about
    node 0, M the total mass)."""
    h, p, first, mass = _momentum_parts(scene, E, at)
    H0, P, S = h.sum(-1), p.sum(-2), first.sum(-2)
    return np.stack([H0, H0 - cross2d(S, P) / mass.sum()], -1), P


def momentum_audit_rows(scene: Scene, E: int, at: Nodes) -> tuple[Array, Array]:
    """(H, G) (N m s, (nt,)) for the angular-momentum audit (``rodval.core.validity``,
    ``momentum_balance``), the same parts as the native models' (each rod with its far node,
    the body): about the system's centre of mass on a free base, about node 0 on a pinned
    chain; H the parts' sum, G the sum of their magnitudes."""
    h, p, first, mass = _momentum_parts(scene, E, at)
    if BODY in at:  # about the centre of mass X: h_X = h_0 - (X - r_0) x p
        X = first.sum(-2) / mass.sum()
        h = h - cross2d(X[:, None, :], p)
    return h.sum(-1), np.abs(h).sum(-1)


def mass_points(
    chain: Chain, ltg: list[list[Array]], E: int, size: int
) -> tuple[Array, Array, Array, Array]:
    """The chain's mass points: the quadrature points of every rod (5 Gauss points per
    element, ``GAUSS_X``, ``GAUSS_W``) and the node masses mu_k at the rods' ends. ``ltg``:
    each rod's beam nodes' ODE2 indices (rod, node 0..E, [x, y, slope x, slope y]); ``size``
    the number of ODE2 coordinates. Returns (Gx, Gy (points, size): rows giving each point's
    x, y (m) from the coordinates; w (points,) its mass, kg; rod_of (points,) its rod)."""
    rows_x: list[Array] = []
    rows_y: list[Array] = []
    wts: list[float] = []
    rod_of: list[int] = []
    for k in range(chain.n):
        le = chain.l[k] / E
        sg = 0.5 * le * (GAUSS_X + 1.0)
        S = hermite_shapes(sg, le)[0]
        for j in range(E):
            a, b = ltg[k][j], ltg[k][j + 1]
            dofs = np.array([a[:2], a[2:], b[:2], b[2:]])  # (4, 2)
            for g in range(sg.size):
                for rows, c in ((rows_x, 0), (rows_y, 1)):
                    r = np.zeros(size)
                    r[dofs[:, c]] = S[g]
                    rows.append(r)
                wts.append(chain.m[k] * 0.5 * le * GAUSS_W[g])
                rod_of.append(k)
        if chain.mu[k] > 0:
            for rows, c in ((rows_x, 0), (rows_y, 1)):
                r = np.zeros(size)
                r[ltg[k][E][c]] = 1.0
                rows.append(r)
            wts.append(chain.mu[k])
            rod_of.append(k)
    return np.array(rows_x), np.array(rows_y), np.array(wts), np.array(rod_of)
