"""The rigid chain: rods that do not bend, the limit EI -> inf of every rung of the ladder
(docs/model.md, "The rigid model"). Coordinates phi (n), state [phi; phi'] (2 n): n ODEs,
O(n) per evaluation (``rigid_kernels``: the ladder's kernels on ``ladder.rigid_constants``).

Hinge angles are the chords' D_k = phi_k - phi_{k-1} (D_0 = phi_0 - theta on a moving base);
springs, dampers and stops act on them, a held latch is the exact linear constraint a_k^T phi
= angle_k, and a lock is the plastic impact of ``lock_records.plastic_jump`` in the metric
M_pp(phi): the rigid-panel lock of ``rodval.mechanics.rigid`` by construction. Everything else
(events, observation, energies, momenta, lock windows) is the stacked systems'
(``paper_system.StackedSystem``) with the bending coordinates identically zero.
"""

from __future__ import annotations

import numpy as np

from rodval.core.scene import Scene
from rodval.models.assembly.paper_energy import NO_LOADS, NO_MATRICES
from rodval.models.assembly.paper_matrices import hinge_matrix
from rodval.models.assembly.stacked_system import StackedSystem
from rodval.models.kinematics.ladder import rigid_constants
from rodval.models.kinematics.rigid_kernels import (
    rigid_accel,
    rigid_accel_locked,
    rigid_hinge_events,
    rigid_mechanics,
    rigid_rhs,
    rigid_rhs_locked,
    rigid_unit_responses,
)

#: The kinematics the rigid chain runs on: the printed (kinematic) mass matrix, the compiled
#: kernels (``PaperSystem``'s options, fixed).
RIGID_OPTIONS = ("printed", "numba")


class RigidSystem(StackedSystem):
    """The rigid chain on a pinned base: N = n coordinates phi (a moving base appends its
    body's, ``moving_base``)."""

    has_jacobian = False
    full = False
    accel_kernel = staticmethod(rigid_accel)
    locked_kernel = staticmethod(rigid_accel_locked)
    unit_kernel = staticmethod(rigid_unit_responses)
    compiled_rhs = staticmethod(rigid_rhs)
    compiled_mechanics = staticmethod(rigid_mechanics)
    compiled_rhs_locked = staticmethod(rigid_rhs_locked)
    compiled_events = staticmethod(rigid_hinge_events)

    def __init__(self, scene: Scene):
        super().__init__(scene, *RIGID_OPTIONS)
        self.Nc = self.n
        self.N = self.Nc + self.body_coordinates
        self.setup_base(scene)
        self.y0 = self.initial_state()
        self.use_kernel()

    def chain_initial_state(self) -> np.ndarray:
        """[phi; phi'] at t = 0 (the scene's bending angles and rates have no place here)."""
        i = self.initial
        return np.concatenate([i["phi"], i["dphi"]])

    def kernel_constants(self) -> np.ndarray:
        return rigid_constants(self.chain)

    def bending(self, times, Y):
        zero = np.zeros((len(Y), self.n))
        return zero, zero, zero, zero

    def generalized_rates(self, y):
        """[phi'; 0; 0] (3 n): the rates in the paper's coordinates, no bending."""
        return np.concatenate([y[self.N : self.N + self.n], np.zeros(2 * self.n)])

    def hinge_rows(self, hinges) -> np.ndarray:
        """Rows a_k = dD_k/dphi (n columns) of these hinges."""
        return hinge_matrix(self.n)[hinges][:, : self.n]

    def kinetic_energy(self, t, y):
        """T = 1/2 phi'^T M_pp phi' (J) (``rigid_kernels.rigid_mechanics``)."""
        self.compiled_mechanics(0.0, y, self.V, self._flags, NO_MATRICES, NO_LOADS, self._mech)
        return float(self._mech[0])

    def energy_budget(self, t, y):
        zero = np.zeros(self.n)
        phi = y[None, : self.n]
        return self.kinetic_energy(t, y) + float(self.potential(phi, zero, zero)[0])

    def bending_energy_at(self, t, y):
        return 0.0

    def max_bending(self, times, Y):
        """None: rigid rods do not bend (no small-bending check)."""
        return None
