"""What every system of the paper's chain shares (the full and reduced models, the chain systems
of ``chain_system``): scene constants, loads, modes and events, energies and momenta (what the
energy audit, the observation map and the lock records read, each from one state or a history)
and the observation map."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager
from functools import cached_property
from typing import Any

import numpy as np

from rodval.core.checks import check_choice
from rodval.core.load_table import LOAD_COLUMNS, load_table
from rodval.core.loads import LoadSet
from rodval.core.scene import Scene, hinge_angles
from rodval.models.assembly.kernels import Loads
from rodval.models.assembly.paper_matrices import (
    DEFAULT_VARIANT,
    ChainConstants,
    angle_differences,
    angular_momentum,
    assemble_mass,
    bending_energy,
    chain_constants,
    damper_power,
    damping_matrix,
    generalized_forces,
    hinge_matrix,
    potential_energy,
    rest_forces,
    rod_momenta,
    stiffness_matrix,
)
from rodval.models.hinge_items import deployment, events, lock_records
from rodval.models.systems.observed import chain_rows
from rodval.solvers.signature import EVENTS_SIGNATURE, RHS_SIGNATURE, first_class
from rodval.solvers.system import CompiledForm, EventRecord, EventSpec, Observed, OdeSystem

#: Right-hand-side implementations: "numba" (compiled, structured; default) or "numpy"
#: (the straightforward dense reference).
KERNELS = ("numba", "numpy")
#: Placeholders for the compiled forms' unused arrays (no dense matrices, no loads) and the
#: kernels' "no hinge moments" (``Tq`` of length 0).
NO_MATRICES = np.zeros((0, 0, 0))
NO_LOADS = np.zeros((0, len(LOAD_COLUMNS)))
NO_TORQUES = np.zeros(0)
#: A mode: which stops act, which latches are locked, which compliant latches engaged (in order).
Mode = tuple[tuple[bool, ...], tuple[int, ...], tuple[int, ...]]


class PaperSystem(OdeSystem):
    """Base of the paper's ODE systems. Subclasses provide ``numpy_rhs``, the compiled
    kernels (``accel_kernel``, ``compiled_rhs``) and their constants (``kernel_constants``),
    ``jacobian`` and ``bending`` (alpha, beta, alpha', beta' at output times)."""

    has_jacobian = True
    has_energy = True
    has_momentum = True
    #: True for the full model (state [q; q'], 6n), False for the reduced one ([phi; phi']).
    full: bool
    #: accel(V, y, loads, damped, out) (``kernel_loads``) and the RHS_TYPE functions (rhs, mechanics;
    #: rhs with locked hinges, ``deployment.lock_scalars``) and the EVENTS_TYPE one.
    accel_kernel: Any
    compiled_rhs: Any
    compiled_mechanics: Any
    compiled_rhs_locked: Any
    compiled_events: Any
    #: True when the rods' momenta are the paper's velocity field on a pinned base
    #: (``paper_matrices.rod_momenta``), so histories are evaluated on whole arrays (the
    #: momentum audit, ``lock_records.window_rows``); a ladder rung's or a moving base's are not.
    whole_arrays = True

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
        self.loads = LoadSet(scene.loads, chain.n, scene.torques)
        self.initial = scene.initial.resolve(chain.n)
        self.latches = tuple(scene.latches)
        self.compliant = tuple(scene.compliant_latches)
        D0 = scene.initial_hinge_angles()
        #: the scene's stops, then the compliant latches' (``events.system_stops``)
        self.stops, self._initial_stops = events.system_stops(scene, D0)
        self.latch_dir, self.compliant_dir = (  # resolved: +1 or -1
            events.directions(group, D0) for group in (self.latches, self.compliant)
        )
        self._initial_locked = tuple(j for j, la in enumerate(self.latches) if la.held)
        #: mode: which stops act, which latches are locked, which compliant latches engaged
        self.stop_active: tuple[bool, ...] = self._initial_stops
        self.locked: tuple[int, ...] = ()
        self.engaged: tuple[int, ...] = ()
        self._history: list[tuple[float, Mode]] = []
        self._lock_h = np.zeros(0, dtype=np.int64)
        self._lock_a = np.zeros(0)
        self._lam = np.zeros(0)
        if any(self.stop_active):
            self._apply_stops()

    def rigid(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """phi, phi' from a state history Y (nt, N)."""
        raise NotImplementedError

    def bending(self, times: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, ...]:
        """alpha, beta, alpha', beta' (each (nt, n)) from a state history."""
        raise NotImplementedError

    def generalized_rates(self, y: np.ndarray) -> np.ndarray:
        """q' = [phi'; alpha'; beta'] (3n; a ladder rung: all N) as the model's equations see
        it at state y."""
        raise NotImplementedError

    def attitude(self, Y: np.ndarray) -> np.ndarray | None:
        """The base's attitude theta (rad, (nt,)) from a state history, hinge 0's reference;
        None on a pinned base (theta = 0)."""
        return None

    def attitude_rate(self, Y: np.ndarray) -> np.ndarray | None:
        """theta' (rad/s, (nt,)) from a history; None on a pinned base."""
        return None

    def root_motion(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(r_0 (m), v_0 (m/s)) of node 0 at one state: zero on a pinned base."""
        return np.zeros(2), np.zeros(2)

    def _kinetic(self, phi: np.ndarray, v: np.ndarray) -> float:
        """1/2 v^T M(phi) v with the kinematic mass matrix: the compiled O(n) form, or the
        dense one with the numpy kernel (the reference)."""
        if self.kernel == "numba":
            n = self.n
            y = (
                np.concatenate([phi, np.zeros(2 * n), v])
                if self.full
                else np.concatenate([phi, v[:n]])
            )
            self.compiled_mechanics(0.0, y, self.V, self._flags, NO_MATRICES, NO_LOADS, self._mech)
            return float(self._mech[0])
        return 0.5 * float(v @ assemble_mass(self.cc_kinetic, angle_differences(phi)[0]) @ v)

    def kinetic_energy(self, t: float, y: np.ndarray) -> float:
        """T = 1/2 q'^T M(phi) q' (J) at one state, without recovering bending angles; O(n)
        with the compiled kernels."""
        return self._kinetic(self.rigid(y[None, :])[0][0], self.generalized_rates(y))

    def potential(
        self,
        phi: np.ndarray,
        alpha: np.ndarray,
        beta: np.ndarray,
        attitude: np.ndarray | None = None,
    ) -> np.ndarray:
        """Pi (J) per row: the scene chain's springs and bending, plus 1/2 k (D - angle)^2 of
        every limit stop acting in the current mode; ``attitude``: a free base's theta (rad)
        per row, hinge 0's reference (``rodval.core.scene.hinge_angles``)."""
        pot = potential_energy(self.base_chain, phi, alpha, beta, attitude)
        if any(self.stop_active):
            D = hinge_angles(phi, alpha, beta, attitude)
            for st, on in zip(self.stops, self.stop_active):
                if on:
                    pot = pot + 0.5 * st.stiffness * (D[..., st.hinge] - st.angle) ** 2
        return pot

    def energy_rows(self, times: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(T, Pi) (J) per state of a history Y in the current mode: kinetic T = 1/2 q'^T
        M(phi) q' with the kinematic (printed) mass matrix, and Pi = 1/2 sum kappa (D -
        rest)^2 + bending (J); O(n) each."""
        phi, dphi = self.rigid(Y)
        alpha, beta, dalpha, dbeta = self.bending(times, Y)
        v = np.concatenate([dphi, dalpha, dbeta], axis=1)
        kin = np.array([self._kinetic(p, vi) for p, vi in zip(phi, v)])
        return kin, self.potential(phi, alpha, beta)

    def energy_history(self, times: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """E = T + Pi (J) per state of a history Y at ``times`` (s), each in the mode in effect
        at its time (``_mode_for``: an event's time is in the mode before it), as ``observe``
        reports it: the energy audit's E on its grid (``rodval.solvers.audit``). One
        ``energy_rows`` per run of states in one mode; O(n) per state."""
        times = np.asarray(times, float)
        E = np.empty(times.size)
        for run in self._mode_runs(times):
            kin, pot = self.energy_rows(times[run], Y[run])
            E[run] = kin + pot
        return E

    def _mode_runs(self, times: np.ndarray) -> Iterator[slice]:
        """The runs of consecutive ``times`` in one mode (``_mode_for``), each yielded with
        its mode in effect."""
        modes = [self._mode_for(float(t)) for t in times]
        start = 0
        for i in range(1, len(times) + 1):
            if i < len(times) and modes[i] == modes[start]:
                continue
            with self._mode(modes[start]):
                yield slice(start, i)
            start = i

    def bending_energy_at(self, t: float, y: np.ndarray) -> float:
        """The rods' bending energy (J) at one state."""
        alpha, beta = self.bending(np.array([t]), y[None, :])[:2]
        return float(bending_energy(self.base_chain, alpha, beta)[0])

    def rod_momenta_at(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(p (n, 2), h (n,), first (n, 2)) of every rod with its far node at one state, in
        the model's velocity field (``paper_matrices.rod_momenta``); O(n)."""
        n = self.n
        v = self.generalized_rates(y)
        phi = self.rigid(y[None, :])[0][0]
        return rod_momenta(self.base_chain, phi, v[:n], v[n : 2 * n], v[2 * n : 3 * n])

    def momenta(self, y: np.ndarray) -> np.ndarray:
        """Linear momentum (N s, (n, 2)) of everything beyond node k (rods k+1..n and their
        far nodes), k = 0..n-1; row 0 is the whole chain's."""
        p = self.rod_momenta_at(y)[0]
        return np.cumsum(p[::-1], axis=0)[::-1]

    def momentum_rows(self, Y: np.ndarray) -> np.ndarray:
        """The chain's linear momentum P = sum_k p_k (N s, (nt, 2)) per state of a history, in
        the model's velocity field (``rod_momenta_at``)."""
        return np.array([self.rod_momenta_at(y)[0].sum(axis=0) for y in Y])

    def momentum_audit_rows(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(H, G) (N m s, (nt,) each) for the angular-momentum audit of a pinned chain
        (``rodval.core.validity.momentum_balance``): the angular momentum about node 0 and the
        gross, sum_k |h_k| of the rods with their far nodes (``rod_momenta_at``). O(n) per
        state."""
        if len(Y) and self.whole_arrays:
            # the paper's velocity field (``rod_momenta_at``) on the whole history at once
            n = self.n
            V = np.array([self.generalized_rates(y) for y in Y])
            phi = self.rigid(Y)[0]
            h = rod_momenta(self.base_chain, phi, V[:, :n], V[:, n : 2 * n], V[:, 2 * n : 3 * n])[1]
        else:
            h = np.array([self.rod_momenta_at(y)[1] for y in Y]).reshape(len(Y), -1)
        return h.sum(axis=1), np.abs(h).sum(axis=1)

    def angular_momentum_rows(self, times: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """The ``angular_momentum`` rows (nt, 2) (``paper_matrices.angular_momentum``)."""
        phi, dphi = self.rigid(Y)
        dalpha, dbeta = self.bending(times, Y)[2:]
        return angular_momentum(self.base_chain, phi, dphi, dalpha, dbeta)

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
            self._flags = np.array([1.0 if self.damped else 0.0])
            self._mech = np.zeros(3)
        self.rhs(0.0, self.y0)

    def kernel_constants(self) -> np.ndarray:
        """The compiled kernels' constant rows V for this system (O(n))."""
        raise NotImplementedError

    def numpy_rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        if self.locked:
            out = np.empty_like(y)
            half = y.size // 2
            out[:half] = y[half:]
            out[half:], self._lam = self.accel_locked(t, y)
            return out
        if self.kernel == "numpy":
            return self.numpy_rhs(t, y)
        half = y.size // 2
        out = np.empty_like(y)
        out[:half] = y[half:]
        self.accel_kernel(self.V, y, self.kernel_loads(t, y), self.damped, out[half:])
        return out

    def compiled(self) -> CompiledForm | None:
        """The compiled form of the current mode (locked hinges in S, the armed latches and
        switching stops as event rows; active stops are in V), or None with the numpy kernel
        or a load that is a plain Python callable (no load-table form). Built once per mode
        (``_forms``): the driver's choice of method and the loop's first segment share it."""
        if self.mode not in self._forms:
            self._forms[self.mode] = self._compiled_form()
        return self._forms[self.mode]

    @cached_property
    def _forms(self) -> dict[Mode, CompiledForm | None]:
        return {}

    def _compiled_form(self) -> CompiledForm | None:
        if self.kernel != "numba":
            return None
        table = self._load_table
        if table is None:
            return None
        rows = events.event_rows(self)
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
        """The scene's compiled load table, its hinge items' moments and rate coefficients
        after the nodal loads' rows (built once: O(rows), ~1 s per 1e5 samples)."""
        return load_table(self.scene.loads, [r for it in self.scene.torques for r in it.rows()])

    def compiled_scratch(self) -> np.ndarray:
        """The compiled form's M: work space its right-hand side reuses (none by default)."""
        return NO_MATRICES

    def generalized_force(self, t: float, phi: np.ndarray) -> np.ndarray | None:
        """Q(phi, t) (N m) on the phi coordinates, or None when no load acts at t."""
        sums = self.loads.suffix_sums(t)
        return None if sums is None else generalized_forces(self.l, phi, *sums)

    def torques_at(self, t: float, y: np.ndarray) -> np.ndarray:
        """Tq (N m, n): the motors' and rate dampers' moments across the hinges at one state
        (positive driving D_k up; ``LoadSet.hinge_moments`` at the rates the model's dampers
        see, ``hinge_rates``), or ``NO_TORQUES`` (length 0, the kernels' "none") without
        torque items. O(n)."""
        if not self.loads.torques:
            return NO_TORQUES
        Tq = self.loads.hinge_moments(t, self.hinge_rates(y))
        return NO_TORQUES if Tq is None else Tq

    def kernel_loads(self, t: float, y: np.ndarray) -> Loads:
        """The compiled kernels' loads at one state (``kernels.Loads``): whether a load acts at
        t, its suffix sums SX, SY (N, n each, contiguous; zeros when none acts) and the hinge
        moments Tq (N m, ``torques_at``). O(n)."""
        sums = self.loads.suffix_sums(t)
        SX, SY = (np.zeros(self.n), np.zeros(self.n)) if sums is None else sums
        Tq = self.torques_at(t, y)
        return sums is not None, np.ascontiguousarray(SX), np.ascontiguousarray(SY), Tq

    def torque_forces(self, t: float, y: np.ndarray) -> np.ndarray | None:
        """A^T Tq (N m, 3n): the hinge moments' generalized forces on q = [phi; alpha; beta]
        (the dense reference's; ``torques_at``), None without torque items. O(n^2)."""
        Tq = self.torques_at(t, y)
        return hinge_matrix(self.n).T @ Tq if Tq.size else None

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
        paper_matrices.generalized_forces) + sum_k Tq_k dD_k/dt (the motors' and rate
        dampers' power, booked as external work: ``torques_at``); P_diss = q'^T C q' =
        sum_k nu_k (dD_k/dt)^2 >= 0, the power taken out by the hinge dampers (D_k: hinge
        angles)."""
        phi, dphi = (a[0] for a in self.rigid(y[None, :]))
        sums = self.loads.suffix_sums(t)
        p_ext = 0.0 if sums is None else float(generalized_forces(self.l, phi, *sums) @ dphi)
        if sums is not None and self.scene.base.free:  # the loads' resultant on node 0's motion
            v0 = self.root_motion(y)[1]
            p_ext += float(sums[0][0] * v0[0] + sums[1][0] * v0[1])
        Tq = self.torques_at(t, y)
        if Tq.size:
            p_ext += float(Tq @ self.hinge_rates(y))
        with self._mode_at(t):
            return p_ext, self.damper_power_at(y) if self.damped else 0.0

    def damper_power_at(self, y: np.ndarray) -> float:
        """q'^T C q' (W) at one state in the current mode (``paper_matrices.damper_power``)."""
        n = self.n
        v = self.generalized_rates(y)
        rate = self.attitude_rate(y[None, :])
        theta = None if rate is None else rate[0]
        return damper_power(self.chain, v[:n], v[n : 2 * n], v[2 * n : 3 * n], theta)

    def _observe_rows(self, times: np.ndarray, Y: np.ndarray) -> Observed:
        """The scene's quantities at ``times`` in the current mode (``observed.chain_rows``)."""
        return chain_rows(self, times, Y)

    def observe(self, times: np.ndarray, Y: np.ndarray) -> Observed:
        """The scene's quantities; each output time is observed in the mode (active stops,
        locked hinges) in effect there (an output time at an event: the mode before it)."""
        times = np.asarray(times, float)
        out: Observed = {}
        for run in self._mode_runs(times):
            for key, (v, k) in self._observe_rows(times[run], Y[run]).items():
                out[key] = (np.concatenate([out[key][0], v]), k) if key in out else (v, k)
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

    def _activate(self, mode: Mode) -> None:
        stops, locked, self.engaged = mode
        if stops != self.stop_active:
            self.stop_active = stops
            self._apply_stops()
        if locked != self.locked:
            self.locked = locked
            self._lock_h = np.array([self.latches[j].hinge for j in locked], dtype=np.int64)
            self._lock_a = np.array([self.latches[j].angle for j in locked], dtype=float)
            self._lam = np.zeros(len(locked))

    @property
    def mode(self) -> Mode:
        return (self.stop_active, self.locked, self.engaged)

    def _mode_for(self, t: float) -> Mode:
        """The mode in effect at time t: set by the last event strictly before t."""
        mode: Mode = (self._initial_stops, self._initial_locked, ())
        for ts, m in self._history:
            if ts < t:
                mode = m
        return mode

    @contextmanager
    def _mode(self, mode: Mode) -> Iterator[None]:
        old = self.mode
        self._activate(mode)
        try:
            yield
        finally:
            self._activate(old)

    def _mode_at(self, t: float) -> AbstractContextManager[None]:
        return self._mode(self._mode_for(t))

    def reset(self) -> None:
        """Back to the initial mode (the held latches locked, the stops the initial state is
        beyond), forgetting the event history: called by the driver before a run."""
        self._history = []
        self._activate((self._initial_stops, self._initial_locked, ()))

    def set_mode(self, mode: Mode, t: float) -> None:
        """Enter ``mode`` at time t (an event), recorded for ``_mode_for``."""
        self._history.append((t, mode))
        self._activate(mode)

    # ------------------------------------------------------------- deployment: events
    def hinge_rows(self, hinges: Any) -> np.ndarray:
        """Rows a_k of the hinge matrix (D = A q, q = [phi; alpha; beta]) of these hinges."""
        rows: np.ndarray = hinge_matrix(self.n)[hinges]
        return rows

    def hinge_angles_at(self, t: float, y: np.ndarray) -> np.ndarray:
        """D_k (rad, n) at one state in the current mode."""
        Y = y[None, :]
        phi = self.rigid(Y)[0]
        alpha, beta = self.bending(np.array([t]), Y)[:2]
        D: np.ndarray = hinge_angles(phi, alpha, beta, self.attitude(Y))[0]
        return D

    def hinge_rates(self, y: np.ndarray) -> np.ndarray:
        """dD_k/dt as the model's dampers see it: A q' (reduced: chord rates, the bending
        rates being dropped)."""
        n = self.n
        v = self.generalized_rates(y)
        rate = self.attitude_rate(y[None, :])
        return hinge_angles(
            v[:n], v[n : 2 * n], v[2 * n : 3 * n], None if rate is None else rate[0]
        )

    def event_functions(self) -> tuple[EventSpec, ...]:
        """The current mode's events (``events.event_specs``)."""
        return events.event_specs(self)

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
        y_new, record = events.switch(self, index, t, y)
        after = self._energy_in_mode(t, y_new)
        record.data.update(
            energy_before=before, energy_after=after, instant_energy_loss=before - after
        )
        return y_new, record

    def window_terms(self, t: float, y: np.ndarray, hinge: int) -> tuple[float, ...]:
        """The lock window's integrands at one state (``lock_records.window_terms``)."""
        return lock_records.window_terms(self, t, y, hinge)

    def window_rows(self, times: np.ndarray, Y: np.ndarray, hinge: int) -> np.ndarray:
        """The integrands at many states in the current mode (``lock_records.window_rows``)."""
        return lock_records.window_rows(self, times, Y, hinge)

    def energy_parts(self, t: float, y: np.ndarray) -> tuple[float, float, float]:
        """(kinetic, hinge, bending) energy (J) in the current mode (``lock_records``)."""
        return lock_records.energy_parts(self, t, y)

    def plastic_jump(
        self, y: np.ndarray, hinges: Any, angles: Any
    ) -> tuple[np.ndarray, np.ndarray]:
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
