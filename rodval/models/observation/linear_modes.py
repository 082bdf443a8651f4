"""Linearized free vibration (modal analysis) of the paper's full and reduced models.

About a configuration at rest, q0 = [phi0; alpha0; beta0], the convective terms (quadratic in
the rates) and dM/dphi q'' (q'' = 0 at an equilibrium) drop out of the linearization, so both
models become

    M(phi0) dq'' + C dq' + (K + K_L(phi0)) dq = 0

with the load stiffness K_L = -dQ/dphi of the constant loads on the phi rows,

    Q_k = l_k (cos phi_k SY_k - sin phi_k SX_k)  ->  (K_L)_kk = l_k (sin phi_k SY_k + cos phi_k SX_k)

(diagonal; SX_k = sum_{j>=k} X_j). Full model: q = [phi; alpha; beta] (3n); reduced model:
q = phi (n) with M_r(phi0), C_r, K_r + K_L (the bending rows condensed quasi-statically).

Configurations (``about``)
--------------------------
``initial``: the scene's initial state (loads left out: free vibration about that shape). It
must be at rest in equilibrium without loads (``check_at_rest``: zero rates, static residual
of the hinge springs about their rest angles and the bending below ``AT_REST_RTOL``); a
pre-stressed fold is refused unless ``allow_unbalanced=True`` (the residual is then
recorded). A chain held by loads is linearized about its equilibrium (``equilibrium``).
``equilibrium``: the static equilibrium under the scene's static loads
(``rodval.mechanics.modal.static_loads``: the loads that act for ever at their final value,
windowed ones left out and named; or, with ``load_at``, every load at that instant) and the
hinge rest angles, found by Newton's method on the static residual

    R(q) = K q - A^T (kappa * rest) - [Q(phi); 0; 0]

(``static_residual``; ``rest``: the chain's hinge rest angles) with its exact Jacobian
K + K_L, and load stepping when the full step fails. The reduced model's equilibrium is the
same phi (its bending rows are the full model's, condensed).

Held latches
------------
A held latch (``Latch.held``, ``rodval.mechanics.modal.held_hinges``) fixes its hinge's relative
rotation: the full model (every rung) solves its pencil on the exact basis Z of the motions
that keep the held hinges (``statics.held_basis``: each row eliminates its alpha_k), the
reduced model condenses its bending with the held hinges as equations (``held_reduced``),
and the equilibrium is found on the same basis. Other latches play no part (not locked at the
configuration). docs/modes.md, "Latches".

Frequencies and damping
-----------------------
Undamped: the generalized eigenproblem (K + K_L) x = omega^2 M x. For the full model with the
kinematic ("printed") coefficients M is symmetric positive definite:
``rodval.mechanics.eigen.symmetric_pencil`` (direct and inverted pencil, each eigenvalue from the
one that carries it: the same digits on every BLAS kernel).
The reduced model's M_r = M_pp - K_pg B^-1 M_gp is not symmetric (a quasi-static
condensation, not a Galerkin projection: asymmetry ~1e-5 of its largest entry at n = 3..8),
and neither is the full M with the ``published`` erratum; both take the general path below.
For the published M the generalized eigenproblem is extremely ill-conditioned for long
uniform chains: right eigenvectors of the bending cluster localize at the tip, left ones at
the root (a "skin effect" of the non-symmetric rod-to-rod coupling), so the eigenvalue
condition numbers grow exponentially with n (94 at n = 8, 2e5 at n = 16, 3e12 at n = 32, 2e14
at n = 64) and double-precision QZ on (K, M) returns complex pairs from n ~ 32 although the
spectrum is real. ``_general_eig`` removes that: it rewrites the pencil in node transverse
displacements (phi_k = (y_k - y_{k-1}) / l_k, exact; the pencil is then block-banded, one rod
coupling only its neighbours, in the straight configuration) ordered rod by rod, applies the
exact diagonal similarity diag(rho^k) per rod for a few rho (undoing the geometric
localization without mixing the band), runs QZ for each, and takes every eigenvalue from the
run whose first-order error estimate (left/right eigenvectors) for it is smallest, matching
the runs' spectra one-to-one. n = 10 and 32 (all eigenvalues) and 64 (all 192) agree with
mpmath at 40 digits (tests/test_modes.py, docs/modes.md).

Damped (nu > 0): the quadratic eigenproblem (s^2 M + s C + K + K_L) x = 0 as a first-order
state-space problem (``rodval.mechanics.eigen.quadratic_eigenvalues``, inverted); each undamped
mode is paired (Hungarian, on the MAC of the displacement parts) with an eigenvalue s of
positive imaginary part, and the damping ratio is zeta = -Re(s) / |s|. Modes with omega = 0
(free rigid rotation) have no damping ratio (NaN).

Mode shapes
-----------
From the linearized kinematics: node displacements dx_k = -sum_{j<=k} l_j sin(phi0_j) dphi_j,
dy_k = sum_{j<=k} l_j cos(phi0_j) dphi_j (nodes k = 0..n, node 0 fixed) and hinge angles
D = A [dphi; dalpha; dbeta] (hinges 0..n-1). The reduced model's bending coordinates follow
from its bending rows at the mode's frequency: gamma = -B^-1 (K_gp - omega^2 M_gp) dphi.
Normalization: the largest node displacement magnitude is 1 (the hinge angles scaled with it),
and the largest node-displacement component is positive.

``mac`` is the modal assurance criterion |a.b|^2 / ((a.a)(b.b)) on the shape vector
[dx; dy; l_mean * D] (hinge angles times the mean rod length, so that both parts are lengths).
Each paper model's ``modes`` (``rodval.core.contract.Model.modes``) runs ``modes_about``.
"""

