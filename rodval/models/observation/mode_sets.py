"""What every native modal analysis ends with (``linear_modes``, ``rigid_modes``,
``free_modes``): the lowest modes of a pencil with their damping ratios, and the ``Modes`` of a
chain about a configuration."""

from __future__ import annotations

from typing import Any

import numpy as np

from rodval.core.modes import Modes
from rodval.mechanics.eigen import angular_frequencies
from rodval.mechanics.modal import damping_ratios

#: (M, C, K) of a linear system, each (N, N)
Pencil = tuple[np.ndarray, np.ndarray, np.ndarray]


def lowest(
    lam: np.ndarray, X: np.ndarray, MCK: Pencil, count: int | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(lam, X, omega (rad/s), damping ratios) of the lowest ``count`` modes (all: None) of
    the eigenpairs lam (ascending), X (columns) of the pencil ``MCK``."""
    count = lam.size if count is None else min(count, lam.size)
    lam, X = lam[:count], X[:, :count]
    omega = angular_frequencies(lam)
    M, C, K = MCK
    return lam, X, omega, damping_ratios(M, C, K, X, omega)


def chain_modes(
    model: str, about: str, omega: np.ndarray, zeta: np.ndarray, shapes: Pencil, **fields: Any
) -> Modes:
    """The ``Modes`` of ``model`` about ``about``: omega, damping ratios ``zeta``, ``shapes``
    (dx, dy, hinge) and the other fields (``phi0``, ``l``, ``equilibrium``, ``info``, ...)."""
    dx, dy, hinge = shapes
    return Modes(
        model=model, about=about, omega=omega, damping=zeta, dx=dx, dy=dy, hinge=hinge, **fields
    )
