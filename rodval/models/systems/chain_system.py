"""The chain systems assembled from parts: a rung (its state layout, the class: the paper's
``ChainSystem``, ``LadderSystem``, ``RigidSystem``) x a base (pinned; free or prescribed: a
``body.Body`` the system holds) x the hinge items (``PaperSystem``'s modes and events), on the
rung x base's compiled kernels (``kernel_tables.KERNEL_TABLES``, docs/base.md).

State [q; x_c, y_c, theta; q'; rates]: the chain's Nc coordinates q (phi, alpha, beta first, a
ladder rung's bubbles after them; the rigid chain: phi only), then a moving base's body (none on
a pin), N = Nc (+ 3). The paper's rung on a pinned base is the full model
(``presets.full.FullSystem``); every other rung x base is built here (``chain_system``).
"""

from __future__ import annotations

from functools import cached_property
from typing import Any

import numpy as np

from rodval.core.motion import motion_at
from rodval.core.scene import Scene
from rodval.models.assembly.kernels import full_constants
from rodval.models.assembly.paper_matrices import angular_momentum_rows as momentum_rows
from rodval.models.assembly.paper_matrices import hinge_matrix
from rodval.models.hinge_items import lock_records
from rodval.models.hinge_items.deployment import lock_scalars
from rodval.models.kinematics.ladder import (
    ladder_constants,
    rigid_constants,
    rod_momenta_exact,
    shapes_of,
)
from rodval.models.kinematics.rungs import (
    PAPER_RUNG,
)
from rodval.models.kinematics.shapes import RodShapes
from rodval.models.systems.body import Body, RodMomenta, Rows
from rodval.models.systems.kernel_tables import KERNEL_TABLES
from rodval.models.systems.paper_system import NO_LOADS, NO_MATRICES, PaperSystem

#: The options every rung but the pinned paper's runs with: the printed (kinematic) mass matrix
#: and the compiled kernels.
COMPILED_OPTIONS = ("printed", "numba")