from __future__ import annotations

import numbers
from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np
import scipy.linalg
from scipy.optimize import linear_sum_assignment

from rodval.core.checks import check_choice, check_type
from rodval.core.modes import ABOUT, Equilibrium, Modes
from rodval.core.scene import Chain, InitialState, Scene
from rodval.mechanics.eigen import symmetric_pencil
from rodval.mechanics.modal import held_hinges, normalize_shapes, static_loads

# ``mac_matrix`` lives with ``damping_ratios`` in ``rodval.mechanics.modal`` (shared with the
# free-base modes, ``rodval.models.observation.free_modes``, without an import cycle); re-exported here
# for its callers (``rodval.analysis.modes``)
from rodval.mechanics.modal import mac_matrix as mac_matrix
from rodval.models.assembly.paper_matrices import (
    DEFAULT_VARIANT,
    chain_constants,
    damping_matrix,
    hinge_matrix,
    mass_matrix,
    stiffness_matrix,
)
from rodval.models.kinematics.ladder import (
    ladder_mass_matrix,
    ladder_stiffness,
)
from rodval.models.kinematics.rungs import (
    PAPER_RUNG,
    check_kinematics,
    check_shapes,
    resolve_kinematics,
)
from rodval.models.observation.held import held_reduced
from rodval.models.observation.mode_sets import chain_modes, lowest
from rodval.models.observation.statics import (
    balance_residual,
    body_rest_angles,
    check_at_rest,
    held_basis,
    load_stiffness,
    no_equilibrium,
    static_equilibrium,
)
from rodval.models.presets.full import FullModel
from rodval.models.presets.reduced import ReducedModel, ReducedSystem

#: The models linearized here: the paper's two.
PAPER_MODELS = (FullModel.name, ReducedModel.name)


#: Diagonal-similarity ratios tried (in order) for non-symmetric mass matrices, see
#: ``_general_eig``. Powers of two scale exactly.
RHO = (1.0, 2.0, 4.0, 0.5, 3.0, 8.0)


#: Relative size of an imaginary part (to the largest |eigenvalue|) still taken as round-off.
IMAG_TOL = 1e-9


#: Relative size (to the largest |eigenvalue|) below which a QZ eigenvalue is a zero mode.
ZERO_TOL = 1e-13


def check_arguments(scene: Scene, count: int | None) -> None:
    """Types before any work: a Scene, and ``count`` an integer >= 1 or None (ValueError)."""
    check_type("scene", scene, Scene, "a rodval.Scene (e.g. rodval.paper_scene())")
    if count is not None and (
        isinstance(count, bool) or not isinstance(count, numbers.Integral) or count < 1
    ):
        raise ValueError(f"count (number of modes) must be an integer >= 1 or None, got {count!r}")


