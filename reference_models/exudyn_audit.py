"""The exudyn model's energy audit and the energy accounts of its lock windows, with rodval's
definitions (``rodval.solvers.audit``, ``rodval.mechanics.lock_window.window_energies``), from
the node states exudyn recorded at every step.

* W_ext(t) = int P_ext dt, P_ext = sum of the nodal forces . the node velocities (W), plus
  the torque items' (motors', rate dampers') work sum_k int M_k dD_k, M_k their moments
  (``HingeTorque.moment``, N m) at the hinge rates the hinge dampers see (``hinge_rates``):
  by the trapezoidal rule along the recorded hinge angles, sum (M_i + M_i+1)/2 (D_i+1 -
  D_i) (``_torque_work``), as the angles are positions: a constant moment's work is M (D -
  D(0)) exactly, whereas the rates carry the element-scale ringing a step moment starts,
  which the trapezoidal rule in time misses at exudyn's step (a motor's torque-speed line
  from t = 0: W off by 2e-3 relative against the full model's, residual 4e-4; along the
  angles 3e-6 and 6e-5);
* D(t) = int P_diss dt, P_diss (W) the power of the scene's dampers on the beam: the hinge
  dampers nu_k (dD_k/dt)^2 (hinge 0's rate from a free base's), the acting stops' dampers
  d (dD_k/dt)^2 (an engaged compliant latch's two stops', internal as theirs, after its
  engagement: ``timed_stops``) and the rods' Kelvin-Voigt bending damping int c (dK/dt)^2 ds (exudyn's
  ``bendingDamping``: the virtual work int c K' delta K ds of its material curvature K; 5
  Gauss points per element; exudyn's C++ ``ComputeODE2LHS`` adds ``bendingDamping *
  curvature_t`` to the bending moment, with curvature_t = (f_t g - f g_t) / g^2, f = r' x r'',
  g = |r'|^2: the rate used here, normalisation included).
  A residual at start-up with bending damping is not this law's: with generalized-alpha's
  computed initial accelerations at spectral radius 0, the first steps kick the overdamped
  element-scale bending modes (E rises by tens of J with no load) and the damping takes that
  energy out again, which D books (issue 37; docs/deployment.md, "exudyn's start-up with
  bending damping"; tests/test_exudyn_kv_audit.py).
  The powers are integrated by the trapezoidal rule over exudyn's steps: second order, as
  its generalized-alpha integrator.
* A lock: exudyn has no instantaneous impact (its latch joint, switched on at the step
  where the hinge crosses the latch angle, ``t_activated``, holds the hinge from the next
  steps on), so its ``instant_energy_loss`` is 0 and D has no lock term: the energy the
  switched-on joint takes out is in R. (Over the first steps after the switch the recorded
  velocities do not yet satisfy the held hinge: E dips by several J and comes back, so no
  energy difference across the switch measures a loss.)
* R(t) = E(t) - E(0) - W_ext(t) + D(t) is then what the integrator itself took out or put in:
  generalized-alpha's numerical dissipation (R < 0) plus the quadrature's O(h^2). The run
  records ``numerical_dissipation`` = -R(t_end) (J) in its settings, and max |R| over the
  energy scale (``rodval.solvers.audit.balance``) as its ``energy_residual``, which the
  validity verdict bounds as every model's (docs/deployment.md, "Where the lock energy
  goes"). That scalar is read on every recorded step (``account``: E of each recorded state,
  W and D there), not at the output times, so it is the run's whatever its output grid
  (issue 47; the native models read theirs on the audit grid,
  ``rodval.solvers.audit.audit_times``); the quantities "work", "dissipated" and
  "energy_residual" are W, D and R at the output times.

Cost: O(steps x n x elements) array operations, once after the run.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from reference_models.exudyn_beam import (
    Array,
    Nodes,
    beam_elements,
    body_attitude,
    cross2d,
    system_energies,
    timed_stops,
    torque_moments,
)
from reference_models.exudyn_observe import (
    Observed,
    chord_angles,
    hinge_rates,
    recorded_hinge_angle,
    rod_ends,
    states_at,
)
from rodval.core.loads import LoadSet
from rodval.core.scene import Scene
from rodval.mechanics.lock_window import window_energies
from rodval.solvers.audit import balance


def step_powers(
    scene: Scene, E: int, t_rec: Array, records: Nodes, engaged: dict[int, float] | None = None
) -> tuple[Array, ...]:
    """(P_ext, P_diss) (W, (steps,)) at the recorded steps, P_ext the nodal loads' only, and
    the torque items' work (J, (steps,), ``_torque_work``) there (see the module docstring);
    ``engaged``: hinge -> the time (s) its compliant latch acts after (``Latches.engaged``)."""
    chain = scene.chain
    qv = {key: (q, v) for key, (q, v, _) in records.items()}
    qL, vL, qR, vR = rod_ends(scene.n, E, qv)
    dD = hinge_rates(qL, vL, qR, vR, body_attitude(qv)[1])
    p_ext = np.zeros(t_rec.size)
    if scene.loads:
        loads = LoadSet(scene.loads, scene.n)
        for i, t in enumerate(t_rec):  # nodes 1..n are the rods' right ends
            forces = loads.nodal(float(t))
            if forces is not None:
                p_ext[i] = float(forces[0] @ vR[i, :, 0] + forces[1] @ vR[i, :, 1])
    p_diss = np.sum(chain.nu * dD**2, -1)
    D0 = scene.initial_hinge_angles()
    for stop, t_on in timed_stops(scene, engaged):
        k = stop.hinge
        inside = stop.acts(recorded_hinge_angle(records, E, k, D0[k], t_rec.size)) & (t_rec > t_on)
        p_diss += np.where(inside, stop.damping * dD[:, k] ** 2, 0.0)
    for k, w, _, dS, ddS, Q, V in beam_elements(chain, E, qv):
        c = chain.bending_damping[k]
        if c == 0:
            continue
        r1, r2 = np.einsum("gi,tic->tgc", dS, Q), np.einsum("gi,tic->tgc", ddS, Q)
        v1, v2 = np.einsum("gi,tic->tgc", dS, V), np.einsum("gi,tic->tgc", ddS, V)
        n2 = np.sum(r1**2, -1)
        curv_rate = (cross2d(v1, r2) + cross2d(r1, v2)) / n2 - 2 * cross2d(r1, r2) * np.sum(
            r1 * v1, -1
        ) / n2**2
        p_diss += c * np.sum(w * curv_rate**2, -1)
    return p_ext, p_diss, _torque_work(scene, E, t_rec, records, dD)


def _torque_work(scene: Scene, E: int, t_rec: Array, records: Nodes, dD: Array) -> Array:
    """The torque items' work sum_k int M_k dD_k (J) at the recorded steps t_rec (s), by the
    trapezoidal rule along the recorded hinge angles D_k (``recorded_hinge_angle``), M_k at
    the hinge rates dD (rad/s, (steps, n)); zeros without torque items. O(steps x n)."""
    M = torque_moments(scene, t_rec, dD)
    if M is None:
        return np.zeros(t_rec.size)
    D0 = scene.initial_hinge_angles()
    D = np.stack(
        [recorded_hinge_angle(records, E, k, D0[k], t_rec.size) for k in range(scene.n)], 1
    )
    steps = np.sum(0.5 * (M[1:] + M[:-1]) * np.diff(D, axis=0), -1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def _cumulative(t: Array, p: Array) -> Array:
    """int_0^t p dt (J) at every recorded step by the trapezoidal rule."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(t))])


