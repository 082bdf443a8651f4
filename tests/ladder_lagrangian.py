"""An independent Lagrangian of the model ladder's exact kinematics, by automatic
differentiation (hyper-dual numbers, exact second derivatives to round-off).

Nothing here uses rodval.models: the rod's points are r = r_{k-1} + s e_k + eta n_k with the
shapes of docs/model.md (sigma, tau and the bubbles (l / 4) B_i(2 s / l - 1), B_i the second
integral of the Legendre polynomial P_i from -1, built here with numpy's Legendre class);
their velocities are the chain rule of that position; T = 1/2 sum int m |r_t|^2 ds + 1/2 sum
mu |node_t|^2 and the bending energy 1/2 int EI eta''^2 ds by Gauss quadrature; the hinge
angles D_k = phi_k + alpha_k - phi_{k-1} - beta_{k-1}. Lagrange's equations give

    M q'' = Q - dV/dq - dR/dq' - [(d^2 T / dq' dq) q' - dT/dq],   M = d^2 T / dq'^2,

every derivative from one hyper-dual evaluation (x + e1 a + e2 b, e1^2 = e2^2 = 0).
"""

from __future__ import annotations

import numpy as np
from numpy.polynomial import Legendre

GAUSS_X, GAUSS_W = np.polynomial.legendre.leggauss(16)  # exact to degree 31


class HD:
    """a + b e1 + c e2 + d e1 e2 (numpy arrays)."""

    __array_ufunc__ = None  # numpy arrays defer to HD's operators

    def __init__(self, a, b=0.0, c=0.0, d=0.0):
        self.a, self.b, self.c, self.d = (np.asarray(x, float) for x in (a, b, c, d))

    @staticmethod
    def of(x):
        return x if isinstance(x, HD) else HD(x)

    def __add__(self, o):
        o = HD.of(o)
        return HD(self.a + o.a, self.b + o.b, self.c + o.c, self.d + o.d)

    __radd__ = __add__

    def __neg__(self):
        return HD(-self.a, -self.b, -self.c, -self.d)

    def __sub__(self, o):
        return self + (-HD.of(o))

    def __rsub__(self, o):
        return HD.of(o) - self

    def __mul__(self, o):
        o = HD.of(o)
        return HD(
            self.a * o.a,
            self.a * o.b + self.b * o.a,
            self.a * o.c + self.c * o.a,
            self.a * o.d + self.b * o.c + self.c * o.b + self.d * o.a,
        )

    __rmul__ = __mul__

    def __getitem__(self, i):
        return HD(*(np.broadcast_to(x, self.a.shape)[i] for x in (self.a, self.b, self.c, self.d)))

    def sum(self, axis=None):
        return HD(
            *(
                np.sum(np.broadcast_to(x, self.a.shape), axis=axis)
                for x in (self.a, self.b, self.c, self.d)
            )
        )

    def cumsum(self):
        return HD(
            *(np.cumsum(np.broadcast_to(x, self.a.shape)) for x in (self.a, self.b, self.c, self.d))
        )


def cos(x: HD) -> HD:
    c, s = np.cos(x.a), np.sin(x.a)
    return HD(c, -s * x.b, -s * x.c, -c * x.b * x.c - s * x.d)


def sin(x: HD) -> HD:
    c, s = np.cos(x.a), np.sin(x.a)
    return HD(s, c * x.b, c * x.c, -s * x.b * x.c + c * x.d)


def shape_values(p: int, l: float, s: np.ndarray):
    """psi_i(s), psi_i''(s) (i = 0..p) of a rod of length l at stations s."""
    xi = s / l
    psi = [xi * (1 - xi) ** 2 * l, -(xi**2) * (1 - xi) * l]
    d2 = [(6 * xi - 4) / l, (6 * xi - 2) / l]  # sigma'', tau''
    for i in range(2, p + 1):
        B = Legendre.basis(i).integ(2, lbnd=-1)
        psi.append(l / 4 * B(2 * xi - 1))
        d2.append(Legendre.basis(i)(2 * xi - 1) / l)
    return np.array(psi), np.array(d2)


