"""The paper's full model: 3n second-order ODEs in q = [phi; alpha; beta] (equations (9)-(10)).

State y = [q; q'] (6n). M(phi) q'' = [Q; 0; 0] - h - C q' - K q, see ``paper_matrices``.
"""
from __future__ import annotations

import numpy as np

from ..scene import Scene
from .paper_matrices import angle_differences, assemble_mass, convective_terms
from .paper_system import PaperModel, PaperSystem


class FullSystem(PaperSystem):
    def __init__(self, scene: Scene, coefficients: str = "printed"):
        super().__init__(scene, coefficients)
        i = self.initial
        self.y0 = np.concatenate([i["phi"], i["alpha"], i["beta"],
                                  i["dphi"], i["dalpha"], i["dbeta"]])

    def rhs(self, t, y):
        n = self.n
        q, v = y[:3 * n], y[3 * n:]
        phi = q[:n]
        ckj, skj = angle_differences(phi)
        h_phi, h_gamma = convective_terms(self.cc, skj, v[:n], v[n:2 * n], v[2 * n:])
        f = -(self.K @ q)
        if self.damped:
            f -= self.C @ v
        f[:n] -= h_phi
        f[n:] -= h_gamma
        Q = self.generalized_force(t, phi)
        if Q is not None:
            f[:n] += Q
        return np.concatenate([v, np.linalg.solve(assemble_mass(self.cc, ckj), f)])

    def generalized_rates(self, y):
        return y[3 * self.n:]

    def rigid(self, Y):
        n = self.n
        return Y[:, :n], Y[:, 3 * n:4 * n]

    def bending(self, times, Y):
        n = self.n
        return Y[:, n:2 * n], Y[:, 2 * n:3 * n], Y[:, 4 * n:5 * n], Y[:, 5 * n:]


class FullModel(PaperModel):
    """Full model (3n ODEs). ``coefficients``: "printed" (default) or "published" (erratum)."""

    name = "full"
    system_class = FullSystem
