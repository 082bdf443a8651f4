"""The rigid-panel lock: the model-independent yardstick of a latch's impulse.

Every model measures its lock impulse on its own solution (the mean over the lock window of
the latch's cumulative impulse, ``rodval.mechanics.lock_window``). Beside it each lock record
carries ``rigid_impulse``: the angular impulse of the same
lock on a chain of **rigid** rods with the model's chord angles and chord rates just before
the lock (docs/deployment_native.md, "The rigid-panel impulse"). It depends on the scene's
masses and lengths and on those 2n numbers only, so the three models' values are comparable,
and in the rigid-panel limit (EI -> inf) every model's own impulse must tend to it.

The impact is perfectly plastic (Gauss' principle): the velocity after it is the one closest
to the velocity before in the kinetic metric, with every held hinge's relative chord rate
zero. Coordinates are the node velocities v_1..v_n (node 0 is pinned): a rigid rod's velocity
is linear along it, so its kinetic energy is exactly (m l / 6)(|v_a|^2 + v_a . v_b + |v_b|^2)
(a block-tridiagonal mass matrix), and the rods' rigidity d_k . (v_k - v_{k-1}) = 0 and the
held hinges omega_{h+1} - omega_h = 0 (omega_k = n_k . (v_k - v_{k-1}) / l_k, hinge 0:
omega_1 = 0) are linear constraints. The KKT system

    [M  -G^T] [v+    ]   [M v-]
    [G   0  ] [lambda] = [0   ]

is banded (each row couples neighbouring nodes), so one sparse LU solves it in O(n). The
multiplier of hinge h's row is the angular impulse on rod h+1 (N m s, counter-clockwise
positive: a couple mu on rod h+1 is the pair of forces +-mu/l n at its ends), the convention
of every model's ``impulse``.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np
import scipy.sparse
import scipy.sparse.linalg

from rodval.core.scene import Chain


def node_velocities(l: np.ndarray, phi: np.ndarray, dphi: np.ndarray) -> np.ndarray:
    """v_k = sum_{i <= k} l_i phi'_i n_i (m/s, (n, 2)), n_i = (-sin phi_i, cos phi_i): the
    nodes' velocities of rigid chords turning at phi' about the pinned node 0. O(n)."""
    rates = (l * dphi)[:, None] * np.stack([-np.sin(phi), np.cos(phi)], axis=-1)
    return np.cumsum(rates, axis=0)


def _mass_matrix(chain: Chain) -> scipy.sparse.csr_matrix:
    """The rigid chain's mass matrix in the node velocities v_1..v_n (kg, 2n x 2n, banded):
    rod k adds m l / 3 on nodes k-1 and k and m l / 6 between them; node k its point mass."""
    rows, cols, vals = _mass_entries(*_mass_key(chain))
    n = chain.n
    return scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(2 * n, 2 * n))


def _mass_key(chain: Chain) -> tuple[bytes, bytes, bytes]:
    """The chain's m, l, mu as bytes: ``_mass_entries``' cache key."""
    m, l, mu = (np.ascontiguousarray(a, float).tobytes() for a in (chain.m, chain.l, chain.mu))
    return m, l, mu


@functools.lru_cache(maxsize=16)
def _mass_entries(m: bytes, l: bytes, mu: bytes) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows, cols, values) of ``_mass_matrix`` from the chain's m, l, mu (as bytes, the
    cache's key: they do not change between the locks of a run). O(n)."""
    ml = np.frombuffer(m) * np.frombuffer(l)
    mu_ = np.frombuffer(mu)
    n = ml.size
    diag = ml / 3.0 + np.concatenate([ml[1:] / 3.0, [0.0]]) + mu_  # node k = 1..n
    rows, cols, vals = [], [], []
    for c in range(2):
        idx = 2 * np.arange(n) + c
        rows.append(idx)
        cols.append(idx)
        vals.append(diag)
        if n > 1:  # rod k + 1 couples node k and k + 1 (k = 1..n-1)
            rows += [idx[:-1], idx[1:]]
            cols += [idx[1:], idx[:-1]]
            vals += [ml[1:] / 6.0, ml[1:] / 6.0]
    out = (np.concatenate(rows), np.concatenate(cols), np.concatenate(vals))
    for a in out:
        a.flags.writeable = False
    return out


