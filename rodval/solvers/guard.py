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

What is checked is a ``GuardSpec``; the check itself is one compiled function, ``guard_step``
(stall count, W+, the budget), and the verdict's text comes from ``verdict``. Three paths use
them: ``DivergenceGuard`` (the scipy loop), the compiled DOP853 loop (which calls
``guard_step`` inside its loop) and the exudyn model's per-step check (``Monitor``), so the
same blow-up is judged by the same arithmetic and reads the same on each.

The energy check needs the system's energy capability (``OdeSystem.has_energy``); it
costs one kinetic-energy evaluation per step: a mass-matrix product, no linear solve, and no
bending recovery in the reduced model (its bending angles stay computed at output times only).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from rodval.core.settings import IntegratorSettings
from rodval.core.status import (
    STATUS_BLOWUP,
    STATUS_DIVERGED,
    STATUS_ERROR,
    STATUS_STALLED,
    exception_line,
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
        compiled check reads (``guard_step``)."""
        return np.array(
            [
                self.min_step_s,
                float(self.stall_steps),
                self.blowup_factor,
                self.energy0_J,
                ENERGY_FLOOR_J,
            ]
        )


#: Codes of ``guard_step`` (and of the compiled loop, ``rodval.solvers.dop853``).
OK, BLOWUP, STALLED = 0, 4, 5


@njit(cache=True, error_model="numpy")
def guard_step(g: np.ndarray, mon: np.ndarray, h: float, mech: np.ndarray, guarded: bool) -> int:
    """The guard after one accepted step of h (s): the one arithmetic of every path.
    ``g``: ``GuardSpec.as_array()``; ``mon``: the run's monitor [short steps in a row, last
    step (s), W+ (J), last positive load power (W), T (J), budget (J)], updated here (the
    figures of a verdict's message); ``mech``: (T, P_ext) at the step's end, read only when
    ``guarded``. Returns ``STALLED``, ``BLOWUP`` or ``OK``. O(1)."""
    mon[0] = mon[0] + 1.0 if h < g[0] else 0.0
    mon[1] = h
    if mon[0] >= g[1]:
        return STALLED
    if guarded:
        p = max(mech[1], 0.0)
        mon[2] += 0.5 * h * (mon[3] + p)
        mon[3] = p
        mon[4] = mech[0]
        mon[5] = g[3] + mon[2] + g[4]
        if not mech[0] <= g[2] * mon[5]:
            return BLOWUP
    return OK


def new_monitor(power0: float = 0.0) -> np.ndarray:
    """A run's monitor for ``guard_step``, the load power at the start ``power0`` (W) in it."""
    mon = np.zeros(6)
    mon[3] = max(power0, 0.0)
    return mon


def verdict(code: int, mon: np.ndarray, t: float, spec: GuardSpec) -> Verdict | None:
    """The status and message of ``guard_step``'s ``code`` on the step that ended at t (s),
    with the monitor's figures; None for OK."""
    if code == STALLED:
        return STATUS_STALLED, stalled_message(int(mon[0]), spec.min_step_s, mon[1], t)
    if code == BLOWUP:
        return STATUS_BLOWUP, blowup_message(mon[4], spec.blowup_factor, mon[5], t)
    return None


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


class Monitor:
    """The blow-up check of a run checked at states it is handed (the exudyn model's):
    ``guard_step`` with W+ by the trapezoid rule between the checked states."""

    def __init__(self, spec: GuardSpec):
        self.spec = spec
        self.g = spec.as_array()
        self.mon = new_monitor()
        self._t: float | None = None  # time of the last checked state (s)

    def check(self, t: float, power: float, kinetic: float) -> Verdict | None:
        """Verdict on the state at t (s) with load power ``power`` (W) and kinetic energy
        ``kinetic`` (J); the first call starts W+ at t."""
        if self._t is None:
            self.mon[3] = max(power, 0.0)
            h = 0.0
        else:
            h = t - self._t
        self._t = t
        code = guard_step(self.g, self.mon, h, np.array([kinetic, power]), True)
        return verdict(code, self.mon, t, self.spec)


class DivergenceGuard:
    """Per-step checks of one run of ``system`` from y0 over [0, t_end] (s) with
    ``settings``; ``check`` returns a verdict or None. Its ``spec`` (the budget's E(0) from
    the system's energy at y0, 0 without an energy check) is what the compiled loop checks."""

    def __init__(
        self, system: OdeSystem, settings: IntegratorSettings, t_end: float, y0: np.ndarray
    ):
        checked = system.has_energy and math.isfinite(settings.blowup_factor)
        energy0 = system.energy_budget(0.0, y0) if checked else 0.0
        power0 = system.power(0.0, y0)[0] if checked else 0.0
        self.spec = GuardSpec.from_settings(settings, t_end, energy0)
        self.g = self.spec.as_array()
        self.system = system if checked else None
        self.mon = new_monitor(power0)

    def check(self, t0: float, t1: float, y: np.ndarray) -> Verdict | None:
        """Verdict after the accepted step [t0, t1] that ended in state y."""
        if not np.all(np.isfinite(y)):
            return STATUS_DIVERGED, diverged_message(t1)
        mech = np.zeros(2)
        if self.system is not None:
            try:
                mech[1] = self.system.power(t1, y)[0]
                mech[0] = self.system.kinetic_energy(t1, y)
            except Exception as exc:  # noqa: BLE001 - reported as data, the run stops
                return numerical_failure(exc, t1) or (
                    STATUS_ERROR,
                    f"energy check failed at t = {t1:.6g} s: {exception_line(exc)}",
                )
        code = guard_step(self.g, self.mon, t1 - t0, mech, self.system is not None)
        return verdict(code, self.mon, t1, self.spec)
