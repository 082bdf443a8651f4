"""What the full and reduced models share: scene constants, loads and the observation map."""

from __future__ import annotations

from functools import cached_property
from typing import Any

import numpy as np

from rodval.core.loads import LoadSet, load_table
from rodval.core.scene import Scene
from rodval.models.paper_matrices import (
    VARIANTS,
    ChainConstants,
    angle_differences,
    assemble_mass,
    chain_constants,
    damper_power,
    damping_matrix,
    generalized_forces,
    node_positions,
    potential_energy,
    rest_forces,
    stiffness_matrix,
)
from rodval.solvers.ode_model import OdeModel
from rodval.solvers.system import CompiledForm, OdeSystem

#: Right-hand-side implementations: "numba" (compiled, structured; default) or "numpy"
#: (the straightforward dense reference).
KERNELS = ("numba", "numpy")


class PaperSystem(OdeSystem):
    """Base of the paper's ODE systems. Subclasses provide ``numpy_rhs``, the compiled
    kernels (``accel_kernel``, ``compiled_rhs``) and their constants (``kernel_constants``),
    ``jacobian`` and ``bending`` (alpha, beta, alpha', beta' at output times)."""

    has_jacobian = True
    has_energy = True
    #: True for the full model (state [q; q'], 6n), False for the reduced one ([phi; phi']).
    full: bool
    #: accel(V, y, has_load, SX, SY, damped, out) and the RHS_TYPE functions (rhs, mechanics).
    accel_kernel: Any
    compiled_rhs: Any
    compiled_mechanics: Any

    def __init__(self, scene: Scene, coefficients: str = "printed", kernel: str = "numba"):
        if kernel not in KERNELS:
            raise ValueError(f"kernel must be one of {KERNELS}, got {kernel!r}")
        self.kernel = kernel
        self.coefficients = coefficients
        chain = scene.chain
        self.chain = chain
        self.scene = scene
        self.n = chain.n
        self.l = chain.l
        self.cc = chain_constants(chain, coefficients)
        self.damped = bool(np.any(chain.nu > 0))
        self.loads = LoadSet(scene.loads, chain.n)
        self.initial = scene.initial.resolve(chain.n)

    # Dense matrices of the numpy reference and the analytic Jacobians (O(n^2) memory): built
    # only when one of those asks; the default O(n) path never does.
    @cached_property
    def K(self) -> np.ndarray:
        return stiffness_matrix(self.chain)

    @cached_property
    def C(self) -> np.ndarray:
        return damping_matrix(self.chain)

    @cached_property
    def rest(self) -> np.ndarray:
        """A^T kappa rest (N m, 3n): spring forces are K q - rest."""
        return rest_forces(self.chain)

    @cached_property
    def cc_kinetic(self) -> ChainConstants:
        """The kinetic energy always uses the kinematic (printed, symmetric) mass matrix."""
        return self.cc if self.coefficients == "printed" else chain_constants(self.chain)

    def use_kernel(self) -> None:
        """Set up the compiled kernel (subclasses call this last in __init__) and evaluate it
        once, so that loading or compiling it is not part of the integration's wall time."""
        if self.kernel == "numba":
            self.V = self.kernel_constants()
            self._no_load = np.zeros(self.n)
            self._flags = np.array([1.0 if self.damped else 0.0])
            self._mech = np.zeros(2)
        self.rhs(0.0, self.y0)

    def kernel_constants(self) -> np.ndarray:
        """The compiled kernels' constant rows V for this system (O(n))."""
        raise NotImplementedError

    def numpy_rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def rhs(self, t, y):
        if self.kernel == "numpy":
            return self.numpy_rhs(t, y)
        sums = self.loads.suffix_sums(t)
        SX, SY = (self._no_load, self._no_load) if sums is None else sums
        half = y.size // 2
        out = np.empty_like(y)
        out[:half] = y[half:]
        self.accel_kernel(self.V, y, sums is not None, SX, SY, self.damped, out[half:])
        return out

    def compiled(self) -> CompiledForm | None:
        """The compiled form, or None with the numpy kernel or a load that is a plain
        Python callable (no load-table form)."""
        if self.kernel != "numba":
            return None
        table = load_table(self.scene.loads)
        if table is None:
            return None
        return CompiledForm(
            self.compiled_rhs,
            self.V,
            self._flags,
            _NO_MATRICES,
            table,
            mechanics=self.compiled_mechanics,
            name=type(self).__name__,
        )

    def generalized_force(self, t: float, phi: np.ndarray) -> np.ndarray | None:
        """Q(phi, t) (N m) on the phi coordinates, or None when no load acts at t."""
        sums = self.loads.suffix_sums(t)
        return None if sums is None else generalized_forces(self.l, phi, *sums)

    def rigid(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """phi, phi' from a state history Y (nt, N)."""
        raise NotImplementedError

    def bending(self, times: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, ...]:
        """alpha, beta, alpha', beta' (each (nt, n)) from a state history."""
        raise NotImplementedError

    def generalized_rates(self, y: np.ndarray) -> np.ndarray:
        """q' = [phi'; alpha'; beta'] (3n) as the model's equations see it at state y."""
        raise NotImplementedError

    def energy(self, t: float, y: np.ndarray) -> float:
        """E = T + Pi (J) at one state (the same energy ``observe`` reports)."""
        Y = y[None, :]
        kin, pot = self.energies(*self.rigid(Y), *self.bending(np.array([t]), Y))
        return float(kin[0] + pot[0])

    def power(self, t: float, y: np.ndarray) -> tuple[float, float]:
        """(P_ext, P_diss) (W): P_ext = Q(phi, t) . phi' (Q on the phi coordinates only, see
        paper_matrices.generalized_forces); P_diss = q'^T C q' = sum_k nu_k (dD_k/dt)^2 >= 0,
        the power taken out by the hinge dampers (D_k: hinge angles)."""
        phi, dphi = (a[0] for a in self.rigid(y[None, :]))
        Q = self.generalized_force(t, phi)
        p_ext = 0.0 if Q is None else float(Q @ dphi)
        if not self.damped:
            return p_ext, 0.0
        n = self.n
        v = self.generalized_rates(y)
        return p_ext, damper_power(self.chain, v[:n], v[n : 2 * n], v[2 * n :])

    def observe(self, times, Y):
        scene, n = self.scene, self.n
        rods = np.arange(1, n + 1)
        phi, dphi = self.rigid(Y)
        out = {}
        if scene.wants("phi"):
            out["phi"] = (phi, rods)
        if scene.wants("dphi"):
            out["dphi"] = (dphi, rods)
        if scene.wants("alpha", "beta", "energy"):
            alpha, beta, dalpha, dbeta = self.bending(times, Y)
            if scene.wants("alpha"):
                out["alpha"] = (alpha, rods)
            if scene.wants("beta"):
                out["beta"] = (beta, rods)
        if scene.wants("x", "y"):
            x, y = node_positions(self.l, phi)
            nodes = np.arange(0, n + 1)
            if scene.wants("x"):
                out["x"] = (x, nodes)
            if scene.wants("y"):
                out["y"] = (y, nodes)
        if scene.wants("energy"):
            kin, pot = self.energies(phi, dphi, alpha, beta, dalpha, dbeta)
            zero = np.zeros(1, dtype=int)
            out["kinetic"] = (kin[:, None], zero)
            out["potential"] = (pot[:, None], zero)
            out["energy"] = ((kin + pot)[:, None], zero)
        return out

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
            self.compiled_mechanics(
                0.0, y, self.V, self._flags, _NO_MATRICES, _NO_LOADS, self._mech
            )
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
        return kin, potential_energy(self.chain, phi, alpha, beta)


#: Placeholders for the compiled forms' unused arrays (no dense matrices, no loads).
_NO_MATRICES = np.zeros((0, 0, 0))
_NO_LOADS = np.zeros((0, 9))


class PaperModel(OdeModel):
    """A model of the paper. ``coefficients``: "printed" (default, from the kinematics) or
    "published" (the erratum that reproduces the paper's alpha/beta; see paper_matrices).
    ``kernel``: "numba" (default, compiled O(n) kernels) or "numpy" (the straightforward
    dense right-hand side, kept as the reference and benchmark baseline)."""

    system_class: type[PaperSystem]
    OPTIONS = ("coefficients", "kernel")

    def __init__(self, coefficients: str = "printed", kernel: str = "numba"):
        if coefficients not in VARIANTS:
            raise ValueError(f"coefficients must be one of {VARIANTS}, got {coefficients!r}")
        if kernel not in KERNELS:
            raise ValueError(f"kernel must be one of {KERNELS}, got {kernel!r}")
        self.coefficients = coefficients
        self.kernel = kernel

    def options(self):
        return {"coefficients": self.coefficients, "kernel": self.kernel}

    def system(self, scene: Scene) -> PaperSystem:
        return self.system_class(scene, self.coefficients, self.kernel)
