"""Modes of the full model on a free base (a spacecraft body), on every rung of the ladder.

The system is the one the full model integrates (``chain_system.chain_system``: the paper's
rung's ``ChainSystem``, a ``LadderSystem`` on the others), coordinates Q = [q; x_c, y_c,
theta] (N = Nc + 3, Nc = 3n or n (p + 2)). About a configuration Q0 at rest

    M(Q0) dQ'' + C dQ' + K dQ = 0

with

* M: the whole system's mass matrix (body included), from the system's compiled kinetic
  energy T(Q0, Q') = 1/2 Q'^T M Q' by polarization (exact: T is quadratic in the rates):
  M_ii = 2 T(e_i), M_ij = (T(a e_i + b e_j) - T(a e_i - b e_j)) / (2 a b) with a, b =
  M_ii^-1/2, M_jj^-1/2 (every T of order 1, so a heavy body's entries do not swamp the
  chain's in round-off); ``mass_matrix``; the pencils are solved in coordinates scaled by powers of
  two to a mass diagonal near 1 (exact: the same eigenvalues, K's null space kept exactly; a
  heavy body's scale kept out of the chain's digits);
* K = A^T diag(kappa) A + the rods' bending blocks (and bubbles on a ladder rung), A the
  hinge rows of the system (``hinge_rows``: hinge 0's row has -1 at theta, its angle measured
  from the body); the body's x_c, y_c have no stiffness; C likewise with the dampers nu and
  the rods' bending damping;
* no load stiffness: about the initial state loads are left out (free vibration), and a free
  body under static loads has no static equilibrium (it accelerates), so
  ``about="equilibrium"`` is refused when the scene has static loads; without them the
  equilibrium is the body's attitude theta with straight rods at the hinges' rest angles
  (phi_k = theta + rest_0 + ... + rest_{k-1}; a held latch's angle on its hinge).
* held latches (``rodval.mechanics.modal.held_hinges``): their hinges' relative rotation fixed,
  the pencil taken on the exact basis Z of the motions that keep them
  (``rodval.mechanics.eigen.constraint_basis``): Z^T M Z, Z^T K Z, Z^T C Z.

K has the three rigid motions as its null space (translations x, y; a rotation of the whole
system, theta and every phi_k together), so the undamped pencil (``symmetric_pencil``,
shifted for the singular K) has three zero eigenvalues. They are separated from the flexible
modes by ``rodval.mechanics.modal.split_rigid``: the three smallest, checked to be below 1e-6 of
the first flexible omega, their span checked to hold the two translations and a rigid
rotation (about the system's centre of mass: the combination M-orthogonal to the
translations) to 1e-4 of the shapes; they are reported first (``Modes.rigid`` = 3), without
damping ratio (NaN), and ``count`` counts the flexible modes.

Mode shapes: node 0 moves with the body, dr_0 = dr_c + dtheta k x R(theta0) h (h the hinge
offset); node k adds the chords' -l_j sin(phi_j) dphi_j, l_j cos(phi_j) dphi_j; hinge angles
D = A dQ (hinge 0 from the body).
"""

from __future__ import annotations

import numpy as np

from rodval.core.modes import Modes
from rodval.core.scene import Chain, Scene
from rodval.mechanics.eigen import angular_frequencies, constraint_basis, symmetric_pencil
from rodval.mechanics.modal import (
    check_no_mechanism,
    damping_ratios,
    equilibrium_angles,
    held_hinges,
    normalize_shapes,
    split_rigid,
    static_loads,
)
from rodval.models.assembly.paper_matrices import damping_matrix, stiffness_matrix
from rodval.models.kinematics.ladder import ladder_stiffness
from rodval.models.kinematics.rungs import check_shapes, resolve_kinematics
from rodval.models.observation.mode_sets import chain_modes
from rodval.models.systems.chain_system import ChainSystem, chain_system

#: The model these modes are of (its registry name, ``presets.full.FullModel.name``).
MODEL = "full"
#: The coefficients of the full model on a moving base (its compiled kernels).
FREE_COEFFICIENTS = "printed"


def free_system(scene: Scene, shapes: int = 1, kinematics: str = "first-order") -> ChainSystem:
    """The full model's system of ``scene`` on a free base (``chain_system``)."""
    return chain_system(scene, shapes, kinematics)


def mass_matrix(system: ChainSystem, Q0: np.ndarray) -> np.ndarray:
    """The whole system's M(Q0) (N, N), symmetric, by polarization of the system's
    ``kinetic_energy`` in the rates (module docstring). O(N^2) evaluations of T."""
    N = system.N
    y = np.zeros(2 * N)
    y[:N] = Q0

    def T(v: np.ndarray) -> float:
        y[N:] = v
        return system.kinetic_energy(0.0, y)

    eye = np.eye(N)
    d = np.array([2.0 * T(eye[i]) for i in range(N)])
    if np.any(d <= 0):
        raise ValueError("the free system's mass matrix is not positive definite")
    s = 1.0 / np.sqrt(d)
    M = np.diag(d)
    for i in range(N):
        for j in range(i):
            a, b = s[i] * eye[i], s[j] * eye[j]
            M[i, j] = M[j, i] = (T(a + b) - T(a - b)) / (2.0 * s[i] * s[j])
    return M