class Chain:
    """A chain's data (arrays over rods) and its rung p."""

    def __init__(self, p, l, m, mu, EI, kappa, nu, rest, cb):
        self.p, self.l, self.m, self.mu = p, l, m, mu
        self.EI, self.kappa, self.nu, self.rest, self.cb = EI, kappa, nu, rest, cb
        self.n = l.size
        self.s = [0.5 * lk * (GAUSS_X + 1) for lk in l]
        self.w = [0.5 * lk * GAUSS_W for lk in l]
        self.tab = [shape_values(p, lk, sk) for lk, sk in zip(l, self.s)]

    def split(self, q):
        n, P1 = self.n, self.p + 1
        return q[:n], [q[n * (1 + i) : n * (2 + i)] for i in range(P1)]

    def kinetic(self, q, v) -> HD:
        n = self.n
        phi, g = self.split(q)
        dphi, dg = self.split(v)
        c, s = cos(phi), sin(phi)
        T = HD(0.0)
        rx, ry = HD(0.0), HD(0.0)  # node k-1's velocity
        for k in range(n):
            psi = self.tab[k][0]
            eta = sum((g[i][k] * psi[i] for i in range(self.p + 1)), HD(0.0))
            deta = sum((dg[i][k] * psi[i] for i in range(self.p + 1)), HD(0.0))
            sk, ck, sn = self.s[k], c[k], s[k]
            # r = R + s e + eta nrm, e = (c, s), nrm = (-s, c):
            # r_t = R_t + (s phi' + eta') nrm - eta phi' e
            along = sk * dphi[k] + deta
            vx = rx + along * (-1.0 * sn) - eta * dphi[k] * ck
            vy = ry + along * ck - eta * dphi[k] * sn
            T = T + 0.5 * self.m[k] * (HD(self.w[k]) * (vx * vx + vy * vy)).sum()
            rx = rx + self.l[k] * dphi[k] * (-1.0 * sn)
            ry = ry + self.l[k] * dphi[k] * ck
            T = T + 0.5 * self.mu[k] * (rx * rx + ry * ry)
        return T

    def hinge_angles(self, q):
        phi, g = self.split(q)
        D = []
        for k in range(self.n):
            Dk = phi[k] + g[0][k]
            if k > 0:
                Dk = Dk - phi[k - 1] - g[1][k - 1]
            D.append(Dk)
        return D

    def curvature_energy(self, q, coeff) -> HD:
        _, g = self.split(q)
        E = HD(0.0)
        for k in range(self.n):
            d2 = self.tab[k][1]
            curv = sum((g[i][k] * d2[i] for i in range(self.p + 1)), HD(0.0))
            E = E + 0.5 * coeff[k] * (HD(self.w[k]) * curv * curv).sum()
        return E

    def potential(self, q) -> HD:
        D = self.hinge_angles(q)
        E = sum(
            (
                0.5 * self.kappa[k] * (D[k] - self.rest[k]) * (D[k] - self.rest[k])
                for k in range(self.n)
            ),
            HD(0.0),
        )
        return E + self.curvature_energy(q, self.EI)

    def rayleigh(self, v) -> HD:
        D = self.hinge_angles(v)
        R = sum((0.5 * self.nu[k] * D[k] * D[k] for k in range(self.n)), HD(0.0))
        return R + self.curvature_energy(v, self.cb)

    def nodes(self, q):
        phi, _ = self.split(q)
        return (self.l * cos(phi)).cumsum(), (self.l * sin(phi)).cumsum()


def _unit(N, i):
    e = np.zeros(N)
    e[i] = 1.0
    return e


def equations(ch: Chain, q, v, X, Y):
    """(M, f): M q'' = f of the exact Lagrangian at (q, v) with nodal forces X, Y (N, nodes
    1..n)."""
    N = q.size
    M = np.empty((N, N))
    for i in range(N):
        for j in range(i, N):
            M[i, j] = M[j, i] = ch.kinetic(HD(q), HD(v, _unit(N, i), _unit(N, j))).d
    f = np.empty(N)
    for i in range(N):
        ei = _unit(N, i)
        mixed = ch.kinetic(HD(q, 0.0, v), HD(v, ei)).d  # (d^2 T / dq'_i dq) q'
        dTdq = ch.kinetic(HD(q, ei), HD(v)).b
        dVdq = ch.potential(HD(q, ei)).b
        dRdv = ch.rayleigh(HD(v, ei)).b
        x, y = ch.nodes(HD(q, ei))
        Q = float(np.sum(X * x.b + Y * y.b))
        f[i] = Q - dVdq - dRdv - (mixed - dTdq)
    return M, f


def kinetic_energy(ch: Chain, q, v) -> float:
    return float(ch.kinetic(HD(q), HD(v)).a)
