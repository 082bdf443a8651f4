"""Latches in the exudyn model: the rotation-locking joints switched on in the pre-step
function when a hinge angle crosses its latch angle, and the lock records (``Latches``)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from reference_models.exudyn_beam import (
    Array,
    force_at,
    hermite_shapes,
    mass_points,
    stop_moment,
    wrap_angle,
)
from reference_models.exudyn_build import BuiltSystem
from reference_models.exudyn_guard import Guard
from rodval.core.hinges import CompliantLatch, Latch, Stop
from rodval.core.loads import NodalForce
from rodval.core.scene import Scene
from rodval.mechanics.lock_window import lock_window
from rodval.mechanics.rigid import rigid_lock
from rodval.mechanics.root_momentum import root_momentum_fields

#: Steps after the activation step at which a lock's "after" state is taken (the index-3
#: constraint brings the relative rate to zero within the activation step; the extra steps let
#: the generalized-alpha velocity transient settle; see docs/deployment.md).
LOCK_SETTLE_STEPS = 2


class Latches:
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

    A compliant latch (``CompliantLatch``) is detected alike but not locked: at its switch its
    two stops' laws are switched on (``_engage``), and its record is the event "latch hinge
    k" at the crossing time, without a lock window (no impact).

    A held latch (``Latch.held``) has its joint active from the start (``exudyn_build``): it is
    never armed and records no lock event; its hinge counts as held for the other latches'
    locks (and for the root's angular momentum), and its lock time is 0 (the hinge moment is
    the beam's from the start, ``exudyn_observe``).

    Hinge 0's left side is a moving (free or prescribed) base's attitude (its body node's
    coordinate) or the ground's x axis. Measures of each lock, on the beam solution: the
    kinetic energy v^T M v / 2 of the whole system (consistent mass, a free base's body
    included; a prescribed base's is massless, as the native models') just before the activation
    step and ``LOCK_SETTLE_STEPS`` steps after it, the chain's angular momentum about the
    root (node 0) and the angular momentum H_k of the outboard part (rods k+1..n and their
    node masses) about the hinge node k. The latch's cumulative angular impulse on the
    outboard part is
    S(tau) = H_k(tau) - H_k(before) - int M_k dt, with M_k the finite moments on the outboard
    part about the moving hinge node (hinge k's spring, damper and stops, the outboard loads,
    and -v_P x p of the moving reference point), integrated by the trapezoid rule (N m s,
    counter-clockwise positive on rod k+1). The reported ``impulse`` is its mean over the lock
    window [t_lock, t_lock + w] (``rodval.mechanics.lock_window``, the same window and measure as
    the native models'), by the trapezoid rule on the steps."""

    def __init__(self, built: BuiltSystem, guard: Guard, scene: Scene, E: int) -> None:
        self.mbs, self.guard, self.scene, self.E = built.mbs, guard, scene, E
        chain = scene.chain
        sd = built.mbs.systemData
        self.ltg = ltg = guard.ltg
        # a moving base's attitude coordinate: hinge 0's left side (None: the ground's x axis);
        # ``free``: node 0 moves (a free or a prescribed base)
        self.free = built.body is not None
        body = int(sd.GetNodeLTGODE2(built.body)[2]) if built.body is not None else None
        size = guard.ref.size
        D0 = scene.initial_hinge_angles()
        self.items: list[dict[str, Any]] = []
        latches: tuple[Latch | CompliantLatch, ...] = (*scene.latches, *scene.compliant_latches)
        for latch in latches:
            k = latch.hinge
            direction = latch.direction or int(np.sign(latch.angle - D0[k]))
            self.items.append(
                {
                    "latch": latch,
                    "k": k,
                    "dir": direction,
                    # an ideal latch's joint, or a compliant latch's switch (None: the other)
                    "joint": built.latch_joints.get(k),
                    "switch": built.latch_switches.get(k),
                    "left": body if k == 0 else ltg[k - 1][E][2:],
                    "right": ltg[k][0][2:],
                    "D": float(D0[k]),
                    # a held latch's joint is active from the start (exudyn_build): never
                    # armed, no lock event
                    "state": "held" if getattr(latch, "held", False) else "armed",
                }
            )
        self.Gx, self.Gy, self.w, self.rod_of = mass_points(chain, ltg, E, size)

        self.loads: list[tuple[NodalForce, Array, int]] = [
            (f, ltg[f.node - 1][E][:2], f.node) for f in scene.loads
        ]
        self.stops: dict[int, list[Stop]] = {}
        for stop in scene.stops:
            self.stops.setdefault(stop.hinge, []).append(stop)
        self.root: dict[str, Any] = {"left": body, "right": ltg[0][0][2:], "D": float(D0[0])}
        # the per-step hinge angles, vectorized: row 0 hinge 0 (root), rows 1.. the latches
        self._sides = _Sides(
            [self.root["left"]] + [it["left"] for it in self.items],
            [self.root["right"]] + [it["right"] for it in self.items],
        )
        self._D = np.array([self.root["D"]] + [it["D"] for it in self.items])
        self._angle_of = np.array([it["latch"].angle for it in self.items], float)
        self._dir = np.array([it["dir"] for it in self.items], float)
        self._armed = np.array([it["state"] == "armed" for it in self.items], bool)
        self.prev: dict[str, Any] | None = None
        self.pending: list[dict[str, Any]] = []
        self.events: list[dict[str, Any]] = []
        # hinge -> time its joint was switched on (s): a held latch's from t = 0
        self.lock_times: dict[int, float] = {
            it["k"]: 0.0 for it in self.items if it["state"] == "held"
        }
        #: hinge -> the time (s) its compliant latch acts after (``_engage``)
        self.engaged: dict[int, float] = {}
        self.step_count = 0
        self._cfg = None  # exudyn's configuration of the last accepted state (StartOfStep)
        self._root_shapes: dict[int, tuple[Array, ...]] = {}  # rod -> its root's slopes

    @classmethod
    def of(cls, built: BuiltSystem, guard: Guard, scene: Scene, E: int) -> Latches | None:
        """A run's latches, None when the scene has neither ideal nor compliant ones."""
        return cls(built, guard, scene, E) if scene.latches or scene.compliant_latches else None

    # -- measures --------------------------------------------------------------------------
    def _state(self, known: tuple[Array, Array] | None = None) -> tuple[Array, ...]:
        """q (absolute: the reference added), v, a of the last accepted state (exudyn's
        StartOfStep configuration, which at the pre-step equals the current one); ``known``:
        (q - reference, v) the guard read in this pre-step (one read of each a step)."""
        import exudyn as exu

        sd, cfg = self.mbs.systemData, self._cfg
        if cfg is None:
            cfg = exu.ConfigurationType.StartOfStep
        if known is not None:
            q, v = known
        else:
            q, v = sd.GetODE2Coordinates(cfg), sd.GetODE2Coordinates_t(cfg)
        return (
            np.asarray(q) + self.guard.ref,
            np.asarray(v),
            np.asarray(sd.GetODE2Coordinates_tt(cfg)),
        )

    @staticmethod
    def _angle(q: Array, v: Array, a: Array, idx: Any) -> tuple[float, ...]:
        """Tangent angle (wrapped), its rate and acceleration of slope dofs ``idx`` (None: the
        x axis; one index: a free base's attitude coordinate, continuous)."""
        if idx is None:
            return 0.0, 0.0, 0.0
        if np.ndim(idx) == 0:
            return float(q[idx]), float(v[idx]), float(a[idx])
        sx, sy = q[idx]
        vx, vy = v[idx]
        ax, ay = a[idx]
        r2 = sx * sx + sy * sy
        cross = sx * vy - sy * vx
        rate = cross / r2
        acc = (sx * ay - sy * ax) / r2 - 2.0 * (sx * vx + sy * vy) * cross / r2**2
        return math.atan2(sy, sx), rate, acc

    def _hinge(self, item: dict[str, Any], *qva: Array) -> tuple[float, float, float]:
        q, v, a = qva
        tl, rl, al = self._angle(q, v, a, item["left"])
        tr, rr, ar = self._angle(q, v, a, item["right"])
        D = item["D"] + float(wrap_angle(np.array((tr - tl) - item["D"])))
        return D, rr - rl, ar - al

    def _momenta(self, q: Array, v: Array) -> tuple[Array, Array]:
        """Per rod: linear momentum (n, 2) and angular momentum about the origin (n,)."""
        x, y, vx, vy = self.Gx @ q, self.Gy @ q, self.Gx @ v, self.Gy @ v
        n = self.scene.n
        px = np.bincount(self.rod_of, self.w * vx, n)
        py = np.bincount(self.rod_of, self.w * vy, n)
        h = np.bincount(self.rod_of, self.w * (x * vy - y * vx), n)
        return np.stack([px, py], -1), h

    def _chord(self, j: int, q: Array, v: Array) -> tuple[float, float]:
        """Angle (rad, in (-pi, pi]) and rate d(phi)/dt = (d x d') / |d|^2 (rad/s) of rod j's
        chord (0-based; d the vector from its root node to its end node)."""
        a, b = self.ltg[j][0][:2], self.ltg[j][self.E][:2]
        d, dd = q[b] - q[a], v[b] - v[a]
        return math.atan2(d[1], d[0]), float((d[0] * dd[1] - d[1] * dd[0]) / (d @ d))

    def _root_moment(self, j: int, q: Array) -> float:
        """EI kappa_b (N m) at the root of rod j (0-based): the moment the hinge there
        transmits, in the sense of its spring's kappa (D - rest)."""
        E, le = self.E, self.scene.chain.l[j] / self.E
        if j not in self._root_shapes:
            self._root_shapes[j] = hermite_shapes(np.zeros(1), le)[1:]
        dS, ddS = self._root_shapes[j]
        a, b = self.ltg[j][0], self.ltg[j][1 if E >= 1 else 0]
        Q = np.stack([q[a[:2]], q[a[2:]], q[b[:2]], q[b[2:]]])  # (4, 2)
        r1, r2 = dS[0] @ Q, ddS[0] @ Q
        return float(self.scene.chain.EI[j] * (r1[0] * r2[1] - r1[1] * r2[0]) / (r1 @ r1))

    def _measures(self, t: float, item: dict[str, Any], *qva: Array) -> dict[str, Any]:
        q, v, a = qva
        k = item["k"]
        p, h = self._momenta(q, v)
        P = q[self.ltg[k][0][:2]]
        vP = v[self.ltg[k][0][:2]]
        p_out = p[k:].sum(0)
        H_out = float(h[k:].sum() - (P[0] * p_out[1] - P[1] * p_out[0]))
        D, dD, moment = self._hinge_moment(item, k, qva)
        finite = self._loads_moment(t, q, P, -moment - (vP[0] * p_out[1] - vP[1] * p_out[0]), k)
        H_root, root_moment = self._root_momentum(t, qva, p, h)
        rel = self._chord(k, q, v)[1] - (self._chord(k - 1, q, v)[1] if k > 0 else 0.0)
        return {
            "t": t,
            "rel": rel,
            "M_beam": self._root_moment(k, q),
            "H_out": H_out,
            "finite": finite,
            "H_root": H_root,
            "root_moment": root_moment,
            "T": 0.5 * float(v @ self.guard.M @ v),
            "D": D,
            "dD": dD,
        }

    def _root_momentum(
        self, t: float, qva: tuple[Array, ...], p: Array, h: Array
    ) -> tuple[float, float]:
        """The chain's angular momentum about node 0 (N m s) and its rate's finite moments
        (N m): hinge 0's spring, damper and stops on rod 1 and all loads, about node 0, and on
        a free base (node 0 moving) -v_0 x P; ``p``, ``h``: the rods' momenta (``_momenta``).
        On a pinned base node 0 is the origin; ``qva`` = (q, v, a)."""
        q, v, _ = qva
        root = q[self.ltg[0][0][:2]] if self.free else np.zeros(2)
        root_moment = self._loads_moment(t, q, root, -self._hinge_moment(self.root, 0, qva)[2])
        H_root = float(h.sum())
        if self.free:
            v0, P = v[self.ltg[0][0][:2]], p.sum(0)
            H_root -= float(root[0] * P[1] - root[1] * P[0])
            root_moment -= float(v0[0] * P[1] - v0[1] * P[0])
        return H_root, root_moment

    def _hinge_moment(
        self, item: dict[str, Any], k: int, qva: tuple[Array, ...]
    ) -> tuple[float, float, float]:
        """Hinge k's (D, dD, moment) at the state ``qva`` = (q, v, a): the moment (N m) of its
        spring, damper and stops, in the sense of kappa (D - rest)."""
        chain = self.scene.chain
        D, dD, _ = self._hinge(item, *qva)
        moment = chain.kappa[k] * (D - chain.rest_angle[k]) + chain.nu[k] * dD
        moment += sum([float(stop_moment(st, D, dD)) for st in self.stops.get(k, [])])
        return D, dD, moment

    def _loads_moment(
        self, t: float, q: Array, about: Array, moment: float, outboard_of: int = 0
    ) -> float:
        """``moment`` plus, one by one, the moments (N m) about the point ``about`` of the loads
        at t on the nodes past node ``outboard_of`` (all of them by default)."""
        for f, idx, node in self.loads:
            if node > outboard_of and f.active(t):
                fx, fy = force_at(f, t)
                r = q[idx] - about
                moment += r[0] * fy - r[1] * fx
        return moment

    # -- per step --------------------------------------------------------------------------
    def pre_step(self, t: float, h: float, solver: Any = None) -> None:
        """Called before the step to t, on the state at t - h (the last accepted step). The
        hinge angles of hinge 0 and of every armed latch and the bound that a crossing needs
        are one compiled call a step (``_latch_step``); the closed-form roots
        (``_taylor_roots``, vectorized over the latches) run only when a latch passes it, and
        Python loops only over the latches that switch or are being measured. ``solver``: exudyn's
        solver, whose Newton Jacobian is renewed in the step a joint is switched on
        (``conv.jacobianUpdateRequested``)."""
        if h <= 0:
            return
        t0 = t - h
        q, v, a = self._state(self.guard.state)
        armed = self._armed
        Dl, dDl, ddDl, maybe = _latch_step(
            q, v, a, self._sides.index, self._D, self._angle_of, self._dir, armed, h
        )
        self.root["D"] = float(self._D[0])
        for ev in list(self.pending):
            self._advance(ev, self._measures(t0, ev["item"], q, v, a))
        prev = self.prev
        self.prev = {"t": t0, "D": Dl, "dD": dDl, "armed": armed.copy()}
        if not maybe:
            return
        g = Dl - self._angle_of
        past = self._dir * g >= 0
        tau = _taylor_roots(g, dDl, ddDl, h)
        switch = armed & (past | np.isfinite(tau))
        if not switch.any():
            return
        for i in np.flatnonzero(switch):
            item = self.items[i]
            item["D"] = float(Dl[i])
            if past[i]:  # already at or past: Hermite root in the last step
                if prev is not None and prev["armed"][i]:
                    t_lock = _hermite_root(
                        prev["t"],
                        t0,
                        prev["D"][i] - item["latch"].angle,
                        prev["dD"][i],
                        float(g[i]),
                        float(dDl[i]),
                    )
                else:
                    t_lock = t0
            else:
                t_lock = t0 + float(tau[i])
            self._switch(int(i), (t0, t_lock, h), q, v, a)
        if solver is not None:
            solver.conv.jacobianUpdateRequested = True

    def _switch(self, i: int, times: tuple[float, float, float], *qva: Array) -> None:
        """Switch latch ``i`` on before the step from t0 and open its lock record; ``times`` =
        (t0, t_lock, h) (s), ``qva`` = (q, v, a) at t0."""
        item, (t0, t_lock, h), (q, v, _) = self.items[i], times, qva
        self._armed[i] = False
        if item["switch"] is not None:
            self._engage(item, t0, t_lock)
            return
        self.mbs.SetObjectParameter(item["joint"], "activeConnector", True)
        item["state"] = "locking"
        self.lock_times[item["k"]] = t0
        before = self._measures(t0, item, *qva)
        # the chords just before the lock and the hinges held after it: the rigid-panel
        # lock's data (rodval.mechanics.rigid)
        before["chords"] = np.array([self._chord(j, q, v) for j in range(self.scene.n)])
        before["held"] = self._held()
        self.pending.append(
            {
                "item": item,
                "t_lock": t_lock,
                "window": lock_window(self.scene.chain, item["latch"], before["held"]),
                "steps": 0,
                "before": before,
                "last": before,
                "settled": None,
                "integral": 0.0,
                "root_integral": 0.0,
                "S": 0.0,
                "mean": 0.0,
                "peak": abs(before["M_beam"]),
                "step": h,
            }
        )

    def _held(self) -> list[int]:
        """The hinges an ideal latch holds (locking, locked or held from the start); an
        engaged compliant latch's hinge is not held: its stops act on it."""
        return [it["k"] for it in self.items if it["state"] not in ("armed", "engaged")]

    def _engage(self, item: dict[str, Any], t0: float, t_lock: float) -> None:
        """Engage a compliant latch before the step from t0 (s): its stops' laws switched on
        (``engaged_law``), its moment in the hinge's from now on (``_hinge_moment``), and its
        event "latch hinge k" at the crossing time t_lock (s), as an ideal latch's lock time;
        no impact, so no lock window. The outputs count it after max(t0, t_lock)
        (``engaged``): from the crossing, but never at a recorded state before its switch.
        O(1)."""
        latch, k = item["latch"], item["k"]
        item["switch"][0] = True
        item["state"] = "engaged"
        self.engaged[k] = max(t0, t_lock)
        self.stops.setdefault(k, []).extend(latch.engaged_stops())
        self.events.append(
            {
                "t": float(t_lock),
                "label": f"latch hinge {k}",
                "hinge": int(k),
                "hinges": [int(k)],
                "angle": float(latch.angle),
                "t_switched_on": float(t0),
                "compliant": True,
            }
        )

    def _advance(self, ev: dict[str, Any], now: dict[str, Any]) -> None:
        """One accepted step of a lock's window: the trapezoid integrals of the finite moments
        and of S(tau) = H_out(tau) - H_out(before) - int finite (linear between the steps,
        over the part of the step inside [t_lock, t_lock + w]; in the activation step, whose
        constraint takes the impact, S is its value at the step's end from t_lock on: the
        plastic part is at t_lock, as in the native models); the window closes on the
        first step that reaches its end."""
        last = ev["last"]
        ev["steps"] += 1
        h = now["t"] - last["t"]
        ev["integral"] += 0.5 * h * (last["finite"] + now["finite"])
        ev["root_integral"] += 0.5 * h * (last["root_moment"] + now["root_moment"])
        ev["peak"] = max(ev["peak"], abs(now["M_beam"]))
        S1 = now["H_out"] - ev["before"]["H_out"] - ev["integral"]
        # the activation step holds the impact: S jumps at t_lock, not along the step
        S0 = S1 if ev["steps"] == 1 else ev["S"]
        lo, hi = max(last["t"], ev["t_lock"]), min(now["t"], ev["t_lock"] + ev["window"])
        if hi > lo and h > 0:
            f0, f1 = (lo - last["t"]) / h, (hi - last["t"]) / h
            ev["mean"] += 0.5 * (hi - lo) * (2 * S0 + (f0 + f1) * (S1 - S0))
        ev["S"], ev["last"] = S1, now
        if ev["steps"] == LOCK_SETTLE_STEPS:
            ev["settled"] = now
        if now["t"] >= ev["t_lock"] + ev["window"]:
            self._finish(ev, closed=True)

    def close(self) -> None:
        """At the end of the run: locks whose window has not closed are recorded over the part
        reached (``window_closed`` False)."""
        for ev in list(self.pending):
            self._finish(ev, closed=False)

    def _finish(self, ev: dict[str, Any], closed: bool) -> None:
        """Record a lock: the impulse is the window mean of S(tau) (``lock_window``); the
        kinetic energy after it is taken ``LOCK_SETTLE_STEPS`` steps after the activation,
        the root's angular momentum jump over the whole window (None, as its before and
        after, once hinge 0 is held: ``rodval.mechanics.root_momentum``);
        ``window_steps``: the window's length in steps of the run's step, impulse_window / h
        (``rodval.analysis.events.MIN_WINDOW_STEPS``)."""
        item, before, last = ev["item"], ev["before"], ev["last"]
        settled = ev["settled"] or last
        root_jump = last["H_root"] - before["H_root"] - ev["root_integral"]
        latch = item["latch"]
        chords = before["chords"]
        # the rigid-panel yardstick is a pinned chain's: none on a moving base (as the native)
        rigid = (
            {}
            if self.free
            else rigid_lock(self.scene.chain, chords[:, 0], chords[:, 1], before["held"], item["k"])
        )
        # the root's angular momentum means nothing once hinge 0 is held (now, earlier, or
        # by the window's end): the ground's (the base's) holding moment is external
        root_held = 0 in self._held()
        self.events.append(
            {
                "t": float(ev["t_lock"]),
                "label": f"latch hinge {latch.hinge}",
                "hinge": int(latch.hinge),
                "angle": float(latch.angle),
                "impulse": float(ev["mean"] / ev["window"]),
                "impulse_window": float(ev["window"]),
                "window_closed": closed,
                "kinetic_before": float(before["T"]),
                "kinetic_after": float(settled["T"]),
                "rate_before": float(before["dD"]),
                "chord_rate_before": float(before["rel"]),
                **root_momentum_fields(
                    float(before["H_root"]), float(last["H_root"]), root_held, float(root_jump)
                ),
                "peak_moment": float(ev["peak"]),
                "t_activated": float(before["t"]),
                "step": float(ev["step"]),
                "window_steps": float(ev["window"] / ev["step"]),
                **rigid,
            }
        )
        item["state"] = "locked"
        self.pending.remove(ev)


