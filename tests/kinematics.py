"""Independent kinematics of the assumed-mode chain, for checking the analytic blocks.

Nothing here uses rodval.models: positions are computed from the definitions in model.md,
velocities by central differences of positions, energies by Gauss-Legendre quadrature over s.
"""

from __future__ import annotations

import numpy as np

GAUSS_S, GAUSS_W = np.polynomial.legendre.leggauss(8)  # exact for degree <= 15


def shape(s, l):
    """sigma(s), tau(s): eta = alpha sigma + beta tau, eta'(0) = alpha, eta'(l) = beta."""
    return s * (l - s) ** 2 / l**2, -(s**2) * (l - s) / l**2


def points(q: np.ndarray, l: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Quadrature points of every rod (n, 8, 2), their weights (n, 8), and nodes (n, 2)."""
    n = l.size
    phi, alpha, beta = q[:n], q[n : 2 * n], q[2 * n :]
    e = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    nrm = np.stack([-np.sin(phi), np.cos(phi)], axis=1)
    nodes = np.cumsum(l[:, None] * e, axis=0)
    roots = np.vstack([[0.0, 0.0], nodes[:-1]])
    s = 0.5 * l[:, None] * (GAUSS_S[None, :] + 1.0)
    w = 0.5 * l[:, None] * GAUSS_W[None, :]
    sig, tau = shape(s, l[:, None])
    eta = alpha[:, None] * sig + beta[:, None] * tau
    r = roots[:, None, :] + s[..., None] * e[:, None, :] + eta[..., None] * nrm[:, None, :]
    return r, w, nodes


def jacobians(q, l, h=1e-30):
    """d(points)/dq and d(nodes)/dq by the complex-step derivative (exact to round-off):
    (n, 8, 2, 3n), (n, 2, 3n)."""
    cols_r, cols_n = [], []
    for i in range(q.size):
        dq = np.zeros(q.size, dtype=complex)
        dq[i] = 1j * h
        r, _, nodes = points(q + dq, l)
        cols_r.append(r.imag / h)
        cols_n.append(nodes.imag / h)
    return np.stack(cols_r, axis=-1), np.stack(cols_n, axis=-1)


def mass_matrix(q, l, m, mu):
    """M(q) with T = 1/2 q'^T M q' = 1/2 sum int m |r_t|^2 ds + 1/2 sum mu |node_t|^2."""
    Jr, Jn = jacobians(q, l)
    _, w, _ = points(np.real(q), l)
    M = np.einsum("ks,ksdi,ksdj->ij", m[:, None] * w, Jr, Jr)
    M += np.einsum("k,kdi,kdj->ij", mu, Jn, Jn)
    return M


def convective(q, v, l, m, mu, h=1e-4):
    """Lagrange's velocity terms sum_l (dM/dq_l v_l) v - 1/2 d/dq (v^T M v) of the exact T."""
    N = q.size
    dM = []
    for i in range(N):
        dq = np.zeros(N)
        dq[i] = h
        dM.append((mass_matrix(q + dq, l, m, mu) - mass_matrix(q - dq, l, m, mu)) / (2 * h))
    dM = np.array(dM)  # dM[l] = dM/dq_l
    term1 = np.einsum("lij,l,j->i", dM, v, v)
    term2 = 0.5 * np.einsum("ijk,j,k->i", dM, v, v)
    return term1 - term2


def node_positions(q, l):
    return points(q, l)[2]


def rod_point(q, l, k, s):
    """Position of the point at arc parameter s (may be slightly outside [0, l]) of rod k."""
    n = l.size
    phi, alpha, beta = q[:n], q[n : 2 * n], q[2 * n :]
    root = np.array([np.sum(l[:k] * np.cos(phi[:k])), np.sum(l[:k] * np.sin(phi[:k]))])
    sig, tau = shape(s, l[k])
    eta = alpha[k] * sig + beta[k] * tau
    e = np.array([np.cos(phi[k]), np.sin(phi[k])])
    return root + s * e + eta * np.array([-e[1], e[0]])


def tangent_angle(q, l, k, s, h=1e-5):
    """Angle of the centre line's tangent from the x axis, by central differences in s."""
    d = (rod_point(q, l, k, s + h) - rod_point(q, l, k, s - h)) / (2 * h)
    return np.arctan2(d[1], d[0])


def potential(q, l, EI, kappa):
    """Pi from its definition: hinge springs on the jump of the tangent angle between rods
    (hinge 0: from the x axis), bending energy int EI kappa_c^2 / 2 ds with the curvature
    eta'' from second differences of the deflection (exact for the cubic shapes)."""
    n = l.size
    left = np.array([tangent_angle(q, l, k, 0.0) for k in range(n)])
    right = np.array([tangent_angle(q, l, k, l[k]) for k in range(n)])
    D = left - np.concatenate([[0.0], right[:-1]])
    energy = 0.5 * np.sum(kappa * D**2)
    alpha, beta = q[n : 2 * n], q[2 * n :]
    for k in range(n):
        s = 0.5 * l[k] * (GAUSS_S + 1.0)
        w = 0.5 * l[k] * GAUSS_W
        hs = 1e-3 * l[k]
        eta = lambda x, k=k: np.dot([alpha[k], beta[k]], shape(x, l[k]))  # noqa: E731
        curv = (eta(s + hs) - 2 * eta(s) + eta(s - hs)) / hs**2
        energy += 0.5 * EI[k] * np.sum(w * curv**2)
    return energy


def hessian(f, x, h=1e-4):
    """Hessian of a scalar function by central differences."""
    N = x.size
    H = np.zeros((N, N))
    E = np.eye(N) * h
    for i in range(N):
        for j in range(i, N):
            H[i, j] = H[j, i] = (
                f(x + E[i] + E[j]) - f(x + E[i] - E[j]) - f(x - E[i] + E[j]) + f(x - E[i] - E[j])
            ) / (4 * h * h)
    return H


def momenta(q, v, l, m, mu):
    """(H_0, H_c): angular momentum about the root (the origin) and about the centre of mass
    (kg m^2/s) of the models' first-order velocity field: points and velocities of the chord
    configuration q_0 = [phi; 0; 0], r_t = (dr/dq)(q_0) q' (chord velocity plus the bending
    rate eta' n), by quadrature; H_c = sum int (r - c) x (r_t - c_t) dm with c, c_t the mass
    averages of r and r_t."""
    n = l.size
    q0 = np.concatenate([np.asarray(q, float)[:n], np.zeros(2 * n)])
    Jr, Jn = jacobians(q0, l)
    r, w, nodes = points(q0, l)
    rt, nt = Jr @ v, Jn @ v  # (n, 8, 2), (n, 2)
    pts = np.concatenate([r.reshape(-1, 2), nodes])
    vel = np.concatenate([rt.reshape(-1, 2), nt])
    dm = np.concatenate([(m[:, None] * w).ravel(), mu])
    c, ct = dm @ pts / dm.sum(), dm @ vel / dm.sum()

    def moment(p, u):
        return float(np.sum(dm * (p[:, 0] * u[:, 1] - p[:, 1] * u[:, 0])))

    return moment(pts, vel), moment(pts - c, vel - ct)