# -- linear matrices ---------------------------------------------------------------------------
def linear_system(
    chain: Chain,
    model: str = "full",
    q0: np.ndarray | None = None,
    coefficients: str = DEFAULT_VARIANT,
    SX: np.ndarray | None = None,
    SY: np.ndarray | None = None,
    shapes: int = 1,
    kinematics: str = "first-order",
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(M, C, K + K_L) of the model linearized about q0 at rest (q0: phi (n) or
    [phi; alpha; beta] (3n); default straight). The bending coordinates of q0 do not enter
    the paper's rung (its M depends on phi only and K is constant); a ladder rung (full
    model, ``shapes`` > 1 or exact ``kinematics``) has N = n (p + 2) coordinates, its
    bubbles at rest zero (node loads and hinge moments do not load them: their stiffness is
    K-orthogonal to the cubic's) and, with exact kinematics, M(q0) with q0's bending."""
    check_choice("model", model, PAPER_MODELS)
    n = chain.n
    phi0 = np.zeros(n) if q0 is None else np.asarray(q0, float)[:n]
    if phi0.shape != (n,):
        raise ValueError(f"phi0 must have length n = {n}, got shape {phi0.shape}")
    if model == "full" and (shapes, kinematics) != PAPER_RUNG:
        p, exact = check_shapes(shapes), check_kinematics(kinematics) == "exact"
        q = np.zeros(n * (p + 2))
        if q0 is not None and len(q0) == 3 * n:
            q[: 3 * n] = q0
        q[:n] = phi0
        M = ladder_mass_matrix(chain, p, exact, q)
        K = ladder_stiffness(chain, p)
        if SX is not None and SY is not None:
            K[:n, :n] += load_stiffness(chain.l, phi0, SX, SY)
        return M, ladder_stiffness(chain, p, damping=True), K
    if model == "full":
        M = mass_matrix(chain_constants(chain, coefficients), phi0)
        K = stiffness_matrix(chain)
        C = damping_matrix(chain)
        if SX is not None and SY is not None:
            K[:n, :n] += load_stiffness(chain.l, phi0, SX, SY)
        return M, C, K
    system = ReducedSystem(
        Scene(chain=chain, t_end=1.0, initial=InitialState(phi=phi0)), coefficients, kernel="numpy"
    )
    M = system.reduced_matrices(phi0)[0]
    K = system.K_r.copy()
    if SX is not None and SY is not None:
        K += load_stiffness(chain.l, phi0, SX, SY)
    return M, system.C_r.copy(), K


def linear_matrices(
    chain: Chain, model: str = "full", phi0: Any = None, coefficients: str = DEFAULT_VARIANT
) -> tuple[np.ndarray, np.ndarray]:
    """(M, K) of the unloaded linearized model about phi0 (default straight along x)."""
    M, _, K = linear_system(chain, model, phi0, coefficients)
    return M, K


def _node_transform(chain: Chain, model: str) -> tuple[np.ndarray, np.ndarray]:
    """T with q = T z, z = per rod [y_k, (alpha_k, beta_k)] (rod-major), phi_k = (y_k -
    y_{k-1}) / l_k; and the rod index of each z coordinate."""
    n = chain.n
    per = 3 if model == "full" else 1
    Tp = (np.eye(n) - np.eye(n, k=-1)) / chain.l[:, None]
    T = np.eye(per * n)
    T[:n, :n] = Tp
    perm = np.arange(per * n).reshape(per, n).T.ravel()  # rod-major ordering of z
    return T[:, perm], np.repeat(np.arange(n), per)


def _qz_run(Kz: np.ndarray, Mz: np.ndarray, rod: np.ndarray, rho: float) -> dict[str, Any] | None:
    """QZ of the pencil (Kz, Mz) (rod-major node displacements) under the exact similarity
    diag(rho^rod) (``_general_eig``): its eigenvalues, right eigenvectors, first-order error
    estimates and which are real; None when QZ returns an infinite or NaN eigenvalue. The
    scaling multiplies an entry (i, j) by rho^(rod_j - rod_i): on a dense pencil (the reduced
    model's condensed bending couples every rod) rho^59 = 3e35 (rho = 4, 60 rods) drowns the
    near-diagonal entries, QZ then finds beta = 0 (59 infinite eigenvalues for 60 rods of
    0.1 m, EI 1e6 N m^2), and such a run carries nothing to match (the Hungarian matching
    of ``_general_eig`` needs finite distances: scipy's "cost matrix is infeasible")."""
    eps = np.finfo(float).eps
    # D^-1 X D with D = diag(rho^rod): entry (i, j) times rho^(rod_j - rod_i); entries far
    # from the band are (near) zero in the straight configuration; the exponent is clipped
    # so that a bent configuration cannot overflow.
    S = np.float64(rho) ** np.clip(rod[None, :] - rod[:, None], -60, 60)
    Ks, Ms = Kz * S, Mz * S
    lam, VL, VR = scipy.linalg.eig(Ks, Ms, left=True, right=True)
    if not np.all(np.isfinite(lam)):
        return None
    kappa = (
        np.linalg.norm(VL, axis=0)
        * np.linalg.norm(VR, axis=0)
        / np.maximum(np.abs(np.sum(VL.conj() * (Ms @ VR), axis=0)), 1e-300)
    )
    err = eps * (np.linalg.norm(Ks, 2) + np.abs(lam) * np.linalg.norm(Ms, 2)) * kappa
    real = np.abs(lam.imag) <= IMAG_TOL * np.max(np.abs(lam))
    return {"rho": rho, "lam": lam, "VR": VR, "err": err, "real": real}


def _general_eig(
    K: np.ndarray, M: np.ndarray, chain: Chain, model: str, vectors: bool = True
) -> tuple[np.ndarray, np.ndarray | None, dict[str, Any]]:
    """Eigenvalues (and right eigenvectors in q) of K x = lam M x for a non-symmetric M, by QZ
    on the equivalent pencil in rod-major node displacements with the exact similarity
    diag(rho^k) per rod, for each rho of ``RHO`` (see the module docstring).

    Each run gives first-order error estimates err = eps (|K| + |lam| |M|) kappa_lam from its
    left and right eigenvectors (kappa_lam = |y| |x| / |y^H M x|). The spectrum starts from the
    run with the fewest complex eigenvalues (then the smallest median relative estimate), its
    complex ones unresolved; then, run by run, its eigenvalues are matched one-to-one
    (Hungarian, on the distance) with the run's, and each is replaced by its match when that
    one is real, has a smaller estimate and lies within the two estimates (an unresolved one:
    by any real match). The geometric scaling that conditions the tip-localized bending
    cluster de-conditions the extended low modes, which the unscaled run gets right. Returns (lam,
    X, info); lam is complex when no rho gave a
    real spectrum (the caller decides)."""
    T, rod = _node_transform(chain, model)
    Kz, Mz = T.T @ K @ T, T.T @ M @ T
    runs = [r for r in (_qz_run(Kz, Mz, rod, rho) for rho in RHO) if r is not None]
    if not runs:
        raise ValueError(
            "the linearized pencil has infinite eigenvalues in every scaling (its mass matrix "
            "is singular to working precision)"
        )

    def rel(r: dict[str, Any]) -> float:
        return float(np.median(r["err"] / np.maximum(np.abs(r["lam"]), 1e-300)))

    base = min(runs, key=lambda r: (int(np.sum(~r["real"])), rel(r)))
    lam = base["lam"].copy()
    err = np.where(base["real"], base["err"], np.inf)  # complex entries: unresolved
    src = [(base, i) for i in range(lam.size)]
    for r in sorted((r for r in runs if r is not base), key=rel):
        # one-to-one matching of the current spectrum with this run's eigenvalues
        rows, cols = linear_sum_assignment(np.abs(lam[:, None] - r["lam"][None, :]))
        for i, j in zip(rows, cols):
            mu, e = r["lam"][j], r["err"][j]
            if r["real"][j] and e < err[i] and (np.isinf(err[i]) or abs(mu - lam[i]) <= err[i] + e):
                lam[i], err[i], src[i] = mu.real, e, (r, j)
    if np.all(np.isfinite(err)):
        lam = lam.real
    X = None
    if vectors:
        X = np.column_stack([T @ ((np.float64(r["rho"]) ** rod) * r["VR"][:, j]) for r, j in src])
        if np.isrealobj(lam):
            X = X.real
    order = np.argsort(lam.real)
    return (
        lam[order],
        None if X is None else X[:, order],
        {"rho": [src[i][0]["rho"] for i in order], "error_estimate": err[order]},
    )


def eigen(
    K: np.ndarray, M: np.ndarray, chain: Chain, model: str, vectors: bool = True
) -> tuple[np.ndarray, np.ndarray | None]:
    """omega^2 (real, ascending) and the eigenvectors (columns) of K x = omega^2 M x."""
    if np.allclose(M, M.T, rtol=0, atol=1e-13 * np.max(np.abs(M))):
        return symmetric_pencil(K, M, vectors=vectors)
    lam, X, _ = _general_eig(K, M, chain, model, vectors)
    if np.max(np.abs(lam.imag)) > IMAG_TOL * np.max(np.abs(lam)):
        raise ValueError("linearized system has complex eigenvalues (non-oscillatory modes)")
    order = np.argsort(lam.real)
    # QZ's absolute round-off is ~eps |lam|_max: below 1e-13 of it an eigenvalue is a zero mode
    lam = lam.real[order]
    lam = np.where(np.abs(lam) <= ZERO_TOL * np.max(np.abs(lam)), 0.0, lam)
    return lam, (None if X is None else np.real_if_close(X[:, order], tol=1e8).real)


def natural_frequencies(
    chain: Chain, model: str = "full", phi0: Any = None, coefficients: str = DEFAULT_VARIANT
) -> np.ndarray:
    """Natural angular frequencies (rad/s) of the unloaded model about phi0, ascending."""
    M, K = linear_matrices(chain, model, phi0, coefficients)
    lam, _ = eigen(K, M, chain, model, vectors=False)
    return np.sort(np.sqrt(np.clip(lam, 0.0, None)))


# -- modes --------------------------------------------------------------------------------------
def node_shapes(
    chain: Chain,
    model: str,
    phi0: np.ndarray,
    X: np.ndarray,
    lam: np.ndarray,
    M: np.ndarray | None = None,
    coefficients: str = DEFAULT_VARIANT,
    recover: Callable[[np.ndarray, float], np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node displacements and hinge angles of eigenvectors X (columns); the reduced model's
    bending from its bending rows at each mode's eigenvalue, or by ``recover`` (dphi, lam)
    -> gamma (with held hinges, ``held_reduced``)."""
    n, l = chain.n, chain.l
    if model == "full":
        Q = X.T  # (count, 3n)
    else:
        K = stiffness_matrix(chain)
        Mfull = mass_matrix(chain_constants(chain, coefficients), phi0)
        g, p = slice(n, 3 * n), slice(0, n)
        B = K[g, g]
        Q = np.zeros((X.shape[1], 3 * n))
        for i in range(X.shape[1]):
            dphi = X[:, i]
            Q[i, :n] = dphi
            Q[i, n:] = (
                recover(dphi, lam[i])
                if recover is not None
                else -np.linalg.solve(B, (K[g, p] - lam[i] * Mfull[g, p]) @ dphi)
            )
    dphi = Q[:, :n]
    dx = np.hstack([np.zeros((Q.shape[0], 1)), np.cumsum(-l * np.sin(phi0) * dphi, axis=1)])
    dy = np.hstack([np.zeros((Q.shape[0], 1)), np.cumsum(l * np.cos(phi0) * dphi, axis=1)])
    hinge = Q @ hinge_matrix(n).T
    return normalize_shapes(dx, dy, hinge)


def mac(a: np.ndarray, b: np.ndarray) -> float:
    """Modal assurance criterion |a.b|^2 / ((a.a)(b.b)) of two real shape vectors."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    den = float(a @ a) * float(b @ b)
    return float((a @ b) ** 2 / den) if den > 0 else 0.0


def modes(
    scene: Scene,
    model: str = "full",
    *,
    about: str = "initial",
    count: int | None = None,
    coefficients: str = DEFAULT_VARIANT,
    load_at: float | None = None,
    allow_unbalanced: bool = False,
    shapes: int = 1,
    kinematics: str = "first-order",
) -> Modes:
    """Linearized modes of the native ``model`` ("full" or "reduced"; the full model on any
    rung of the ladder: ``shapes``, ``kinematics``) about the scene's
    initial state at rest (``check_at_rest`` unless ``allow_unbalanced``) or its static
    equilibrium under its static loads (``rodval.mechanics.modal.static_loads``: the loads acting
    for ever, or every load at ``load_at`` s) and hinge rest angles (see module docstring).
    ``count``: the lowest ``count`` modes (default all)."""
    check_arguments(scene, count)
    check_choice("model", model, PAPER_MODELS)
    rung = (check_shapes(shapes), check_kinematics(kinematics, auto=True))
    if model != "full" and rung != PAPER_RUNG:
        raise ValueError(
            f"shapes and kinematics are options of the full model, not of {model!r} "
            "(docs/model.md, 'The model ladder')"
        )
    balance = check_configuration(scene, about, load_at, allow_unbalanced)
    m = modes_about(
        scene,
        model,
        about=about,
        count=count,
        coefficients=coefficients,
        load_at=load_at,
        shapes=shapes,
        kinematics=kinematics,
    )
    m.info.update(balance)
    return m


def modes_about(
    scene: Scene,
    model: str,
    *,
    about: str,
    count: int | None,
    coefficients: str = DEFAULT_VARIANT,
    load_at: float | None = None,
    shapes: int = 1,
    kinematics: str = "first-order",
) -> Modes:
    """``modes`` about a configuration already checked (``check_configuration``): the
    static equilibrium when asked for, the linear system, its eigen-solution and shapes.
    Dense: O(N^3) for the N = 3n (full; n (p + 2) on a ladder rung) or n (reduced)
    coordinates. ``kinematics = "auto"`` is resolved as a run's is (``auto_kinematics``)."""
    if model == FullModel.name:
        kinematics = resolve_kinematics(kinematics, scene, coefficients)
    if scene.base.moving:
        if not (scene.base.free and model == FullModel.name):
            raise ValueError(
                f"model {model!r}: modes of a chain on a {scene.base.kind} base are not built "
                "(the full model has them on a free base, docs/base.md)"
            )
        from rodval.models.observation.free_modes import free_modes

        return free_modes(
            scene,
            about=about,
            count=count,
            coefficients=coefficients,
            load_at=load_at,
            shapes=shapes,
            kinematics=kinematics,
        )
    chain, n = scene.chain, scene.n
    held = check_held(scene, model, coefficients)
    q0, eq, SX, SY = _configuration(scene, about, load_at)
    M, C, K = linear_system(chain, model, q0, coefficients, SX, SY, shapes, kinematics)
    M, C, K, Z, recover = _held_pencil(scene, model, (M, C, K), q0, (coefficients, SX, SY))
    lam, X = eigen(K, M, chain, model)
    assert X is not None
    lam, X, omega, zeta = lowest(lam, X, (M, C, K), count)
    X = X if Z is None else Z @ X
    # node displacements and hinge angles need phi, alpha, beta only (bubbles: zero at the ends)
    displacements = node_shapes(
        chain, model, q0[:n], X[: 3 * n], lam, coefficients=coefficients, recover=recover
    )
    return chain_modes(
        model,
        about,
        omega,
        zeta,
        displacements,
        phi0=q0[:n].copy(),
        l=chain.l.copy(),
        equilibrium=eq,
        info={
            "coefficients": coefficients,
            "q0": q0,
            "shapes": shapes,
            "kinematics": kinematics,
            "held_hinges": held.tolist(),
        },
    )


def check_held(scene: Scene, model: str, coefficients: str) -> np.ndarray:
    """The scene's held hinges (``held_hinges``), after the check that ``model`` holds them
    with these ``coefficients``: the full model on its symmetric (printed) mass matrix only
    (ValueError naming the held hinges otherwise; the reduced model takes both)."""
    held = held_hinges(scene)
    if held.size and model == FullModel.name and coefficients != DEFAULT_VARIANT:
        raise ValueError(
            f"held latches (hinges {held.tolist()}): the full model's modes hold them on its "
            f"symmetric mass matrix, coefficients={DEFAULT_VARIANT!r}; got "
            f"coefficients={coefficients!r} (the reduced model takes both)"
        )
    return held


def _configuration(
    scene: Scene, about: str, load_at: float | None
) -> tuple[np.ndarray, Equilibrium | None, np.ndarray | None, np.ndarray | None]:
    """(q0 = [phi; alpha; beta] (rad) the modes are about, its static solve or None, the
    static loads' suffix sums SX, SY (N) or None): the initial state, or the static
    equilibrium under the static loads and hinge rest angles with the held latches held
    (``static_equilibrium`` on ``held_basis``)."""
    chain, n = scene.chain, scene.n
    ini = scene.initial.resolve(n)
    q0 = np.concatenate([ini["phi"], ini["alpha"], ini["beta"]])
    if about != "equilibrium":
        return q0, None, None, None
    loads = static_loads(scene, load_at)
    eq = static_equilibrium(
        chain, loads.SX, loads.SY, q0=q0, rest=chain.rest_angle, held=held_basis(scene)
    )
    eq.loads = loads
    if not eq.converged:
        raise ValueError(no_equilibrium(chain, eq, held_hinges(scene)))
    return eq.q, eq, loads.SX, loads.SY


def _held_pencil(
    scene: Scene, model: str, MCK: tuple[np.ndarray, ...], q0: np.ndarray, variant: tuple[Any, ...]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None, Callable[..., np.ndarray] | None]:
    """The linear system (M, C, K) = ``MCK`` with the scene's held latches held: (M, C, K) in
    the coordinates it is solved in, Z mapping them back to q (None: q itself) and the
    reduced model's bending recovery (None: the model's own). Full model (every rung): the
    exact basis Z of ``held_basis``, Z^T M Z, Z^T C Z, Z^T K Z. Reduced model: its bending
    condensed with the held hinges as equations (``held_reduced``; ``variant`` = the
    coefficients and static loads' SX, SY it is linearized with)."""
    M, C, K = MCK
    held = held_hinges(scene)
    if not held.size:
        return M, C, K, None, None
    if model == FullModel.name:
        Z = held_basis(scene, M.shape[0])
        assert Z is not None
        return Z.T @ M @ Z, Z.T @ C @ Z, Z.T @ K @ Z, Z, None
    n = scene.n
    full = linear_system(scene.chain, FullModel.name, q0, *variant)
    M_r, C_r, K_r, gamma = held_reduced(full, hinge_matrix(n)[held], n)
    return M_r, C_r, K_r, None, gamma


def check_configuration(
    scene: Scene, about: str, load_at: float | None, allow_unbalanced: bool
) -> dict[str, float]:
    """The checks of what every model's modes are about, before any work: ``about`` among
    ``ABOUT``; ``load_at`` (equilibrium only) a time >= 0 or None, and the scene's loads with a
    static value (``static_loads``); for ``about="initial"`` the state at rest in equilibrium
    (``check_at_rest``) unless ``allow_unbalanced``, whose residual is then returned as
    ``{"unbalanced_residual_Nm": r}`` for the record."""
    check_choice("about", about, ABOUT)
    if not isinstance(allow_unbalanced, bool):
        raise ValueError(f"allow_unbalanced must be True or False, got {allow_unbalanced!r}")
    if about == "equilibrium":
        if allow_unbalanced:
            raise ValueError("allow_unbalanced applies to about='initial' only")
        static_loads(scene, load_at)
        return {}
    if load_at is not None:
        raise ValueError(
            "load_at applies to about='equilibrium' only (loads are left out about the "
            "initial state)"
        )
    if not allow_unbalanced:
        check_at_rest(scene)
        return {}
    ini = scene.initial.resolve(scene.n)
    q0 = np.concatenate([ini["phi"], ini["alpha"], ini["beta"]])
    R = balance_residual(scene, q0, body_rest_angles(scene))
    return {"unbalanced_residual_Nm": float(np.max(np.abs(R)))}


#: ``FullModel.MODAL_ANALYSIS`` and ``ReducedModel.MODAL_ANALYSIS``: f(scene, *, about, count,
#: load_at, coefficients, ...) -> Modes, the form ``Model.modes`` calls
full_modes = partial(modes_about, model=FullModel.name)
reduced_modes = partial(modes_about, model=ReducedModel.name)
#: The full model has modes on a free base (``rodval.models.observation.free_modes``: its three rigid
#: modes separated), on every rung; ``Model.modes`` refuses a free base to the others.
full_modes.FREE_BASE = True  # type: ignore[attr-defined]