def _constraint_entries(
    chain: Chain, phi: np.ndarray, held: Sequence[int]
) -> tuple[list[int], list[int], list[float]]:
    """(rows, cols, values) of G (n + m, 2n), duplicates not yet summed: rows 0..n-1 the rods'
    rigidity d_k . (v_k - v_{k-1}); then one row per held hinge h, omega_{h+1} - omega_h
    (omega_k = n_k . (v_k - v_{k-1}) / l_k; no omega_0)."""
    n = chain.n
    d = np.stack([np.cos(phi), np.sin(phi)], axis=-1)
    nrm = np.stack([-np.sin(phi), np.cos(phi)], axis=-1) / chain.l[:, None]
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []

    def rod(row: int, k: int, vec: np.ndarray, sign: float) -> None:
        """sign * vec . (v_k - v_{k-1}) into ``row`` (rod k, 0-based: nodes k and k + 1)."""
        for node, s in ((k + 1, sign), (k, -sign)):
            if node == 0:
                continue  # the pinned root
            for c in range(2):
                rows.append(row)
                cols.append(2 * (node - 1) + c)
                vals.append(s * vec[c])

    for k in range(n):
        rod(k, k, d[k], 1.0)
    for j, h in enumerate(held):
        rod(n + j, h, nrm[h], 1.0)
        if h > 0:
            rod(n + j, h - 1, nrm[h - 1], -1.0)
    return rows, cols, vals


def _constraints(chain: Chain, phi: np.ndarray, held: Sequence[int]) -> scipy.sparse.csr_matrix:
    """G (n + m, 2n) (``_constraint_entries``; a node's two entries in a hinge row summed)."""
    rows, cols, vals = _constraint_entries(chain, phi, held)
    return scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(chain.n + len(held), 2 * chain.n))


def _kkt(chain: Chain, phi: np.ndarray, held: Sequence[int]) -> scipy.sparse.csc_matrix:
    """[[M, -G^T], [G, 0]] in one assembly (the entries of ``_mass_matrix`` and
    ``_constraints``; a duplicate is two terms of one hinge row, so its sum is the same in
    any order). O(n + m)."""
    n = chain.n
    mr, mc, mv = _mass_entries(*_mass_key(chain))
    gr, gc, gv = (np.asarray(a) for a in _constraint_entries(chain, phi, held))
    size = 2 * n + n + len(held)
    rows = np.concatenate([mr, gc, 2 * n + gr])
    cols = np.concatenate([mc, 2 * n + gr, gc])
    vals = np.concatenate([mv, -gv.astype(float), gv.astype(float)])
    return scipy.sparse.csc_matrix((vals, (rows, cols)), shape=(size, size))


def rigid_lock(
    chain: Chain, phi: np.ndarray, dphi: np.ndarray, held: Sequence[int], hinge: int
) -> dict[str, float]:
    """The plastic lock of rigid rods with chord angles ``phi`` (rad) and rates ``dphi``
    (rad/s) just before it, every hinge in ``held`` (all hinges held after the lock, 0-based,
    ``hinge`` among them) held afterwards: ``rigid_impulse`` (N m s, on rod hinge + 1,
    counter-clockwise positive) and the rigid chain's kinetic energy before and after
    (``rigid_kinetic_before``, ``rigid_kinetic_after``, J). O(n + m) (one sparse LU of the
    banded KKT system; module docstring)."""
    held = [int(h) for h in held]
    if hinge not in held:
        raise ValueError(f"hinge {hinge} must be among the held hinges {held}")
    n = chain.n
    M = _mass_matrix(chain)
    kkt = _kkt(chain, np.asarray(phi, float), held)
    v0 = node_velocities(chain.l, np.asarray(phi, float), np.asarray(dphi, float)).ravel()
    rhs = np.concatenate([M @ v0, np.zeros(n + len(held))])
    z = scipy.sparse.linalg.spsolve(kkt, rhs)
    v1, lam = z[: 2 * n], z[2 * n :]
    return {
        "rigid_impulse": float(lam[n + held.index(hinge)]),
        "rigid_kinetic_before": float(0.5 * v0 @ (M @ v0)),
        "rigid_kinetic_after": float(0.5 * v1 @ (M @ v1)),
    }
