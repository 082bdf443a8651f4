"""When the compiled loop of "auto" leaves DOP853 for Radau IIA, and when it comes back
(``rodval.solvers.dop853.SWITCHING_STEPPER``).

The test is the one an engineer would make, done by the loop itself on its own figures:

1. **Does DOP853 spend its steps on the fastest mode?** The spectral radius rho of the
   Jacobian at each segment's start (``spectral_radius``: power iteration on J^2, so that
   the undamped bending pairs +-i omega of an elastic chain count at full size;
   2 x ``POWER_ITERATIONS`` evaluations): ``STIFF_STEPS`` accepted steps in a row with
   h rho > ``STIFF_H_RHO`` (fewer than 4 pi steps per period of that mode) mean that the
   step is set by that mode, either at DOP853's stability boundary (h rho =
   ``STABILITY_IMAG`` = 5.96 on the imaginary axis, from its stability polynomial) or by the
   tolerance on the mode's own motion. Hairer's test of dop853.f (h |f(y1) - f(s12)| /
   |y1 - s12| > 6.1) asks only the first: on the paper chain at EI = 1e9 its estimate is
   right (1.7 at the median, h rho = 1.6) but DOP853 is not at its boundary, it resolves the
   bending mode to the tolerance (about 4 steps per period), so the test never fires while
   Radau IIA, which damps that mode, needs 46x fewer evaluations.
2. **Is Radau IIA cheaper on this motion?** A fast mode that the motion excites above the
   tolerance must be resolved by either method (the paper chain at EI = 1e5 sits at
   h rho = 2-4, yet Radau IIA needs 6x DOP853's evaluations there). So Radau IIA's cost
   per simulated second (``implicit_cost``: evaluations, factorizations and solves, in
   evaluations) since its start is compared every ``TRIAL_STEPS`` steps while it runs
   with DOP853's over its last stiff steps; when it is ``BACK_FACTOR`` higher,
   DOP853 takes over again, and waits ``RETRY_STEPS`` steps, doubling with each such
   return, before the next trial.

Both costs are counts, never clock readings, so the choice and the results are the same on
every machine. The switch is recorded (``SolverStats.switch``) with both figures.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rodval.solvers.signature import Arr, Form, rhs_at

#: DOP853's stability boundary on the imaginary axis: the largest y with |R(i y')| <= 1 for
#: all y' <= y, R its stability function (``tests/test_radau.py`` computes it from scipy's
#: coefficients; a constant here, so that importing the loop does not pay 0.07 s for it).
STABILITY_IMAG = 5.96
#: Steps with h rho above this count as spent on the fastest mode (fewer than 4 pi steps
#: per its period): limited by stability (h rho near STABILITY_IMAG) or by the tolerance on
#: that mode's own motion; either way the trial of Radau IIA is worth making.
STIFF_H_RHO = 0.5
#: Consecutive steps spent on the fastest mode before the switch, Radau steps between two
#: comparisons of the costs, DOP853 steps after a failed trial before the next one (doubling with
#: each failure: a trial costs about TRIAL_STEPS Radau steps and a Jacobian, so failed trials
#: cost a few per cent of the DOP853 steps between them).
STIFF_STEPS, TRIAL_STEPS, RETRY_STEPS = 15, 24, 200
#: Radau IIA gives way only when it costs this much more than DOP853 did: both rates
#: vary with the motion (a load pulse, a lock), and each switch costs a start.
BACK_FACTOR = 1.5
#: Power iterations of ``spectral_radius``.
POWER_ITERATIONS = 12

#: Slots of the switching state (``new_state``), carried over a run's restarts: rho (1/s)
#: at the segment's start; stiff steps in a row, the time (s) and cost where they began, the
#: cost at the last step's end; at the last switch to Radau IIA: time (s), the step h (s),
#: DOP853's cost per simulated second over the stiff steps; Radau steps since, their cost per
#: simulated second over the trial; the stepper now
#: (1: Radau IIA); switches to Radau IIA so far; failed trials so far; DOP853 steps to wait
#: before the next trial; the time (s) of the first switch.
(
    RHO,
    COUNT,
    T0,
    C0,
    C_LAST,
    T_SWITCH,
    H_SWITCH,
    RATE_EXPLICIT,
    STEPS,
    RATE_IMPLICIT,
    IMPLICIT,
    SWITCHES,
    FAILED,
    WAIT,
    T_FIRST,
) = range(15)


def new_state() -> Arr:
    """The switching state of a new run: no estimate, no switch (NaN times)."""
    sw = np.zeros(15)
    sw[[RHO, T_SWITCH, RATE_IMPLICIT, T_FIRST]] = np.nan
    return sw


@njit(cache=True)
def implicit_cost(evaluations: float, factorizations: float, iterations: float, N: int) -> float:
    """Radau IIA's work in evaluations of an O(N) right-hand side (about 50 N flops): the
    evaluations, each pair of LU factorizations (real and complex, about 3.3 N^3 flops) as
    N^2 / 15 and each Newton iteration's two solves (about 5 N^2 flops) as N / 10."""
    return evaluations + factorizations * N * N / 15.0 + iterations * N / 10.0


