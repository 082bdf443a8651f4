"""Energies and momenta of the paper's systems (a mixin of ``paper_system.PaperSystem``): what
the energy audit, the observation map and the lock records read, each from one state or a
history. The model ladder (``rodval.models.kinematics.ladder``) overrides the hooks that depend on its
coordinates (``energy_rows``, ``bending_energy_at``, ``rod_momenta_at``, ``kinetic_energy``)."""

from __future__ import annotations

from collections.abc import Callable
from contextlib import AbstractContextManager
from typing import Any

import numpy as np

from rodval.core.loads import LOAD_COLUMNS
from rodval.core.scene import hinge_angles
from rodval.models.assembly.paper_matrices import (
    angle_differences,
    angular_momentum,
    assemble_mass,
    bending_energy,
    potential_energy,
    rod_momenta,
)

#: Placeholders for the compiled forms' unused arrays (no dense matrices, no loads).
NO_MATRICES = np.zeros((0, 0, 0))
NO_LOADS = np.zeros((0, len(LOAD_COLUMNS)))


class PaperEnergy:
    """T, Pi and the momenta of a paper system (attributes from ``PaperSystem``)."""

    kernel: str
    n: int
    full: bool
    V: np.ndarray
    _flags: np.ndarray
    _mech: np.ndarray
    compiled_mechanics: Any
    cc_kinetic: Any
    base_chain: Any
    stops: tuple
    stop_active: tuple[bool, ...]
    #: the mode in effect at a time, and a context in a mode (``PaperSystem``)
    _mode_for: Callable[[float], tuple]
    _mode: Callable[[tuple], AbstractContextManager]

    def rigid(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """phi, phi' from a state history Y (nt, N)."""
        raise NotImplementedError

    def bending(self, times: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, ...]:
        """alpha, beta, alpha', beta' (each (nt, n)) from a state history."""
        raise NotImplementedError

    def generalized_rates(self, y: np.ndarray) -> np.ndarray:
        """q' = [phi'; alpha'; beta'] (3n; a ladder rung: all N) as the model's equations see
        it at state y."""
        raise NotImplementedError

    def attitude(self, Y: np.ndarray) -> np.ndarray | None:
        """The base's attitude theta (rad, (nt,)) from a state history, hinge 0's reference;
        None on a pinned base (theta = 0)."""
        return None

    def attitude_rate(self, Y: np.ndarray) -> np.ndarray | None:
        """theta' (rad/s, (nt,)) from a history; None on a pinned base."""
        return None

    def root_motion(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(r_0 (m), v_0 (m/s)) of node 0 at one state: zero on a pinned base."""
        return np.zeros(2), np.zeros(2)

    def _kinetic(self, phi: np.ndarray, v: np.ndarray) -> float:
        """1/2 v^T M(phi) v with the kinematic mass matrix: the compiled O(n) form, or the
        dense one with the numpy kernel (the reference)."""
        if self.kernel == "numba":
            n = self.n
            y = (
                np.concatenate([phi, np.zeros(2 * n), v])
                if self.full
                else np.concatenate([phi, v[:n]])
            )
            self.compiled_mechanics(0.0, y, self.V, self._flags, NO_MATRICES, NO_LOADS, self._mech)
            return float(self._mech[0])
        return 0.5 * float(v @ assemble_mass(self.cc_kinetic, angle_differences(phi)[0]) @ v)

    def kinetic_energy(self, t: float, y: np.ndarray) -> float:
        """T = 1/2 q'^T M(phi) q' (J) at one state, without recovering bending angles; O(n)
        with the compiled kernels."""
        return self._kinetic(self.rigid(y[None, :])[0][0], self.generalized_rates(y))

    def energies(self, phi, dphi, alpha, beta, dalpha, dbeta) -> tuple[np.ndarray, np.ndarray]:
        """Kinetic T = 1/2 q'^T M(phi) q' with the kinematic (printed) mass matrix, and
        Pi = 1/2 sum kappa (D - rest)^2 + bending (J), per output time; O(n) each."""
        v = np.concatenate([dphi, dalpha, dbeta], axis=1)
        kin = np.array([self._kinetic(p, vi) for p, vi in zip(phi, v)])
        return kin, self.potential(phi, alpha, beta)

    def potential(self, phi, alpha, beta, attitude=None) -> np.ndarray:
        """Pi (J) per row: the scene chain's springs and bending, plus 1/2 k (D - angle)^2 of
        every limit stop acting in the current mode; ``attitude``: a free base's theta (rad)
        per row, hinge 0's reference (``rodval.core.scene.hinge_angles``)."""
        pot = potential_energy(self.base_chain, phi, alpha, beta, attitude)
        if any(self.stop_active):
            D = hinge_angles(phi, alpha, beta, attitude)
            for st, on in zip(self.stops, self.stop_active):
                if on:
                    pot = pot + 0.5 * st.stiffness * (D[..., st.hinge] - st.angle) ** 2
        return pot

    def energy_rows(self, times: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(T, Pi) (J) per state of a history Y in the current mode; O(n) each."""
        return self.energies(*self.rigid(Y), *self.bending(times, Y))

    def energy_history(self, times: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """E = T + Pi (J) per state of a history Y at ``times`` (s), each in the mode in effect
        at its time (``_mode_for``: an event's time is in the mode before it), as ``observe``
        reports it: the energy audit's E on its grid (``rodval.solvers.audit``). One
        ``energy_rows`` per run of states in one mode; O(n) per state."""
        times = np.asarray(times, float)
        E = np.empty(times.size)
        modes = [self._mode_for(float(t)) for t in times]
        start = 0
        for i in range(1, times.size + 1):
            if i < times.size and modes[i] == modes[start]:
                continue
            with self._mode(modes[start]):
                kin, pot = self.energy_rows(times[start:i], Y[start:i])
            E[start:i] = kin + pot
            start = i
        return E

    def bending_energy_at(self, t: float, y: np.ndarray) -> float:
        """The rods' bending energy (J) at one state."""
        alpha, beta = self.bending(np.array([t]), y[None, :])[:2]
        return float(bending_energy(self.base_chain, alpha, beta)[0])

    def rod_momenta_at(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(p (n, 2), h (n,), first (n, 2)) of every rod with its far node at one state, in
        the model's velocity field (``paper_matrices.rod_momenta``); O(n)."""
        n = self.n
        v = self.generalized_rates(y)
        phi = self.rigid(y[None, :])[0][0]
        return rod_momenta(self.base_chain, phi, v[:n], v[n : 2 * n], v[2 * n : 3 * n])

    def momenta(self, y: np.ndarray) -> np.ndarray:
        """Linear momentum (N s, (n, 2)) of everything beyond node k (rods k+1..n and their
        far nodes), k = 0..n-1; row 0 is the whole chain's."""
        p = self.rod_momenta_at(y)[0]
        return np.cumsum(p[::-1], axis=0)[::-1]

    def momentum_rows(self, Y: np.ndarray) -> np.ndarray:
        """The chain's linear momentum P = sum_k p_k (N s, (nt, 2)) per state of a history, in
        the model's velocity field (``rod_momenta_at``)."""
        return np.array([self.rod_momenta_at(y)[0].sum(axis=0) for y in Y])

    def momentum_audit_rows(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(H, G) (N m s, (nt,) each) for the angular-momentum audit of a pinned chain
        (``rodval.core.validity.momentum_balance``): the angular momentum about node 0 and the
        gross, sum_k |h_k| of the rods with their far nodes (``rod_momenta_at``). O(n) per
        state."""
        if len(Y) and type(self).rod_momenta_at is PaperEnergy.rod_momenta_at:
            # the paper's velocity field (``rod_momenta_at``) on the whole history at once
            n = self.n
            V = np.array([self.generalized_rates(y) for y in Y])
            phi = self.rigid(Y)[0]
            h = rod_momenta(self.base_chain, phi, V[:, :n], V[:, n : 2 * n], V[:, 2 * n : 3 * n])[1]
        else:
            h = np.array([self.rod_momenta_at(y)[1] for y in Y]).reshape(len(Y), -1)
        return h.sum(axis=1), np.abs(h).sum(axis=1)

    def angular_momentum_rows(self, times: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """The ``angular_momentum`` rows (nt, 2) (``paper_matrices.angular_momentum``)."""
        phi, dphi = self.rigid(Y)
        dalpha, dbeta = self.bending(times, Y)[2:]
        return angular_momentum(self.base_chain, phi, dphi, dalpha, dbeta)
