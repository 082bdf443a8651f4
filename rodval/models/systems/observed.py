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
            out["hinge_moment"] = (system.hinge_moments(times, Y, D), hinges)
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