@njit(cache=True, inline="always", error_model="numpy")
def _unit_product(
    form: Form, t: float, y: Arr, f: Arr, v: Arr, out: Arr, tmp: Arr, eps: float
) -> float:
    """J v (v a unit vector) by a forward difference of size eps into out; returns |J v|.
    One evaluation, O(N)."""
    N = y.shape[0]
    for i in range(N):
        tmp[i] = y[i] + eps * v[i]
    rhs_at(form, t, tmp, out)
    acc = 0.0
    for i in range(N):
        out[i] = (out[i] - f[i]) / eps
        acc += out[i] * out[i]
    return float(np.sqrt(acc))


@njit(cache=True, error_model="numpy")
def spectral_radius(form: Form, t: float, y: Arr, f: Arr, v: Arr, w: Arr, tmp: Arr) -> float:
    """|lambda|max of df/dy at (t, y) (f = rhs(t, y); ``form``: ``signature.FORM_TYPE``) by
    power iteration on J^2, J v by forward differences: sqrt(|J^2 v|) for unit v.
    2 x POWER_ITERATIONS evaluations, O(N) each (v, w, tmp: scratch). From below when the
    top eigenvalues cluster (n similar rods), within the cluster, which is what the switch
    needs; NaN if a product is not finite."""
    N = y.shape[0]
    eps = np.sqrt(np.finfo(np.float64).eps) * (1.0 + np.sqrt(np.sum(y * y)))
    for i in range(N):
        v[i] = np.sin(i + 1.0)
    v /= np.sqrt(np.sum(v * v))
    rho: float = 0.0
    for _ in range(POWER_ITERATIONS):
        a = _unit_product(form, t, y, f, v, w, tmp, eps)
        if not np.isfinite(a):
            return np.nan
        if a == 0.0:
            return rho
        w /= a
        b = _unit_product(form, t, y, f, w, v, tmp, eps)
        if not np.isfinite(b):
            return np.nan
        rho = np.sqrt(a * b)
        if b == 0.0:
            return rho
        v /= b
    return rho


@njit(cache=True, inline="always")
def watch_explicit(sw: Arr, h: float, t_new: float, cost: float) -> bool:
    """After an accepted DOP853 step h (s) ending at t_new (s), ``cost`` evaluations so far:
    counts the steps spent on the fastest mode (h rho > STIFF_H_RHO) unless a failed trial
    still asks to wait; True when STIFF_STEPS in a row say so: switch now (recorded)."""
    if sw[WAIT] > 0.0:
        sw[WAIT] -= 1.0
        sw[COUNT] = 0.0
    elif h * sw[RHO] > STIFF_H_RHO:
        if sw[COUNT] == 0.0:
            sw[T0], sw[C0] = t_new - h, sw[C_LAST]
        sw[COUNT] += 1.0
    else:
        sw[COUNT] = 0.0
    sw[C_LAST] = cost
    if sw[COUNT] < STIFF_STEPS:
        return False
    sw[T_SWITCH], sw[H_SWITCH] = t_new, h
    sw[RATE_EXPLICIT] = (cost - sw[C0]) / (t_new - sw[T0])
    sw[STEPS], sw[COUNT], sw[IMPLICIT] = 0.0, 0.0, 1.0
    sw[SWITCHES] += 1.0
    if np.isnan(sw[T_FIRST]):
        sw[T_FIRST] = t_new
    return True


@njit(cache=True, inline="always")
def watch_implicit(sw: Arr, t_new: float, cost: float) -> bool:
    """After an accepted Radau step ending at t_new (s), ``cost``: its work so far
    (``implicit_cost``). Radau's cost per simulated second since its first
    TRIAL_STEPS // 2 steps (which pay the start: a Jacobian, steps growing from DOP853's)
    is compared with DOP853's every TRIAL_STEPS steps; True when it is
    higher by BACK_FACTOR: switch back, and wait RETRY_STEPS x 2^(failed trials - 1) DOP853 steps before
    another trial."""
    sw[STEPS] += 1.0
    start = TRIAL_STEPS // 2
    if sw[STEPS] == start:
        sw[T0], sw[C0] = t_new, cost
    if sw[STEPS] <= start or (sw[STEPS] - start) % TRIAL_STEPS != 0:
        return False
    sw[RATE_IMPLICIT] = (cost - sw[C0]) / (t_new - sw[T0])
    if sw[RATE_IMPLICIT] <= BACK_FACTOR * sw[RATE_EXPLICIT]:
        return False
    sw[IMPLICIT] = 0.0
    sw[FAILED] += 1.0
    sw[WAIT] = RETRY_STEPS * 2.0 ** (sw[FAILED] - 1.0)
    sw[C_LAST] = cost
    return True
