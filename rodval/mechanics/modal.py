"""The computations of a modal analysis (the results' types are ``rodval.core.modes``):
the loads a static equilibrium holds, the hinges held, the rigid modes of a free chain split
from the flexible ones, mode matching (MAC) and damping ratios of a damped pencil.

Units: as ``rodval.core.modes``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.optimize import linear_sum_assignment

from rodval.core.modes import ConstantLoads
from rodval.core.scene import Scene
from rodval.mechanics.eigen import quadratic_eigenvalues

if TYPE_CHECKING:
    from rodval.core.loads import NodalForce

#: Load laws that settle to a constant when they act for ever (t_off = inf): their value
#: after their last kink is the load a static equilibrium holds.
SETTLING_LAWS = ("constant", "ramp")


def _force_at(f: NodalForce, t: float) -> tuple[float, float]:
    return (float(f.fx(t)) if f.fx else 0.0, float(f.fy(t)) if f.fy else 0.0)


def static_loads(scene: Scene, at: float | None = None) -> ConstantLoads:
    """The loads a static equilibrium of ``scene`` holds fixed (one definition for every
    model's ``about="equilibrium"``).

    ``at = None``: the loads that act for ever. A load whose support ends (t_off < inf: a
    pulse, a windowed step, a tabulated history) is left out and named with its end time; a
    constant or ramp load acting for ever counts at its final value; any other load acting for
    ever (harmonic, a Python callable) has no static value: ValueError asking for ``at``.
    ``at = t`` (s, finite, >= 0): every load frozen at its value at t; loads not acting at t
    are named. Cost O(loads + n)."""
    n = scene.n
    X, Y = np.zeros(n), np.zeros(n)
    ignored = []
    if at is not None:
        if isinstance(at, bool) or not isinstance(at, (int, float)) or not 0 <= at < np.inf:
            raise ValueError(f"load_at must be a finite time >= 0 s, got {at!r}")
        at = float(at)
    for f in scene.loads:
        what = f"{f.name} load at node {f.node}"
        if at is not None:
            if not f.active(at):
                ignored.append(f"{what} (not acting at t = {at:g} s)")
                continue
            fx, fy = _force_at(f, at)
        elif f.support[1] < np.inf:
            ignored.append(f"{what} (acts only until t = {f.support[1]:g} s)")
            continue
        elif f.name in SETTLING_LAWS:
            fx, fy = _force_at(f, max((f.support[0], *f.breakpoints)))
        else:
            raise ValueError(
                f"the {what} acts for ever without settling to a constant, so the scene has no "
                "static equilibrium of its own; give load_at (--load-at T, s) to hold every "
                "load at its value at time T"
            )
        X[f.node - 1] += fx
        Y[f.node - 1] += fy
    return ConstantLoads(
        np.cumsum(X[::-1])[::-1], np.cumsum(Y[::-1])[::-1], tuple(ignored), X, Y, at
    )


def normalize_shapes(
    dx: np.ndarray, dy: np.ndarray, hinge: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scale each mode (row) so that the largest node displacement magnitude is 1 (or, if the
    nodes do not move, the largest |hinge angle| is 1) and the largest node-displacement
    component (else hinge angle) is positive."""
    dx, dy, hinge = (np.array(a, float) for a in (dx, dy, hinge))
    for i in range(dx.shape[0]):
        mag = np.hypot(dx[i], dy[i])
        ref = np.concatenate([dx[i], dy[i]])
        if mag.max() <= 1e-12 * max(np.max(np.abs(hinge[i])), 1e-300):
            scale, ref = np.max(np.abs(hinge[i])), hinge[i]
        else:
            scale = mag.max()
        sign = np.sign(ref[np.argmax(np.abs(ref))]) or 1.0
        s = sign / scale if scale > 0 else 1.0
        dx[i] *= s
        dy[i] *= s
        hinge[i] *= s
    return dx, dy, hinge


def held_hinges(scene: Any) -> np.ndarray:
    """The hinges (ascending indices 0..n-1) of the scene's held latches (``Latch.held``:
    clamped from t = 0), which every model's modes hold: a held hinge's relative rotation is
    fixed (a constraint: the native models condense it out of M, C and K, exudyn keeps its
    latch joint active). The other latches play no part in modes: at the configuration the
    modes are about they have not locked (a latch ahead of its hinge's angle)."""
    return np.array(sorted(latch.hinge for latch in scene.latches if latch.held), dtype=int)


def equilibrium_angles(scene: Any) -> np.ndarray:
    """The hinge angles D_k (rad, n) of the unloaded equilibrium: each hinge's rest angle, a
    held latch's angle on its hinge (the latch holds the spring's moment there)."""
    D = np.array(scene.chain.rest_angle, float)
    for latch in scene.latches:
        if latch.held:
            D[latch.hinge] = float(latch.angle)
    return D


#: A free base's three rigid modes must have omega below this fraction of the first flexible
#: omega (``split_rigid``).
RIGID_RATIO = 1e-6
#: Largest relative residual of a rigid mode's shape against an exact rigid motion of the
#: nodes (``split_rigid``): the eigenvectors of the zero cluster carry round-off of about
#: eps lam_max / lam_flexible (exudyn's axial modes make that ~1e-7 for the beam model).
RIGID_SHAPE_TOL = 1e-4


def check_no_mechanism(scene: Any) -> None:
    """ValueError (before any work) when a chain on a free base has a hinge without a spring
    (kappa = 0) that no held latch holds: it is then a mechanism, with a zero-frequency mode
    of its own beside the body's three rigid ones, which ``split_rigid`` could not tell
    apart. Names the hinges and the fix."""
    held = set(held_hinges(scene).tolist())  # a held hinge is no mechanism (no rotation)
    loose = [
        int(k) for k in np.flatnonzero(np.asarray(scene.chain.kappa) == 0.0) if int(k) not in held
    ]
    if loose:
        raise ValueError(
            f"modes of a free spacecraft: hinge(s) {loose} have no spring (chain.kappa = 0), so "
            "the chain is a mechanism with zero-frequency modes beside the three rigid ones; "
            "give every hinge a spring (kappa > 0) or hold it (a held latch) for its modes"
        )


def split_rigid(
    lam: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
    hinge: np.ndarray,
    x: np.ndarray,
    y: np.ndarray,
    l_mean: float,
    *,
    ratio: float = RIGID_RATIO,
    tol: float = RIGID_SHAPE_TOL,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    """Separate the three rigid modes of a chain on a free base from its flexible modes, the
    same way for every model (native ``rodval.models.observation.free_modes``, exudyn's
    ``reference_models.exudyn_modes``).

    ``lam`` (ascending, 1/s^2) are the eigenvalues of K x = lam M x, M symmetric positive
    definite, whose eigenvectors x_i are M-orthonormal; dx, dy (modes, n+1), hinge (modes, n)
    their (unnormalized) node displacements and hinge angles; x, y the nodes' coordinates
    (m) of the configuration; l_mean scales the hinge angles in the shape vectors
    [dx; dy; l_mean D]. The rigid modes are:

    * the three smallest eigenvalues, each of |omega| <= ``ratio`` (1e-6) x the fourth's
      omega (the first flexible mode), else ValueError;
    * their span must hold the two translations of the whole system (node shapes [1..1; 0..0;
      0] and [0..0; 1..1; 0], hinge angles 0), each to a relative least-squares residual below
      ``tol``, else ValueError; the rotation is the combination M-orthogonal to both (in
      coefficients of M-orthonormal eigenvectors: the cross product of theirs), i.e. the one
      of zero linear momentum, a rotation about the system's centre of mass; its shape must be
      a rigid rotation of the nodes (dx = a - w y, dy = b + w x, D = 0) to ``tol``.

    Returns (lam, dx, dy, hinge, info): the three rigid modes first (translation x,
    translation y, rotation, each with the Rayleigh quotient of its combination as lam),
    then the flexible ones as given; ``info`` records the ratio and the shape residuals."""
    lam = np.asarray(lam, float)
    n1 = dx.shape[1]
    measured = _rigid_ratio(lam, ratio)
    S = np.hstack([dx[:3], dy[:3], l_mean * hinge[:3]])  # (3, L)
    C, R, residual = _rigid_combinations(S, n1, hinge.shape[1], x, y)
    bad = {k: v for k, v in residual.items() if not v <= tol}
    if bad:
        raise ValueError(
            "the free base's three smallest modes are not rigid motions: shape residual "
            + ", ".join(f"{k} {v:.3g}" for k, v in bad.items())
            + f" (at most {tol:g})"
        )
    lam_r = np.einsum("ij,j,ij->i", C, lam[:3], C) / np.einsum("ij,ij->i", C, C)
    L = n1
    out = (
        np.concatenate([lam_r, lam[3:]]),
        np.vstack([R[:, :L], dx[3:]]),
        np.vstack([R[:, L : 2 * L], dy[3:]]),
        np.vstack([R[:, 2 * L :] / l_mean, hinge[3:]]),
    )
    info = {
        "rigid_ratio": measured,
        "rigid_shape_residual": residual,
        "rigid_modes": ("translation_x", "translation_y", "rotation"),
    }
    return (*out, info)


def _rigid_ratio(lam: np.ndarray, ratio: float) -> float:
    """The ratio (dimensionless) of the largest |omega| of the three smallest eigenvalues
    ``lam`` (ascending, 1/s^2) to the fourth's omega (rad/s, the first flexible mode); at
    least four modes, and the ratio at most ``ratio``, else ValueError."""
    if lam.size < 4:
        raise ValueError(
            f"a chain on a free base has three rigid modes and at least one flexible mode; "
            f"got {lam.size} modes"
        )
    first = np.sqrt(abs(lam[3]))
    measured = float(np.sqrt(np.max(np.abs(lam[:3]))) / first) if first > 0 else np.inf
    if not measured <= ratio:
        raise ValueError(
            "the free base's three rigid modes were not found: the third smallest |omega| is "
            f"{measured:.3g} of the first flexible one (at most {ratio:g} expected)"
        )
    return measured


def _rigid_combinations(
    S: np.ndarray, n1: int, n_hinge: int, x: np.ndarray, y: np.ndarray
) -> tuple[np.ndarray, np.ndarray, dict[str, float]]:
    """The rigid modes as combinations of the three smallest modes' shape vectors ``S`` (3, L)
    = [dx; dy; l_mean D] (m; n1 nodes, n_hinge hinges; x, y the nodes' coordinates, m):
    (C (3 rigid, 3 eigenvectors), dimensionless coefficients; R = C S (3, L) their shapes,
    m; the relative least-squares residuals, dimensionless, of translation x, translation y
    and the rotation against exact rigid motions, ``split_rigid``)."""
    zeros_h = np.zeros(n_hinge)
    tx = np.concatenate([np.ones(n1), np.zeros(n1), zeros_h])
    ty = np.concatenate([np.zeros(n1), np.ones(n1), zeros_h])
    coef, residual = [], {}
    for name, t in (("translation_x", tx), ("translation_y", ty)):
        c = np.linalg.lstsq(S.T, t, rcond=None)[0]
        residual[name] = float(np.linalg.norm(S.T @ c - t) / np.linalg.norm(t))
        coef.append(c)
    cr = np.cross(coef[0], coef[1])
    coef.append(cr / np.linalg.norm(cr))
    C = np.array(coef)  # (3 rigid, 3 eigenvectors)
    R = C @ S
    tr = np.concatenate([-np.asarray(y, float), np.asarray(x, float), zeros_h])
    basis = np.column_stack([tx, ty, tr])
    fit = np.linalg.lstsq(basis, R[2], rcond=None)[0]
    residual["rotation"] = float(
        np.linalg.norm(basis @ fit - R[2]) / max(float(np.linalg.norm(R[2])), 1e-300)
    )
    if not abs(fit[2]) > 0:
        residual["rotation"] = np.inf
    return C, R, residual


def mac_matrix(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """MAC of every row of A against every row of B (dimensionless, in [0, 1]; shape vectors
    in any one unit, real or complex)."""
    A, B = np.asarray(A), np.asarray(B)
    num = np.abs(A.conj() @ B.T) ** 2
    den = np.outer(np.sum(np.abs(A) ** 2, 1), np.sum(np.abs(B) ** 2, 1))
    mac: np.ndarray = np.divide(num, den, out=np.zeros_like(num, dtype=float), where=den > 0)
    return mac


def damping_ratios(
    M: np.ndarray, C: np.ndarray, K: np.ndarray, X: np.ndarray, omega: np.ndarray
) -> np.ndarray:
    """zeta_i (dimensionless) of the quadratic eigenproblem (M s^2 + C s + K) z = 0, paired
    with the undamped modes X (columns, in the coordinates of M, C, K) of angular frequencies
    ``omega`` (rad/s) by MAC (``mac_matrix``, Hungarian pairing): zeta = -Re(s) / |s| of the
    paired eigenvalue (Im s > 0, 1/s); 0 for every omega > 0 without damping (C = 0), NaN where
    undefined (omega <= 0, no partner). M, C, K in consistent units (kg, N s/m, N/m or their
    rotational counterparts). Shared by the native fixed-base and free-base modes
    (``rodval.models.observation.linear_modes``, ``rodval.models.observation.free_modes``)."""
    zeta = np.full(omega.size, np.nan)
    if not np.any(C):
        zeta[omega > 0] = 0.0
        return zeta
    s, V = quadratic_eigenvalues(M, C, K)
    up = s.imag > 0
    s, Z = s[up], V[:, up]
    keep = omega > 0
    if not np.any(keep) or s.size == 0:
        return zeta
    cost = 1.0 - mac_matrix(X[:, keep].T, Z.T)
    rows, cols = linear_sum_assignment(cost)
    idx = np.flatnonzero(keep)
    zeta[idx[rows]] = -s[cols].real / np.abs(s[cols])
    return zeta