def stiffness_and_damping(
    system: ChainSystem, chain: Chain, shapes: int
) -> tuple[np.ndarray, np.ndarray]:
    """(K, C) (N, N) of the free system: the chain's hinge springs (dampers) on the system's
    hinge rows (hinge 0 from theta) plus its rods' bending (and bubble) blocks."""
    n, Nc, N = chain.n, system.Nc, system.N
    A = system.hinge_rows(np.arange(n))
    Ac = A[:, :Nc]
    if Nc == 3 * n:
        Kc, Cc = stiffness_matrix(chain), damping_matrix(chain)
    else:
        Kc, Cc = ladder_stiffness(chain, shapes), ladder_stiffness(chain, shapes, damping=True)
    out = []
    for Bc, w in ((Kc, chain.kappa), (Cc, chain.nu)):
        B = np.zeros((N, N))
        B[:Nc, :Nc] = Bc - Ac.T @ (w[:, None] * Ac)
        out.append(B + A.T @ (w[:, None] * A))
    return out[0], out[1]


def configuration(
    system: ChainSystem, scene: Scene, about: str, load_at: float | None
) -> np.ndarray:
    """Q0 (N): the initial state's positions, or (``about="equilibrium"``, no static loads)
    the body's attitude with straight rods at the hinges' rest angles (a held latch's angle
    on its hinge, ``equilibrium_angles``)."""
    Q0 = np.array(system.y0[: system.N], float)
    if about != "equilibrium":
        return Q0
    loads = static_loads(scene, load_at)
    if loads.any:
        raise ValueError(
            "a free base under static loads has no static equilibrium (the body accelerates); "
            "use about='initial' (free vibration, loads left out)"
        )
    n, Nc = scene.n, system.Nc
    theta = Q0[Nc + 2]
    Q0[:Nc] = 0.0
    Q0[:n] = theta + np.cumsum(equilibrium_angles(scene))
    return Q0


def held_free_basis(system: ChainSystem, scene: Scene) -> np.ndarray | None:
    """Z (N, N - m): the motions of the free system that keep the scene's m held hinges at
    their angles (``constraint_basis`` of their hinge rows, hinge 0's from the body's
    theta; each eliminates its alpha_k), or None without held latches."""
    held = held_hinges(scene)
    return constraint_basis(system.hinge_rows(held)) if held.size else None


def free_residual(
    K: np.ndarray, A: np.ndarray, Q0: np.ndarray, chain: Chain, Z: np.ndarray | None
) -> float:
    """The springs' and bending's static residual max |K Q0 - A^T kappa rest| (N m; K (N, N),
    A (n, N) the hinge rows, Q0 (N)) that no held latch carries (Z^T of it with the held
    basis Z, ``held_free_basis``; None: none held). The caller checked it is small."""
    R = K @ Q0 - A.T @ (chain.kappa * chain.rest_angle)
    return float(np.max(np.abs(R if Z is None else Z.T @ R)))


def check_free_base(scene: Scene, coefficients: str) -> None:
    """ValueError unless ``scene`` has a free base and ``coefficients`` is
    ``FREE_COEFFICIENTS`` (the moving bases are built on the compiled kernels)."""
    if not scene.base.free:
        raise ValueError(f"free_modes needs a free base, got kind {scene.base.kind!r}")
    check_no_mechanism(scene)
    if coefficients != FREE_COEFFICIENTS:
        raise ValueError(
            f"full model on a free base: coefficients must be {FREE_COEFFICIENTS!r} (the "
            f"moving bases are built on the compiled kernels, docs/base.md), got {coefficients!r}"
        )


