"""The paper's reduced model ("quasi-static bending", equations (11)-(15)): n ODEs in phi.

Dropping alpha'', beta'', alpha', beta', the bending rows of the full model become algebraic:

    B gamma = -(M_gp phi'' + G_gp phi'^2 + C_gp phi' + K_gp phi),   B = K_gg,  gamma = [alpha; beta]

Substituting gamma into the phi rows (with P = K_pg B^-1, constant):

    (M_pp - P M_gp) phi'' + (G_pp - P G_gp) phi'^2 + (C_pp - P C_gp) phi' + (K_pp - P K_gp) phi = Q

gamma is recovered from the first line only at output times, and only if alpha/beta (or the
energy) are asked for. State y = [phi; phi'] (2n).
"""

from __future__ import annotations

from functools import cached_property
from types import SimpleNamespace
from typing import Any

import numpy as np

from rodval.core.scene import Scene
from rodval.core.validity import DAMPING_FIX, setting
from rodval.models.assembly import kernels
from rodval.models.assembly.paper_matrices import (
    DEFAULT_VARIANT,
    angle_differences,
    angle_jacobian,
    assemble_mass,
    convective_terms,
    hinge_matrix,
    quasi_static_bending,
    rate_damping_matrix,
)
from rodval.models.bending import reduced_banded
from rodval.models.hinge_items import deployment
from rodval.models.systems.paper_model import PaperModel
from rodval.models.systems.paper_system import PaperSystem


