"""The reduced model's linearized modes with held latches: its quasi-static bending condensed
out with the held hinges as equations (``held_reduced``), used by
``rodval.models.observation.linear_modes``. Dense linear algebra, O(n^3)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.linalg


def held_reduced(
    MCK: tuple[np.ndarray, ...], A: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, Callable[[np.ndarray, float], np.ndarray]]:
    """The reduced model's (M_r, C_r, K_r) (n, n) with held hinges, from the full model's
    linear (M, C, K) = ``MCK`` (3n) and the held hinges' rows A (m, 3n): the reduced model
    holds them as equations of its quasi-static bending (``ReducedSystem.solve_locked``, the
    kappa -> infinity limit), so with S = [[B, A_g^T], [A_g, 0]] (B = K_gg) and
    E = [K_pg, A_p^T] the bending and the latches' multipliers are condensed out exactly:

        M_r = M_pp - E S^-1 [M_gp; 0],  C_r = C_pp - E S^-1 [C_gp; 0],
        K_r = K_pp - E S^-1 [K_gp; A_p]

    (without held hinges S = B and these are the reduced model's own). Also returns
    gamma(dphi, lam): a mode's bending coordinates (2n) from its chord angles at eigenvalue
    lam = omega^2. O(n^3) (dense)."""
    M, C, K = MCK
    p, g = slice(0, n), slice(n, 3 * n)
    m = A.shape[0]
    S = np.zeros((2 * n + m, 2 * n + m))
    S[: 2 * n, : 2 * n] = K[g, g]
    S[: 2 * n, 2 * n :] = A[:, g].T
    S[2 * n :, : 2 * n] = A[:, g]
    E = np.hstack([K[p, g], A[:, p].T])
    lu = scipy.linalg.lu_factor(S)
    none = np.zeros((m, n))

    def condense(B: np.ndarray, rows: np.ndarray) -> np.ndarray:
        return np.asarray(B[p, p] - E @ scipy.linalg.lu_solve(lu, np.vstack([B[g, p], rows])))

    def gamma(dphi: np.ndarray, lam: float) -> np.ndarray:
        rhs = np.concatenate([(K[g, p] - lam * M[g, p]) @ dphi, A[:, p] @ dphi])
        return np.asarray(-scipy.linalg.lu_solve(lu, rhs)[: 2 * n])

    return condense(M, none), condense(C, none), condense(K, A[:, p]), gamma