class _Sides:
    """The hinge angles D = (right tangent angle) - (left tangent angle) of a set of hinges
    (rows), with their rates and accelerations, in one compiled call a step (``_hinge_rows``).
    Each side is None (the ground's x axis), one coordinate index (a free base's attitude,
    continuous) or the two slope coordinates of a beam node (tangent angle atan2(s_y, s_x))."""

    def __init__(self, left: list[Any], right: list[Any]) -> None:
        sides = list(left) + list(right)
        self.rows = len(left)
        #: per side (columns): its kind, first and second coordinate index (``_hinge_rows``)
        self.index = np.array(
            [
                [0 if s is None else (1 if np.ndim(s) == 0 else 2) for s in sides],
                [0 if s is None else (int(s) if np.ndim(s) == 0 else int(s[0])) for s in sides],
                [int(s[1]) if np.ndim(s) == 1 else 0 for s in sides],
            ],
            np.int64,
        )

    def hinges(self, *qva: Array) -> tuple[Array, ...]:
        """D (continuous from ``D_prev``), dD, ddD of every row; ``qva`` = (q, v, a, D_prev)."""
        q, v, a, D_prev = qva
        out = np.empty((3, self.rows))
        _hinge_rows(q, v, a, self.index, np.asarray(D_prev, float), out)
        return out[0], out[1], out[2]


