"""The native models' lock records: what a latch's lock did (the plastic impact, the rigid-panel
yardstick) and the terms of the windowed lock impulse (``rodval.mechanics.lock_window``) the driver
integrates over the window after it (``rodval.solvers.outputs.LockWindows``).

The windowed impulse is measured twice on the model's own solution (docs/deployment.md, "The
lock impulse"):

* ``impulse``: the latch's reaction, mu + int lambda (1 - s/w) ds, with mu the instantaneous
  plastic impulse and lambda the multiplier of the held hinge (N m, on the outboard rod,
  counter-clockwise positive);
* ``impulse_momentum``: the same from the outboard part's angular momentum about the hinge
  node k, H_out, whose rate is lambda plus the finite moments on it,
  M_fin = -(hinge k's spring, damper and acting stops) + Tq_k (hinge k's motors and rate
  dampers) - v_k x p_out + the moments of the loads on nodes beyond k about node k (v_k: node
  k's velocity, p_out: the outboard linear momentum); the window mean of H_out(tau) -
  H_out(0-) - int_0^tau M_fin ds.

Both use the model's velocity field (its ``rod_momenta_at``); they agree when the
model's equations are the Newton-Euler equations of that field, and the gap is reported.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rodval.core.scene import hinge_angles
from rodval.mechanics.lock_window import lock_window
from rodval.mechanics.rigid import node_velocities, rigid_lock
from rodval.mechanics.root_momentum import root_momentum_fields
from rodval.models.assembly.paper_matrices import generalized_forces, node_positions, rod_momenta

#: The systems these functions read: ``rodval.models.systems.paper_system.PaperSystem`` (which
#: imports this module, so it is not imported here).
PaperSystem = Any


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b (z component) of 2-vectors along the last axis."""
    z: np.ndarray = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return z


def outboard_momentum(
    system: PaperSystem, y: np.ndarray, k: int
) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """(H_out (N m s): the angular momentum of rods k+1..n (1-based) and their far nodes about
    node k; p_out (N s, (2,)): their linear momentum; r (m, (n+1, 2)): the node positions;
    v_k (m/s, (2,)): node k's velocity). O(n)."""
    v = system.generalized_rates(y)
    phi = system.rigid(y[None, :])[0][0]
    chain = system.base_chain
    p, h, _ = system.rod_momenta_at(y)
    x, yy = node_positions(chain.l, phi)
    r0, v0 = system.root_motion(y)  # node 0 (zero on a pinned base)
    r = np.stack([x, yy], axis=-1) + r0
    v_k = v0 + (node_velocities(chain.l, phi, v[: system.n])[k - 1] if k > 0 else 0.0)
    p_out = p[k:].sum(axis=0)
    return float(h[k:].sum()) - float(cross(r[k], p_out)), p_out, r, v_k


def energy_parts(system: PaperSystem, t: float, y: np.ndarray) -> tuple[float, float, float]:
    """(kinetic, hinge, bending) energy (J) at one state in the current mode: T, the hinge
    springs and acting stops, the rods' bending; their sum is the model's E = T + Pi. O(n)."""
    kin, pot = system.energy_rows(np.array([t]), y[None, :])
    bend = system.bending_energy_at(t, y)
    return float(kin[0]), float(pot[0]) - bend, bend


def window_terms(system: PaperSystem, t: float, y: np.ndarray, k: int) -> tuple[float, ...]:
    """(lambda (N m): the held hinge k's reaction on the outboard rod; H_out (N m s); M_fin
    (N m); P_ext, P_diss (W): the power of the loads, motors and rate dampers and of the hinge
    dampers (``power``)) at one state in the current mode (see the module docstring). O(n)."""
    lam = system.accel_locked(t, y)[1]
    held = [int(h) for h in system._lock_h]
    H, p_out, r, v_k = outboard_momentum(system, y, k)
    ch = system.chain  # the mode's effective chain: acting stops are in its kappa, nu, rest
    D = system.hinge_angles_at(t, y)[k]
    rate = system.hinge_rates(y)[k]
    finite = -(ch.kappa[k] * (D - ch.rest_angle[k]) + ch.nu[k] * rate) - float(cross(v_k, p_out))
    Tq = system.torques_at(t, y)
    if Tq.size:
        finite += float(Tq[k])
    forces = system.loads.nodal(t)
    if forces is not None:
        X, Y = forces  # at nodes 1..n
        arm = r[k + 1 :] - r[k]
        finite += float(np.sum(arm[:, 0] * Y[k:] - arm[:, 1] * X[k:]))
    return (float(lam[held.index(k)]), H, float(finite), *system.power(t, y))


