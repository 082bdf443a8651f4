"""The observation map of a native system: the scene's quantities at output times in the
system's current mode (a ``paper_system.PaperSystem``, which imports this module:
``PaperSystem._observe_rows``; a moving base's body adds its own, ``body.Body.observe``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from rodval.core.quantities import tip_deflection
from rodval.core.scene import hinge_angles
from rodval.models.assembly.paper_matrices import node_positions
from rodval.solvers.system import Observed


def hinge_moments(system: Any, times: np.ndarray, Y: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Hinge moments (N m, (nt, n)) at the hinge angles D, positive when resisting an increase
    of D: spring kappa (D - rest) + damper nu dD/dt + acting stops (the mode's chain) - the
    motors' and rate dampers' Tq (``PaperSystem.torques_at``: a motor driving D up is a
    negative resisting moment) + the constraint moment -lambda of locked hinges (from the
    constrained acceleration solve)."""
    ch = system.chain
    rates = np.array([system.hinge_rates(y) for y in Y]).reshape(D.shape)
    M: np.ndarray = ch.kappa * (D - ch.rest_angle) + ch.nu * rates
    if system.loads.torques:
        Tq = [system.loads.hinge_moments(t, r) for t, r in zip(times, rates)]
        M -= np.array(Tq).reshape(M.shape)
    if system.locked:
        for i, (t, y) in enumerate(zip(times, Y)):
            lam = system.accel_locked(t, y)[1]
            M[i, system._lock_h] -= lam
    return M


def chain_rows(system: Any, times: np.ndarray, Y: np.ndarray) -> Observed:
    """The chain's quantities the scene wants, at the states Y (nt, 2N) at ``times`` (s), all
    in the current mode: angles, rates, node positions, hinge angles and moments, energies
    and momenta."""
    scene, n = system.scene, system.n
    rods = np.arange(1, n + 1)
    phi, dphi = system.rigid(Y)
    out: Observed = {}
    if scene.wants("phi"):
        out["phi"] = (phi, rods)
    if scene.wants("dphi"):
        out["dphi"] = (dphi, rods)
    if scene.wants("alpha", "beta", "energy", "hinge_angle", "hinge_moment", "angular_momentum"):
        alpha, beta, dalpha, dbeta = system.bending(times, Y)
        if scene.wants("alpha"):
            out["alpha"] = (alpha, rods)
        if scene.wants("beta"):
            out["beta"] = (beta, rods)
    if scene.wants("x", "y", "tip_deflection"):
        x, y = node_positions(system.l, phi)
        nodes = np.arange(0, n + 1)
        if scene.wants("x"):
            out["x"] = (x, nodes)
        if scene.wants("y"):
            out["y"] = (y, nodes)
        if scene.wants("tip_deflection"):
            tip = tip_deflection(x, y, system.attitude(Y))
            out["tip_deflection"] = (tip[:, None], np.zeros(1, dtype=int))
    if scene.wants("hinge_angle", "hinge_moment"):
        D = hinge_angles(phi, alpha, beta, system.attitude(Y))
        hinges = np.arange(n)
        if scene.wants("hinge_angle"):
            out["hinge_angle"] = (D, hinges)
        if scene.wants("hinge_moment"):
            out["hinge_moment"] = (hinge_moments(system, times, Y, D), hinges)
    if scene.wants("energy"):
        kin, pot = system.energy_rows(times, Y)
        zero = np.zeros(1, dtype=int)
        out["kinetic"] = (kin[:, None], zero)
        out["potential"] = (pot[:, None], zero)
        out["energy"] = ((kin + pot)[:, None], zero)
    if scene.wants("angular_momentum"):
        out["angular_momentum"] = (system.angular_momentum_rows(times, Y), np.arange(2))
    if scene.wants("momentum"):
        out["momentum"] = (system.momentum_rows(Y), np.arange(2))
    return out
