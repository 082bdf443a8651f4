"""The lock window: the declared stretch of time after a latch locks over which every model
measures the lock's impulse (docs/deployment.md, "The lock impulse").

A latch joins two elastic rods; at the lock the relative rate of the rods' end tangents drops
to zero, but the rods' chords keep turning against each other and the latch's reaction rings
at the locked structure's bending frequencies. The cumulative impulse of the reaction,
S(tau) = mu + int_0^tau lambda ds (mu: the instantaneous part, lambda: the constraint moment
on the outboard rod, N m), therefore oscillates: for one mode of frequency omega without
damping, S(tau) = S_pl (1 - cos omega tau) with S_pl the plastic (rigid-panel) impulse, so
the plain integral over one period is 0 and over half a period 2 S_pl. Its mean over the
window has the limit: the reported lock impulse is

    S_w = (1/w) int_0^w S(tau) dtau = mu + int_0^w lambda(s) (1 - s/w) ds,

the integral of the reaction over the window with the weight falling linearly from 1 at the
lock to 0 at its end. Over one period of the first bending mode it removes that mode's ring
exactly (undamped) or to O(zeta^2) (damped), and it equals S_pl for rigid rods up to the
smooth reaction's lambda w / 2.

The window w (s) is the latch's ``window`` when the scene sets one; by default the period of
the first bending mode of the **locked pair**: the two rods the hinge joins (rods k and k+1
for hinge k), clamped together into one Euler-Bernoulli beam with their node masses, pinned at
the inboard end (hinge 0: rod 1 clamped at the root). ``ELEMENTS_PER_ROD`` cubic Hermite
elements per rod give its period to 3e-6 relative (the element's error falls as h^4; from
above in frequency), far below what the window's length needs. One period is the smallest window over
which the first ring averages out; a chain whose longer locked parts ring lower than the pair
should set ``window`` (docs/deployment.md).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from rodval.core.scene import Chain, Latch

#: Cubic Hermite Euler-Bernoulli elements per rod of the locked pair's beam.
ELEMENTS_PER_ROD = 8
#: The window's quadrature: Gauss-Legendre on equal panels (degree 2 * NODES - 1 per panel).
WINDOW_PANELS = 64
WINDOW_NODES = 4
_GL_X, _GL_W = np.polynomial.legendre.leggauss(WINDOW_NODES)


def _element(EI: float, rho: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass of one Hermite element of length h (m), EI (N m^2), mass
    per length rho (kg/m); dofs (w_a, theta_a, w_b, theta_b) (m, rad)."""
    k = (EI / h**3) * np.array(
        [
            [12, 6 * h, -12, 6 * h],
            [6 * h, 4 * h * h, -6 * h, 2 * h * h],
            [-12, -6 * h, 12, -6 * h],
            [6 * h, 2 * h * h, -6 * h, 4 * h * h],
        ]
    )
    m = (rho * h / 420.0) * np.array(
        [
            [156, 22 * h, 54, -13 * h],
            [22 * h, 4 * h * h, 13 * h, -3 * h * h],
            [54, 13 * h, 156, -22 * h],
            [-13 * h, -3 * h * h, -22 * h, 4 * h * h],
        ]
    )
    return k, m


def first_bending_period(chain: Chain, hinge: int) -> float:
    """Period (s) of the first bending mode of the locked pair at ``hinge`` (see the module
    docstring): rods hinge, hinge+1 (1-based; rod 1 alone for hinge 0) as one Euler-Bernoulli
    beam, EI and mass per length m of each rod, the node masses mu at the rods' far ends,
    pinned (hinge 0: clamped) at the inboard end. O(1): a 2 * 8-element beam, one dense
    generalized eigenproblem of at most 34 x 34."""
    if not 0 <= hinge < chain.n:
        raise ValueError(f"hinge must be 0..{chain.n - 1}, got {hinge!r}")
    rods = [0] if hinge == 0 else [hinge - 1, hinge]
    size = 2 * (ELEMENTS_PER_ROD * len(rods) + 1)
    K, M = np.zeros((size, size)), np.zeros((size, size))
    e = 0
    for r in rods:
        h = chain.l[r] / ELEMENTS_PER_ROD
        k, m = _element(float(chain.EI[r]), float(chain.m[r]), h)
        for _ in range(ELEMENTS_PER_ROD):
            K[2 * e : 2 * e + 4, 2 * e : 2 * e + 4] += k
            M[2 * e : 2 * e + 4, 2 * e : 2 * e + 4] += m
            e += 1
        M[2 * e, 2 * e] += chain.mu[r]  # the rod's far node
    free = np.arange(2 if hinge == 0 else 1, size)  # clamped: w, theta; pinned: w
    values = scipy.linalg.eigh(
        K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True, subset_by_index=[0, 1]
    )
    # pinned: the rigid rotation about the pin is the zero eigenvalue, the first bending
    # mode the next one; clamped: the first one
    lam = float(values[0] if hinge == 0 else values[1])
    return 2.0 * np.pi / np.sqrt(lam)


def lock_window(chain: Chain, latch: Latch) -> float:
    """The latch's window w (s): its ``window``, or ``first_bending_period`` of its hinge."""
    if latch.window is not None:
        return float(latch.window)
    return first_bending_period(chain, latch.hinge)


def window_nodes(t_lock: float, w: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Quadrature over the window [t_lock, t_lock + w]: (times (s), weights of
    int f(s) (1 - (s - t_lock)/w) ds, weights of the mean (1/w) int f ds), each
    (WINDOW_PANELS * WINDOW_NODES,). Exact for piecewise polynomials of degree
    2 WINDOW_NODES - 2 on each panel (the taper takes one degree)."""
    edges = np.linspace(0.0, w, WINDOW_PANELS + 1)
    half = 0.5 * np.diff(edges)
    s = (edges[:-1, None] + half[:, None] * (_GL_X + 1.0)).ravel()
    base = (half[:, None] * _GL_W).ravel()
    return t_lock + s, base * (1.0 - s / w), base / w
