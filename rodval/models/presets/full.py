"""The paper's full model: 3n second-order ODEs in q = [phi; alpha; beta] (equations (9)-(10)).

State y = [q; q'] (6n). M(phi) q'' = [Q; 0; 0] - h - C q' - K q, see ``paper_matrices``.
``numpy_rhs`` is the straightforward dense form; the default compiled kernel
(``kernels.full_accel``) computes the same in O(n).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rodval.core.damping import DEPLOYED, first_free_free_frequency
from rodval.core.scene import Scene
from rodval.core.validity import DAMPING_FIX, setting
from rodval.models.assembly import kernels
from rodval.models.assembly.paper_matrices import (
    DEFAULT_VARIANT,
    angle_differences,
    angle_jacobian,
    assemble_mass,
    convective_terms,
    hinge_matrix,
    rate_damping_matrix,
)
from rodval.models.hinge_items import deployment
from rodval.models.hinge_items.lock_records import plastic_jump
from rodval.models.kinematics.rungs import (
    AUTO,
    PAPER_RUNG,
    auto_kinematics,
    check_kinematics,
    check_rung_options,
    check_shapes,
)
from rodval.models.systems.paper_model import PaperModel
from rodval.models.systems.paper_system import PaperSystem


class FullSystem(PaperSystem):
    full = True
    accel_kernel = staticmethod(kernels.full_accel)
    compiled_rhs = staticmethod(kernels.full_rhs)
    compiled_mechanics = staticmethod(kernels.full_mechanics)
    compiled_rhs_locked = staticmethod(deployment.full_rhs_locked)
    compiled_events = staticmethod(deployment.full_hinge_events)

    def __init__(self, scene: Scene, coefficients: str = DEFAULT_VARIANT, kernel: str = "numba"):
        super().__init__(scene, coefficients, kernel)
        i = self.initial
        self.y0 = np.concatenate(
            [i["phi"], i["alpha"], i["beta"], i["dphi"], i["dalpha"], i["dbeta"]]
        )
        self.use_kernel()

    def kernel_constants(self) -> np.ndarray:
        return kernels.full_constants(self.cc, self.chain)

    def forces(self, t: float, q: np.ndarray, v: np.ndarray, skj: np.ndarray) -> np.ndarray:
        """Right-hand side f = [Q; 0; 0] + A^T Tq - h - C q' - K q of M q'' = f (3n), Tq the
        motors' and rate dampers' hinge moments (``torque_forces``)."""
        n = self.n
        h_phi, h_gamma = convective_terms(self.cc, skj, v[:n], v[n : 2 * n], v[2 * n :])
        f: np.ndarray = self.rest - self.K @ q
        if self.damped:
            f -= self.C @ v
        f[:n] -= h_phi
        f[n:] -= h_gamma
        Q = self.generalized_force(t, q[:n])
        if Q is not None:
            f[:n] += Q
        tau = self.torque_forces(t, np.concatenate([q, v]))
        if tau is not None:
            f += tau
        return f

    def numpy_rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        n = self.n
        q, v = y[: 3 * n], y[3 * n :]
        ckj, skj = angle_differences(q[:n])
        f = self.forces(t, q, v, skj)
        return np.concatenate([v, np.linalg.solve(assemble_mass(self.cc, ckj), f)])

    def jacobian(self, t: float, y: np.ndarray) -> np.ndarray:
        """Analytic Jacobian df/dy (6n, 6n): [[0, I], [M^-1 (df/dq - dM/dphi q''), M^-1 df/dq']]."""
        if self.locked:
            return self.difference_jacobian(t, y)
        n, cc = self.n, self.cc
        q, v = y[: 3 * n], y[3 * n :]
        phi, dphi, dgam = q[:n], v[:n], v[n : 2 * n] - v[2 * n :]
        ckj, skj = angle_differences(phi)
        M = assemble_mass(cc, ckj)
        a = np.linalg.solve(M, self.forces(t, q, v, skj))
        Wt = cc.w_upper.T
        w2, u = dphi * dphi, dphi * dgam
        # d(M q'')/dphi at fixed q'' (only the angle-dependent blocks; d cos = -sin)
        dM_a = np.vstack(
            [
                angle_jacobian(cc.pp_scale, -skj, a[:n])
                + angle_jacobian(cc.w_upper, -skj, a[n : 2 * n] - a[2 * n :]),
                angle_jacobian(Wt, -skj, a[:n]),
                -angle_jacobian(Wt, -skj, a[:n]),
            ]
        )
        # dh/dphi at fixed rates (d sin = cos); h_alpha = -G_pa^T w2 = (W^T o s_jk) w2
        dh_alpha = angle_jacobian(Wt, ckj, w2)
        dh = np.vstack(
            [
                angle_jacobian(cc.pp_scale, ckj, w2) + 2 * angle_jacobian(cc.w_upper, ckj, u),
                dh_alpha,
                -dh_alpha,
            ]
        )
        dfdq = -self.K.copy()
        dfdq[:, :n] -= dh + dM_a
        sums = self.loads.suffix_sums(t)
        if sums is not None:
            SX, SY = sums
            dfdq[np.arange(n), np.arange(n)] -= self.l * (np.sin(phi) * SY + np.cos(phi) * SX)
        G_pp, G_pa = cc.pp_scale * skj, cc.w_upper * skj
        dhdv = np.zeros((3 * n, 3 * n))
        dhdv[:n, :n] = 2 * G_pp * dphi + 2 * G_pa * dgam
        dhdv[:n, n : 2 * n] = 2 * G_pa * dphi
        dhdv[:n, 2 * n :] = -2 * G_pa * dphi
        dhdv[n : 2 * n, :n] = -2 * G_pa.T * dphi
        dhdv[2 * n :, :n] = 2 * G_pa.T * dphi
        dfdv = -dhdv - self.C if self.damped else -dhdv
        rate_damping = rate_damping_matrix(self.loads.torques, t, n)
        if rate_damping is not None:  # the torque items' rate coefficients
            dfdv = dfdv - rate_damping
        J = np.zeros((6 * n, 6 * n))
        J[: 3 * n, 3 * n :] = np.eye(3 * n)
        J[3 * n :] = np.linalg.solve(M, np.hstack([dfdq, dfdv]))
        return J

    def generalized_rates(self, y: np.ndarray) -> np.ndarray:
        return y[3 * self.n :]

    def accel_locked(self, t: float, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """q'' and the multipliers of M q'' = f + A_L^T lambda, A_L q'' = 0 (A_L: the rows of
        the locked hinges): the dense KKT system with the numpy kernel, superposition of
        O(n) solves with the compiled one (deployment.full_accel_locked)."""
        n, h = self.n, self._lock_h
        if self.kernel == "numba":
            out = np.empty(3 * n)
            lam = np.empty(h.size)
            loads = self.kernel_loads(t, y)
            deployment.full_accel_locked(self.V, y, loads, self.damped, h, out, lam)
            return out, lam
        q, v = y[: 3 * n], y[3 * n :]
        ckj, skj = angle_differences(q[:n])
        A = hinge_matrix(n)[h]
        m = h.size
        K = np.zeros((3 * n + m, 3 * n + m))
        K[: 3 * n, : 3 * n] = assemble_mass(self.cc, ckj)
        K[: 3 * n, 3 * n :] = -A.T
        K[3 * n :, : 3 * n] = A
        rhs = np.concatenate([self.forces(t, q, v, skj), np.zeros(m)])
        z = np.linalg.solve(K, rhs)
        return z[: 3 * n], z[3 * n :]

    def unit_responses(self, q: np.ndarray, hinges: Any) -> np.ndarray:
        """M(q)^-1 a_k for each hinge k, (m, 3n) (the paper's M depends on phi = q[:n])."""
        n = self.n
        phi = q[:n]
        if self.kernel == "numba":
            U = np.empty((len(hinges), 3 * n))
            deployment.full_unit_responses(self.V, phi, np.asarray(hinges, np.int64), U)
            return U
        M = assemble_mass(self.cc, angle_differences(phi)[0])
        return np.linalg.solve(M, hinge_matrix(n)[hinges].T).T

    def plastic_jump(
        self, y: np.ndarray, hinges: Any, angles: Any
    ) -> tuple[np.ndarray, np.ndarray]:
        return plastic_jump(self, y, hinges, angles)

    def energy_budget(self, t: float, y: np.ndarray) -> float:
        n = self.n
        return self.kinetic_energy(t, y) + float(
            self.potential(y[:n], y[n : 2 * n], y[2 * n : 3 * n])
        )

    def rigid(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = self.n
        return Y[:, :n], Y[:, 3 * n : 4 * n]

    def bending(self, times: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, ...]:
        n = self.n
        return Y[:, n : 2 * n], Y[:, 2 * n : 3 * n], Y[:, 4 * n : 5 * n], Y[:, 5 * n :]


class FullModel(PaperModel):
    """Full model (3n ODEs). ``coefficients``: "printed" (default) or "published" (erratum);
    ``kernel``: "numba" (default) or "numpy"; the model ladder (``rodval.models.kinematics.ladder``):
    ``shapes`` p = 1..8 bending shapes per rod (default 1, the paper's cubic) and
    ``kinematics`` "first-order" (the paper's), "exact" or "auto" (default: one of them chosen
    for each scene, ``rodval.models.kinematics.rungs.auto_kinematics``)."""

    name = "full"
    system_class = FullSystem
    MODAL_ANALYSIS = "rodval.models.observation.linear_modes:full_modes"
    OPTIONS = ("coefficients", "kernel", "shapes", "kinematics")
    MODES_OPTIONS = ("coefficients", "shapes", "kinematics")

    def __init__(
        self,
        coefficients: str = DEFAULT_VARIANT,
        kernel: str = "numba",
        shapes: int = 1,
        kinematics: str = AUTO,
    ):
        super().__init__(coefficients, kernel)
        self.shapes = check_shapes(shapes)
        self.kinematics = check_kinematics(kinematics, auto=True)
        if (self.shapes, self.kinematics) not in (PAPER_RUNG, (PAPER_RUNG[0], AUTO)):
            check_rung_options(self.coefficients, self.kernel)

    def options(self) -> dict[str, Any]:
        return {**super().options(), "shapes": self.shapes, "kinematics": self.kinematics}

    @classmethod
    def scene_options(
        cls, scene: Scene, options: dict[str, Any]
    ) -> tuple[dict[str, Any], list[str]]:
        """``options`` with ``kinematics = "auto"`` (the default) resolved for ``scene``
        (``auto_kinematics``, the one rule), and the note that says what it chose and why; as
        given, no note, when the kinematics was given (a bad value is refused by the model)."""
        kinematics = options.get("kinematics", AUTO)
        if not (isinstance(kinematics, str) and kinematics == AUTO):
            return options, []
        coefficients = options.get("coefficients", DEFAULT_VARIANT)
        kinematics, note = auto_kinematics(scene, coefficients, options.get("kernel", "numba"))
        return {**options, "kinematics": kinematics}, [note]

    def energy_fix(self) -> str:
        """The first-order kinematics does not keep energy (docs/stability.md): its exact
        rung does (to round-off); on the exact rung what is left is integration error."""
        if self.kinematics == "first-order":
            return (
                f"{setting('kinematics', 'exact')} (the first-order kinematics drops "
                "O(bending) terms of the kinetic energy; docs/model.md)"
            )
        return "a tighter rtol (integration error)"

    def stiffness_fix(self, scene: Scene) -> str:
        """Stiff vibrations of the full model are its rods' bending modes: damp them (more,
        with the figure of what the scene has: ``damping_figure``), or drop them (the reduced
        model, on a pinned base only; the rigid model)."""
        drop = (
            "the rigid model (no bending)"
            if scene.base.moving
            else "the reduced model (quasi-static bending, no bending vibrations) or the rigid "
            "model (no bending)"
        )
        c = np.asarray(scene.chain.bending_damping, float)
        if not np.any(c > 0):
            damp = (
                f"damp the rods' bending ({DAMPING_FIX}; a ratio of each rod's first mode damps "
                "a locked segment's slower modes less, docs/model.md)"
            )
        else:
            request = scene.damping
            deployed = request is not None and request.of == DEPLOYED
            damp = (
                f"the rods' bending is damped already ({damping_figure(scene)}): a larger ratio"
                + (
                    ""
                    if deployed
                    else ', or of = "deployed" (the deployed structure\'s first mode)'
                )
            )
        return f"{damp}, {drop}, or a looser rtol and atol"

    def check_base(self, scene: Scene) -> None:
        """A free or prescribed base runs on every rung with the printed coefficients and the
        compiled kernel (``free_base``, ``chain_base``); other options are refused for it,
        naming the option."""
        if not scene.base.moving:
            return
        for option, value, needed in (
            ("coefficients", self.coefficients, "printed"),
            ("kernel", self.kernel, "numba"),
        ):
            if value != needed:
                raise ValueError(
                    f"full model on a {scene.base.kind} base: {option} must be {needed!r} "
                    f"(the moving bases are built on the compiled kernels, docs/base.md), "
                    f"got {value!r}"
                )

    def system(self, scene: Scene) -> PaperSystem:
        """The system of ``scene`` on this model's rung and base; the free base's, the moving
        bases' and the ladder's modules (and their compiled kernels) are imported only by a
        scene that uses them."""
        if self.kinematics == AUTO:  # a model built without its scene: resolved for it here
            return FullModel(**self.scene_options(scene, self.options())[0]).system(scene)
        self.check_base(scene)
        if not scene.base.moving and (self.shapes, self.kinematics) == PAPER_RUNG:
            return FullSystem(scene, self.coefficients, self.kernel)
        from rodval.models.systems.chain_system import chain_system

        return chain_system(scene, self.shapes, self.kinematics, self.coefficients, self.kernel)


def damping_figure(scene: Scene) -> str:
    """The bending damping ``scene``'s rods have: c (N m^2 s) and the ratio it gives each
    rod's first free-free mode (zeta = c omega_1 / (2 EI), ``rodval.core.damping``), one
    figure when every rod has the same, and the request it came from (a deployed one)."""
    chain = scene.chain
    c = np.broadcast_to(np.asarray(chain.bending_damping, float), np.shape(chain.EI))
    zeta = c * first_free_free_frequency(chain.l, chain.m, chain.EI) / (2.0 * chain.EI)

    def figure(values: np.ndarray) -> str:
        if np.all(values == values[0]):
            return f"{values[0]:.3g}"
        return "[" + ", ".join(f"{v:.3g}" for v in values) + "]"

    request = scene.damping
    stated = ""
    if request is not None and request.of == DEPLOYED:
        stated = f'; bending_damping = {{ ratio = {request.ratio:g}, of = "deployed" }}'
    return f"c = {figure(c)} N m^2 s, a ratio of {figure(zeta)} of each rod's first mode{stated}"