@njit(cache=True, error_model="numpy")  # pragma: no cover - compiled
def _hinge_rows(q: Array, v: Array, a: Array, index: Array, D_prev: Array, out: Array) -> None:
    """``_Sides.hinges`` compiled: rows 0..R-1 of ``out`` (3, R) <- D, dD, ddD, the sides
    0..R-1 left and R..2R-1 right (``index`` (3, 2R): kind 0 ground, 1 body coordinate i0,
    2 slope (i0, i1); then i0, i1)."""
    R = out.shape[1]
    kind, i0, i1 = index[0], index[1], index[2]
    for r in range(R):
        ang = np.zeros(2)
        rate = np.zeros(2)
        acc = np.zeros(2)
        for side in range(2):
            j = r + side * R
            if kind[j] == 1:
                ang[side], rate[side], acc[side] = q[i0[j]], v[i0[j]], a[i0[j]]
            elif kind[j] == 2:
                sx, sy = q[i0[j]], q[i1[j]]
                vx, vy = v[i0[j]], v[i1[j]]
                ax, ay = a[i0[j]], a[i1[j]]
                r2 = sx * sx + sy * sy
                rt = (sx * vy - sy * vx) / r2
                ang[side] = np.arctan2(sy, sx)
                rate[side] = rt
                acc[side] = (sx * ay - sy * ax - 2.0 * (sx * vx + sy * vy) * rt) / r2
        x = (ang[1] - ang[0]) - D_prev[r]
        out[0, r] = D_prev[r] + (np.pi - (np.pi - x) % (2.0 * np.pi))
        out[1, r] = rate[1] - rate[0]
        out[2, r] = acc[1] - acc[0]


