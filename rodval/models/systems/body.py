"""A moving base's body as a part of a chain system (``chain_system.ChainSystem``), docs/base.md:
a free body in the plane (a spacecraft) or a prescribed one (massless, following its laws,
``rodval.core.base.Motion``). Its coordinates x_c, y_c, theta follow the chain's ``Nc``
(N = Nc + 3); hinge 0 is measured from theta. It gives the kernels' body rows, the initial
state, the body's and node 0's motion, the whole system's momenta and the body's outputs."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rodval.core.base import root_state
from rodval.core.scene import Chain, Scene
from rodval.models.hinge_items.lock_records import cross

#: (p (n, 2), h (n,), first (n, 2)) of every rod with its far node at one state
RodMomenta = tuple[np.ndarray, np.ndarray, np.ndarray]
#: Observed rows: quantity -> (values (nt, k), k indices)
Rows = dict[str, tuple[np.ndarray, np.ndarray]]


class Body:
    """The body of ``scene``'s moving base after a chain of ``Nc`` coordinates."""

    def __init__(self, scene: Scene, chain: Chain, Nc: int):
        b = self.base = scene.base
        self.Nc, self.N = Nc, Nc + 3
        if b.prescribed:
            self.mass, self.inertia = 0.0, 0.0
            self.start = b.state_at(0.0)
            #: the laws' table (``rodval.core.motion.motion_at``)
            self.motion = b.motion_table()
        else:
            self.mass, self.inertia = b.inertial()
            self.start = (np.array(b.position), np.array(b.velocity), b.attitude, b.rate)
        #: each rod's mass with its far node's (kg)
        self.rod_mass = chain.m * chain.l + chain.mu
        self.total = self.mass + float(self.rod_mass.sum())

    def rows(self, n: int) -> np.ndarray:
        """The kernels' body rows (appended to the chain's V): body mass, inertia, hinge
        offset, chain mass, each the same in every column."""
        h = self.base.hinge_offset
        rows = [self.mass, self.inertia, h[0], h[1], float(self.rod_mass.sum())]
        return np.outer(rows, np.ones(n))

    def with_body(self, y0: np.ndarray) -> np.ndarray:
        """The state [q; x_c, y_c, theta; q'; rates] from the chain's [q; q']."""
        (r, v, th, w), Nc = self.start, self.Nc
        return np.concatenate([y0[:Nc], r, [th], y0[Nc:], v, [w]])

    def attitude(self, Y: np.ndarray) -> np.ndarray:
        """theta (rad, (nt,)) from a state history."""
        return Y[:, self.Nc + 2]

    def attitude_rate(self, Y: np.ndarray) -> np.ndarray:
        """theta' (rad/s, (nt,))."""
        return Y[:, self.N + self.Nc + 2]

    def states(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(r_c (m), v_c (m/s)) of the body's centre of mass, each (nt, 2)."""
        Nc, N = self.Nc, self.N
        return Y[:, Nc : Nc + 2], Y[:, N + Nc : N + Nc + 2]

    def root_states(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(r_0 (m), v_0 (m/s)) of node 0, each (nt, 2): r_c + rho, v_c + theta' k x rho."""
        return root_state(self.base, *self.states(Y), self.attitude(Y), self.attitude_rate(Y))

    def root_motion(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(r_0 (m), v_0 (m/s)) of node 0 at one state."""
        r0, v0 = self.root_states(y[None, :])
        return r0[0], v0[0]

    def moved(self, parts: RodMomenta, y: np.ndarray) -> RodMomenta:
        """The pinned chain's rod momenta with node 0 moving: p += m_k v_0, h (about the
        origin) += m_k r_0 x v_0 + r_0 x p + first x v_0, first += m_k r_0."""
        p, h, first = parts
        r0, v0 = self.root_motion(y)
        mass = self.rod_mass
        h = h + mass * cross(r0, v0) + cross(r0, p) + cross(first, v0)
        return p + mass[:, None] * v0, h, first + mass[:, None] * r0

    def angular_momentum_rows(
        self, Y: np.ndarray, P: np.ndarray, rod_momenta: Callable[[np.ndarray], RodMomenta]
    ) -> np.ndarray:
        """[H about node 0, H about the system's centre of mass] (N m s, (nt, 2)), body
        included: H_O = J theta' + m_b r_c x v_c + sum_k h_k (about the origin), H_X = H_O -
        X x P for X = node 0 and the centre of mass (docs/quantities.md); P: the total
        linear momentum per state."""
        rc, vc = self.states(Y)
        r0 = self.root_states(Y)[0]
        mb = self.mass
        out = np.empty((len(Y), 2))
        spin = self.inertia * self.attitude_rate(Y)
        for i, y in enumerate(Y):
            _, h, first = rod_momenta(y)
            HO = spin[i] + mb * cross(rc[i], vc[i]) + h.sum()
            X = (mb * rc[i] + first.sum(axis=0)) / self.total
            out[i] = HO - cross(r0[i], P[i]), HO - cross(X, P[i])
        return out

    def momentum_audit_rows(
        self, Y: np.ndarray, rod_momenta: Callable[[np.ndarray], RodMomenta]
    ) -> tuple[np.ndarray, np.ndarray]:
        """(H, G) (N m s) about the system's centre of mass X for the angular-momentum audit:
        the parts are the rods with their far nodes, h_k - X x p_k (about the origin), and the
        body, J theta' + m_b (r_c - X) x v_c; H their sum, G the sum of their magnitudes.
        O(n) per state."""
        rc, vc = self.states(Y)
        spin = self.inertia * self.attitude_rate(Y)
        mb = self.mass
        H, G = np.empty(len(Y)), np.empty(len(Y))
        for i, y in enumerate(Y):
            p, h, first = rod_momenta(y)
            X = (mb * rc[i] + first.sum(axis=0)) / self.total
            rods = h - (X[0] * p[:, 1] - X[1] * p[:, 0])
            body = spin[i] + mb * cross(rc[i] - X, vc[i])
            H[i] = rods.sum() + body
            G[i] = np.abs(rods).sum() + abs(body)
        return H, G

    def observe(self, out: Rows, Y: np.ndarray, wants: Callable[..., bool]) -> Rows:
        """The chain's rows ``out`` with node 0's motion added to the node positions, and the
        body's pose and rates (``base_*``) when the scene ``wants`` them."""
        r0 = self.root_states(Y)[0]
        for key, axis in (("x", 0), ("y", 1)):
            if key in out:
                v, k = out[key]
                out[key] = (v + r0[:, axis : axis + 1], k)
        if wants("base"):
            rc, vc = self.states(Y)
            pair, one = np.arange(2), np.zeros(1, dtype=int)
            out["base_position"] = (rc, pair)
            out["base_velocity"] = (vc, pair)
            out["base_attitude"] = (self.attitude(Y)[:, None], one)
            out["base_rate"] = (self.attitude_rate(Y)[:, None], one)
        return out
