"""The exudyn model's per-step divergence and resolution check (``Guard``), on the guard
spec, energy budget and messages of ``rodval.solvers.guard``."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from reference_models.exudyn_beam import (
    BODY,
    GAUSS_W,
    GAUSS_X,
    Array,
    force_at,
    hermite_shapes,
    system_energies,
)
from reference_models.exudyn_build import BuiltSystem
from rodval.core.loads import LoadSet
from rodval.core.scene import Scene
from rodval.core.status import (
    STATUS_DIVERGED,
    STATUS_ERROR,
    STATUS_FAILED,
    numerical_failure,
)
from rodval.solvers.guard import GuardSpec, Monitor, diverged_message


@njit(cache=True, error_model="numpy")  # pragma: no cover - compiled
def _state_kernel(
    q: Array, v: Array, M: Array, end: Array, root: Array, d_ref: Array
) -> tuple[bool, float, float, int]:
    """One pass over the state (issue 39: one compiled call a step instead of ~20 numpy
    calls): whether q and v are finite (q.q + v.v), the kinetic energy v^T M v / 2, and the
    largest chord rate |d x d'| / |d|^2 (rad/s, NaN if any is) with its rod (0-based); the
    chords d = q[end] - q[root] + d_ref (rows x, y)."""
    s = 0.0
    for i in range(q.size):
        s += q[i] * q[i] + v[i] * v[i]
    if not np.isfinite(s):
        return False, np.nan, np.nan, -1
    kinetic = 0.0
    n = v.size
    for i in range(n):
        vi = v[i]
        if vi != 0.0:
            row = 0.0
            for j in range(n):
                row += M[i, j] * v[j]
            kinetic += vi * row
    rate_max, k_max = -1.0, 0
    for k in range(end.shape[1]):
        dx = q[end[0, k]] - q[root[0, k]] + d_ref[0, k]
        dy = q[end[1, k]] - q[root[1, k]] + d_ref[1, k]
        ddx = v[end[0, k]] - v[root[0, k]]
        ddy = v[end[1, k]] - v[root[1, k]]
        r = abs(dx * ddy - dy * ddx) / (dx * dx + dy * dy)
        if np.isnan(r):
            return True, 0.5 * kinetic, np.nan, k
        if r > rate_max:
            rate_max, k_max = r, k
    return True, 0.5 * kinetic, rate_max, k_max


class Guard:
    """Divergence and resolution checks of one run, on every accepted step (exudyn's
    PreStepUserFunction: called before each step with t = the end of the coming step, on the
    state of the last accepted step, at t - step). A verdict stops the solver after the coming
    step; ``verdict`` is then (status, message, time of the checked state, whether output times
    at that time are kept).

    * non-finite coordinates or velocities: STATUS_DIVERGED;
    * kinetic energy T = v^T M v / 2 (consistent mass of the cubic elements plus the point
      masses and a free base's body, diag(m, m, J); the hinge data nodes carry no mass)
      above ``factor`` x the budget of ``rodval.solvers.guard`` (``GuardSpec``, ``Monitor``:
      W+ on the power of the loads and torque items (``_power``) at the checked states),
      E(0) the initial T + Pi (``system_energies``): STATUS_BLOWUP;
    * max_k |dphi_k| x step above ``max_rotation``: STATUS_FAILED (under-resolved)."""

    def __init__(
        self,
        built: BuiltSystem,
        scene: Scene,
        E: int,
        EA: float,
        factor: float,
        max_rotation: float,
        checks_energy: bool = True,
    ) -> None:
        mbs, chain = built.mbs, scene.chain
        ref, q0, v0 = built.initial
        self.mbs = mbs
        self.solver: Any = None  # exudyn's solver, set by the run
        self.max_rotation = float(max_rotation)
        size = mbs.systemData.ODE2Size()
        #: each rod's beam nodes' ODE2 indices (rod, node 0..E, [x, y, slope x, slope y])
        self.ltg = ltg = [
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
            s = 0.5 * le * (GAUSS_X + 1.0)
            S = hermite_shapes(s, le)[0]
            Me = chain.m[k] * np.einsum("g,gi,gj->ij", 0.5 * le * GAUSS_W, S, S)  # (4, 4)
            for j in range(E):
                a, b = ltg[k][j], ltg[k][j + 1]
                dofs = np.array([a[:2], a[2:], b[:2], b[2:]])  # (4, 2)
                for c in range(2):
                    self.M[np.ix_(dofs[:, c], dofs[:, c])] += Me
            if chain.mu[k] > 0:
                tip = ltg[k][E][:2]
                self.M[tip, tip] += chain.mu[k]
        # chord vectors d = q[end] - q[root] + d_ref (rows: x, y; a column per rod)
        self._end = np.array([[ltg[k][E][c] for k in range(chain.n)] for c in range(2)], int)
        self._root = np.array([[ltg[k][0][c] for k in range(chain.n)] for c in range(2)], int)
        self._d_ref = self.ref[self._end] - self.ref[self._root]
        self.loads = [(f, ltg[f.node - 1][E][:2]) for f in scene.loads]
        self._torques = _TorqueRates(scene, ltg, built, mbs) if scene.torques else None
        ini = scene.initial.resolve(chain.n)
        at0: dict[tuple[int, int], tuple[Array, ...]] = {
            (k, j): ((ref + q0)[k, j][None], v0[k, j][None])
            for k in range(chain.n)
            for j in range(E + 1)
        }
        if built.body is not None:
            at0[BODY] = self._add_body(scene, np.asarray(mbs.systemData.GetNodeLTGODE2(built.body)))
        parts = system_energies(
            scene, E, EA, at0, (ini["phi"][None], ini["alpha"][None], ini["beta"][None])
        )
        self.spec = GuardSpec(blowup_factor=float(factor), energy0_J=float(np.sum(parts)))
        self.energy = Monitor(self.spec)
        #: False where the work done on the chain is not measured (a prescribed base's drive)
        self._checks_energy = self.spec.checks_energy and checks_energy
        self.verdict: tuple[Any, ...] | None = None
        self.min_step, self.max_rotation_seen = math.inf, 0.0
        self.h = 0.0  # the coming step (s), set by pre_step
        self.state: tuple[Array, Array] | None = None  # (q - ref, v) of the last check

    def _add_body(self, scene: Scene, idx: Array) -> tuple[Array, Array]:
        """A free base's body node (coordinates ``idx``): its reference [x_c, y_c, theta] into
        ``ref`` and its mass diag(m, m, J) into ``M``; returns its initial state and rates
        (1, 3) each."""
        b = scene.base
        mass, inertia = scene.base.inertial()
        state = np.array([[b.position[0], b.position[1], b.attitude]])
        self.ref[idx] = state[0]
        self.M[idx, idx] += np.array([mass, mass, inertia])
        return state, np.array([[b.velocity[0], b.velocity[1], b.rate]])

    def _power(self, t: float, q: Array, v: Array) -> float:
        """The power (W) of the loads and torque items at the state (q - ref, v) at t (s)."""
        p = 0.0 if self._torques is None else self._torques.power(t, self.ref + q, v)
        for f, idx in self.loads:
            if f.active(t):
                fx, fy = force_at(f, t)
                p += fx * v[idx[0]] + fy * v[idx[1]]
        return p

    def pre_step(self, mbs: Any, t: float) -> bool:
        h = float(self.solver.it.currentStepSize) if self.solver is not None else 0.0
        self.h = h
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
            self.state = (q, v)  # read once a step: the latches use it too
            finite, kinetic, rate_max, k_max = _state_kernel(
                q, v, self.M, self._end, self._root, self._d_ref
            )
            if not finite:
                self.verdict = (STATUS_DIVERGED, diverged_message(t), t, False)
                return False
            if self._checks_energy:
                p = self._power(t, q, v)
                if not math.isfinite(p):
                    self.verdict = (
                        STATUS_ERROR,
                        (f"a load is not finite at t = {t:.6g} s (load power {p!r} W)"),
                        t,
                        False,
                    )
                    return False
                blown = self.energy.check(t, p, kinetic)
                if blown is not None:
                    self.verdict = (*blown, t, False)
                    return False
            if h > 0:
                rot = rate_max * h
                self.max_rotation_seen = max(self.max_rotation_seen, rot)
                if rot > self.max_rotation:
                    k = k_max + 1
                    self.verdict = (
                        STATUS_FAILED,
                        (
                            f"under-resolved: rod {k} turns by {rot:.3g} rad in one step of {h:.3g} s "
                            f"(|dphi| = {rate_max:.4g} rad/s) at t = {t:.6g} s, above "
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


class _TorqueRates:
    """The torque items' power sum_k M_k dD_k/dt (W) at an exudyn state: dD_k the rate of rod
    k+1's root tangent minus rod k's tip tangent (hinge 0: minus a moving base's attitude
    rate, 0 on a pinned base), as ``exudyn_observe.hinge_rates`` measures it. O(n + items)."""

    def __init__(self, scene: Scene, ltg: list[list[Array]], built: BuiltSystem, mbs: Any) -> None:
        E = len(ltg[0]) - 1
        self.loads = LoadSet((), scene.n, torques=scene.torques)
        self.root = np.array([rod[0][2:] for rod in ltg])  # (n, 2): slope x, y indices
        self.tip = np.array([rod[E][2:] for rod in ltg])
        body = built.body
        self.attitude = (
            None if body is None else int(np.asarray(mbs.systemData.GetNodeLTGODE2(body))[2])
        )

    def power(self, t: float, x: Array, v: Array) -> float:
        """At the coordinates x (total) and their rates v (ODE2 vectors)."""

        def rate(idx: Array) -> Array:
            sx, sy, wx, wy = x[idx[:, 0]], x[idx[:, 1]], v[idx[:, 0]], v[idx[:, 1]]
            return np.asarray((sx * wy - sy * wx) / (sx * sx + sy * sy))

        dD = rate(self.root)
        dD[1:] -= rate(self.tip)[:-1]
        if self.attitude is not None:
            dD[0] -= v[self.attitude]
        M = self.loads.hinge_moments(t, dD)
        return 0.0 if M is None else float(M @ dD)
