"""What the full and reduced models share: scene constants, loads and the observation map."""

from __future__ import annotations

from collections.abc import Callable
from contextlib import contextmanager
from functools import cached_property
from typing import Any, ClassVar, NamedTuple

import numpy as np

from rodval.core.checks import check_choice
from rodval.core.loads import LoadSet, load_table
from rodval.core.quantities import tip_deflection
from rodval.core.scene import Scene, hinge_angles
from rodval.core.trajectory import Trajectory
from rodval.core.validity import Check, small_bending
from rodval.models.assembly.paper_energy import NO_MATRICES, PaperEnergy
from rodval.models.assembly.paper_matrices import (
    DEFAULT_VARIANT,
    VARIANTS,
    ChainConstants,
    chain_constants,
    damper_power,
    damping_matrix,
    generalized_forces,
    hinge_matrix,
    node_positions,
    rest_forces,
    stiffness_matrix,
)
from rodval.models.hinge_items import deployment, lock_records
from rodval.solvers.ode_model import OdeModel
from rodval.solvers.signature import EVENTS_SIGNATURE, RHS_SIGNATURE, first_class
from rodval.solvers.system import CompiledForm, EventRecord, EventSpec, OdeSystem

#: Right-hand-side implementations: "numba" (compiled, structured; default) or "numpy"
#: (the straightforward dense reference).
KERNELS = ("numba", "numpy")


class EventRow(NamedTuple):
    """One event of the current mode: a latch or stop (``kind``; ``item``: its index among the
    scene's latches or stops), on ``hinge``, g = D_hinge - ``angle`` (rad) crossing in ``direction``."""

    kind: str
    item: int
    hinge: int
    angle: float
    direction: int