class ChainSystem(PaperSystem):
    """The paper's rung (q = [phi; alpha; beta], Nc = 3n) on a free base (on a pin it is
    ``FullSystem``, with its own kernels), and what every rung shares: the stacked layout, the
    kernel table of its rung x base, the base's body (``body``: None on a pin) and, on a
    prescribed base, the drive (the laws reach the kernels as the compiled form's M[0]; a
    massless body, so the drive's power is booked as external). Subclasses set ``rung`` and
    ``chain_size``."""

    full = True
    #: the rung's name in ``KERNEL_TABLES``
    rung = "paper"

    def __init__(
        self,
        scene: Scene,
        coefficients: str = COMPILED_OPTIONS[0],
        kernel: str = COMPILED_OPTIONS[1],
    ):
        super().__init__(scene, coefficients, kernel)
        k = self.kernels = KERNEL_TABLES[self.rung, scene.base.kind]
        self.accel_kernel, self.compiled_rhs, self.compiled_mechanics = k.accel, k.rhs, k.mechanics
        self.compiled_rhs_locked, self.compiled_events = k.rhs_locked, k.events
        self.Nc = self.chain_size()
        self.body = Body(scene, self.base_chain, self.Nc) if scene.base.moving else None
        self.N = self.Nc if self.body is None else self.body.N
        self.whole_arrays = self.whole_arrays and self.body is None
        y0 = self.chain_initial_state()
        self.y0 = y0 if self.body is None else self.body.with_body(y0)
        self.use_kernel()

    def chain_size(self) -> int:
        """Nc: the chain's coordinates."""
        return 3 * self.n

    def chain_constants(self) -> np.ndarray:
        """The chain's rows of the kernels' V (``kernels.full_constants``)."""
        return full_constants(self.cc, self.chain)

    def kernel_constants(self) -> np.ndarray:
        rows = self.chain_constants()
        return rows if self.body is None else np.vstack([rows, self.body.rows(self.n)])

    def chain_initial_state(self) -> np.ndarray:
        """The chain's [q; q'] at t = 0."""
        i = self.initial
        return np.concatenate([i["phi"], i["alpha"], i["beta"], i["dphi"], i["dalpha"], i["dbeta"]])

    # ------------------------------------------------------------------ state layout
    def generalized_rates(self, y: np.ndarray) -> np.ndarray:
        return y[self.N :]

    def rigid(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n, N = self.n, self.N
        return Y[:, :n], Y[:, N : N + n]

    def bending(self, times: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, ...]:
        n, N = self.n, self.N
        return (
            Y[:, n : 2 * n],
            Y[:, 2 * n : 3 * n],
            Y[:, N + n : N + 2 * n],
            Y[:, N + 2 * n : N + 3 * n],
        )

    def bubble_energies(self, Y: np.ndarray) -> np.ndarray:
        """The bending energy (J) of shapes beyond the paper's cubic, per state: none."""
        return np.zeros(len(Y))

    def attitude(self, Y: np.ndarray) -> np.ndarray | None:
        return None if self.body is None else self.body.attitude(Y)

    def attitude_rate(self, Y: np.ndarray) -> np.ndarray | None:
        return None if self.body is None else self.body.attitude_rate(Y)

    def root_motion(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return super().root_motion(y) if self.body is None else self.body.root_motion(y)

    def hinge_rows(self, hinges: Any) -> np.ndarray:
        """Rows of D = A Q (N columns): the paper's hinge matrix on the chain's coordinates
        (a rung's bubbles take none), hinge 0 measured from the body (-1 at theta)."""
        hinges = np.asarray(hinges, dtype=np.int64)
        A = np.zeros((hinges.size, self.N))
        width = min(3 * self.n, self.Nc)
        A[:, :width] = hinge_matrix(self.n)[hinges][:, :width]
        if self.body is not None:
            A[hinges == 0, self.Nc + 2] = -1.0
        return A

    def jacobian(self, t: float, y: np.ndarray) -> np.ndarray:
        return self.difference_jacobian(t, y)

    # ------------------------------------------------------------------ equations
    def compiled_scratch(self) -> np.ndarray:
        """A prescribed base's laws (M[0]); none otherwise."""
        motion = getattr(self.body, "motion", None)
        return NO_MATRICES if motion is None else motion[None, :, :]

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        if self.accel_kernel is not None:
            return super().rhs(t, y)
        out = np.empty_like(y)  # a prescribed base: the constrained solve, locks or not
        half = y.size // 2
        out[:half] = y[half:]
        out[half:], self._lam = self.accel_locked(t, y)
        return out

    def accel_locked(self, t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        out = np.empty(self.N)
        lam = np.empty(self._lock_h.size)
        loads = self.kernel_loads(t, y)
        if self.kernels.drive is None:
            self.kernels.locked(self.V, y, loads, self.damped, self._lock_h, out, lam)
        else:
            mo = motion_at(self.compiled_scratch()[0], t)
            self.kernels.locked(self.V, y, mo, loads, self.damped, self._lock_h, (out, lam))
        return out, lam

    def unit_responses(self, q: np.ndarray, hinges: Any) -> np.ndarray:
        U = np.empty((len(hinges), self.N))
        self.kernels.unit(self.V, q, np.asarray(hinges, np.int64), U)
        return U

    def plastic_jump(
        self, y: np.ndarray, hinges: Any, angles: Any
    ) -> tuple[np.ndarray, np.ndarray]:
        return lock_records.plastic_jump(self, y, hinges, angles)

    # ------------------------------------------------------------------ energies, momenta
    def _mechanics(self, kernel: Any, y: np.ndarray) -> np.ndarray:
        """(T, P_ext, P_diss) of ``kernel`` (RHS_TYPE) at one state, no loads, flags now."""
        kernel(0.0, y, self.V, self._flags, NO_MATRICES, NO_LOADS, self._mech)
        return self._mech

    def kinetic_energy(self, t: float, y: np.ndarray) -> float:
        """T (J) at one state (a prescribed base: the massless body's, ``KernelTable``)."""
        return float(self._mechanics(self.kernels.kinetic, y)[0])

    def energy_rows(self, times: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        kin = np.array([self.kinetic_energy(t, y) for t, y in zip(times, Y)])
        phi = self.rigid(Y)[0]
        alpha, beta = self.bending(times, Y)[:2]
        pot = self.potential(phi, alpha, beta, self.attitude(Y))
        return kin, pot + self.bubble_energies(Y)

    def energy_budget(self, t: float, y: np.ndarray) -> float:
        return self._energy_in_mode(t, y)

    def damper_power_at(self, y: np.ndarray) -> float:
        if not self.kernels.damper_mechanics:
            return super().damper_power_at(y)
        return float(self._mechanics(self.compiled_mechanics, y)[2])

    def mode_flags(self) -> np.ndarray:
        """The compiled S of the current mode (its held hinges)."""
        return lock_scalars(self._flags[0], self._lock_h, self._lock_a)

    def power(self, t: float, y: np.ndarray) -> tuple[float, float]:
        """(P_ext, P_diss) (W); on a prescribed base P_ext holds the drive's power
        (``chain_base.prescribed_mechanics``, in the mode in effect at t)."""
        if self.kernels.drive is None:
            return super().power(t, y)
        out = np.zeros(3)
        with self._mode_at(t):
            S, M = self.mode_flags(), self.compiled_scratch()
            self.compiled_mechanics(t, y, self.V, S, M, self._loads(), out)
        return float(out[1]), float(out[2])

    def _loads(self) -> np.ndarray:
        """The compiled load table (an empty one for a plain Python load)."""
        table = self._load_table
        return NO_LOADS if table is None else table

    def chain_momenta(self, y: np.ndarray) -> RodMomenta:
        """The rods' momenta about a pinned node 0 (``PaperSystem.rod_momenta_at``)."""
        return super().rod_momenta_at(y)

    def rod_momenta_at(self, y: np.ndarray) -> RodMomenta:
        parts = self.chain_momenta(y)
        return parts if self.body is None else self.body.moved(parts, y)

    def momentum_rows(self, Y: np.ndarray) -> np.ndarray:
        """The whole system's P (N s, (nt, 2)); a moving base's from its kernel (kept
        exactly)."""
        if self.body is None:
            return super().momentum_rows(Y)
        return np.array([self.kernels.momentum(self.V, y) for y in Y])

    def angular_momentum_rows(self, times: np.ndarray, Y: np.ndarray) -> np.ndarray:
        if self.body is None:
            return super().angular_momentum_rows(times, Y)
        return self.body.angular_momentum_rows(Y, self.momentum_rows(Y), self.rod_momenta_at)

    def momentum_audit_rows(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.body is None:
            return super().momentum_audit_rows(Y)
        return self.body.momentum_audit_rows(Y, self.rod_momenta_at)

    # ------------------------------------------------------------------ outputs
    def drive_rows(self, times: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """[F_dx, F_dy (N), M_d (N m)] per output time: a prescribed base's force on the
        chain at node 0 and its moment about the body's centre, M_d = rho x F_d + m_1
        (``chain_base.drive``), each in the mode in effect there."""
        assert self.body is not None
        out = np.empty((len(Y), 3))
        L = self._loads()
        r0 = self.body.root_states(Y)[0]
        rc = self.body.states(Y)[0]
        for i, (t, y) in enumerate(zip(times, Y)):
            with self._mode_at(t):
                mo = motion_at(self.compiled_scratch()[0], t)
                Fx, Fy, m1 = self.kernels.drive(self.V, y, mo, self.mode_flags(), L, t)
            rho = r0[i] - rc[i]
            out[i] = Fx, Fy, rho[0] * Fy - rho[1] * Fx + m1
        return out

    def _observe_rows(self, times: np.ndarray, Y: np.ndarray) -> Rows:
        out = super()._observe_rows(times, Y)
        if self.body is None:
            return out
        out = self.body.observe(out, Y, self.scene.wants)
        if self.kernels.drive is not None and self.scene.wants("drive"):
            drive = self.drive_rows(times, Y)
            out["drive_force"] = (drive[:, :2], np.arange(2))
            out["drive_moment"] = (drive[:, 2:], np.zeros(1, dtype=int))
        return out


class LadderSystem(ChainSystem):
    """A rung of the ladder (``shapes`` p, ``kinematics``; ``kinematics.ladder``) on any base:
    q = [phi; alpha; beta; g_2 .. g_p] (Nc = n (p + 2)); the compiled kernels only (the dense
    numpy kernel is the paper model's reference)."""

    has_jacobian = False
    whole_arrays = False
    rung = "ladder"

    def __init__(self, scene: Scene, coefficients: str, kernel: str, shapes: int, kinematics: str):
        """The options as ``FullModel`` checked them (``check_shapes``, ``check_kinematics``,
        ``check_rung_options``: once, when the model is made)."""
        self.p = int(shapes)
        self.exact = kinematics == "exact"
        super().__init__(scene, coefficients, kernel)

    def chain_size(self) -> int:
        return self.n * (self.p + 2)

    def chain_initial_state(self) -> np.ndarray:
        """[q; q'] of the chain at t = 0: the paper's coordinates, the bubbles at rest."""
        i = self.initial
        bubbles = np.zeros(self.n * (self.p - 1))
        return np.concatenate(
            [i["phi"], i["alpha"], i["beta"], bubbles, i["dphi"], i["dalpha"], i["dbeta"], bubbles]
        )

    @cached_property
    def shapes(self) -> RodShapes:
        return shapes_of(self.base_chain, self.p)

    def chain_constants(self) -> np.ndarray:
        return ladder_constants(self.chain, self.p, self.exact)

    def _split(self, y: np.ndarray) -> tuple[np.ndarray, ...]:
        """(phi, phi', g (p+1, n), g' (p+1, n)) of one state."""
        n, N, Nc, P1 = self.n, self.N, self.Nc, self.p + 1
        g = y[n:Nc].reshape(P1, n)
        return y[:n], y[N : N + n], g, y[N + n : N + Nc].reshape(P1, n)

    def bubble_energy(self, y: np.ndarray) -> float:
        """1/2 sum_i>=2 K_ii g_i^2 (J): the bubbles' bending energy (their stiffness block
        is diagonal and K-orthogonal to the cubic's, whose energy the paper's Pi holds)."""
        g = self._split(y)[2]
        return 0.5 * float(np.sum(self._bubble_stiffness * g[2:] ** 2))

    @cached_property
    def _bubble_stiffness(self) -> np.ndarray:
        """K_ii (N m) of the bubbles i = 2..p, (p - 1, n)."""
        K: np.ndarray = np.einsum("kii->ik", self.shapes.K)[2:]
        return K

    def bubble_energies(self, Y: np.ndarray) -> np.ndarray:
        return np.array([self.bubble_energy(y) for y in Y])

    def bending_energy_at(self, t: float, y: np.ndarray) -> float:
        return super().bending_energy_at(t, y) + self.bubble_energy(y)

    def chain_momenta(self, y: np.ndarray) -> RodMomenta:
        phi, dphi, g, dg = self._split(y)
        return rod_momenta_exact(self.base_chain, self.shapes, self.exact, phi, dphi, g, dg)

    def angular_momentum_rows(self, times: np.ndarray, Y: np.ndarray) -> np.ndarray:
        if self.body is not None:
            return super().angular_momentum_rows(times, Y)
        return np.array([momentum_rows(*self.rod_momenta_at(y), self.base_chain) for y in Y])


class RigidSystem(ChainSystem):
    """The rigid chain on any base (docs/model.md, "The rigid model"): q = phi (Nc = n), the
    ladder's kernels on zero bending mobility (``ladder.rigid_constants``) restricted to phi
    (``rigid_kernels``, ``base.rigid_base``); hinge angles are the chords', a lock is the
    plastic impact in the metric M_pp(phi), the rigid-panel lock of
    ``rodval.mechanics.rigid``; the bending coordinates are identically zero."""

    has_jacobian = False
    full = False
    rung = "rigid"

    def __init__(self, scene: Scene):
        super().__init__(scene, *COMPILED_OPTIONS)

    def chain_size(self) -> int:
        return self.n

    def chain_initial_state(self) -> np.ndarray:
        """[phi; phi'] at t = 0 (the scene's bending angles and rates have no place here)."""
        i = self.initial
        return np.concatenate([i["phi"], i["dphi"]])

    def chain_constants(self) -> np.ndarray:
        return rigid_constants(self.chain)

    def bending(self, times: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, ...]:
        zero = np.zeros((len(Y), self.n))
        return zero, zero, zero, zero

    def generalized_rates(self, y: np.ndarray) -> np.ndarray:
        """[phi'; 0; 0] (3 n): the rates in the paper's coordinates, no bending."""
        return np.concatenate([y[self.N : self.N + self.n], np.zeros(2 * self.n)])

    def bending_energy_at(self, t: float, y: np.ndarray) -> float:
        return 0.0

    def max_bending(self, times: np.ndarray, Y: np.ndarray) -> float | None:
        """None: rigid rods do not bend (no small-bending check)."""
        return None


def chain_system(
    scene: Scene,
    shapes: int,
    kinematics: str,
    coefficients: str = COMPILED_OPTIONS[0],
    kernel: str = COMPILED_OPTIONS[1],
) -> ChainSystem:
    """The full model's system on rung (``shapes``, ``kinematics``) and ``scene``'s base: the
    paper's rung on a free base (``ChainSystem``), a ladder rung otherwise (which refuses
    options other than ``COMPILED_OPTIONS``; the pinned paper rung is ``FullSystem``)."""
    if scene.base.free and (shapes, kinematics) == PAPER_RUNG:
        return ChainSystem(scene, coefficients, kernel)
    return LadderSystem(scene, coefficients, kernel, shapes, kinematics)
