"""Divergence detection, checked after every accepted step: one definition for every path.

Three verdicts, each with its own status (``rodval.core.status``):

* ``STATUS_DIVERGED``: a non-finite state (NaN or inf).
* ``STATUS_BLOWUP``: the kinetic energy T(t) exceeds ``blowup_factor`` times its physical
  budget E(0) + W+(t) + ``ENERGY_FLOOR_J``, where W+(t) is the positive work of the loads
  (trapezoid rule on P_ext at the checked states: cheap, and within a factor 2 of the exact
  integral for the smooth load pulses of rodval). The dampers only remove energy and
  Pi >= 0 (K is positive semi-definite), so a valid solution has T <= E within that budget
  up to the model's balance residual.
* ``STATUS_STALLED``: ``stall_steps`` consecutive accepted steps shorter than
  ``min_step_fraction * t_end``.

What is checked is a ``GuardSpec``; the verdict's text comes from the message functions here.
Three paths use them: ``DivergenceGuard`` (the scipy loop), the compiled DOP853 loop
(``rodval.solvers.dop853.guard_step`` on ``GuardSpec.as_array``, its figures formatted by
``rodval.solvers.compiled``) and the exudyn model's per-step check (``EnergyBudget``), so the
same blow-up reads the same on each.

The energy check needs the system's energy capability (``OdeSystem.has_energy``); it
costs one kinetic-energy evaluation per step: a mass-matrix product, no linear solve, and no
bending recovery in the reduced model (its bending angles stay computed at output times only).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

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

#: A verdict: the status and its one-line message.
Verdict = tuple[int, str]


@dataclass(frozen=True)
class GuardSpec:
    """What the guard checks on one run.

    min_step_s : a step shorter than this (s) counts towards a stall (0: never).
    stall_steps : that many consecutive short steps are a stall.
    blowup_factor : T above this times the budget is a blow-up (inf: no energy check).
    energy0_J : E(0) of the budget (J), the energy of the initial state.
    """

    min_step_s: float = 0.0
    stall_steps: int = 2**62
    blowup_factor: float = math.inf
    energy0_J: float = 0.0

    @classmethod
    def from_settings(
        cls, settings: IntegratorSettings, t_end: float, energy0_J: float = 0.0
    ) -> GuardSpec:
        """The spec of a run of ``t_end`` s with ``settings``, budget from E(0) = energy0_J."""
        return cls(
            min_step_s=settings.min_step_fraction * t_end,
            stall_steps=settings.stall_steps,
            blowup_factor=settings.blowup_factor,
            energy0_J=energy0_J,
        )

    @property
    def checks_energy(self) -> bool:
        return math.isfinite(self.blowup_factor)

    def budget(self, w_plus: float) -> float:
        """E(0) + W+ + ENERGY_FLOOR_J (J) after positive load work ``w_plus`` (J)."""
        return self.energy0_J + w_plus + ENERGY_FLOOR_J

    def as_array(self) -> np.ndarray:
        """[min_step_s, stall_steps, blowup_factor, energy0_J, ENERGY_FLOOR_J], the form the
        compiled loop reads (``rodval.solvers.dop853.guard_step``)."""
        return np.array(
            [
                self.min_step_s,
                float(self.stall_steps),
                self.blowup_factor,
                self.energy0_J,
                ENERGY_FLOOR_J,
            ]
        )


def diverged_message(t: float) -> str:
    """The STATUS_DIVERGED message for a non-finite state at t (s)."""
    return f"diverged: non-finite state at t = {t:.6g} s"


def stalled_message(count: int, min_step_s: float, last_s: float, t: float) -> str:
    """The STATUS_STALLED message: ``count`` steps shorter than ``min_step_s``, the last
    ``last_s`` (s), ending at t (s)."""
    return (
        f"step size collapse: {count} consecutive steps shorter than "
        f"min_step_fraction x t_end = {min_step_s:.3g} s (last {last_s:.3g} s) "
        f"at t = {t:.6g} s"
    )


def blowup_message(kinetic: float, factor: float, budget: float, t: float) -> str:
    """The STATUS_BLOWUP message: kinetic energy ``kinetic`` (J) above ``factor`` x
    ``budget`` (J) at t (s)."""
    return (
        f"energy blow-up: kinetic energy {kinetic:.4g} J > blowup_factor {factor:g} x budget "
        f"E(0) + W+ = {budget:.4g} J at t = {t:.6g} s"
    )


class EnergyBudget:
    """The blow-up check of one run: W+ by the trapezoid rule on the positive load power
    at the checked states, and the verdict on T against ``spec``'s budget. O(1) per check."""

    def __init__(self, spec: GuardSpec):
        self.spec = spec
        self.w_plus = 0.0
        self._last: tuple[float, float] | None = None  # (t, positive power) of the last state

    def start(self, t: float, power: float) -> None:
        """Start W+ at t (s) with load power ``power`` (W), without a verdict."""
        self._last = (t, max(power, 0.0))

    def check(self, t: float, power: float, kinetic: float) -> Verdict | None:
        """Verdict on the state at t (s) with load power ``power`` (W) and kinetic energy
        ``kinetic`` (J); without ``start`` the first call starts W+ at t."""
        p = max(power, 0.0)
        if self._last is not None:
            t0, p0 = self._last
            self.w_plus += 0.5 * (t - t0) * (p0 + p)
        self._last = (t, p)
        budget = self.spec.budget(self.w_plus)
        if not kinetic <= self.spec.blowup_factor * budget:
            return STATUS_BLOWUP, blowup_message(kinetic, self.spec.blowup_factor, budget, t)
        return None


class DivergenceGuard:
    """Per-step checks of one run of ``system`` from y0 over [0, t_end] (s) with
    ``settings``; ``check`` returns a verdict or None. Its ``spec`` (the budget's E(0) from
    the system's energy at y0, 0 without an energy check) is what the compiled loop checks."""

    def __init__(
        self, system: OdeSystem, settings: IntegratorSettings, t_end: float, y0: np.ndarray
    ):
        checked = system.has_energy and math.isfinite(settings.blowup_factor)
        energy0 = system.energy_budget(0.0, y0) if checked else 0.0
        self.spec = GuardSpec.from_settings(settings, t_end, energy0)
        self.n_short = 0
        self.system = system if checked else None
        self.energy: EnergyBudget | None = None
        if self.system is not None:
            self.energy = EnergyBudget(self.spec)
            self.energy.start(0.0, self.system.power(0.0, y0)[0])

    def check(self, t0: float, t1: float, y: np.ndarray) -> Verdict | None:
        """Verdict after the accepted step [t0, t1] that ended in state y."""
        if not np.all(np.isfinite(y)):
            return STATUS_DIVERGED, diverged_message(t1)
        self.n_short = self.n_short + 1 if t1 - t0 < self.spec.min_step_s else 0
        if self.n_short >= self.spec.stall_steps:
            return STATUS_STALLED, stalled_message(self.n_short, self.spec.min_step_s, t1 - t0, t1)
        if self.system is None or self.energy is None:
            return None
        try:
            p = self.system.power(t1, y)[0]
            kinetic = self.system.kinetic_energy(t1, y)
        except Exception as exc:  # noqa: BLE001 - reported as data, the run stops
            return numerical_failure(exc, t1) or (
                STATUS_ERROR,
                f"energy check failed at t = {t1:.6g} s: {type(exc).__name__}: {exc}",
            )
        return self.energy.check(t1, p, kinetic)
