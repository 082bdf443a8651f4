"""Divergence detection, checked after every accepted integrator step.

Three verdicts, each with its own status (``rodval.core.status``):

* ``STATUS_DIVERGED``: a non-finite state (NaN or inf).
* ``STATUS_BLOWUP``: the kinetic energy T(t) exceeds ``blowup_factor`` times its physical
  budget E(0) + W+(t) + ``ENERGY_FLOOR_J``, where W+(t) is the positive work of the loads
  (trapezoid rule on P_ext at the step ends: cheap, and within a factor 2 of the exact
  integral for the smooth load pulses of rodval). The dampers only remove energy and
  Pi >= 0 (K is positive semi-definite), so a valid solution has T <= E within that budget
  up to the model's balance residual.
* ``STATUS_STALLED``: ``stall_steps`` consecutive accepted steps shorter than
  ``min_step_fraction * t_end``.

The energy check needs the system's energy capability (``OdeSystem.has_energy``); it
costs one kinetic-energy evaluation per step: a mass-matrix product, no linear solve, and no
bending recovery in the reduced model (its bending angles stay computed at output times only).
"""

from __future__ import annotations

import math

import numpy as np

from rodval.core.settings import IntegratorSettings
from rodval.core.status import (
    STATUS_BLOWUP,
    STATUS_DIVERGED,
    STATUS_ERROR,
    STATUS_STALLED,
    numerical_failure,
)
from rodval.solvers.system import OdeSystem

#: Absolute slack of the energy budget (J): below it no energy counts as a blow-up (a chain
#: at rest without loads has E(0) = W+ = 0 and may pick up rounding-level motion).
ENERGY_FLOOR_J = 1e-6


class DivergenceGuard:
    """Per-step checks of one run; ``check`` returns (status, message) or None."""

    def __init__(
        self, system: OdeSystem, settings: IntegratorSettings, t_end: float, y0: np.ndarray
    ):
        self.h_min = settings.min_step_fraction * t_end
        self.stall_steps = settings.stall_steps
        self.n_short = 0
        self.factor = settings.blowup_factor
        self.system = system if (system.has_energy and math.isfinite(self.factor)) else None
        #: E(0) of the budget (J); 0 when there is no energy check
        self.E0 = 0.0
        if self.system is not None:
            self.E0 = system.energy_budget(0.0, y0)
            self.w_plus = 0.0
            self.p_prev = self._positive_power(0.0, y0)

    def _positive_power(self, t: float, y: np.ndarray) -> float:
        assert self.system is not None
        return max(self.system.power(t, y)[0], 0.0)

    def check(self, t0: float, t1: float, y: np.ndarray) -> tuple[int, str] | None:
        """Verdict after the accepted step [t0, t1] that ended in state y."""
        if not np.all(np.isfinite(y)):
            return STATUS_DIVERGED, f"diverged: non-finite state at t = {t1:.6g} s"
        self.n_short = self.n_short + 1 if t1 - t0 < self.h_min else 0
        if self.n_short >= self.stall_steps:
            return STATUS_STALLED, (
                f"step size collapse: {self.n_short} consecutive steps shorter than "
                f"min_step_fraction x t_end = {self.h_min:.3g} s (last {t1 - t0:.3g} s) "
                f"at t = {t1:.6g} s"
            )
        if self.system is None:
            return None
        try:
            p = self._positive_power(t1, y)
            E = self.system.kinetic_energy(t1, y)
        except Exception as exc:  # noqa: BLE001 - reported as data, the run stops
            return numerical_failure(exc, t1) or (
                STATUS_ERROR,
                f"energy check failed at t = {t1:.6g} s: {type(exc).__name__}: {exc}",
            )
        self.w_plus += 0.5 * (t1 - t0) * (self.p_prev + p)
        self.p_prev = p
        budget = self.E0 + self.w_plus + ENERGY_FLOOR_J
        if not E <= self.factor * budget:
            return STATUS_BLOWUP, (
                f"energy blow-up: kinetic energy {E:.4g} J > blowup_factor {self.factor:g} x budget "
                f"E(0) + W+ = {budget:.4g} J at t = {t1:.6g} s"
            )
        return None
