"""Statics of the paper models: the load stiffness, the static residual and the static
equilibrium by Newton's method with load stepping, and the at-rest check of a configuration
(see ``rodval.models.observation.linear_modes`` for the equations)."""

from __future__ import annotations

from typing import Any

import numpy as np

from rodval.core.modes import Equilibrium
from rodval.core.scene import Chain, Scene
from rodval.mechanics.eigen import constraint_basis
from rodval.mechanics.modal import held_hinges
from rodval.models.assembly.paper_matrices import (
    hinge_matrix,
    stiffness_matrix,
)


# -- loads and statics ------------------------------------------------------------------------
def load_stiffness(l: np.ndarray, phi: np.ndarray, SX: np.ndarray, SY: np.ndarray) -> np.ndarray:
    """K_L = -dQ/dphi (n, n), diagonal: l_k (sin phi_k SY_k + cos phi_k SX_k) (N m/rad)."""
    return np.diag(l * (np.sin(phi) * SY + np.cos(phi) * SX))


def held_basis(scene: Scene, columns: int | None = None) -> np.ndarray | None:
    """Z (N, N - m) with q = Z u exactly the motions that keep the scene's m held hinges
    (``rodval.mechanics.modal.held_hinges``) at their angles (``constraint_basis`` of their hinge
    rows, each eliminating its alpha_k), or None without held latches. ``columns``: N, the
    model's coordinates (default 3n; a ladder rung's n (p + 2), whose hinge rows are the
    paper's padded with zeros for the bubbles)."""
    held = held_hinges(scene)
    if not held.size:
        return None
    n = scene.n
    A = np.zeros((held.size, 3 * n if columns is None else columns))
    A[:, : 3 * n] = hinge_matrix(n)[held]
    return constraint_basis(A)


def static_residual(
    chain: Chain,
    q: np.ndarray,
    SX: np.ndarray | None = None,
    SY: np.ndarray | None = None,
    rest: Any = None,
    K: np.ndarray | None = None,
) -> np.ndarray:
    """R(q) = K q - A^T (kappa * rest) - [Q(phi); 0; 0] (3n): the gradient of
    Pi(q) - work of the constant loads. ``rest``: hinge rest angles (rad, n; None = 0), the
    spring moments being kappa_k (D_k - rest_k)."""
    n = chain.n
    K = stiffness_matrix(chain) if K is None else K
    R = K @ q
    if rest is not None:
        R -= hinge_matrix(n).T @ (chain.kappa * np.broadcast_to(np.asarray(rest, float), (n,)))
    if SX is not None:
        phi = q[:n]
        R[:n] -= chain.l * (np.cos(phi) * SY - np.sin(phi) * SX)
    return np.asarray(R)


