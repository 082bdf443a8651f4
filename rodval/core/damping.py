"""Rod bending damping stated as engineers state it: a modal damping ratio.

A rod's Kelvin-Voigt damping c (N m^2 s; bending moment EI kappa_b + c dkappa_b/dt,
docs/model.md) is proportional to its stiffness, so every bending mode of a uniform rod has
the damping ratio zeta_k = c omega_k / (2 EI): one number fixes c once the mode it refers to is
named. Here it is the rod's **first free-free Euler-Bernoulli bending mode**, of the rod alone
(its own l, mass per length m and EI; node masses, hinges and neighbours left out, so that c is
a property of the panel and the same in every model and every chain it sits in):

    omega_1 = (beta_1 l)^2 / l^2 sqrt(EI / m),  beta_1 l = 4.730040744862704,
    c = 2 zeta EI / omega_1.

Higher modes of the rod are damped more (zeta_k = zeta omega_k / omega_1), as with any
stiffness-proportional damping. A scene file writes ``[chain] bending_damping = { ratio =
0.01 }`` (1 % of critical; a number or one per rod); the scene holds the converted c in
N m^2 s, which is what run.json records and every model uses.
"""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np

#: beta_1 l of a free-free Euler-Bernoulli beam's first bending mode (cos x cosh x = 1).
FREE_FREE_BETA_L = 4.730040744862704
#: The allowed ratios: a fraction of critical damping, 0 <= zeta < 1 (0.01 is 1 %).
MAX_RATIO = 1.0


def first_free_free_frequency(l: Any, m: Any, EI: Any) -> np.ndarray:
    """omega_1 (rad/s) of each rod's first free-free bending mode: l (m), m (kg/m), EI (N m^2),
    scalars or arrays (broadcast). O(n)."""
    l, m, EI = (np.asarray(v, dtype=float) for v in (l, m, EI))
    return (FREE_FREE_BETA_L / l) ** 2 * np.sqrt(EI / m)


def bending_damping_for_ratio(ratio: Any, l: Any, m: Any, EI: Any) -> np.ndarray:
    """The Kelvin-Voigt damping c (N m^2 s) that gives each rod's first free-free bending mode
    the damping ratio ``ratio`` (a fraction of critical, 0 <= ratio < 1): c = 2 ratio EI /
    omega_1. ValueError naming ``bending_damping.ratio`` and the allowed range otherwise."""
    values = ratio if isinstance(ratio, (list, tuple, np.ndarray)) else [ratio]
    if not all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in values) or not all(
        0.0 <= float(v) < MAX_RATIO for v in values
    ):
        raise ValueError(
            "bending_damping.ratio must be a damping ratio (a fraction of critical damping, "
            f">= 0 and < {MAX_RATIO:g}; 1 % is 0.01) or one per rod, got {ratio!r}"
        )
    zeta = np.asarray(values, dtype=float)
    EI = np.asarray(EI, dtype=float)
    if zeta.size not in (1, np.size(EI)):
        raise ValueError(
            f"bending_damping.ratio must be one number or one per rod ({np.size(EI)}), "
            f"got {zeta.size}"
        )
    zeta = zeta if zeta.size > 1 else zeta[0]
    return 2.0 * zeta * EI / first_free_free_frequency(l, m, EI)
