"""The paper's reduced model ("quasi-static bending", equations (11)-(15)): n ODEs in phi.

Dropping alpha'', beta'', alpha', beta', the bending rows of the full model become algebraic:

    B gamma = -(M_gp phi'' + G_gp phi'^2 + C_gp phi' + K_gp phi),   B = K_gg,  gamma = [alpha; beta]

Substituting gamma into the phi rows (with P = K_pg B^-1, constant):

    (M_pp - P M_gp) phi'' + (G_pp - P G_gp) phi'^2 + (C_pp - P C_gp) phi' + (K_pp - P K_gp) phi = Q

gamma is recovered from the first line only at output times, and only if alpha/beta (or the
energy) are asked for. State y = [phi; phi'] (2n).
"""
from __future__ import annotations

import numpy as np

from ..scene import Scene
from .paper_matrices import angle_differences
from .paper_system import PaperModel, PaperSystem


class ReducedSystem(PaperSystem):
    def __init__(self, scene: Scene, coefficients: str = "printed"):
        super().__init__(scene, coefficients)
        n = self.n
        p, g = slice(0, n), slice(n, 3 * n)
        K, C = self.K, self.C
        self.B = K[g, g]
        self.B_inv = np.linalg.inv(self.B)
        P = K[p, g] @ self.B_inv                      # K_pg B^-1, (n, 2n)
        self.P_diff = P[:, :n] - P[:, n:]             # P_a - P_b
        self.P_a, self.P_b = P[:, :n], P[:, n:]
        self.K_r = K[p, p] - P @ K[g, p]
        self.C_r = C[p, p] - P @ C[g, p]
        self.K_gp, self.C_gp = K[g, p], C[g, p]
        i = self.initial
        self.y0 = np.concatenate([i["phi"], i["dphi"]])

    def reduced_matrices(self, phi: np.ndarray):
        """M_r(phi), G_r(phi) and the bending-row blocks M_gp, G_gp (for recovery)."""
        cc = self.cc
        ckj, skj = angle_differences(phi)
        U, G_pa = cc.w_upper * ckj, cc.w_upper * skj
        M_pp = cc.pp_scale * ckj
        np.fill_diagonal(M_pp, cc.pp_diag)
        # M_ap = U^T + diag(ap), M_bp = -U^T + diag(bp); G_ap = -G_pa^T, G_bp = G_pa^T
        M_r = M_pp - self.P_diff @ U.T - self.P_a * cc.ap_diag - self.P_b * cc.bp_diag
        G_r = cc.pp_scale * skj + self.P_diff @ G_pa.T
        return M_r, G_r, U, G_pa

    def rhs(self, t, y):
        n = self.n
        phi, dphi = y[:n], y[n:]
        M_r, G_r, _, _ = self.reduced_matrices(phi)
        f = -(self.K_r @ phi) - G_r @ (dphi * dphi)
        if self.damped:
            f -= self.C_r @ dphi
        Q = self.generalized_force(t, phi)
        if Q is not None:
            f += Q
        return np.concatenate([dphi, np.linalg.solve(M_r, f)])

    def recover_bending(self, t: float, y: np.ndarray) -> np.ndarray:
        """gamma = [alpha; beta] (rad) at one time from the algebraic bending rows."""
        n, cc = self.n, self.cc
        phi, dphi = y[:n], y[n:]
        ddphi = self.rhs(t, y)[n:]
        _, _, U, G_pa = self.reduced_matrices(phi)
        w2 = dphi * dphi
        Ut_dd = U.T @ ddphi
        GT_w2 = G_pa.T @ w2
        r = np.concatenate([Ut_dd + cc.ap_diag * ddphi - GT_w2,
                            -Ut_dd + cc.bp_diag * ddphi + GT_w2])
        r += self.K_gp @ phi
        if self.damped:
            r += self.C_gp @ dphi
        return -self.B_inv @ r

    def generalized_rates(self, y):
        """[phi'; 0; 0]: the reduced model drops the bending rates from its kinetic energy and
        from its phi rows, so its dampers dissipate phi'^T C_pp phi' (see docs/stability.md)."""
        n = self.n
        return np.concatenate([y[n:], np.zeros(2 * n)])

    def rigid(self, Y):
        n = self.n
        return Y[:, :n], Y[:, n:]

    def bending(self, times, Y):
        n = self.n
        gamma = np.array([self.recover_bending(t, y) for t, y in zip(times, Y)]).reshape(-1, 2 * n)
        zeros = np.zeros_like(gamma[:, :n])
        # alpha', beta' are dropped by the reduced model: they carry no kinetic energy in it.
        return gamma[:, :n], gamma[:, n:], zeros, zeros


class ReducedModel(PaperModel):
    """Reduced model (n ODEs). ``coefficients``: "printed" (default) or "published"."""

    name = "reduced"
    system_class = ReducedSystem