def static_equilibrium(
    chain: Chain,
    SX: np.ndarray | None = None,
    SY: np.ndarray | None = None,
    q0: np.ndarray | None = None,
    rest: Any = None,
    *,
    rtol: float = 1e-12,
    max_iter: int = 30,
    max_steps: int = 256,
    held: np.ndarray | None = None,
) -> Equilibrium:
    """Static equilibrium R(q) = 0 (``static_residual``) by Newton's method with the exact
    Jacobian K + K_L, starting from q0 (default straight). If a Newton solve fails, the load
    (and rest angles) are applied in more equal steps (1, 2, 4, ... up to ``max_steps``).
    Converged when max |R| <= rtol * (max |K q| + max |Q| + 1 N m). ``held``: the basis Z of
    the motions that keep the held hinges at their angles (``held_basis``; q0 must hold them):
    q stays on q0 + Z u, the residual is then Z^T R (the held hinges' moments are the
    latches' reactions) and the Jacobian Z^T (K + K_L) Z."""
    n = chain.n
    K = stiffness_matrix(chain)
    SX = np.zeros(n) if SX is None else np.asarray(SX, float)
    SY = np.zeros(n) if SY is None else np.asarray(SY, float)
    rest = None if rest is None else np.broadcast_to(np.asarray(rest, float), (n,))
    start = np.zeros(3 * n) if q0 is None else np.asarray(q0, float).copy()
    total = 0
    steps = 1
    while steps <= max_steps:
        q = start.copy()
        ok = True
        for i in range(1, steps + 1):
            f = i / steps
            args = (f * SX, f * SY, None if rest is None else f * rest)
            q, residual, scale, used = _newton(chain, K, q, args, held, rtol, max_iter)
            total += used
            if not (np.all(np.isfinite(q)) and residual <= rtol * scale):
                ok = False
                break
        if ok:
            return Equilibrium(q, total, steps, residual, True)
        steps *= 2
    R = static_residual(chain, q, SX, SY, rest, K=K)
    R = R if held is None else held.T @ R
    return Equilibrium(q, total, steps // 2, float(np.max(np.abs(R))), False)


def _newton(
    chain: Chain,
    K: np.ndarray,
    q: np.ndarray,
    args: tuple[np.ndarray, np.ndarray, np.ndarray | None],
    held: np.ndarray | None,
    rtol: float,
    max_iter: int,
) -> tuple[np.ndarray, float, float, int]:
    """Newton's method on the static residual at the loads and rest angles ``args`` (SX, SY,
    rest) from q (3n), on q + Z u when ``held`` is the basis Z: (q, max |R| (N m; Z^T R when
    held), its convergence scale (N m), Newton iterations). A singular Jacobian gives a NaN q
    (the caller then tries more load steps)."""
    n = chain.n
    used = 0
    for _ in range(max_iter + 1):
        R = static_residual(chain, q, args[0], args[1], args[2], K=K)
        R = R if held is None else held.T @ R
        Q = chain.l * (np.cos(q[:n]) * args[1] - np.sin(q[:n]) * args[0])
        scale = np.max(np.abs(K @ q)) + np.max(np.abs(Q)) + 1.0
        residual = float(np.max(np.abs(R)))
        if residual <= rtol * scale or used == max_iter or not np.all(np.isfinite(q)):
            break
        J = K.copy()
        J[:n, :n] += load_stiffness(chain.l, q[:n], args[0], args[1])
        try:
            if held is None:
                q = q - np.linalg.solve(J, R)
            else:
                q = q - held @ np.linalg.solve(held.T @ J @ held, R)
        except np.linalg.LinAlgError:  # singular: no Newton step; try more load steps
            q = np.full_like(q, np.nan)
        used += 1
    return q, residual, scale, used


def no_equilibrium(chain: Chain, eq: Equilibrium, held: np.ndarray | None = None) -> str:
    """Why ``static_equilibrium`` found none, in one line: hinges without stiffness
    (kappa = 0) that neither a held latch (``held``: their indices) nor the loads hold leave
    the chain free to turn there (a singular stiffness, no unique equilibrium); otherwise
    Newton's method did not converge."""
    fixed = set() if held is None else {int(k) for k in held}
    free = [int(k) for k in np.flatnonzero(chain.kappa == 0) if int(k) not in fixed]
    if free:
        return (
            f"static equilibrium not found: hinge(s) {free} have no stiffness (kappa = 0), so "
            "where the loads do not hold them the chain turns freely and its stiffness is "
            "singular (no unique equilibrium, or none Newton's method reaches from the initial "
            "state); give those hinges kappa > 0, start nearer an equilibrium ([initial] phi), "
            "or linearize about the initial state (about='initial', --about initial)"
        )
    return (
        f"static equilibrium not found (max |R| = {eq.residual:.3g} N m after "
        f"{eq.iterations} Newton iterations and {eq.load_steps} load steps)"
    )


#: Largest static residual of an initial state still taken as an equilibrium, relative to
#: max |K q0| + max |A^T kappa rest| + max |Q| + 1 N m: a state written with 9 significant
#: digits from an equilibrium (static_equilibrium converges to 1e-12 of the same scale)
#: passes; a pre-stressed fold (residuals of order kappa x angle) does not.
AT_REST_RTOL = 1e-8


def body_rest_angles(scene: Scene) -> np.ndarray:
    """The hinge rest angles (rad, n) in the chain's own hinge angles (hinge 0 from theta = 0):
    on a free base hinge 0 is measured from the body's attitude theta (D_0 = phi_1 + alpha_1 -
    theta), so its spring relaxes where phi_1 + alpha_1 = theta + rest_0."""
    rest = np.array(scene.chain.rest_angle, float)
    attitude = scene.base.initial_attitude() if scene.base.free else None
    if attitude:
        rest[0] += attitude
    return rest


def check_at_rest(scene: Scene) -> float:
    """The initial state's static residual max |R(q0)| (N m, ``static_residual`` with the
    hinge rest angles and without loads, which the linearization about the initial state
    leaves out), or ValueError when the state is not at rest in equilibrium (rates not zero,
    or max |R| above ``AT_REST_RTOL`` of its scale): a linearization about a state the chain
    immediately leaves describes no motion of the scene. A scene-level check, made before any
    model's modal analysis. O(n^2) (the dense K of the paper's matrices)."""
    chain, n = scene.chain, scene.n
    ini = scene.initial.resolve(n)
    moving = [f"initial.{k}" for k in ("dphi", "dalpha", "dbeta") if np.any(ini[k] != 0)]
    if moving:
        raise ValueError(
            f"the initial state is not at rest ({', '.join(moving)} not zero), so there is no "
            "configuration to vibrate about; linearize about the static equilibrium "
            "(about='equilibrium', --about equilibrium) or pass allow_unbalanced=True "
            "(--allow-unbalanced) to linearize about the initial positions anyway"
        )
    base = scene.base
    if base.free and (any(base.velocity) or base.rate):
        raise ValueError(
            "the initial state is not at rest (the free base's velocity or rate is not zero), "
            "so there is no configuration to vibrate about; start the body at rest or pass "
            "allow_unbalanced=True (--allow-unbalanced) to linearize about the initial "
            "positions anyway"
        )
    q0 = np.concatenate([ini["phi"], ini["alpha"], ini["beta"]])
    K = stiffness_matrix(chain)
    rest = body_rest_angles(scene)
    R = balance_residual(scene, q0, rest, K)
    spring = hinge_matrix(n).T @ (chain.kappa * rest)
    scale = np.max(np.abs(K @ q0)) + np.max(np.abs(spring)) + 1.0
    worst = int(np.argmax(np.abs(R)))
    residual = float(abs(R[worst]))
    if residual > AT_REST_RTOL * scale:
        row = ("phi", "alpha", "beta")[worst // n] + f"[{worst % n}]"
        raise ValueError(
            f"the initial state is not an equilibrium: static residual {residual:.3g} N m on "
            f"{row} (hinge springs about their rest angles and bending; loads are left out "
            "about the initial state), so the chain does not stay there; linearize about the "
            "static equilibrium (about='equilibrium', --about equilibrium, which holds the "
            "loads) or pass allow_unbalanced=True (--allow-unbalanced) to linearize about it "
            "anyway"
        )
    return residual


def balance_residual(
    scene: Scene, q0: np.ndarray, rest: np.ndarray, K: np.ndarray | None = None
) -> np.ndarray:
    """The static residual (N m, 3n) of q0 without loads that no held latch carries: R(q0)
    (``static_residual`` about the hinge rest angles ``rest``) with each held hinge's moment
    taken by its latch, i.e. R less its component along the held hinges' rows (the least-
    squares multipliers; R itself without held latches). A held hinge away from its rest
    angle is thus in equilibrium (the latch holds the spring's moment)."""
    R = static_residual(scene.chain, q0, rest=rest, K=K)
    held = held_hinges(scene)
    if not held.size:
        return R
    A = hinge_matrix(scene.n)[held]
    lam = np.linalg.lstsq(A.T, R, rcond=None)[0]
    return np.asarray(R - A.T @ lam)
