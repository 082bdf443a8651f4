"""The exudyn model's outputs: the scene's quantities at the output times from the recorded
beam-node states (``observe``; definitions in docs/quantities.md), and the run's peaks on
every recorded step (``recorded_peaks``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from reference_models.exudyn_beam import (
    BODY,
    Array,
    Nodes,
    body_attitude,
    hermite_interpolate,
    hermite_shapes,
    momentum_audit_rows,
    stop_moment,
    system_energies,
    system_momenta,
    timed_stops,
    torque_moments,
    wrap_angle,
)
from rodval.core.base import Base
from rodval.core.bounds import MIN_POSITIVE
from rodval.core.quantities import PEAK_QUANTITIES, peak_values, tip_deflection
from rodval.core.scene import QUANTITIES, Chain, Scene, hinge_angles
from rodval.solvers.audit import audit_times

#: The mass (kg) and inertia (kg m^2) the beam quadratures (``exudyn_beam``, which read a
#: moving body's from ``scene.base.inertial()``) give a prescribed base's body: massless as in
#: the native models (the drive's force is external to the chain), to round-off: its kinetic
#: energy is below 1e-12 J per (m/s)^2 and (rad/s)^2.
MASSLESS = MIN_POSITIVE


def body_view(scene: Scene) -> Scene:
    """The scene as the beam quadratures and the guard see it: ``scene`` itself, but a
    prescribed base as a free body of mass and inertia ``MASSLESS`` starting in the laws'
    state at t = 0 (its motion is the recorded body node's: only its mass is read)."""
    b = scene.base
    if not b.prescribed:
        return scene
    r, v, th, w = b.state_at(0.0)
    free = Base(
        "free",
        mass=MASSLESS,
        inertia=MASSLESS,
        hinge_offset=b.hinge_offset,
        position=(float(r[0]), float(r[1])),
        velocity=(float(v[0]), float(v[1])),
        attitude=th,
        rate=w,
    )
    return scene.with_(base=free)


#: Observed quantities: name -> (values (nt, K), k (K,)).
Observed = dict[str, tuple[Array, Array]]


def states_at(times: Array, t_rec: Array, records: Nodes) -> Nodes:
    """Each recorded node's (state, rate) at ``times`` (cubic Hermite on the records)."""
    return {
        key: (hermite_interpolate(times, t_rec, q, v), hermite_interpolate(times, t_rec, v, a))
        for key, (q, v, a) in records.items()
    }


def momentum_audit(
    scene: Scene, E: int, reached: float, t_rec: Array, records: Nodes
) -> tuple[Array, Array]:
    """(H, G) (N m s) for the angular-momentum audit (``momentum_audit_rows``) on the audit
    grid's times up to ``reached`` (s): ``rodval.solvers.audit.audit_times``, the grid every
    model reads, whatever the output times."""
    grid = audit_times(scene.t_end)
    return momentum_audit_rows(scene, E, states_at(grid[grid <= reached], t_rec, records))


def observe(
    scene: Scene,
    E: int,
    EA: float,
    times: Array,
    t_rec: Array,
    records: Nodes,
    lock_steps: dict[int, float] | None = None,
    engaged: dict[int, float] | None = None,
) -> Observed:
    """The scene's quantities at ``times`` from recorded node states (see module docstring).

    "hinge_angle": D_k (k = 0..n-1) from the continuous tangent angles; "hinge_moment" (N m):
    the moment of hinge k, in the sense of its spring's kappa (D - rest): the spring, damper
    and stop laws at the measured D and dD, less the torque items' moments (motors, rate
    dampers: ``HingeTorque.moment``, positive driving D up; an engaged compliant latch's two
    stops after its engagement, ``engaged``: hinge -> s, ``Latches.engaged``), while the hinge
    is free, and
    from the state
    where its latch was switched on (``lock_steps``: hinge -> time, s) the beam's own bending
    moment EI kappa_b at the root of rod k+1 (the hinge has no inertia: it transmits that
    moment), kappa_b the curvature of the cable's field there. Hinge 0 is measured from a free
    base's attitude (its body node's record, ``BODY``), which also gives "base"; "momentum"
    and "angular_momentum" are the whole system's (``system_momenta``). A prescribed base's
    body is massless (``body_view``): "energy", "momentum" and "angular_momentum" are the
    chain's, as the native models'."""
    scene = body_view(scene)
    n = scene.n
    rods = np.arange(1, n + 1)
    at = states_at(times, t_rec, records)
    out: Observed = {}
    if not scene.wants(*QUANTITIES):
        return out
    phi, dphi, alpha, beta = chord_angles(scene, E, times, t_rec, records, at)
    qL, vL, qR, vR = rod_ends(n, E, at)
    for name, val in (("phi", phi), ("dphi", dphi), ("alpha", alpha), ("beta", beta)):
        if scene.wants(name):
            out[name] = (val, rods)
    if scene.wants("x", "y", "tip_deflection"):
        nodes = np.arange(0, n + 1)
        x = np.concatenate([qL[:, :1, 0], qR[..., 0]], 1)
        y = np.concatenate([qL[:, :1, 1], qR[..., 1]], 1)
        if scene.wants("x"):
            out["x"] = (x, nodes)
        if scene.wants("y"):
            out["y"] = (y, nodes)
        if scene.wants("tip_deflection"):
            tip = tip_deflection(x, y, body_attitude(at)[0])
            out["tip_deflection"] = (tip[:, None], np.zeros(1, dtype=int))
    if scene.wants("hinge_angle", "hinge_moment"):
        _hinge_quantities(
            scene, E, (times, at), (phi, alpha, beta), (qL, vL, qR, vR), (lock_steps, engaged), out
        )
    if scene.wants("energy"):
        kin, strain, hinge = system_energies(scene, E, EA, at, (phi, alpha, beta), (times, engaged))
        zero = np.zeros(1, dtype=int)
        out["kinetic"] = (kin[:, None], zero)
        out["potential"] = ((strain + hinge)[:, None], zero)
        out["energy"] = ((kin + strain + hinge)[:, None], zero)
    if scene.wants("angular_momentum", "momentum"):
        H, P = system_momenta(scene, E, at)
        if scene.wants("angular_momentum"):
            out["angular_momentum"] = (H, np.arange(2))
        if scene.wants("momentum"):
            out["momentum"] = (P, np.arange(2))
    if scene.wants("base"):
        _base_quantities(at, out)
    return out


def recorded_peaks(
    scene: Scene,
    E: int,
    EA: float,
    steps: Array,
    t_rec: Array,
    records: Nodes,
    lock_steps: dict[int, float] | None = None,
    engaged: dict[int, float] | None = None,
) -> dict[str, Any] | None:
    """The run's peaks (``SolverStats.peaks``) of the ``PEAK_QUANTITIES`` the scene outputs:
    ``peak_values`` of ``observe`` (the outputs' own quantity functions) at every recorded
    step ``steps`` (s, those the run kept), whatever the output times (``lock_steps``,
    ``engaged``: as ``observe``'s); None when the scene outputs none of them."""
    wanted = tuple(q for q in PEAK_QUANTITIES if scene.wants(q))
    if not wanted:
        return None
    observed = observe(
        scene.with_(outputs=wanted), E, EA, steps, t_rec, records, lock_steps, engaged
    )
    return {"read_on": "every recorded step", "values": peak_values(steps, observed)}


def _base_quantities(at: Nodes, out: Observed) -> None:
    """A moving base's "base" quantities into ``out``: base_position, base_velocity (m, m/s;
    its centre of mass, k = 0, 1), base_attitude, base_rate (rad, rad/s; k = 0), from its body
    node's record."""
    q, v = at[BODY]
    pair, one = np.arange(2), np.zeros(1, dtype=int)
    out["base_position"] = (q[:, :2], pair)
    out["base_velocity"] = (v[:, :2], pair)
    out["base_attitude"] = (q[:, 2:3], one)
    out["base_rate"] = (v[:, 2:3], one)


def rod_ends(n: int, E: int, at: Nodes) -> tuple[Array, ...]:
    """The rods' left and right node states and rates (qL, vL, qR, vR), (nt, n, 4)."""
    qL = np.stack([at[(k, 0)][0] for k in range(n)], 1)
    qR = np.stack([at[(k, E)][0] for k in range(n)], 1)
    vL = np.stack([at[(k, 0)][1] for k in range(n)], 1)
    vR = np.stack([at[(k, E)][1] for k in range(n)], 1)
    return qL, vL, qR, vR


def chord_angles(
    scene: Scene, E: int, times: Array, t_rec: Array, records: Nodes, at: Nodes
) -> tuple[Array, ...]:
    """(phi, dphi, alpha, beta) (rad, rad/s; (nt, n)) at ``times`` from the node states ``at``
    there: the chord angles continuous in time (unwrapped along every recorded step from the
    initial phi) and the end tangents' angles to the chord."""
    n = scene.n
    left = [records[(k, 0)] for k in range(n)]
    right = [records[(k, E)] for k in range(n)]
    # chord angles on every recorded step, unwrapped in time from the initial phi
    chord_rec = np.stack([r[0][:, :2] - lft[0][:, :2] for lft, r in zip(left, right)], 1)
    raw_rec = np.arctan2(chord_rec[..., 1], chord_rec[..., 0])
    phi_rec = np.unwrap(raw_rec, axis=0)
    phi0 = scene.initial.resolve(n)["phi"]
    phi_rec += 2 * np.pi * np.round((phi0 - phi_rec[0]) / (2 * np.pi))
    i = np.clip(np.searchsorted(t_rec, times, side="right") - 1, 0, t_rec.size - 1)
    qL, vL, qR, vR = rod_ends(n, E, at)
    d, dd = qR[..., :2] - qL[..., :2], vR[..., :2] - vL[..., :2]
    phi = phi_rec[i] + wrap_angle(np.arctan2(d[..., 1], d[..., 0]) - phi_rec[i])
    dphi = (d[..., 0] * dd[..., 1] - d[..., 1] * dd[..., 0]) / np.sum(d**2, -1)
    alpha = wrap_angle(np.arctan2(qL[..., 3], qL[..., 2]) - phi)
    beta = wrap_angle(np.arctan2(qR[..., 3], qR[..., 2]) - phi)
    return phi, dphi, alpha, beta


def _hinge_quantities(
    scene: Scene,
    E: int,
    states: tuple[Array, Nodes],
    angles: tuple[Array, ...],
    ends: tuple[Array, ...],
    switched: tuple[dict[int, float] | None, dict[int, float] | None],
    out: Observed,
) -> None:
    """ "hinge_angle" D_k (rad) and "hinge_moment" (N m) into ``out`` (see ``observe``):
    ``states`` = (the times, s, the node states there); ``angles`` = (phi, alpha, beta) (nt,
    n); ``ends`` = the rods' left and right node states and rates (qL, vL, qR, vR), (nt, n,
    4); ``switched`` = (``lock_steps``, ``engaged``), each hinge -> s."""
    times, at = states
    lock_steps, engaged = switched
    phi, alpha, beta = angles
    qL, vL, qR, vR = ends
    hinges = np.arange(scene.n)
    attitude, rate = body_attitude(at)
    D = hinge_angles(phi, alpha, beta, attitude)
    dD = hinge_rates(qL, vL, qR, vR, rate)
    if scene.wants("hinge_angle"):
        out["hinge_angle"] = (D, hinges)
    if scene.wants("hinge_moment"):
        chain = scene.chain
        M = chain.kappa * (D - chain.rest_angle) + chain.nu * dD
        for stop, t_on in timed_stops(scene, engaged):
            moment = stop_moment(stop, D[:, stop.hinge], dD[:, stop.hinge])
            M[:, stop.hinge] += np.where(times > t_on, moment, 0.0)
        driving = torque_moments(scene, times, dD)
        if driving is not None:
            M -= driving
        for k, t_on in (lock_steps or {}).items():
            after = times >= t_on - 1e-12
            if after.any():
                M[after, k] = _root_bending_moment(chain, E, at, k)[after]
        out["hinge_moment"] = (M, hinges)


def hinge_rates(
    qL: Array, vL: Array, qR: Array, vR: Array, base_rate: Array | None = None
) -> Array:
    """dD_k/dt (rad/s, (nt, n)): the rate of rod k+1's left end tangent minus rod k's right
    one (for the root: minus a free base's rate ``base_rate`` (nt,), 0 on a pinned base) from
    the rods' end node states and rates (nt, n, 4)."""

    def rate(q: Array, v: Array) -> Any:
        return (q[..., 2] * v[..., 3] - q[..., 3] * v[..., 2]) / (q[..., 2] ** 2 + q[..., 3] ** 2)

    right = rate(qR, vR)[:, :-1]
    dD: Array = rate(qL, vL) - np.concatenate([np.zeros((right.shape[0], 1)), right], 1)
    if base_rate is not None:
        dD[:, 0] -= base_rate
    return dD


def _root_bending_moment(chain: Chain, E: int, at: Nodes, k: int) -> Array:
    """The beam's bending moment EI kappa_b (N m) at the root of rod k+1 at every output time,
    kappa_b the curvature of its first cable element's field at s = 0."""
    le = chain.l[k] / E
    ddS = hermite_shapes(np.zeros(1), le)[2][0]  # (4,) at s = 0
    dS = hermite_shapes(np.zeros(1), le)[1][0]
    qa, qb = at[(k, 0)][0], at[(k, 1)][0]
    Q = np.stack([qa[:, :2], qa[:, 2:], qb[:, :2], qb[:, 2:]], 1)  # (nt, 4, 2)
    r1 = np.einsum("i,tic->tc", dS, Q)
    r2 = np.einsum("i,tic->tc", ddS, Q)
    curv = (r1[:, 0] * r2[:, 1] - r1[:, 1] * r2[:, 0]) / np.sum(r1**2, -1)
    return np.asarray(chain.EI[k] * curv)


def stop_events(
    scene: Scene, E: int, t_rec: Array, records: Nodes, lock_times: dict[int, float]
) -> list[dict[str, Any]]:
    """The limit stops' contacts as events, as the native models record them: "stop hinge k
    on" when hinge k's angle D_k enters the stop's side, "stop hinge k off" when it leaves
    (``hinge``, ``active``), none for a stop that acts from the start (it is in the initial
    mode) and none on a hinge after its latch has locked (``lock_times``: hinge -> s). exudyn
    integrates the stop law as a spring, without events: each crossing is found afterwards
    between two recorded states (every quarter step) and located by linear interpolation of
    D_k - angle (an O(h^2) time; ``located`` says so). O(steps) per stop."""
    if not scene.stops or t_rec.size < 2:
        return []
    D0 = scene.initial_hinge_angles()
    events = []
    for stop in scene.stops:
        k = stop.hinge
        D = recorded_hinge_angle(records, E, k, D0[k], t_rec.size)
        g, inside = D - stop.angle, stop.acts(D)
        for i in np.flatnonzero(inside[1:] != inside[:-1]):
            t = t_rec[i] + (t_rec[i + 1] - t_rec[i]) * g[i] / (g[i] - g[i + 1])
            if t >= lock_times.get(k, np.inf):
                break
            on = bool(inside[i + 1])
            events.append(
                {
                    "t": float(t),
                    "label": f"stop hinge {k} {'on' if on else 'off'}",
                    "hinge": k,
                    "active": on,
                    "located": "linear between recorded states",
                }
            )
    return events


def recorded_hinge_angle(records: Nodes, E: int, k: int, D0: float, nt: int) -> Array:
    """D_k (rad) at the first ``nt`` recorded steps: the difference of the end tangents'
    angles (for the root: rod 1's minus a free base's attitude, 0 on a pinned base),
    unwrapped in time from the initial hinge angle D0 (rad)."""

    def tangent(key: tuple[int, int]) -> Any:  # tangent angle (rad, wrapped) of a rod end
        return np.arctan2(*records[key][0][:nt, [3, 2]].T)  # at the recorded times

    if k > 0:
        left = tangent((k - 1, E))
    else:
        left = records[BODY][0][:nt, 2] if BODY in records else 0.0
    D = np.unwrap(tangent((k, 0)) - left)
    return np.asarray(D + 2 * np.pi * np.round((D0 - D[0]) / (2 * np.pi)))