@njit(cache=True, error_model="numpy")  # pragma: no cover - compiled
def _latch_step(
    q: Array,
    v: Array,
    a: Array,
    index: Array,
    D: Array,
    angle: Array,
    direction: Array,
    armed: Array,
    h: float,
) -> tuple[Array, Array, Array, bool]:
    """One pre-step of the latches compiled: row 0 hinge 0, rows 1.. the latches. ``D``
    (continued in place for row 0 and the armed rows); returns D, dD, ddD of the latch rows
    and whether an armed latch is at or past its angle or may cross it within the step h
    (|g| <= |dD| h + |ddD| h^2 / 2, g = D - angle): only then the closed-form roots run."""
    out = np.empty((3, D.size))
    _hinge_rows(q, v, a, index, D, out)
    D[0] = out[0, 0]
    maybe = False
    for r in range(1, D.size):
        if armed[r - 1]:
            D[r] = out[0, r]
            g = out[0, r] - angle[r - 1]
            if direction[r - 1] * g >= 0.0 or abs(g) <= abs(out[1, r]) * h + abs(out[2, r]) * (
                0.5 * h * h
            ):
                maybe = True
    return out[0, 1:].copy(), out[1, 1:].copy(), out[2, 1:].copy(), maybe


def _taylor_roots(g: Array, dg: Array, ddg: Array, h: float) -> Array:
    """Per row, the smallest tau in (0, h] where g + dg tau + ddg tau^2 / 2 changes sign from
    that of g, in closed form (NaN where it does not within the step): the stable quadratic
    formula (roots q / c2 and g / q with q = -(dg + sign(dg) sqrt(disc)) / 2, c2 = ddg / 2,
    disc = dg^2 - 2 ddg g), the linear root -g / dg where ddg = 0. A double root (disc = 0)
    counts; complex roots (disc < 0) do not."""
    g, dg, ddg = (np.asarray(x, float) for x in (g, dg, ddg))
    c2 = 0.5 * ddg
    disc = dg * dg - 4.0 * c2 * g
    with np.errstate(all="ignore"):
        sq = np.sqrt(np.where(disc >= 0, disc, np.nan))
        qq = -0.5 * (dg + np.where(dg >= 0, sq, -sq))
        r1 = np.where(c2 != 0, qq / c2, np.where(dg != 0, -g / dg, np.nan))
        r2 = np.where((c2 != 0) & (qq != 0), g / qq, np.nan)
    r1 = np.where((r1 > 0) & (r1 <= h), r1, np.nan)
    r2 = np.where((r2 > 0) & (r2 <= h), r2, np.nan)
    return np.fmin(r1, r2)


def _hermite_root(t0: float, t1: float, g0: float, dg0: float, g1: float, dg1: float) -> float:
    """Where the cubic Hermite interpolant of g between (t0, g0, dg0) and (t1, g1, dg1) crosses
    zero (g0 and g1 of opposite sign or g1 = 0), by bisection; t1 when not bracketed."""
    h = t1 - t0
    if h <= 0 or g0 * g1 > 0:
        return t1

    def g(th: float) -> float:
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
