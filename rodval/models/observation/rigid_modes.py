"""Linearized modes of the rigid model (``rodval.models.presets.rigid``): the full model's
linear system (``linear_modes.linear_system``, the paper's rung, printed coefficients) on the
exact basis of the rigid motions, the limit EI -> inf of its modes.

A rigid motion has alpha = beta = 0 and every held hinge (``Latch.held``) at its angle: in the
hinge angles D_k = phi_k - phi_{k-1} (pinned base), phi = L D with L the lower triangle of
ones, so the columns of L of the free hinges, padded with zeros for alpha and beta, are an
exact basis Z (3n, r) of those motions (``rigid_basis``). The pencil Z^T (M, C, K + K_L) Z is
the rigid chain's: M_pp(phi0) with its far nodes, the hinge springs and dampers A^T kappa A,
A^T nu A and the load stiffness. The equilibrium about which ``about="equilibrium"`` linearizes
is the full model's static solve on the same basis (``statics.static_equilibrium`` with
``held=Z``), i.e. the rigid chain's. O(n^3), dense.
"""

from __future__ import annotations

import numpy as np

from rodval.core.modes import Modes
from rodval.core.scene import Scene
from rodval.mechanics.eigen import symmetric_pencil
from rodval.mechanics.modal import held_hinges, static_loads
from rodval.models.observation.linear_modes import linear_system, node_shapes
from rodval.models.observation.mode_sets import chain_modes, lowest
from rodval.models.observation.statics import no_equilibrium, static_equilibrium

#: The name the modes carry.
RIGID = "rigid"


def rigid_basis(scene: Scene) -> np.ndarray:
    """Z (3n, n - m): q = [phi; alpha; beta] = Z u exactly the rigid motions that keep the
    scene's m held hinges (module docstring); u are the free hinges' angle increments."""
    n = scene.n
    free = np.setdiff1d(np.arange(n), held_hinges(scene))
    Z = np.zeros((3 * n, free.size))
    Z[:n] = np.tril(np.ones((n, n)))[:, free]
    return Z


def rigid_modes(
    scene: Scene,
    *,
    about: str = "initial",
    count: int | None = None,
    load_at: float | None = None,
) -> Modes:
    """The rigid chain's modes about the scene's initial state (its phi; the rods straight)
    or its static equilibrium under the static loads (``rodval.mechanics.modal.static_loads``)
    and the hinge rest angles: Modes with the node displacements and hinge angles of each
    mode (``linear_modes.node_shapes``), the lowest ``count`` (default all). The configuration
    check (at rest, balanced) is the caller's (``rodval.analysis.modes``). Pinned base only
    (``Model.modes`` refuses the others: ``rigid_modes`` has no ``FREE_BASE``)."""
    chain, n = scene.chain, scene.n
    Z = rigid_basis(scene)
    if not Z.shape[1]:
        raise ValueError(
            "rigid model: every hinge is held (latches held from t = 0), so the rigid chain "
            "has no motion and no modes; the full model or exudyn has the held chain's bending "
            "modes"
        )
    q0 = np.zeros(3 * n)
    q0[:n] = scene.initial.resolve(n)["phi"]
    eq, SX, SY = None, None, None
    if about == "equilibrium":
        loads = static_loads(scene, load_at)
        eq = static_equilibrium(chain, loads.SX, loads.SY, q0=q0, rest=chain.rest_angle, held=Z)
        eq.loads = loads
        if not eq.converged:
            raise ValueError(no_equilibrium(chain, eq, held_hinges(scene)))
        q0, SX, SY = eq.q, loads.SX, loads.SY
    M, C, K = (Z.T @ A @ Z for A in linear_system(chain, "full", q0, "printed", SX, SY))
    lam, X = symmetric_pencil(K, M)
    assert X is not None
    lam, X, omega, zeta = lowest(lam, X, (M, C, K), count)
    shapes = node_shapes(chain, "full", q0[:n], Z @ X, lam)
    return chain_modes(
        RIGID,
        about,
        omega,
        zeta,
        shapes,
        phi0=q0[:n].copy(),
        l=chain.l.copy(),
        equilibrium=eq,
        info={"q0": q0, "held_hinges": held_hinges(scene).tolist()},
    )