def scaled_pencil(
    M: np.ndarray, K: np.ndarray, C: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The undamped pencil K x = lam M x solved in coordinates scaled to a mass diagonal
    within a factor 2 of 1: D M D, D K D (and D C D), D = the powers of two nearest
    diag(M)^-1/2 (exact, so K's null space stays exact; eigenvalues unchanged, x = D x'). A
    heavy body's 1e9 kg would otherwise set the shift and the Cholesky factors' round-off for
    the chain's entries of order 1. M, K, C (N, N) in the system's coordinates (kg, N/m,
    N s/m and their rotational counterparts).

    Returns (lam (N,) ascending, 1/s^2; X (N, N) the eigenvectors in the system's
    coordinates, columns; Xs (N, N) the same in the scaled coordinates, M-orthonormal there;
    (Ms, Ks, Cs) the scaled matrices)."""
    Dm = np.exp2(np.round(-0.5 * np.log2(np.diag(M))))
    Ms, Ks, Cs = (Dm[:, None] * B * Dm[None, :] for B in (M, K, C))
    lam, Xs = symmetric_pencil(Ks, Ms)
    if Xs is None:  # symmetric_pencil returns vectors unless vectors=False
        raise RuntimeError("symmetric_pencil returned no eigenvectors")
    return lam, Dm[:, None] * Xs, Xs, (Ms, Ks, Cs)


def mode_shapes(
    scene: Scene, Q: np.ndarray, Q0: np.ndarray, Nc: int, A: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Node displacements and hinge angles of the modes Q (modes, N) (rows in the system's
    coordinates [q; x_c, y_c, theta]: rad for the chord angles and theta, m for x_c, y_c)
    about Q0 (N), module docstring: node 0 moves with the body, node k adds the chords'
    rotations; A (n, N) the hinge rows (hinge 0 from the body).

    Returns (dx, dy (modes, n+1), m per unit of the mode's coordinates; hinge (modes, n),
    rad per the same unit; xn, yn (n+1), the nodes' coordinates at Q0 relative to node 0, m).
    """
    chain, n, N = scene.chain, scene.n, Q.shape[0]
    phi0, theta0 = Q0[:n], Q0[Nc + 2]
    dphi, body = Q[:, :n], Q[:, Nc:]
    c, s = np.cos(theta0), np.sin(theta0)
    h = np.asarray(scene.base.hinge_offset, float)
    rho = np.array([c * h[0] - s * h[1], s * h[0] + c * h[1]])
    dx0 = body[:, 0] - rho[1] * body[:, 2]
    dy0 = body[:, 1] + rho[0] * body[:, 2]
    l = chain.l
    dx = dx0[:, None] + np.hstack([np.zeros((N, 1)), np.cumsum(-l * np.sin(phi0) * dphi, axis=1)])
    dy = dy0[:, None] + np.hstack([np.zeros((N, 1)), np.cumsum(l * np.cos(phi0) * dphi, axis=1)])
    hinge = Q @ A.T
    xn = np.concatenate([[0.0], np.cumsum(l * np.cos(phi0))])
    yn = np.concatenate([[0.0], np.cumsum(l * np.sin(phi0))])
    return dx, dy, hinge, xn, yn


def free_modes(
    scene: Scene,
    *,
    about: str = "initial",
    count: int | None = None,
    coefficients: str = FREE_COEFFICIENTS,
    load_at: float | None = None,
    shapes: int = 1,
    kinematics: str = "first-order",
) -> Modes:
    """Modes of the full model (any rung: ``shapes``, ``kinematics``) of a chain on a free
    base, about its initial state at rest or its unloaded equilibrium (module docstring): the
    three rigid modes first (``Modes.rigid`` = 3, omega ~ 0: translation x, translation y,
    rotation about the system's centre of mass), then the lowest ``count`` flexible modes
    (default all). The configuration check (at rest, balanced) is the caller's
    (``check_configuration``). Dense: O(N^2) evaluations of T and O(N^3) eigensolves."""
    check_free_base(scene, coefficients)
    p, kin = check_shapes(shapes), resolve_kinematics(kinematics, scene, coefficients)
    chain, n = scene.chain, scene.n
    system = free_system(scene, p, kin)
    Nc = system.Nc
    Q0 = configuration(system, scene, about, load_at)
    M = mass_matrix(system, Q0)
    K, C = stiffness_and_damping(system, chain, p)
    A = system.hinge_rows(np.arange(n))
    Z = held_free_basis(system, scene)
    residual = free_residual(K, A, Q0, chain, Z)
    if Z is not None:  # the held hinges held: the pencil on the motions that keep them
        M, K, C = (Z.T @ B @ Z for B in (M, K, C))
    lam, X, Xs, (Ms, Ks, Cs) = scaled_pencil(M, K, C)
    X = X if Z is None else Z @ X
    dx, dy, hinge, xn, yn = mode_shapes(scene, X.T, Q0, Nc, A)
    l = chain.l
    lam, dx, dy, hinge, rigid = split_rigid(lam, dx, dy, hinge, xn, yn, float(np.mean(l)))
    flex = Xs[:, 3:]
    total = lam.size - 3 if count is None else min(int(count), lam.size - 3)
    lam, dx, dy, hinge, flex = (
        lam[: 3 + total],
        dx[: 3 + total],
        dy[: 3 + total],
        hinge[: 3 + total],
        flex[:, :total],
    )
    omega = angular_frequencies(lam)
    zeta = np.full(omega.size, np.nan)
    zeta[3:] = damping_ratios(Ms, Cs, Ks, flex, omega[3:])
    return chain_modes(
        MODEL,
        about,
        omega,
        zeta,
        normalize_shapes(dx, dy, hinge),
        phi0=Q0[:n].copy(),
        l=l.copy(),
        info={
            "coefficients": coefficients,
            "q0": Q0,
            "shapes": p,
            "kinematics": kin,
            "base": "free",
            "static_residual_Nm": residual,
            "held_hinges": held_hinges(scene).tolist(),
            **rigid,
        },
        rigid=3,
    )
