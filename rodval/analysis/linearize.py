"""Linearized free vibration of the paper's models about a configuration at rest.

About phi = phi0, alpha = beta = 0, q' = 0 with no load and no damping, the convective terms
(quadratic in the rates) vanish and both models reduce to M q'' + K q = 0 (full: M(phi0), K;
reduced: M_r(phi0), K_r). Natural angular frequencies (rad/s) are the square roots of the
generalized eigenvalues of (K, M), ascending; rigid-body (zero-stiffness) modes give 0.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from rodval.core.scene import Chain, InitialState, Scene
from rodval.models.full import FullSystem
from rodval.models.reduced import ReducedSystem

_SYSTEMS = {"full": FullSystem, "reduced": ReducedSystem}


def linear_matrices(
    chain: Chain, model: str = "full", phi0=None, coefficients: str = "printed"
) -> tuple[np.ndarray, np.ndarray]:
    """(M, K) of the linearized model about phi0 (default: straight along x)."""
    if model not in _SYSTEMS:
        raise ValueError(f"model must be one of {tuple(_SYSTEMS)}, got {model!r}")
    scene = Scene(chain=chain, t_end=1.0, initial=InitialState(phi=phi0))
    system = _SYSTEMS[model](scene, coefficients)
    phi = system.initial["phi"]
    if model == "full":
        from rodval.models.paper_matrices import mass_matrix

        return mass_matrix(system.cc, phi), system.K
    return system.reduced_matrices(phi)[0], system.K_r


def natural_frequencies(
    chain: Chain, model: str = "full", phi0=None, coefficients: str = "printed"
) -> np.ndarray:
    """Natural angular frequencies (rad/s), ascending."""
    M, K = linear_matrices(chain, model, phi0, coefficients)
    lam = scipy.linalg.eigvals(K, M)
    if np.max(np.abs(lam.imag)) > 1e-8 * np.max(np.abs(lam)):
        raise ValueError("linearized system has complex eigenvalues (non-oscillatory modes)")
    return np.sort(np.sqrt(np.clip(lam.real, 0.0, None)))
