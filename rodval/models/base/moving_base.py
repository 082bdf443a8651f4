"""Every ladder rung (shapes p, first-order or exact kinematics) and the rigid chain on a moving
base: a free body (``LadderFreeSystem``, ``RigidFreeSystem``) or a prescribed motion
(``LadderPrescribedSystem``, ``RigidPrescribedSystem``), on the compiled kernels of
``chain_base`` (docs/base.md derives them; the rigid chain runs them on its own state through
``rigid_base``). What a base adds to a chain system is written once, in ``FreeMotion`` and
``PrescribedMotion``, whatever the chain. The paper's rung on a free body keeps its own kernels
(``free_base_system.FreeBaseSystem``); on a prescribed base it runs here (the first rung of the
ladder is the paper's model to 1e-13, docs/model.md).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rodval.core.motion import motion_at
from rodval.core.scene import Scene
from rodval.models.assembly.paper_energy import NO_LOADS, NO_MATRICES
from rodval.models.base import chain_base as cb
from rodval.models.base import rigid_base as rb
from rodval.models.base.free_base_system import FreeBody
from rodval.models.hinge_items.deployment import lock_scalars
from rodval.models.kinematics.ladder import LadderSystem
from rodval.models.kinematics.rigid import RigidSystem


class FreeMotion(FreeBody):
    """What a free body adds to a chain system (a ladder rung, the rigid chain) beyond
    ``FreeBody``: its set-up, initial state and kernel rows (mixed in before the chain's
    class, whose ``kernel_constants`` gives the chain's rows)."""

    body_coordinates = 3
    chain_initial_state: Any

    def setup_base(self, scene: Scene) -> None:
        self.body_setup(scene)

    def initial_state(self) -> np.ndarray:
        return self.with_body(self.chain_initial_state())

    def kernel_constants(self) -> np.ndarray:
        return np.vstack([super().kernel_constants(), self.body_rows()])  # type: ignore[misc]

    def damper_power_at(self, y: np.ndarray) -> float:
        """The dampers' power (W) in the current mode, hinge 0's rate from the body's
        (``chain_base.moving_mechanics``)."""
        self.compiled_mechanics(0.0, y, self.V, self._flags, NO_MATRICES, NO_LOADS, self._mech)
        return float(self._mech[2])


class PrescribedMotion(FreeMotion):
    """A chain whose base moves by prescribed laws (``rodval.core.base.Motion``): a free
    body's state whose accelerations are the laws', which reach the kernels as the compiled
    form's M[0]; a massless body, so the drive's power is booked as external. The kernels
    (class attributes) are ``chain_base``'s on the chain's state."""

    #: (V, y, mo, has_load, SX, SY, damped, locks, out, lam): Q'' with ``locks`` held
    prescribed_kernel: Any
    #: RHS_TYPE: a massless free body's (T, P_ext, P_diss), the drive's power left out
    body_mechanics: Any
    #: (V, y, mo, S, L, t) -> (F_dx, F_dy, m_1): the base's force and moment on the chain
    drive_kernel: Any
    #: the chain system's attributes used here
    N: int
    _lock_h: np.ndarray
    _lock_a: np.ndarray
    _lam: np.ndarray
    _load_table: np.ndarray | None
    loads: Any
    damped: bool
    _no_load: np.ndarray
    _mode_at: Any

    def setup_base(self, scene: Scene) -> None:
        self.body_setup(scene)
        self.motion = scene.base.motion_table()

    def compiled_scratch(self) -> np.ndarray:
        return self.motion[None, :, :]

    def _sums(self, t: float) -> tuple[bool, np.ndarray, np.ndarray]:
        sums = self.loads.suffix_sums(t)
        SX, SY = (self._no_load, self._no_load) if sums is None else sums
        return sums is not None, SX, SY

    def rhs(self, t, y):
        out = np.empty_like(y)
        half = y.size // 2
        out[:half] = y[half:]
        out[half:], self._lam = self.accel_locked(t, y)
        return out

    def accel_locked(self, t, y):
        has, SX, SY = self._sums(t)
        out = np.empty(self.N)
        lam = np.empty(self._lock_h.size)
        mo = motion_at(self.motion, t)
        self.prescribed_kernel(self.V, y, mo, has, SX, SY, self.damped, self._lock_h, out, lam)
        return out, lam

    def mode_flags(self) -> np.ndarray:
        """The compiled S of the current mode (its held hinges)."""
        return lock_scalars(self._flags[0], self._lock_h, self._lock_a)

    def kinetic_energy(self, t, y):
        """T (J): a massless body's free-body T (``chain_base.free_mechanics``); the drive's
        power, which needs the laws at t and a solve, is not part of it."""
        self.body_mechanics(0.0, y, self.V, self._flags, NO_MATRICES, NO_LOADS, self._mech)
        return float(self._mech[0])

    def mechanics_at(self, t: float, y: np.ndarray) -> np.ndarray:
        """(T (J), P_ext with the drive's power (W), P_diss (W)) at one state in the current
        mode (``chain_base.prescribed_mechanics``)."""
        out = np.zeros(3)
        table = self._load_table
        L = NO_LOADS if table is None else table
        M = self.compiled_scratch()
        self.compiled_mechanics(t, y, self.V, self.mode_flags(), M, L, out)
        return out

    def power(self, t, y):
        with self._mode_at(t):
            mech = self.mechanics_at(t, y)
        return float(mech[1]), float(mech[2])

    def drive_rows(self, times, Y) -> np.ndarray:
        """[F_dx, F_dy (N), M_d (N m)] per output time: the base's force on the chain at node 0
        and its moment about the body's centre, M_d = rho x F_d + m_1 (``chain_base.drive``),
        each in the mode in effect there."""
        out = np.empty((len(Y), 3))
        table = self._load_table
        L = NO_LOADS if table is None else table
        r0 = self.root_states(Y)[0]
        rc = self.body_states(Y)[0]
        for i, (t, y) in enumerate(zip(times, Y)):
            with self._mode_at(t):
                mo = motion_at(self.motion, t)
                Fx, Fy, m1 = self.drive_kernel(self.V, y, mo, self.mode_flags(), L, t)
            rho = r0[i] - rc[i]
            out[i] = Fx, Fy, rho[0] * Fy - rho[1] * Fx + m1
        return out

    def _observe_rows(self, times, Y):
        out = super()._observe_rows(times, Y)
        if self.scene.wants("drive"):
            drive = self.drive_rows(times, Y)
            out["drive_force"] = (drive[:, :2], np.arange(2))
            out["drive_moment"] = (drive[:, 2:], np.zeros(1, dtype=int))
        return out


class LadderFreeSystem(FreeMotion, LadderSystem):
    """A ladder rung on a free body: state [q; x_c, y_c, theta; q'; rates] (N = n (p + 2) + 3)."""

    accel_kernel = staticmethod(cb.free_accel)
    locked_kernel = staticmethod(cb.free_accel_locked)
    unit_kernel = staticmethod(cb.free_unit_responses)
    compiled_rhs = staticmethod(cb.free_rhs)
    compiled_mechanics = staticmethod(cb.free_mechanics)
    compiled_rhs_locked = staticmethod(cb.free_rhs_locked)
    compiled_events = staticmethod(cb.free_hinge_events)
    momentum_kernel = staticmethod(cb.free_momentum)


class LadderPrescribedSystem(PrescribedMotion, LadderSystem):
    """A ladder rung on a prescribed base: a free body's state (N = n (p + 2) + 3)."""

    unit_kernel = staticmethod(cb.prescribed_unit_responses)
    compiled_rhs = staticmethod(cb.prescribed_rhs)
    compiled_mechanics = staticmethod(cb.prescribed_mechanics)
    compiled_rhs_locked = staticmethod(cb.prescribed_rhs)  # it reads the held hinges from S
    compiled_events = staticmethod(cb.free_hinge_events)
    momentum_kernel = staticmethod(cb.free_momentum)
    prescribed_kernel = staticmethod(cb.prescribed_accel_locked)
    body_mechanics = staticmethod(cb.free_mechanics)
    drive_kernel = staticmethod(cb.drive)


class RigidFreeSystem(FreeMotion, RigidSystem):
    """The rigid chain on a free body: state [phi; x_c, y_c, theta; phi'; rates] (N = n + 3)."""

    accel_kernel = staticmethod(rb.free_accel)
    locked_kernel = staticmethod(rb.free_accel_locked)
    unit_kernel = staticmethod(rb.free_unit_responses)
    compiled_rhs = staticmethod(rb.free_rhs)
    compiled_mechanics = staticmethod(rb.free_mechanics)
    compiled_rhs_locked = staticmethod(rb.free_rhs_locked)
    compiled_events = staticmethod(rb.free_hinge_events)
    momentum_kernel = staticmethod(rb.free_momentum)


class RigidPrescribedSystem(PrescribedMotion, RigidSystem):
    """The rigid chain on a prescribed base: a free body's state (N = n + 3)."""

    unit_kernel = staticmethod(rb.prescribed_unit_responses)
    compiled_rhs = staticmethod(rb.prescribed_rhs)
    compiled_mechanics = staticmethod(rb.prescribed_mechanics)
    compiled_rhs_locked = staticmethod(rb.prescribed_rhs)  # it reads the held hinges from S
    compiled_events = staticmethod(rb.free_hinge_events)
    momentum_kernel = staticmethod(rb.free_momentum)
    prescribed_kernel = staticmethod(rb.prescribed_accel_locked)
    body_mechanics = staticmethod(rb.free_mechanics)
    drive_kernel = staticmethod(rb.drive)