def energy_parts(
    scene: Scene,
    E: int,
    EA: float,
    times: Any,
    t_rec: Array,
    records: Nodes,
    engaged: dict[int, float] | None = None,
) -> Array:
    """(kinetic, hinge, rod strain) energy (J), (3, len(times)), at any times (s) inside the
    recorded steps (``system_energies`` on the node states interpolated there; ``engaged``:
    hinge -> the time (s) its compliant latch acts after (``Latches.engaged``)); the rod strain is the
    bending and the (small) axial strain energy."""
    times = np.asarray(times, float)
    at = states_at(times, t_rec, records)
    phi, _, alpha, beta = chord_angles(scene, E, times, t_rec, records, at)
    kin, strain, hinge = system_energies(scene, E, EA, at, (phi, alpha, beta), (times, engaged))
    return np.array([kin, hinge, strain])


def ledger(
    scene: Scene,
    E: int,
    EA: float,
    recorded: tuple[Array, Nodes],
    events: list[dict[str, Any]],
    engaged: dict[int, float] | None = None,
) -> tuple[Array, Array]:
    """W_ext and D (J) at the recorded steps (``recorded`` = (their times, their node
    states); ``engaged``: hinge -> the time (s) its compliant latch acts after (``Latches.engaged``)); the
    lock records in ``events`` get their ``instant_energy_loss`` (0), hinge and bending
    energy before the lock and, for a window the recorded steps reach to its end, its energy
    accounts (module docstring)."""
    t_rec, records = recorded
    p_ext, p_diss, w_torque = step_powers(scene, E, t_rec, records, engaged)
    W, D = _cumulative(t_rec, p_ext) + w_torque, _cumulative(t_rec, p_diss)

    locks = [ev for ev in events if "t_activated" in ev]
    # every lock's two times at once: one interpolation of the records, O(steps x n)
    ta = np.array([ev["t_activated"] for ev in locks])
    te = np.array([ev["t"] + ev["impulse_window"] for ev in locks])
    closed = te <= t_rec[-1]
    parts = energy_parts(scene, E, EA, np.concatenate([ta, te[closed]]), *recorded, engaged)
    before, end = parts[:, : ta.size].T.tolist(), iter(parts[:, ta.size :].T.tolist())
    work, lost = (
        np.interp(te, t_rec, W) - np.interp(ta, t_rec, W),
        np.interp(te, t_rec, D) - np.interp(ta, t_rec, D),
    )
    for i, ev in enumerate(locks):
        # kinetic_before is the latches' v^T M v / 2 at the same state
        ev.update(instant_energy_loss=0.0, hinge_before=before[i][1], bending_before=before[i][2])
        if closed[i]:
            ev.update(window_energies(ev, tuple(next(end)), work[i], lost[i]))
    return W, D


