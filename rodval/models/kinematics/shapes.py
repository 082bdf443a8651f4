"""Bending shapes of one rod and their integrals: the model ladder's per-rod constants.

Rod of length l (m), mass per length m (kg/m), bending stiffness EI (N m^2), Kelvin-Voigt
bending damping c (N m^2 s). Its transverse deflection from the chord is
eta(s) = sum_i g_i psi_i(s), s in [0, l], with p + 1 shapes (``shapes = p``):

* psi_0 = sigma = s (l - s)^2 / l^2 and psi_1 = tau = -s^2 (l - s) / l^2, the paper's cubic
  shapes (g_0 = alpha, g_1 = beta: the end slopes relative to the chord, rad);
* psi_i, i = 2..p: hierarchical bubbles that vanish with their slope at both ends, the second
  integrals of Legendre polynomials: psi_i(s) = (l / 4) B_i(x), x = 2 s / l - 1,
  B_i(x) = int_-1^x int_-1^t P_i(u) du dt, so that psi_i'' = P_i(x) / l. For i >= 2,
  int_-1^1 P_i = int_-1^1 x P_i = 0 makes B_i and B_i' vanish at x = 1: the end slopes keep
  their meaning and every hinge and latch definition stays that of the paper.

The second derivatives of sigma and tau are linear in x (P_0, P_1), so the bending stiffness
matrix int EI psi_i'' psi_j'' is block diagonal: the paper's 2 x 2 block (4 EI / l)[[1, 1/2],
[1/2, 1]] and EI / (l (2 i + 1)) per bubble. Every integral is evaluated by Gauss-Legendre
quadrature exact for the polynomial degrees involved (shapes of degree <= p + 2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre as L
from numpy.polynomial import polynomial as Poly

#: The largest number of shapes per rod (``shapes`` = p, 1 <= p <= MAX_SHAPES): enough for
#: the eigenvalue checks of docs/model.md; the cost of a kernel evaluation is O(n p^2).
MAX_SHAPES = 8


def shape_polynomials(p: int) -> list[np.ndarray]:
    """Power-series coefficients in xi = s / l of psi_i / l (i = 0..p), lowest first."""
    sigma = np.array([0.0, 1.0, -2.0, 1.0])  # xi (1 - xi)^2
    tau = np.array([0.0, 0.0, -1.0, 1.0])  # -xi^2 (1 - xi)
    out = [sigma, tau]
    # x = 2 xi - 1: B_i(x) as a polynomial in xi, times 1/4 (psi = l/4 B)
    to_xi = np.array([-1.0, 2.0])
    for i in range(2, p + 1):
        B = L.leg2poly(L.legint(L.legint(np.eye(i + 1)[i], lbnd=-1), lbnd=-1))
        coef: np.ndarray = np.zeros(1)
        for power, b in enumerate(B):
            coef = Poly.polyadd(coef, b * Poly.polypow(to_xi, power))
        out.append(coef / 4.0)
    return out


@dataclass(frozen=True)
class RodShapes:
    """Per-rod integrals of the p + 1 shapes, arrays over rods (n, p+1) or (n, p+1, p+1):

    * ``a`` = int m psi_i ds (kg m), ``b`` = int m s psi_i ds (kg m^2);
    * ``P`` = int m psi_i psi_j ds (kg m^2): the bending block of the mass matrix;
    * ``K`` = int EI psi_i'' psi_j'' ds (N m), ``C`` = int c psi_i'' psi_j'' ds (N m s).
    """

    p: int
    a: np.ndarray
    b: np.ndarray
    P: np.ndarray
    K: np.ndarray
    C: np.ndarray


def rod_shapes(p: int, l: np.ndarray, m: np.ndarray, EI: np.ndarray, c: np.ndarray) -> RodShapes:
    """The integrals of ``RodShapes`` for rods of lengths l, masses per length m, bending
    stiffness EI and bending damping c (arrays (n,)). O(n p^2)."""
    polys = shape_polynomials(p)
    xg, wg = L.leggauss(p + 4)  # exact to degree 2 p + 7 >= 2 (p + 2) + 1
    xi, wxi = (xg + 1.0) / 2.0, wg / 2.0
    S = np.array([Poly.polyval(xi, c_) for c_ in polys])  # psi_i / l at the nodes
    one = np.einsum("iq,q->i", S, wxi)  # int_0^1 psi/l dxi
    first = np.einsum("iq,q,q->i", S, xi, wxi)
    gram = np.einsum("iq,jq,q->ij", S, S, wxi)
    # int_0^1 (l psi_i'')(l psi_j'') dxi, exactly: the cubic block and 1 / (2 i + 1) per
    # bubble (Legendre orthogonality; the quadrature agrees to round-off, tests/test_ladder.py)
    stiff = np.diag(1.0 / (2.0 * np.arange(p + 1) + 1.0))
    stiff[:2, :2] = [[4.0, 2.0], [2.0, 4.0]]
    ml = m * l
    return RodShapes(
        p=p,
        a=(ml * l)[:, None] * one,
        b=(ml * l * l)[:, None] * first,
        P=(ml * l * l)[:, None, None] * gram,
        K=(EI / l)[:, None, None] * stiff,
        C=(c / l)[:, None, None] * stiff,
    )


def deflection(p: int, l: float, g: np.ndarray, s: np.ndarray) -> np.ndarray:
    """eta(s) = sum_i g_i psi_i(s) (m) of one rod at stations s (m); g: (p+1,) or (..., p+1)."""
    polys = shape_polynomials(p)
    S = np.array([l * Poly.polyval(np.asarray(s) / l, c_) for c_ in polys])
    return np.tensordot(g, S, axes=([-1], [0]))
