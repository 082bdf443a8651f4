"""The full model on a free base: the paper's chain hanging from a rigid body free in the plane
(a spacecraft), docs/base.md. Its equations and kernels: ``rodval.models.base.free_base``.

State y = [Q; Q'], Q = [phi; alpha; beta; x_c, y_c, theta] (3n + 3). Everything the pinned
full model does runs here too: the compiled O(n) right-hand side, latches (a plastic lock in
the total mass matrix, hinge 0's lock holding rod 1 to the body), stops, the energy audit
(the body's kinetic energy and the loads' power on node 0's motion included) and the
outputs, which add the body's motion (``base``) and the whole system's momenta.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rodval.core.base import root_state
from rodval.core.scene import Scene
from rodval.models.assembly.kernels import full_constants
from rodval.models.assembly.paper_energy import NO_LOADS, NO_MATRICES
from rodval.models.assembly.stacked_system import StackedSystem
from rodval.models.base import free_base as fb


class FreeBody:
    """What a free body adds to a stacked chain system (``StackedSystem``) whose chain has
    ``Nc`` coordinates: the body's x_c, y_c, theta after them (N = Nc + 3), its initial state,
    hinge 0 measured from theta, the whole system's energies and momenta, and the outputs.
    Mixed in before the chain's system class (``FreeBaseSystem``: the paper's rung;
    ``moving_base.LadderFreeSystem``: every ladder rung); ``momentum_kernel(V, y)`` gives P."""

    Nc: int
    N: int
    momentum_kernel: Any
    #: the chain system's (``StackedSystem``) attributes and methods used here
    n: int
    V: np.ndarray
    scene: Scene
    base_chain: Any
    initial: dict
    compiled_mechanics: Any
    _flags: np.ndarray
    _mech: np.ndarray

    def body_setup(self, scene: Scene) -> None:
        """The body's constants (call before the chain system's kernel set-up); a prescribed
        base is a massless body following its laws."""
        b = self.body = scene.base
        if b.prescribed:
            self.body_mass, self.body_inertia = 0.0, 0.0
            self.body_start = b.state_at(0.0)
        else:
            self.body_mass, self.body_inertia = b.inertial()
            self.body_start = (np.array(b.position), np.array(b.velocity), b.attitude, b.rate)
        #: each rod's mass with its far node's (kg)
        self.rod_mass = self.base_chain.m * self.base_chain.l + self.base_chain.mu

    def body_rows(self) -> np.ndarray:
        """The kernels' body rows (appended to the chain's V): body mass, inertia, hinge
        offset, chain mass, each the same in every column."""
        h = self.body.hinge_offset
        rows = [self.body_mass, self.body_inertia, h[0], h[1], float(self.rod_mass.sum())]
        return np.outer(rows, np.ones(self.n))

    def with_body(self, y0: np.ndarray) -> np.ndarray:
        """The state [q; x_c, y_c, theta; q'; rates] from the chain's [q; q']."""
        (r, v, th, w), Nc = self.body_start, self.Nc
        return np.concatenate([y0[:Nc], r, [th], y0[Nc:], v, [w]])

    def jacobian(self, t: float, y: np.ndarray) -> np.ndarray:
        return self.difference_jacobian(t, y)  # type: ignore[attr-defined]

    def attitude(self, Y):
        return Y[:, self.Nc + 2]

    def attitude_rate(self, Y):
        return Y[:, self.N + self.Nc + 2]

    def body_states(self, Y) -> tuple[np.ndarray, np.ndarray]:
        """(r_c (m), v_c (m/s)) of the body's centre of mass, each (nt, 2)."""
        Nc, N = self.Nc, self.N
        return Y[:, Nc : Nc + 2], Y[:, N + Nc : N + Nc + 2]

    def root_states(self, Y) -> tuple[np.ndarray, np.ndarray]:
        """(r_0 (m), v_0 (m/s)) of node 0, each (nt, 2): r_c + rho, v_c + theta' k x rho."""
        return root_state(self.body, *self.body_states(Y), self.attitude(Y), self.attitude_rate(Y))

    def root_motion(self, y):
        r0, v0 = self.root_states(y[None, :])
        return r0[0], v0[0]

    # ------------------------------------------------------------------ locks
    def hinge_rows(self, hinges) -> np.ndarray:
        """Rows of D = A Q (N columns): hinge 0 is measured from the body (-1 at theta)."""
        hinges = np.asarray(hinges, dtype=np.int64)
        A = np.zeros((hinges.size, self.N))
        A[:, : self.Nc] = super().hinge_rows(hinges)  # type: ignore[misc]
        A[hinges == 0, self.Nc + 2] = -1.0
        return A

    # ------------------------------------------------------------------ energies, momenta
    def kinetic_energy(self, t, y):
        self.compiled_mechanics(0.0, y, self.V, self._flags, NO_MATRICES, NO_LOADS, self._mech)
        return float(self._mech[0])

    def energy_rows(self, times, Y):
        kin = np.array([self.kinetic_energy(t, y) for t, y in zip(times, Y)])
        phi = self.rigid(Y)[0]  # type: ignore[attr-defined]
        alpha, beta = self.bending(times, Y)[:2]  # type: ignore[attr-defined]
        pot = self.potential(phi, alpha, beta, self.attitude(Y))  # type: ignore[attr-defined]
        return kin, pot + self.bubble_energies(Y)  # type: ignore[attr-defined]

    def energy_budget(self, t, y):
        return self._energy_in_mode(t, y)  # type: ignore[attr-defined]

    def rod_momenta_at(self, y):
        """The pinned chain's rod momenta (``PaperEnergy.rod_momenta_at``) with node 0 moving:
        p += m_k v_0, h (about the origin) += m_k r_0 x v_0 + r_0 x p + first x v_0, first +=
        m_k r_0 (m_k: rod k's mass with its far node's)."""
        p, h, first = super().rod_momenta_at(y)  # type: ignore[misc]
        r0, v0 = self.root_motion(y)
        mass = self.rod_mass
        h = h + mass * cross(r0, v0) + cross(r0, p) + cross(first, v0)
        return p + mass[:, None] * v0, h, first + mass[:, None] * r0

    def momentum_rows(self, Y) -> np.ndarray:
        """The whole system's P (N s, (nt, 2)), ``momentum_kernel`` (kept exactly)."""
        return np.array([self.momentum_kernel(self.V, y) for y in Y])

    def angular_momentum_rows(self, times, Y):
        """[H about node 0, H about the system's centre of mass] (N m s, (nt, 2)), body
        included: H_O = J theta' + m_b r_c x v_c + sum_k h_k (about the origin), H_X = H_O -
        X x P for X = node 0 and the centre of mass (docs/quantities.md)."""
        rc, vc = self.body_states(Y)
        r0 = self.root_states(Y)[0]
        mb = self.body_mass
        out = np.empty((len(Y), 2))
        total = mb + float(self.rod_mass.sum())
        P = self.momentum_rows(Y)
        spin = self.body_inertia * self.attitude_rate(Y)
        for i, y in enumerate(Y):
            _, h, first = self.rod_momenta_at(y)
            HO = spin[i] + mb * cross(rc[i], vc[i]) + h.sum()
            X = (mb * rc[i] + first.sum(axis=0)) / total
            out[i] = HO - cross(r0[i], P[i]), HO - cross(X, P[i])
        return out

    def momentum_audit_rows(self, Y) -> tuple[np.ndarray, np.ndarray]:
        """(H, G) (N m s) about the system's centre of mass X for the angular-momentum audit:
        the parts are the rods with their far nodes, h_k - X x p_k (``rod_momenta_at``, about
        the origin), and the body, J theta' + m_b (r_c - X) x v_c; H their sum, G the sum of
        their magnitudes. O(n) per state."""
        rc, vc = self.body_states(Y)
        spin = self.body_inertia * self.attitude_rate(Y)
        mb = self.body_mass
        total = mb + float(self.rod_mass.sum())
        H, G = np.empty(len(Y)), np.empty(len(Y))
        for i, y in enumerate(Y):
            p, h, first = self.rod_momenta_at(y)
            X = (mb * rc[i] + first.sum(axis=0)) / total
            rods = h - (X[0] * p[:, 1] - X[1] * p[:, 0])
            body = spin[i] + mb * cross(rc[i] - X, vc[i])
            H[i] = rods.sum() + body
            G[i] = np.abs(rods).sum() + abs(body)
        return H, G

    def _observe_rows(self, times, Y):
        out = super()._observe_rows(times, Y)  # type: ignore[misc]
        r0 = self.root_states(Y)[0]
        for key, axis in (("x", 0), ("y", 1)):
            if key in out:
                v, k = out[key]
                out[key] = (v + r0[:, axis : axis + 1], k)
        if self.scene.wants("base"):
            rc, vc = self.body_states(Y)
            pair, one = np.arange(2), np.zeros(1, dtype=int)
            out["base_position"] = (rc, pair)
            out["base_velocity"] = (vc, pair)
            out["base_attitude"] = (self.attitude(Y)[:, None], one)
            out["base_rate"] = (self.attitude_rate(Y)[:, None], one)
        return out


class FreeBaseSystem(FreeBody, StackedSystem):
    """The full model (the paper's rung, printed coefficients, compiled kernel) on a free
    base (``free_base``)."""

    accel_kernel = staticmethod(fb.base_accel)
    locked_kernel = staticmethod(fb.base_accel_locked)
    unit_kernel = staticmethod(fb.base_unit_responses)
    compiled_rhs = staticmethod(fb.base_rhs)
    compiled_mechanics = staticmethod(fb.base_mechanics)
    compiled_rhs_locked = staticmethod(fb.base_rhs_locked)
    compiled_events = staticmethod(fb.base_hinge_events)
    momentum_kernel = staticmethod(fb.momentum)

    def __init__(self, scene: Scene, coefficients: str = "printed", kernel: str = "numba"):
        super().__init__(scene, coefficients, kernel)
        self.Nc = 3 * self.n
        self.N = self.Nc + 3
        self.body_setup(scene)
        self.y0 = self.with_body(self.chain_initial_state())
        self.use_kernel()

    def kernel_constants(self) -> np.ndarray:
        return np.vstack([full_constants(self.cc, self.chain), self.body_rows()])


def cross(a: np.ndarray, b: np.ndarray):
    """a x b (z component) of 2-vectors along the last axis."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