class PaperSystem(PaperEnergy, OdeSystem):
    """Base of the paper's ODE systems. Subclasses provide ``numpy_rhs``, the compiled
    kernels (``accel_kernel``, ``compiled_rhs``) and their constants (``kernel_constants``),
    ``jacobian`` and ``bending`` (alpha, beta, alpha', beta' at output times)."""

    has_jacobian = True
    has_energy = True
    #: True for the full model (state [q; q'], 6n), False for the reduced one ([phi; phi']).
    full: bool
    #: accel(V, y, has_load, SX, SY, damped, out) and the RHS_TYPE functions (rhs, mechanics;
    #: rhs with locked hinges, ``deployment.lock_scalars``) and the EVENTS_TYPE one.
    accel_kernel: Any
    compiled_rhs: Any
    compiled_mechanics: Any
    compiled_rhs_locked: Any
    compiled_events: Any

    def __init__(self, scene: Scene, coefficients: str = DEFAULT_VARIANT, kernel: str = "numba"):
        self.kernel = check_choice("kernel", kernel, KERNELS)
        self.coefficients = coefficients
        chain = scene.chain
        #: the scene's chain; ``chain`` is the effective one of the current mode (active
        #: limit stops add their spring and damper to their hinge's)
        self.base_chain = chain
        self.chain = chain
        self.scene = scene
        self.n = chain.n
        self.l = chain.l
        self.cc = chain_constants(chain, coefficients)
        self.damped = chain.damped
        self.loads = LoadSet(scene.loads, chain.n)
        self.initial = scene.initial.resolve(chain.n)
        self.latches = tuple(scene.latches)
        self.stops = tuple(scene.stops)
        D0 = scene.initial_hinge_angles()
        #: latch directions resolved (None: towards the angle from the initial state)
        self.latch_dir = tuple(
            int(np.sign(la.angle - D0[la.hinge])) if la.direction is None else la.direction
            for la in self.latches
        )
        self._initial_stops = tuple(bool(st.acts(D0[st.hinge])) for st in self.stops)
        self._initial_locked = tuple(j for j, la in enumerate(self.latches) if la.held)
        #: mode: which stops act, which latches are locked (in lock order)
        self.stop_active: tuple[bool, ...] = self._initial_stops
        self.locked: tuple[int, ...] = ()
        self._history: list[tuple[float, tuple]] = []
        self._lock_h = np.zeros(0, dtype=np.int64)
        self._lock_a = np.zeros(0)
        self._lam = np.zeros(0)
        if any(self.stop_active):
            self._apply_stops()

    # Dense matrices of the numpy reference and the analytic Jacobians (O(n^2) memory): built
    # only when one of those asks; the default O(n) path never does.
    @cached_property
    def K(self) -> np.ndarray:
        return stiffness_matrix(self.chain)

    @cached_property
    def C(self) -> np.ndarray:
        return damping_matrix(self.chain)

    @cached_property
    def rest(self) -> np.ndarray:
        """A^T kappa rest (N m, 3n): spring forces are K q - rest."""
        return rest_forces(self.chain)

    @cached_property
    def cc_kinetic(self) -> ChainConstants:
        """The kinetic energy always uses the kinematic (printed, symmetric) mass matrix."""
        return self.cc if self.coefficients == "printed" else chain_constants(self.chain)

    def use_kernel(self) -> None:
        """Set up the compiled kernel (subclasses call this last in __init__) and evaluate it
        once, so that loading or compiling it is not part of the integration's wall time."""
        if self.kernel == "numba":
            self.V = self.kernel_constants()
            self._no_load = np.zeros(self.n)
            self._flags = np.array([1.0 if self.damped else 0.0])
            self._mech = np.zeros(3)
        self.rhs(0.0, self.y0)

    def kernel_constants(self) -> np.ndarray:
        """The compiled kernels' constant rows V for this system (O(n))."""
        raise NotImplementedError

    def numpy_rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def rhs(self, t, y):
        if self.locked:
            out = np.empty_like(y)
            half = y.size // 2
            out[:half] = y[half:]
            out[half:], self._lam = self.accel_locked(t, y)
            return out
        if self.kernel == "numpy":
            return self.numpy_rhs(t, y)
        sums = self.loads.suffix_sums(t)
        SX, SY = (self._no_load, self._no_load) if sums is None else sums
        half = y.size // 2
        out = np.empty_like(y)
        out[:half] = y[half:]
        self.accel_kernel(self.V, y, sums is not None, SX, SY, self.damped, out[half:])
        return out

    def compiled(self) -> CompiledForm | None:
        """The compiled form of the current mode (locked hinges in S, the armed latches and
        switching stops as event rows; active stops are in V), or None with the numpy kernel
        or a load that is a plain Python callable (no load-table form)."""
        if self.kernel != "numba":
            return None
        table = self._load_table
        if table is None:
            return None
        rows = self.event_rows()
        locked = bool(self.locked)
        rhs = self.compiled_rhs_locked if locked else self.compiled_rhs
        return CompiledForm(
            first_class(rhs, RHS_SIGNATURE),
            self.V,
            deployment.lock_scalars(self._flags[0], self._lock_h, self._lock_a)
            if locked
            else self._flags,
            self.compiled_scratch(),
            table,
            mechanics=first_class(self.compiled_mechanics, RHS_SIGNATURE),
            name=type(self).__name__,
            # no event rows: the integrators' own no_events, and this kernel is not compiled
            events=first_class(self.compiled_events, EVENTS_SIGNATURE) if rows else None,
            E=np.array([[r.hinge, r.angle] for r in rows], float).reshape(-1, 2),
            directions=np.array([r.direction for r in rows], float),
        )

    @cached_property
    def _load_table(self) -> np.ndarray | None:
        """The scene's compiled load table (built once: O(rows), ~1 s per 1e5 samples)."""
        return load_table(self.scene.loads)

    def compiled_scratch(self) -> np.ndarray:
        """The compiled form's M: work space its right-hand side reuses (none by default)."""
        return NO_MATRICES

    def generalized_force(self, t: float, phi: np.ndarray) -> np.ndarray | None:
        """Q(phi, t) (N m) on the phi coordinates, or None when no load acts at t."""
        sums = self.loads.suffix_sums(t)
        return None if sums is None else generalized_forces(self.l, phi, *sums)

    def max_bending(self, times: np.ndarray, Y: np.ndarray) -> float | None:
        """max |alpha|, |beta| (rad) over the states Y (the reduced model's: O(n) per state)."""
        largest = 0.0
        for t, y in zip(times, Y):
            with self._mode_at(t):  # the mode (locked hinges, stops) in effect at t
                alpha, beta = self.bending(np.array([t]), y[None, :])[:2]
            largest = max(largest, float(np.max(np.abs(alpha))), float(np.max(np.abs(beta))))
        return largest

    def bending_mask(self) -> np.ndarray | None:
        """The full model's bending coordinates (alpha, beta, a rung's bubbles: q[n:Nc]) and
        their rates in [q; q'] (a body's coordinates after Nc are not); None when reduced."""
        if not self.full:
            return None
        N = self.y0.size // 2
        q = np.zeros(N, dtype=bool)
        q[self.n : getattr(self, "Nc", 3 * self.n)] = True
        return np.concatenate([q, q])

    def energy(self, t: float, y: np.ndarray) -> float:
        """E = T + Pi (J) at one state (the same energy ``observe`` reports)."""
        with self._mode_at(t):
            return self._energy_in_mode(t, y)

    def _energy_in_mode(self, t: float, y: np.ndarray) -> float:
        """E = T + Pi (J) at one state in the current mode (active stops, locked hinges); O(n)
        with the compiled kernels."""
        kin, pot = self.energy_rows(np.array([t]), y[None, :])
        return float(kin[0] + pot[0])

    def power(self, t: float, y: np.ndarray) -> tuple[float, float]:
        """(P_ext, P_diss) (W): P_ext = Q(phi, t) . phi' (Q on the phi coordinates only, see
        paper_matrices.generalized_forces); P_diss = q'^T C q' = sum_k nu_k (dD_k/dt)^2 >= 0,
        the power taken out by the hinge dampers (D_k: hinge angles)."""
        phi, dphi = (a[0] for a in self.rigid(y[None, :]))
        sums = self.loads.suffix_sums(t)
        p_ext = 0.0 if sums is None else float(generalized_forces(self.l, phi, *sums) @ dphi)
        if sums is not None and self.scene.base.free:  # the loads' resultant on node 0's motion
            v0 = self.root_motion(y)[1]
            p_ext += float(sums[0][0] * v0[0] + sums[1][0] * v0[1])
        with self._mode_at(t):
            return p_ext, self.damper_power_at(y) if self.damped else 0.0

    def damper_power_at(self, y: np.ndarray) -> float:
        """q'^T C q' (W) at one state in the current mode (``paper_matrices.damper_power``)."""
        n = self.n
        v = self.generalized_rates(y)
        rate = self.attitude_rate(y[None, :])
        theta = None if rate is None else rate[0]
        return damper_power(self.chain, v[:n], v[n : 2 * n], v[2 * n : 3 * n], theta)

    def observe(self, times, Y):
        """The scene's quantities; each output time is observed in the mode (active stops,
        locked hinges) in effect there (an output time at an event: the mode before it)."""
        times = np.asarray(times, float)
        modes = [self._mode_for(t) for t in times]
        out: dict = {}
        start = 0
        for i in range(1, len(times) + 1):
            if i < len(times) and modes[i] == modes[start]:
                continue
            with self._mode(modes[start]):
                part = self._observe_rows(times[start:i], Y[start:i])
            for key, (v, k) in part.items():
                out[key] = (np.concatenate([out[key][0], v]), k) if key in out else (v, k)
            start = i
        return out

    def _observe_rows(self, times, Y):
        scene, n = self.scene, self.n
        rods = np.arange(1, n + 1)
        phi, dphi = self.rigid(Y)
        out = {}
        if scene.wants("phi"):
            out["phi"] = (phi, rods)
        if scene.wants("dphi"):
            out["dphi"] = (dphi, rods)
        if scene.wants(
            "alpha", "beta", "energy", "hinge_angle", "hinge_moment", "angular_momentum"
        ):
            alpha, beta, dalpha, dbeta = self.bending(times, Y)
            if scene.wants("alpha"):
                out["alpha"] = (alpha, rods)
            if scene.wants("beta"):
                out["beta"] = (beta, rods)
        if scene.wants("x", "y", "tip_deflection"):
            x, y = node_positions(self.l, phi)
            nodes = np.arange(0, n + 1)
            if scene.wants("x"):
                out["x"] = (x, nodes)
            if scene.wants("y"):
                out["y"] = (y, nodes)
            if scene.wants("tip_deflection"):
                tip = tip_deflection(x, y, self.attitude(Y))
                out["tip_deflection"] = (tip[:, None], np.zeros(1, dtype=int))
        if scene.wants("hinge_angle", "hinge_moment"):
            D = hinge_angles(phi, alpha, beta, self.attitude(Y))
            hinges = np.arange(n)
            if scene.wants("hinge_angle"):
                out["hinge_angle"] = (D, hinges)
            if scene.wants("hinge_moment"):
                out["hinge_moment"] = (self.hinge_moments(times, Y, D), hinges)
        if scene.wants("energy"):
            kin, pot = self.energy_rows(times, Y)
            zero = np.zeros(1, dtype=int)
            out["kinetic"] = (kin[:, None], zero)
            out["potential"] = (pot[:, None], zero)
            out["energy"] = ((kin + pot)[:, None], zero)
        if scene.wants("angular_momentum"):
            out["angular_momentum"] = (self.angular_momentum_rows(times, Y), np.arange(2))
        if scene.wants("momentum"):
            out["momentum"] = (self.momentum_rows(Y), np.arange(2))
        return out

    # ----------------------------------------------------------------- deployment: modes
    def _apply_stops(self) -> None:
        """Rebuild the effective chain (and every constant derived from it) for the current
        stop activity: an acting stop adds its stiffness and damping to its hinge, the rest
        angle becomes the stiffness-weighted mean (kappa (D - rest) + k (D - angle) =
        (kappa + k)(D - rest'))."""
        base = self.base_chain
        kappa = base.kappa.copy()
        ka = base.kappa * base.rest_angle
        nu = base.nu.copy()
        for st, on in zip(self.stops, self.stop_active):
            if on:
                kappa[st.hinge] += st.stiffness
                ka[st.hinge] += st.stiffness * st.angle
                nu[st.hinge] += st.damping
        safe = np.where(kappa > 0, kappa, 1.0)
        rest = np.where(kappa > 0, ka / safe, base.rest_angle)
        self.chain = base.with_(kappa=kappa, nu=nu, rest_angle=rest)
        for name in ("K", "C", "rest", "_dense"):
            self.__dict__.pop(name, None)
        self.damped = self.chain.damped
        if self.kernel == "numba" and hasattr(self, "V"):
            self.V[:] = self.kernel_constants()
            self._flags[0] = 1.0 if self.damped else 0.0

    def _activate(self, mode: tuple) -> None:
        stops, locked = mode
        if stops != self.stop_active:
            self.stop_active = stops
            self._apply_stops()
        if locked != self.locked:
            self.locked = locked
            self._lock_h = np.array([self.latches[j].hinge for j in locked], dtype=np.int64)
            self._lock_a = np.array([self.latches[j].angle for j in locked], dtype=float)
            self._lam = np.zeros(len(locked))

    @property
    def mode(self) -> tuple:
        return (self.stop_active, self.locked)

    def _mode_for(self, t: float) -> tuple:
        """The mode in effect at time t: set by the last event strictly before t."""
        mode = (self._initial_stops, self._initial_locked)
        for ts, m in self._history:
            if ts < t:
                mode = m
        return mode

    @contextmanager
    def _mode(self, mode: tuple):
        old = self.mode
        self._activate(mode)
        try:
            yield
        finally:
            self._activate(old)

    def _mode_at(self, t: float):
        return self._mode(self._mode_for(t))

    def reset(self) -> None:
        """Back to the initial mode (the held latches locked, the stops the initial state is
        beyond), forgetting the event history: called by the driver before a run."""
        self._history = []
        self._activate((self._initial_stops, self._initial_locked))

    def _set_mode(self, mode: tuple, t: float) -> None:
        self._history.append((t, mode))
        self._activate(mode)

    # ------------------------------------------------------------- deployment: events
    def hinge_rows(self, hinges) -> np.ndarray:
        """Rows a_k of the hinge matrix (D = A q, q = [phi; alpha; beta]) of these hinges."""
        return hinge_matrix(self.n)[hinges]

    def hinge_angles_at(self, t: float, y: np.ndarray) -> np.ndarray:
        """D_k (rad, n) at one state in the current mode."""
        Y = y[None, :]
        phi = self.rigid(Y)[0]
        alpha, beta = self.bending(np.array([t]), Y)[:2]
        return hinge_angles(phi, alpha, beta, self.attitude(Y))[0]

    def _hinge_crossing(self, hinge: int, angle: float) -> Callable[[float, np.ndarray], float]:
        """The event function g(t, y) = D_hinge - angle (rad) of a latch or stop."""

        def g(t: float, y: np.ndarray) -> float:
            return float(self.hinge_angles_at(t, y)[hinge] - angle)

        return g

    def hinge_rates(self, y: np.ndarray) -> np.ndarray:
        """dD_k/dt as the model's dampers see it: A q' (reduced: chord rates, the bending
        rates being dropped)."""
        n = self.n
        v = self.generalized_rates(y)
        rate = self.attitude_rate(y[None, :])
        return hinge_angles(
            v[:n], v[n : 2 * n], v[2 * n : 3 * n], None if rate is None else rate[0]
        )

    def hinge_moments(self, times, Y, D) -> np.ndarray:
        """Hinge moments (N m, (nt, n)), positive when resisting an increase of D: spring
        kappa (D - rest) + damper nu dD/dt + acting stops + the constraint moment -lambda of
        locked hinges (from the constrained acceleration solve)."""
        ch = self.chain
        rates = np.array([self.hinge_rates(y) for y in Y]).reshape(D.shape)
        M = ch.kappa * (D - ch.rest_angle) + ch.nu * rates
        if self.locked:
            for i, (t, y) in enumerate(zip(times, Y)):
                lam = self.accel_locked(t, y)[1]
                M[i, self._lock_h] -= lam
        return M

    def event_rows(self) -> tuple[EventRow, ...]:
        """The current mode's events, in one order for the Python event functions and the
        compiled event table: latches not yet locked (g = D_k - angle in the latch's
        direction) and limit stops on hinges not locked (g = D_k - angle in the direction
        that switches the stop: into its side while it is off, out of it while it acts; a
        root found again just after the switch, where g may sit a rounding error on the old
        side, then cannot fire twice)."""
        rows = []
        held = {self.latches[j].hinge for j in self.locked}
        for j, la in enumerate(self.latches):
            if j not in self.locked:
                rows.append(EventRow("latch", j, la.hinge, la.angle, self.latch_dir[j]))
        for i, st in enumerate(self.stops):
            if st.hinge in held:
                continue
            entering = 1 if st.side == "upper" else -1
            direction = -entering if self.stop_active[i] else entering
            rows.append(EventRow("stop", i, st.hinge, st.angle, direction))
        return tuple(rows)

    def event_functions(self) -> tuple[EventSpec, ...]:
        """The current mode's events (``event_rows``) as g(t, y) = D_k - angle."""
        return tuple(
            EventSpec(
                g=self._hinge_crossing(r.hinge, r.angle),
                direction=r.direction,
                label=f"{r.kind} hinge {r.hinge}",
            )
            for r in self.event_rows()
        )

    def apply_event(self, index: int, t: float, y: np.ndarray) -> tuple[np.ndarray, EventRecord]:
        """A stop switching (no jump: the integrator restarts at the kink) or a latch locking
        (a plastic impact, then the hinge is held); see docs/deployment_native.md. The record
        carries the energy E = T + Pi (J) in the mode before the event (``energy_before``) and
        after it, at the state after the jump (``energy_after``), and their difference
        ``instant_energy_loss`` (J, positive: taken out), which the energy audit books as
        dissipation: a lock's plastic loss, and in the reduced model the jump of its
        quasi-static bending when a moment switches (docs/deployment_native.md, "Energy
        through events")."""
        before = self._energy_in_mode(t, y)
        y_new, record = self._switch(index, t, y)
        after = self._energy_in_mode(t, y_new)
        record.data.update(
            energy_before=before, energy_after=after, instant_energy_loss=before - after
        )
        return y_new, record

    def _switch(self, index: int, t: float, y: np.ndarray) -> tuple[np.ndarray, EventRecord]:
        """Event ``index`` at (t, y): the new mode, the state after the jump and the record."""
        row = self.event_rows()[index]
        kind, j = row.kind, row.item
        if kind == "stop":
            st = self.stops[j]
            on = not self.stop_active[j]  # the event looks for the crossing that switches
            active = list(self.stop_active)
            active[j] = on
            self._set_mode((tuple(active), self.locked), t)
            return y.copy(), EventRecord(
                t,
                f"stop hinge {st.hinge} {'on' if on else 'off'}",
                {"hinge": st.hinge, "active": on},
            )
        D = self.hinge_angles_at(t, y)
        group = [j] + [
            i
            for i, la in enumerate(self.latches)
            if i != j
            and i not in self.locked
            and abs(D[la.hinge] - la.angle) <= deployment.SIMULTANEOUS_RAD
        ]
        locked = self.locked + tuple(group)
        y_new, data = lock_records.lock_record(self, t, y, locked, tuple(group))
        self._set_mode((self.stop_active, locked), t)
        hinges = [self.latches[i].hinge for i in group]
        label = "latch hinge " + ", ".join(str(h) for h in hinges)
        return y_new, EventRecord(t, label, data)

    def window_terms(self, t: float, y: np.ndarray, hinge: int) -> tuple[float, ...]:
        """The lock window's integrands at one state (``lock_records.window_terms``)."""
        return lock_records.window_terms(self, t, y, hinge)

    def window_rows(self, times: np.ndarray, Y: np.ndarray, hinge: int) -> np.ndarray:
        """The integrands at many states in the current mode (``lock_records.window_rows``)."""
        return lock_records.window_rows(self, times, Y, hinge)

    def energy_parts(self, t: float, y: np.ndarray) -> tuple[float, float, float]:
        """(kinetic, hinge, bending) energy (J) in the current mode (``lock_records``)."""
        return lock_records.energy_parts(self, t, y)

    def plastic_jump(self, y, hinges, angles) -> tuple[np.ndarray, np.ndarray]:
        """(state after the impact, multiplier impulses mu (N m s))."""
        raise NotImplementedError

    def difference_jacobian(self, t: float, y: np.ndarray) -> np.ndarray:
        """df/dy by central differences (the analytic Jacobians do not include the locked
        hinges' multipliers): for implicit methods on a run with latches."""
        J = np.empty((y.size, y.size))
        for i in range(y.size):
            h = 1e-7 * max(1.0, abs(y[i]))
            yp, ym = y.copy(), y.copy()
            yp[i] += h
            ym[i] -= h
            J[:, i] = (self.rhs(t, yp) - self.rhs(t, ym)) / (2 * h)
        return J

    def accel_locked(self, t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(accelerations, multipliers lambda (N m)) with the locked hinges held."""
        raise NotImplementedError


class PaperModel(OdeModel):
    """A model of the paper. ``coefficients``: "printed" (default, from the kinematics) or
    "published" (the erratum that reproduces the paper's alpha/beta; see paper_matrices).
    ``kernel``: "numba" (default, compiled O(n) kernels) or "numpy" (the straightforward
    dense right-hand side, kept as the reference and benchmark baseline)."""

    system_class: type[PaperSystem]
    OPTIONS: ClassVar[tuple[str, ...]] = ("coefficients", "kernel")
    MODES_OPTIONS: ClassVar[tuple[str, ...]] = ("coefficients",)

    def __init__(self, coefficients: str = DEFAULT_VARIANT, kernel: str = "numba"):
        self.coefficients = check_choice("coefficients", coefficients, VARIANTS)
        self.kernel = check_choice("kernel", kernel, KERNELS)

    def options(self):
        return {"coefficients": self.coefficients, "kernel": self.kernel}

    def system(self, scene: Scene) -> PaperSystem:
        return self.system_class(scene, self.coefficients, self.kernel)

    def validity_checks(self, scene: Scene, trajectory: Trajectory) -> list[Check]:
        """The energy balance (where audited) and the small-bending assumption of the paper's
        first-order kinematics (largest |alpha|, |beta| over the output times reached)."""
        return super().validity_checks(scene, trajectory) + small_bending(
            trajectory.stats.max_bending
        )