class ReducedSystem(PaperSystem):
    full = False
    accel_kernel = staticmethod(reduced_banded.reduced_accel)
    compiled_rhs = staticmethod(reduced_banded.reduced_rhs)
    compiled_mechanics = staticmethod(kernels.reduced_mechanics)
    compiled_rhs_locked = staticmethod(deployment.reduced_rhs_locked)
    compiled_events = staticmethod(deployment.reduced_hinge_events)

    def __init__(self, scene: Scene, coefficients: str = DEFAULT_VARIANT, kernel: str = "numba"):
        super().__init__(scene, coefficients, kernel)
        i = self.initial
        self.y0 = np.concatenate([i["phi"], i["dphi"]])
        self._scratch: np.ndarray | None = None
        self._bending_seen = 0.0
        self._gamma = np.zeros(2 * self.n)
        self._work = np.zeros(reduced_banded.sweep_work_size(self.n))
        self.use_kernel()

    def kernel_constants(self) -> np.ndarray:
        return reduced_banded.banded_constants(self.cc, self.chain)

    def compiled_scratch(self) -> np.ndarray:
        """Work space of ``reduced_banded.reduced_rhs`` (one per system, O(n)); its last slot
        holds the largest |alpha|, |beta| the compiled solves met."""
        if self._scratch is None:
            self._scratch = np.zeros((1, 1, reduced_banded.rhs_work_size(self.n)))
        return self._scratch

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """The compiled O(n) solve gives gamma with phi'': it is kept for the small-bending
        check (``max_bending``) at no extra cost."""
        if self.kernel != "numba" or self.locked:
            return super().rhs(t, y)
        n = self.n
        out = np.empty_like(y)
        out[:n] = y[n:]
        reduced_banded.reduced_solve_work(
            self.V,
            y,
            self.kernel_loads(t, y),
            self.damped,
            (out[n:], self._gamma),
            self._work,
            reduced_banded.METHOD_AUTO,
        )
        self._bending_seen = reduced_banded.track_bending(self._gamma, self._bending_seen)
        return out

    def reset(self) -> None:
        super().reset()
        self._bending_seen = 0.0
        if self._scratch is not None:
            self._scratch[0, 0, -1] = 0.0

    def max_bending(self, times: np.ndarray, Y: np.ndarray) -> float | None:
        """The largest |alpha|, |beta| (rad) the O(n) solves met during the run (every
        evaluation: no recovery at output times); with the numpy kernel, or once a hinge has
        locked, over the output times (recovered in the mode in effect at each)."""
        if self.kernel == "numba" and not self._history:
            compiled = self._scratch[0, 0, -1] if self._scratch is not None else 0.0
            return float(max(self._bending_seen, compiled))
        return super().max_bending(times, Y)

    # The dense reference (kernel="numpy") and the analytic Jacobian: O(n^2) memory, O(n^3)
    # set-up, built only when one of them asks.
    @cached_property
    def _dense(self) -> SimpleNamespace:
        n = self.n
        p, g = slice(0, n), slice(n, 3 * n)
        K, C = self.K, self.C
        B_inv = np.linalg.inv(K[g, g])
        P = K[p, g] @ B_inv  # K_pg B^-1, (n, 2n)
        return SimpleNamespace(
            B_inv=B_inv,
            P_a=P[:, :n],
            P_b=P[:, n:],
            P_diff=P[:, :n] - P[:, n:],
            K_r=K[p, p] - P @ K[g, p],
            C_r=C[p, p] - P @ C[g, p],
            K_gp=K[g, p],
            C_gp=C[g, p],
            rest_r=self.rest[p] - P @ self.rest[g],
            rest_g=self.rest[g],
        )

    @property
    def K_r(self) -> np.ndarray:
        """Reduced stiffness K_pp - K_pg B^-1 K_gp (N m/rad, n x n, dense)."""
        K_r: np.ndarray = self._dense.K_r
        return K_r

    @property
    def C_r(self) -> np.ndarray:
        """Reduced damping C_pp - K_pg B^-1 C_gp (N m s/rad, n x n, dense)."""
        C_r: np.ndarray = self._dense.C_r
        return C_r

    def reduced_matrices(
        self, phi: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """M_r(phi), G_r(phi) and the bending-row blocks M_gp, G_gp (for recovery)."""
        cc, d = self.cc, self._dense
        ckj, skj = angle_differences(phi)
        U, G_pa = cc.w_upper * ckj, cc.w_upper * skj
        M_pp = cc.pp_scale * ckj
        np.fill_diagonal(M_pp, cc.pp_diag)
        # M_ap = U^T + diag(ap), M_bp = -U^T + diag(bp); G_ap = -G_pa^T, G_bp = G_pa^T
        M_r = M_pp - d.P_diff @ U.T - d.P_a * cc.ap_diag - d.P_b * cc.bp_diag
        G_r = cc.pp_scale * skj + d.P_diff @ G_pa.T
        return M_r, G_r, U, G_pa

    def reduce(self, F: np.ndarray) -> np.ndarray:
        """F_p - K_pg B^-1 F_g: generalized forces F (3n, ...) on q = [phi; alpha; beta] as
        the reduced model's phi rows take them (the bending rows eliminated)."""
        n, d = self.n, self._dense
        reduced: np.ndarray = F[:n] - d.P_a @ F[n : 2 * n] - d.P_b @ F[2 * n :]
        return reduced

    def forces(self, t: float, phi: np.ndarray, dphi: np.ndarray, G_r: np.ndarray) -> np.ndarray:
        """f_r = Q + reduce(A^T Tq) - G_r phi'^2 - C_r phi' - K_r phi + rest_r of M_r phi'' =
        f_r (n), Tq the motors' and rate dampers' hinge moments (``torque_forces``)."""
        d = self._dense
        f: np.ndarray = d.rest_r - d.K_r @ phi - G_r @ (dphi * dphi)
        if self.damped:
            f -= d.C_r @ dphi
        Q = self.generalized_force(t, phi)
        if Q is not None:
            f += Q
        tau = self.torque_forces(t, np.concatenate([phi, dphi]))
        if tau is not None:
            f += self.reduce(tau)
        return f

    def numpy_rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        n = self.n
        phi, dphi = y[:n], y[n:]
        M_r, G_r, _, _ = self.reduced_matrices(phi)
        return np.concatenate([dphi, np.linalg.solve(M_r, self.forces(t, phi, dphi, G_r))])

    def jacobian(self, t: float, y: np.ndarray) -> np.ndarray:
        """Analytic Jacobian df/dy (2n, 2n): [[0, I], [M_r^-1 (df_r/dphi - dM_r/dphi phi''),
        M_r^-1 df_r/dphi']]."""
        if self.locked:
            return self.difference_jacobian(t, y)
        n, cc, d = self.n, self.cc, self._dense
        phi, dphi = y[:n], y[n:]
        ckj, skj = angle_differences(phi)
        M_r, G_r, _, G_pa = self.reduced_matrices(phi)
        a = np.linalg.solve(M_r, self.forces(t, phi, dphi, G_r))
        Wt, w2 = cc.w_upper.T, dphi * dphi
        # M_r a = M_pp a - P_diff (W^T o c_jk) a - const;  G_pa^T w2 = -(W^T o s_jk) w2
        dM_a = angle_jacobian(cc.pp_scale, -skj, a) - d.P_diff @ angle_jacobian(Wt, -skj, a)
        dG_w2 = angle_jacobian(cc.pp_scale, ckj, w2) - d.P_diff @ angle_jacobian(Wt, ckj, w2)
        dfdphi = -d.K_r - dG_w2 - dM_a
        sums = self.loads.suffix_sums(t)
        if sums is not None:
            SX, SY = sums
            dfdphi[np.arange(n), np.arange(n)] -= self.l * (np.sin(phi) * SY + np.cos(phi) * SX)
        dfdv = -2.0 * G_r * dphi - (d.C_r if self.damped else 0.0)
        rate_damping = rate_damping_matrix(self.loads.torques, t, n)
        if rate_damping is not None:  # the torque items' rate coefficients, on the chord rates
            dfdv = dfdv - self.reduce(rate_damping[:, :n])
        J = np.zeros((2 * n, 2 * n))
        J[:n, n:] = np.eye(n)
        J[n:] = np.linalg.solve(M_r, np.hstack([dfdphi, dfdv]))
        return J

    def recover_bending(self, t: float, y: np.ndarray) -> np.ndarray:
        """gamma = [alpha; beta] (rad) at one time from the algebraic bending rows: the O(n)
        solve with the compiled kernel, the dense elimination with the numpy one."""
        n = self.n
        phi, dphi = y[:n], y[n:]
        if self.locked:
            return self.solve_locked(t, y)[1]
        if self.kernel == "numba":
            loads = self.kernel_loads(t, y)
            return reduced_banded.bending_at(self.V, phi, dphi, loads, self.damped)[1]
        cc, d = self.cc, self._dense
        M_r, G_r, U, G_pa = self.reduced_matrices(phi)  # once: phi'' and gamma share them
        ddphi = np.linalg.solve(M_r, self.forces(t, phi, dphi, G_r))
        w2 = dphi * dphi
        Ut_dd = U.T @ ddphi
        GT_w2 = G_pa.T @ w2
        r = np.concatenate(
            [Ut_dd + cc.ap_diag * ddphi - GT_w2, -Ut_dd + cc.bp_diag * ddphi + GT_w2]
        )
        r += d.K_gp @ phi - d.rest_g
        if self.damped:
            r += d.C_gp @ dphi
        tau = self.torque_forces(t, y)
        if tau is not None:
            r -= tau[n:]
        gamma: np.ndarray = -d.B_inv @ r
        return gamma

    def solve_locked(self, t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """phi'' (n), gamma (2n) and the multipliers (m) with the locked hinges held at their
        angles, D_k = a_p^T phi + a_g^T gamma = angle_k an equation of the solve (the
        kappa_k -> infinity limit of the reduced model). numpy: the dense unreduced system
        [M_pp K_pg -A_p^T; M_gp B -A_g^T; 0 A_g 0] [phi''; gamma; lambda] = [r_p; r_g;
        angle - A_p phi]; numba: superposition of m + 1 O(n) sweeps."""
        n, h = self.n, self._lock_h
        phi, dphi = y[:n], y[n:]
        m = h.size
        if self.kernel == "numba":
            x, gamma, lam = np.empty(n), np.empty(2 * n), np.empty(m)
            loads = self.kernel_loads(t, y)
            held = (h, self._lock_a)
            ok = deployment.reduced_solve_locked(
                self.V, y, loads, self.damped, held, (x, gamma), lam
            )
            if not ok:
                raise FloatingPointError("singular constrained reduced solve")
            return x, gamma, lam
        ckj, skj = angle_differences(phi)
        h_phi, h_gamma = convective_terms(self.cc, skj, dphi)
        r = self.rest - self.K[:, :n] @ phi - np.concatenate([h_phi, h_gamma])
        if self.damped:
            r -= self.C[:, :n] @ dphi
        Q = self.generalized_force(t, phi)
        if Q is not None:
            r[:n] += Q
        tau = self.torque_forces(t, y)
        if tau is not None:
            r += tau
        A = hinge_matrix(n)[h]
        Kz = np.zeros((3 * n + m, 3 * n + m))
        Kz[: 3 * n, :n] = assemble_mass(self.cc, ckj)[:, :n]
        Kz[: 3 * n, n : 3 * n] = self.K[:, n:]
        Kz[: 3 * n, 3 * n :] = -A.T
        Kz[3 * n :, n : 3 * n] = A[:, n:]
        rhs = np.concatenate([r, self._lock_a - A[:, :n] @ phi])
        z = np.linalg.solve(Kz, rhs)
        return z[:n], z[n : 3 * n], z[3 * n :]

    def accel_locked(self, t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x, _, lam = self.solve_locked(t, y)
        return x, lam

    def plastic_jump(
        self, y: np.ndarray, hinges: Any, angles: Any
    ) -> tuple[np.ndarray, np.ndarray]:
        """Delta phi' = M_pp^-1 C^T mu, (C M_pp^-1 C^T) mu = -C phi', with C the rows
        c_k = dD_k/dphi of the static hinge angles (deployment.reduced_hinge_gradient) and
        M_pp the reduced model's kinetic metric (T = 1/2 phi'^T M_pp phi'): the velocity
        closest to the old one in that metric with the locking hinges' static rates zero.
        No position change: the constrained solve holds D_k exactly."""
        n = self.n
        y = y.copy()
        phi, dphi = y[:n], y[n:]
        C = np.array([deployment.reduced_hinge_gradient(self.chain, int(k)) for k in hinges])
        if self.kernel == "numba":
            W = np.empty((len(hinges), n))
            for j in range(len(hinges)):
                deployment.mpp_solve(self.V, phi, np.ascontiguousarray(C[j]), W[j])
        else:
            M_pp = assemble_mass(self.cc_kinetic, angle_differences(phi)[0])[:n, :n]
            W = np.linalg.solve(M_pp, C.T).T
        mu = np.linalg.solve(C @ W.T, -(C @ dphi))
        dphi += W.T @ mu
        return y, mu

    def generalized_rates(self, y: np.ndarray) -> np.ndarray:
        """[phi'; 0; 0]: the reduced model drops the bending rates from its kinetic energy and
        from its phi rows, so its dampers dissipate phi'^T C_pp phi' (see docs/stability.md)."""
        n = self.n
        return np.concatenate([y[n:], np.zeros(2 * n)])

    def energy_budget(self, t: float, y: np.ndarray) -> float:
        """T + Pi at the quasi-static bending gamma = B^-1 (A_g^T kappa rest - K_gp phi)
        (exact when phi'' = phi' = 0); O(n)."""
        n = self.n
        gamma = quasi_static_bending(self.chain, y[:n])
        return self.kinetic_energy(t, y) + float(self.potential(y[:n], gamma[:n], gamma[n:]))

    def rigid(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = self.n
        return Y[:, :n], Y[:, n:]

    def bending(self, times: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, ...]:
        n = self.n
        gamma = np.array([self.recover_bending(t, y) for t, y in zip(times, Y)]).reshape(-1, 2 * n)
        zeros = np.zeros_like(gamma[:, :n])
        # alpha', beta' are dropped by the reduced model: they carry no kinetic energy in it.
        return gamma[:, :n], gamma[:, n:], zeros, zeros


#: The initial-state entries of the bending coordinates (the full model's alone).
BENDING_STATE = ("alpha", "beta", "dalpha", "dbeta")


class ReducedModel(PaperModel):
    """Reduced model (n ODEs). ``coefficients``: "printed" (default) or "published"."""

    name = "reduced"
    system_class = ReducedSystem
    MODAL_ANALYSIS = "rodval.models.observation.linear_modes:reduced_modes"

    def energy_fix(self) -> str:
        """The quasi-static bending has no energy balance of its own (docs/stability.md)."""
        return (
            f"the full model with {setting('kinematics', 'exact')} (the reduced model's "
            "quasi-static bending keeps no energy balance; docs/stability.md)"
        )

    def stiffness_fix(self, scene: Scene) -> str:
        """The reduced model's stiff vibration is a held hinge's locked pair ringing against
        the quasi-static bending (undamped: the bending damping has nothing to act on)."""
        return (
            f"the full model with damped bending ({DAMPING_FIX}: a "
            "held hinge's pair rings against the quasi-static bending here, undamped), or a "
            "looser rtol and atol"
        )

    def scene_notes(self, scene: Scene) -> list[str]:
        """The scene data the quasi-static bending has nowhere to put: the rods' bending
        damping (it acts on bending rates, which the model drops with the bending inertia and
        the hinge dampers' bending-rate part, docs/model.md) and initial bending angles or
        rates (the bending follows phi)."""
        notes = []
        c = scene.chain.bending_damping
        if np.any(c > 0):
            notes.append(
                f"bending_damping (up to {float(c.max()):g} N m^2 s) has no effect in the reduced "
                "model: its bending is quasi-static, without bending rates to damp"
            )
        given = [k for k in BENDING_STATE if getattr(scene.initial, k) is not None]
        if any(np.any(np.asarray(getattr(scene.initial, k)) != 0) for k in given):
            notes.append(
                "initial alpha, beta, dalpha, dbeta are not used by the reduced model: its "
                "bending is quasi-static, set by phi"
            )
        return notes
