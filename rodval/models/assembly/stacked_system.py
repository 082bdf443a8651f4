"""The stacked full-model systems' base: a state [Q; Q'] with the chain's phi, alpha, beta first
and more coordinates after them (a ladder rung's bubbles, a free base's body), on compiled
kernels (``rodval.models.kinematics.ladder``, ``rodval.models.base``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from rodval.core.scene import Scene
from rodval.models.assembly.paper_system import PaperSystem
from rodval.models.hinge_items import lock_records


class StackedSystem(PaperSystem):
    """A full-model system whose state is [Q; Q'] with N = len(Q) coordinates, the chain's
    phi, alpha, beta first and more after them (a ladder rung's bubbles, a free base's body),
    on compiled kernels: ``locked_kernel(V, y, has_load, SX, SY, damped, locks, out, lam)``
    and ``unit_kernel(V, q, locks, U)`` (U[j] = M^-1 a_{locks[j]})."""

    full = True
    N: int
    #: coordinates after the chain's (a moving base's body: ``rodval.models.base.moving_base``)
    body_coordinates = 0
    locked_kernel: Any
    unit_kernel: Any

    def setup_base(self, scene: Scene) -> None:
        """What a base adds before the kernels are set up (``moving_base``): nothing on a pin."""

    def initial_state(self) -> np.ndarray:
        """The state at t = 0: the chain's (``chain_initial_state``)."""
        return self.chain_initial_state()

    def chain_initial_state(self) -> np.ndarray:
        """The chain's [q; q'] at t = 0 (a ladder rung adds its bubbles, at rest)."""
        i = self.initial
        return np.concatenate([i["phi"], i["alpha"], i["beta"], i["dphi"], i["dalpha"], i["dbeta"]])

    def bubble_energies(self, Y: np.ndarray) -> np.ndarray:
        """The bending energy (J) of shapes beyond the paper's cubic, per state: none."""
        return np.zeros(len(Y))

    def generalized_rates(self, y):
        return y[self.N :]

    def rigid(self, Y):
        n, N = self.n, self.N
        return Y[:, :n], Y[:, N : N + n]

    def bending(self, times, Y):
        n, N = self.n, self.N
        return (
            Y[:, n : 2 * n],
            Y[:, 2 * n : 3 * n],
            Y[:, N + n : N + 2 * n],
            Y[:, N + 2 * n : N + 3 * n],
        )

    def accel_locked(self, t, y):
        sums = self.loads.suffix_sums(t)
        SX, SY = (self._no_load, self._no_load) if sums is None else sums
        out = np.empty(self.N)
        lam = np.empty(self._lock_h.size)
        self.locked_kernel(self.V, y, sums is not None, SX, SY, self.damped, self._lock_h, out, lam)
        return out, lam

    def unit_responses(self, q, hinges) -> np.ndarray:
        U = np.empty((len(hinges), self.N))
        self.unit_kernel(self.V, q, np.asarray(hinges, np.int64), U)
        return U

    def plastic_jump(self, y, hinges, angles):
        return lock_records.plastic_jump(self, y, hinges, angles)