def window_rows(system: PaperSystem, times: np.ndarray, Y: np.ndarray, k: int) -> np.ndarray:
    """``window_terms`` (lambda, H_out, M_fin, P_ext, P_diss) at the states Y (nt, N) at
    ``times`` (s), all in the current mode, as rows (nt, 5): the same arithmetic on whole
    arrays (one compiled constrained solve per state; the momenta, hinge angles and rates,
    dampers' power vectorized), equal to the per-state values to round-off (the sums over
    rods in another order for n >= 8: a few ulp of the largest term). A system whose
    momenta or powers are its own (``whole_arrays`` false) is evaluated state by state."""
    times = np.asarray(times, float)
    if not times.size:
        return np.zeros((0, 5))
    if system.whole_arrays:
        return _window_rows(system, times, np.asarray(Y, float), k)
    return np.array([window_terms(system, float(t), y, k) for t, y in zip(times, Y)])


def _window_rows(system: PaperSystem, times: np.ndarray, Y: np.ndarray, k: int) -> np.ndarray:
    """``window_rows`` of a pinned paper system (``whole_arrays``)."""
    n = system.n
    j = [int(h) for h in system._lock_h].index(k)
    solve = getattr(system, "solve_locked", None)  # the reduced model: lambda and gamma at once
    if solve is not None and system.locked:
        solved = [solve(float(t), y) for t, y in zip(times, Y)]
        lam = np.array([s[2][j] for s in solved])
        gamma = np.array([s[1] for s in solved]).reshape(-1, 2 * n)
        alpha, beta = gamma[:, :n], gamma[:, n:]
    else:
        lam = np.array([system.accel_locked(float(t), y)[1][j] for t, y in zip(times, Y)])
        alpha, beta = system.bending(times, Y)[:2]
    V = np.array([system.generalized_rates(y) for y in Y])
    dphi_r, dalpha, dbeta = V[:, :n], V[:, n : 2 * n], V[:, 2 * n : 3 * n]
    phi, dphi = system.rigid(Y)
    chain = system.base_chain
    # outboard_momentum, per row
    p, h, _ = rod_momenta(chain, phi, dphi_r, dalpha, dbeta)
    x, yy = node_positions(chain.l, phi)
    r = np.stack([x, yy], axis=-1)
    p_out = p[:, k:].sum(axis=1)
    H = h[:, k:].sum(axis=1) - cross(r[:, k], p_out)
    if k > 0:
        nodes = np.stack([-np.sin(phi), np.cos(phi)], axis=-1)
        v_k = np.cumsum((chain.l * dphi_r)[..., None] * nodes, axis=-2)[:, k - 1]
        finite_v = cross(v_k, p_out)
    else:
        finite_v = np.zeros(times.size)  # node 0 is pinned
    ch = system.chain  # the mode's effective chain (acting stops in its kappa, nu, rest)
    D = hinge_angles(phi, alpha, beta, None)[:, k]
    rates = hinge_angles(dphi_r, dalpha, dbeta, None)
    finite = -(ch.kappa[k] * (D - ch.rest_angle[k]) + ch.nu[k] * rates[:, k]) - finite_v
    p_ext = np.zeros(times.size)
    for i, t in enumerate(times):
        forces = system.loads.nodal(float(t))
        if forces is None:
            continue
        X, Yf = forces  # at nodes 1..n
        arm = r[i, k + 1 :] - r[i, k]
        finite[i] += float(np.sum(arm[:, 0] * Yf[k:] - arm[:, 1] * X[k:]))
        sums = system.loads.suffix_sums(float(t))
        p_ext[i] = float(generalized_forces(system.l, phi[i], *sums) @ dphi[i])
    if system.loads.torques:  # motors and rate dampers: Tq_k on the outboard part, power
        Tq = np.array([system.loads.hinge_moments(float(t), r) for t, r in zip(times, rates)])
        finite += Tq[:, k]
        p_ext += np.sum(Tq * rates, axis=-1)
    if system.damped:
        cb = 4.0 * ch.bending_damping / ch.l
        bending = cb * (dalpha * dalpha + dalpha * dbeta + dbeta * dbeta)
        p_diss = np.sum(ch.nu * rates * rates, axis=-1) + np.sum(bending, axis=-1)
    else:
        p_diss = np.zeros(times.size)
    return np.stack([lam, H, finite, p_ext, p_diss], axis=-1)


