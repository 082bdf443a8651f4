"""The full model on a free base: the paper's chain hanging from a rigid body free in the plane
(a spacecraft), docs/base.md. Its equations and kernels: ``rodval.models.free_base``.

State y = [Q; Q'], Q = [phi; alpha; beta; x_c, y_c, theta] (3n + 3). Everything the pinned
full model does runs here too: the compiled O(n) right-hand side, latches (a plastic lock in
the total mass matrix, hinge 0's lock holding rod 1 to the body), stops, the energy audit
(the body's kinetic energy and the loads' power on node 0's motion included) and the
outputs, which add the body's motion (``base``) and the whole system's momenta.
"""

from __future__ import annotations

import numpy as np

from rodval.core.base import rotate
from rodval.core.scene import Scene
from rodval.models import free_base as fb
from rodval.models.kernels import full_constants
from rodval.models.lock_records import plastic_jump
from rodval.models.paper_matrices import hinge_matrix
from rodval.models.paper_system import PaperSystem


class FreeBaseSystem(PaperSystem):
    """The full model (the paper's rung, printed coefficients, compiled kernel) on a free
    base."""

    full = True
    accel_kernel = staticmethod(fb.base_accel)
    compiled_rhs = staticmethod(fb.base_rhs)
    compiled_mechanics = staticmethod(fb.base_mechanics)
    compiled_rhs_locked = staticmethod(fb.base_rhs_locked)
    compiled_events = staticmethod(fb.base_hinge_events)

    def __init__(self, scene: Scene, coefficients: str = "printed", kernel: str = "numba"):
        super().__init__(scene, coefficients, kernel)
        b, i = scene.base, self.initial
        self.N = 3 * self.n + 3
        self.body = b
        assert b.mass is not None and b.inertia is not None  # a free base has both (Base)
        self.body_mass, self.body_inertia = b.mass, b.inertia
        self.y0 = np.concatenate(
            [
                i["phi"],
                i["alpha"],
                i["beta"],
                b.position,
                [b.attitude],
                i["dphi"],
                i["dalpha"],
                i["dbeta"],
                b.velocity,
                [b.rate],
            ]
        )
        self.use_kernel()

    def kernel_constants(self) -> np.ndarray:
        chain, b = self.chain, self.body
        mass = float(np.sum(chain.m * chain.l + chain.mu))
        rows = [self.body_mass, self.body_inertia, b.hinge_offset[0], b.hinge_offset[1], mass]
        V = full_constants(self.cc, chain)
        return np.vstack([V, np.outer(rows, np.ones(self.n))])

    def numpy_rhs(self, t, y):  # the kernel is the compiled one (FreeBaseModel refuses numpy)
        raise NotImplementedError

    def jacobian(self, t: float, y: np.ndarray) -> np.ndarray:
        return self.difference_jacobian(t, y)

    def plastic_jump(self, y, hinges, angles):
        return plastic_jump(self, y, hinges, angles)

    # ------------------------------------------------------------------ coordinates
    def generalized_rates(self, y):
        return y[self.N :]

    def rigid(self, Y):
        n, N = self.n, self.N
        return Y[:, :n], Y[:, N : N + n]

    def bending(self, times, Y):
        n, N = self.n, self.N
        return (
            Y[:, n : 2 * n],
            Y[:, 2 * n : 3 * n],
            Y[:, N + n : N + 2 * n],
            Y[:, N + 2 * n : N + 3 * n],
        )

    def attitude(self, Y):
        return Y[:, 3 * self.n + 2]

    def attitude_rate(self, Y):
        return Y[:, self.N + 3 * self.n + 2]

    def body_states(self, Y) -> tuple[np.ndarray, np.ndarray]:
        """(r_c (m), v_c (m/s)) of the body's centre of mass, each (nt, 2)."""
        n, N = self.n, self.N
        return Y[:, 3 * n : 3 * n + 2], Y[:, N + 3 * n : N + 3 * n + 2]

    def root_states(self, Y) -> tuple[np.ndarray, np.ndarray]:
        """(r_0 (m), v_0 (m/s)) of node 0, each (nt, 2): r_c + rho, v_c + theta' k x rho."""
        rc, vc = self.body_states(Y)
        rho = rotate(self.attitude(Y), np.asarray(self.body.hinge_offset))
        perp = np.stack([-rho[:, 1], rho[:, 0]], axis=-1)
        return rc + rho, vc + self.attitude_rate(Y)[:, None] * perp

    def root_motion(self, y):
        r0, v0 = self.root_states(y[None, :])
        return r0[0], v0[0]

    # ------------------------------------------------------------------ locks
    def hinge_rows(self, hinges) -> np.ndarray:
        """Rows of D = A Q (3n + 3 columns): hinge 0 is measured from the body (-1 at theta)."""
        hinges = np.asarray(hinges, dtype=np.int64)
        A = np.zeros((hinges.size, self.N))
        A[:, : 3 * self.n] = hinge_matrix(self.n)[hinges]
        A[hinges == 0, 3 * self.n + 2] = -1.0
        return A

    def unit_responses(self, q, hinges) -> np.ndarray:
        U = np.empty((len(hinges), self.N))
        fb.base_unit_responses(self.V, q, np.asarray(hinges, np.int64), U)
        return U

    def accel_locked(self, t, y):
        sums = self.loads.suffix_sums(t)
        SX, SY = (self._no_load, self._no_load) if sums is None else sums
        out = np.empty(self.N)
        lam = np.empty(self._lock_h.size)
        fb.base_accel_locked(
            self.V, y, sums is not None, SX, SY, self.damped, self._lock_h, out, lam
        )
        return out, lam

    # ------------------------------------------------------------------ energies, momenta
    def kinetic_energy(self, t, y):
        self.compiled_mechanics(
            0.0, y, self.V, self._flags, np.zeros((0, 0, 0)), np.zeros((0, 6)), self._mech
        )
        return float(self._mech[0])

    def energy_rows(self, times, Y):
        kin = np.array([self.kinetic_energy(t, y) for t, y in zip(times, Y)])
        phi = self.rigid(Y)[0]
        alpha, beta = self.bending(times, Y)[:2]
        return kin, self.potential(phi, alpha, beta, self.attitude(Y))

    def energy_budget(self, t, y):
        kin, pot = self.energy_rows(np.array([t]), y[None, :])
        return float(kin[0] + pot[0])

    def rod_momenta_at(self, y):
        """The pinned chain's rod momenta (``PaperEnergy.rod_momenta_at``) with node 0 moving:
        p += m_k v_0, h (about the origin) += m_k r_0 x v_0 + r_0 x p + first x v_0, first +=
        m_k r_0 (m_k: rod k's mass with its far node's)."""
        p, h, first = super().rod_momenta_at(y)
        r0, v0 = self.root_motion(y)
        mass = self.base_chain.m * self.base_chain.l + self.base_chain.mu
        h = h + mass * _cross(r0, v0) + _cross(r0, p) + _cross(first, v0)
        return p + mass[:, None] * v0, h, first + mass[:, None] * r0

    def momentum_rows(self, Y) -> np.ndarray:
        """The whole system's P (N s, (nt, 2)), ``free_base.momentum`` (kept exactly)."""
        return np.array([fb.momentum(self.V, y) for y in Y])

    def angular_momentum_rows(self, times, Y):
        """[H about node 0, H about the system's centre of mass] (N m s, (nt, 2)), body
        included: H_O = J theta' + m_b r_c x v_c + sum_k h_k (about the origin), H_X = H_O -
        X x P for X = node 0 and the centre of mass (docs/quantities.md)."""
        rc, vc = self.body_states(Y)
        r0 = self.root_states(Y)[0]
        mb = self.body_mass
        out = np.empty((len(Y), 2))
        total = mb + float(np.sum(self.base_chain.m * self.base_chain.l + self.base_chain.mu))
        P = self.momentum_rows(Y)
        for i, y in enumerate(Y):
            _, h, first = self.rod_momenta_at(y)
            HO = self.body_inertia * self.attitude_rate(Y)[i] + mb * _cross(rc[i], vc[i]) + h.sum()
            X = (mb * rc[i] + first.sum(axis=0)) / total
            out[i] = HO - _cross(r0[i], P[i]), HO - _cross(X, P[i])
        return out

    def _observe_rows(self, times, Y):
        out = super()._observe_rows(times, Y)
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


def _cross(a: np.ndarray, b: np.ndarray):
    """a x b (z component) of 2-vectors along the last axis."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