def audit_quantities(
    times: Array, energy: Array, E0: float, t_rec: Array, W: Array, D: Array
) -> tuple[Observed, float]:
    """ "work", "dissipated" and "energy_residual" at the output ``times`` (``energy``: E
    there, E0 (J) at t = 0; W, D at the recorded steps, interpolated linearly) and the
    numerical dissipation -R(t_end) (J)."""
    W_out, D_out = np.interp(times, t_rec, W), np.interp(times, t_rec, D)
    R = balance(energy, E0, W_out, D_out)[0]
    k = np.zeros(1, dtype=int)
    quantities = {
        "work": (W_out[:, None], k),
        "dissipated": (D_out[:, None], k),
        "energy_residual": (R[:, None], k),
    }
    return quantities, float(-R[-1])


def account(
    scene: Scene,
    E: int,
    EA: float,
    times: Array,
    t_rec: Array,
    records: Nodes,
    events: list[dict[str, Any]],
    observed: Observed,
    engaged: dict[int, float] | None = None,
) -> tuple[float | None, dict[str, float]]:
    """The audit of a run that reached ``times`` (``engaged``: hinge -> the time (s) its
    compliant latch acts after, ``Latches.engaged``):
    the lock records completed (``ledger``) and, where the scene asks for "energy", the
    audit quantities added to ``observed``;
    returns the scalar residual (None without the audit) and the settings entry
    {"numerical_dissipation": J} (empty without the audit).

    The scalar is read on every recorded step (``rodval.solvers.audit.balance`` of E, the
    energy ``observe`` reports, of each recorded state, ``energy_parts``, and W, D there),
    not at the output times; E0 is the recorded state's at t = 0 (the first output time
    need not be 0)."""
    n = int(np.searchsorted(t_rec, times[-1], side="right")) if times.size else 0
    if n < 2 or not (scene.latches or "energy" in observed):  # nothing to account for
        return None, {}
    reached = {key: tuple(x[:n] for x in arrs) for key, arrs in records.items()}
    W, D = ledger(scene, E, EA, (t_rec[:n], reached), events, engaged)
    if "energy" not in observed:
        return None, {}
    steps = energy_parts(scene, E, EA, t_rec[:n], t_rec[:n], reached, engaged).sum(axis=0)
    energy = observed["energy"][0][:, 0]
    quantities, lost = audit_quantities(times, energy, float(steps[0]), t_rec[:n], W, D)
    observed.update(quantities)
    return balance(steps, float(steps[0]), W, D)[1], {"numerical_dissipation": lost}