def lock_record(
    system: PaperSystem, t: float, y: np.ndarray, locked: tuple[int, ...], new: tuple[int, ...]
) -> tuple[np.ndarray, dict[str, Any]]:
    """The state after the plastic lock of the latches ``new`` with ``locked`` (all held
    after it) and the event's data: the instantaneous angular impulses (N m s, on the
    outboard rod k+1, counter-clockwise positive: the convention of every model's event
    records), joint linear impulses (N s), kinetic energy before and after (J), the
    rigid-panel lock of the chords before it (``rodval.mechanics.rigid.rigid_lock``), the angular
    momentum about the root just before and after (N m s; the impact is internal, so it is
    kept while hinge 0 is free) and what the lock window needs (its length, the
    instantaneous impulse, H_out just before).

    The root's angular momentum (``angular_momentum_root_before``, ``_after``, ``_jump``) is
    None when hinge 0 is held after the lock (locked now or earlier), on a pinned chain and on
    a free base alike: the held root hinge passes an impulsive moment from the ground (or the
    base's body) onto rod 1, so the chain's angular momentum about node 0 is no longer kept
    and its jump measures nothing. While hinge 0 is free its spring, damper and stops are
    finite moments, which take no part in the instantaneous jump: the jump is meaningful
    whatever kappa[0] and nu[0] are (docs/deployment.md)."""
    latches = system.latches
    hinges = np.array([latches[j].hinge for j in locked], dtype=np.int64)
    angles = np.array([latches[j].angle for j in locked])
    phi, dphi = (a[0] for a in system.rigid(y[None, :]))
    k = latches[new[0]].hinge
    # the rigid-panel yardstick is a pinned chain's: none on a moving base (docs/base.md)
    rigid = (
        {}
        if system.scene.base.moving
        else rigid_lock(system.base_chain, phi, dphi, hinges.tolist(), int(hinges[-len(new)]))
    )
    T0, hinge0, bending0 = energy_parts(system, t, y)
    P0 = system.momenta(y)
    H0 = outboard_momentum(system, y, k)[0]
    root0 = outboard_momentum(system, y, 0)[0]  # node 0 is the root
    y_new, mu = system.plastic_jump(y, hinges, angles)
    root1 = outboard_momentum(system, y_new, 0)[0]
    T1 = system.kinetic_energy(t, y_new)
    S = system.momenta(y_new) - P0
    impulses = [float(m) for m in mu]  # A^T mu: +mu on the outboard rod's coordinates
    return y_new, {
        "hinge": k,
        "hinges": [latches[j].hinge for j in new],
        "impulse_instant": impulses[len(locked) - len(new)],
        "impulse_window": lock_window(system.base_chain, latches[new[0]], hinges.tolist()),
        "outboard_momentum_before": H0,
        "held_hinges": [int(h) for h in hinges],
        "angular_impulses": impulses,
        "joint_impulses": S.tolist(),
        "root_impulse": S[0].tolist(),
        "kinetic_before": T0,
        "hinge_before": hinge0,
        "bending_before": bending0,
        "kinetic_after": T1,
        **root_momentum_fields(root0, root1, 0 in hinges.tolist()),
        **rigid,
    }


def plastic_jump(
    system: PaperSystem, y: np.ndarray, hinges: Any, angles: Any
) -> tuple[np.ndarray, np.ndarray]:
    """The plastic lock of ``hinges`` at ``angles`` (rad) in a model whose state is [q; q']
    (the full model, every ladder rung): Delta q' = M^-1 A^T mu, (A M^-1 A^T) mu = -A q' (the
    hinges' rates become zero; the velocity closest to the old one in the kinetic metric
    M(q)); q is first projected onto the latch angles in the same metric (a round-off-sized
    correction). Returns (state after, mu (N m s)); O(N m) with the compiled unit responses."""
    y = y.copy()
    half = y.size // 2
    q, v = y[:half], y[half:]
    U = system.unit_responses(q, hinges)
    A = system.hinge_rows(hinges)
    G = A @ U.T
    q += U.T @ np.linalg.solve(G, angles - A @ q)
    mu = np.linalg.solve(G, -(A @ v))
    v += U.T @ mu
    return y, mu
