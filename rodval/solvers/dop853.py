"""DOP853 (Dormand-Prince 8(5,3), Hairer's step control) as one compiled (numba) loop.

The same method, coefficients (scipy's ``dop853_coefficients``), error norm, step-size control,
initial-step selection and 7th-order dense output as ``scipy.integrate.DOP853``, but the whole
integration (all steps, across the scene's load breakpoints, dense output at output times)
runs without returning to Python, so the per-step overhead of the Python loop (~50-100 us)
disappears. The right-hand side is the system's compiled form (``rodval.solvers.system.CompiledForm``):
a first-class numba function of type ``RHS_TYPE`` called with the form's arrays, so this loop
imports no model and is compiled (and cached on disk) once for every model.

Cost: 12 right-hand-side evaluations per accepted step (+3 on steps holding output times), and
O(N) work per stage combination. Arithmetic is IEEE (numba's numpy error model): a huge
state gives inf or NaN, never an exception: an attempt with non-finite stages is rejected and
the step cut (``_step_control``); when that continues down to the smallest step, or an
accepted state is not finite, the run ends as ``NON_FINITE`` at the time it
reached (a division by zero in the initial-step choice raised ZeroDivisionError). The
wall-clock budget reads the clock (a call back into Python, ~1 us) before a step attempt once
every ``budget.WALL_CHECK_EVALUATIONS`` evaluations, or as soon as ``budget.READ_INTERVAL_S``
of work has gone by when evaluations are dear (``budget.read_interval``): a run stops within
one step of its deadline.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit, types
from scipy.integrate._ivp import dop853_coefficients as dc

from rodval.solvers import radau, stiffness
from rodval.solvers.audit import GAUSS_NODES
from rodval.solvers.budget import (
    EVENT,
    NON_FINITE,
    OK,
    Settings,
    counters,
    next_attempt,
    smallest_step,
)
from rodval.solvers.dop853_events import any_crossing, interpolate, locate
from rodval.solvers.guard import guard_step
from rodval.solvers.limits import MAX_IMPLICIT_SIZE
from rodval.solvers.signature import F1 as _F1
from rodval.solvers.signature import F2 as _F2
from rodval.solvers.signature import (
    FORM_TYPE,
    Arr,
    Form,
    Kernel,
    background_allowed,
    compile_in_background,
    events_at,
    in_cache,
    mechanics_at,
    rhs_at,
    tuple_type,
    wait_for,
)

N_STAGES = dc.N_STAGES
_A = np.ascontiguousarray(dc.A)
_B = np.ascontiguousarray(dc.B)
_C = np.ascontiguousarray(dc.C)
_E3 = np.ascontiguousarray(dc.E3)
_E5 = np.ascontiguousarray(dc.E5)
_D = np.ascontiguousarray(dc.D)
_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(GAUSS_NODES)

#: Steppers of ``run`` (controls[6]): this module's DOP853, ``rodval.solvers.radau``'s Radau
#: IIA, or DOP853 that switches to Radau IIA when its steps are limited by stability and
#: Radau IIA proves cheaper (``rodval.solvers.stiffness``: "auto").
DOP853_STEPPER, RADAU_STEPPER, SWITCHING_STEPPER = 0, 1, 2


SAFETY, MIN_FACTOR, MAX_FACTOR, ERROR_EXPONENT = 0.9, 0.2, 10.0, -1.0 / 8.0

#: The loop's work arrays (``_buffers``): y, y_new, K (16, N: the stages), F (7, N: the
#: interpolant), tmp, zero (N zeros), mech (3: ``mechanics``' output), total (2: the audit's
#: running [W_ext, D], J), g, g_old, g_new (the events' values: scratch, at the step's start,
#: at its end).
Buffers = tuple[Arr, ...]
#: The loop's outputs: (times (s), Y: the states at them, W: the audit's rows, (0, 2) for none).
Outputs = tuple[Arr, Arr, Arr]
#: The stepper's state: (Radau IIA's work ``radau.work``, its scalars, the switching state).
Stepper = tuple[radau.Work, Arr, Arr]


@njit(cache=True, inline="always", error_model="numpy")
def _combine(out: Arr, base: Arr, K: Arr, coef: Arr, count: int, h: float) -> None:
    """out = base + h * sum_{j < count} coef[j] K[j], as contiguous loops over K's rows (no
    temporary arrays; ``out`` must not alias ``base`` or K)."""
    N = out.shape[0]
    for i in range(N):
        out[i] = 0.0
    for j in range(count):
        c = coef[j]
        if c != 0.0:
            row = K[j]
            for i in range(N):
                out[i] += c * row[i]
    for i in range(N):
        out[i] = base[i] + h * out[i]


@njit(cache=True, error_model="numpy")
def _rms(x: Arr) -> float:
    return float(np.sqrt(np.mean(x * x)))


@njit(cache=True, error_model="numpy")
def _initial_step(
    form: Form,
    t0: float,
    y0: Arr,
    f0: Arr,
    t_bound: float,
    settings: Settings,
    order: int,
    tmp: Arr,
    f1: Arr,
) -> float:
    """scipy's select_initial_step (Hairer, Sec. II.4) for a method of the given order (the
    ``settings``' rtol, max_step and atol, one per coordinate); uses one evaluation."""
    controls, atol = settings[0], settings[1]
    rtol, max_step = controls[0], controls[2]
    scale = atol + np.abs(y0) * rtol
    d0 = _rms(y0 / scale)
    d1 = _rms(f0 / scale)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, t_bound - t0)
    for i in range(y0.shape[0]):  # a loop: a slice assignment compiles numba's shape check
        tmp[i] = y0[i] + h0 * f0[i]
    rhs_at(form, t0 + h0, tmp, f1)
    d2 = _rms((f1 - f0) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1.0))
    return float(min(100.0 * h0, h1, t_bound - t0, max_step))


@njit(cache=True, inline="always", error_model="numpy")
def _attempt(form: Form, t: float, t_new: float, buffers: Buffers, settings: Settings) -> float:
    """One DOP853 step from (t, y) to t_new (s): the stages into K, the solution into y_new
    (``buffers``); returns Hairer's error norm (< 1: accepted) with the scale atol[i] + rtol
    max(|y_i|, |y_new_i|) (the ``settings``' atol: one per coordinate). 12 evaluations, O(N)
    each combination."""
    y, y_new, K, tmp = buffers[0], buffers[1], buffers[2], buffers[4]
    rtol, atol = settings[0][0], settings[1]
    N = y.shape[0]
    h = t_new - t
    P, S, M, L, rhs = form[0], form[1], form[2], form[3], form[6]  # once, not per evaluation
    for s in range(1, N_STAGES):
        _combine(tmp, y, K, _A[s], s, h)
        rhs(t + _C[s] * h, tmp, P, S, M, L, K[s])
    _combine(y_new, y, K, _B, N_STAGES, h)
    rhs(t_new, y_new, P, S, M, L, K[N_STAGES])
    err5 = 0.0
    err3 = 0.0
    for i in range(N):
        sc = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
        e5 = 0.0
        e3 = 0.0
        for j in range(N_STAGES + 1):
            e5 += K[j, i] * _E5[j]
            e3 += K[j, i] * _E3[j]
        err5 += (e5 / sc) ** 2
        err3 += (e3 / sc) ** 2
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    return float(h * err5 / np.sqrt((err5 + 0.01 * err3) * N))


@njit(cache=True, inline="always", error_model="numpy")
def _check_state(
    form: Form, t: float, t_new: float, buffers: Buffers, settings: Settings, mon: Arr
) -> int:
    """The accepted state y_new (``buffers``) at t_new (step from t): ``NON_FINITE`` if it is
    not finite, else the guard's code (``guard_step`` on the ``settings``' guard and its
    monitor ``mon``; the mechanics evaluated when it checks energy)."""
    y_new, mech, guard = buffers[1], buffers[6], settings[2]
    if not np.all(np.isfinite(y_new)):
        return NON_FINITE
    guarded = np.isfinite(guard[2])
    if guarded:
        mechanics_at(form, t_new, y_new, mech)
    return int(guard_step(guard, mon, t_new - t, mech, guarded))


@njit(cache=True, inline="always")
def _flip(
    sw: Arr, implicit: bool, h: float, t_new: float, evaluations: int, sc: Arr, N: int
) -> bool:
    """Whether the switching stepper changes stepper after the accepted step h (s) ending at
    t_new (s) (``stiffness.watch_explicit``/``watch_implicit`` on the cost so far; sc:
    Radau's scalars, for its factorizations and Newton iterations)."""
    if implicit:
        cost = stiffness.implicit_cost(evaluations, sc[radau.NLU], sc[radau.NITER], N)
        return stiffness.watch_implicit(sw, t_new, cost)
    return stiffness.watch_explicit(sw, h, t_new, float(evaluations))


@njit(cache=True, inline="always", error_model="numpy")
def _dense_coefficients(form: Form, t: float, t_new: float, buffers: Buffers) -> None:
    """The 7th-order interpolant's coefficients F over the accepted step [t, t_new] (into
    ``buffers``): three extra stages (3 evaluations), O(N) each combination."""
    y, y_new, K, F, tmp, zero = (
        buffers[0],
        buffers[1],
        buffers[2],
        buffers[3],
        buffers[4],
        buffers[5],
    )
    N = y.shape[0]
    h = t_new - t
    P, S, M, L, rhs = form[0], form[1], form[2], form[3], form[6]  # once, not per evaluation
    for s in range(N_STAGES + 1, 16):
        _combine(tmp, y, K, _A[s], s, h)
        rhs(t + _C[s] * h, tmp, P, S, M, L, K[s])
    for i in range(N):
        f0 = y_new[i] - y[i]
        F[0, i] = f0
        F[1, i] = h * K[0, i] - f0
        F[2, i] = 2.0 * f0 - h * (K[N_STAGES, i] + K[0, i])
    for p in range(4):
        _combine(F[3 + p], zero, K, _D[p], 16, h)


@njit(cache=True, inline="always", error_model="numpy")
def _write_outputs(
    buffers: Buffers, t: float, t_new: float, t_cut: float, outputs: Outputs, n_out: int
) -> int:
    """The interpolated states at every output time in (t, t_cut] (t_cut <= t_new, the
    step's end) into the ``outputs``' Y from row n_out; returns the next row."""
    F, y = buffers[3], buffers[0]
    times, Y = outputs[0], outputs[1]
    nt = times.shape[0]
    h = t_new - t
    while n_out < nt and times[n_out] <= t_cut:
        interpolate(F, y, (times[n_out] - t) / h, Y[n_out])
        n_out += 1
    return n_out


@njit(cache=True, inline="always", error_model="numpy")
def _power_integral(
    form: Form, buffers: Buffers, t: float, h: float, span: float, acc: Arr
) -> None:
    """[int P_ext, int P_diss] (J) over [t, t + span] inside the step [t, t + h] into acc[:2]:
    Gauss-Legendre with ``rodval.solvers.audit.GAUSS_NODES`` nodes on the dense output (the
    scipy path's ``step_integral``). GAUSS_NODES evaluations of ``mechanics``, O(N) each."""
    F, y, tmp, mech = buffers[3], buffers[0], buffers[4], buffers[6]
    acc[0] = 0.0
    acc[1] = 0.0
    if span <= 0.0:
        return
    P, S, M, L, mechanics = form[0], form[1], form[2], form[3], form[7]
    for i in range(_GAUSS_X.shape[0]):
        ts = t + 0.5 * span * (_GAUSS_X[i] + 1.0)
        interpolate(F, y, (ts - t) / h, tmp)
        mechanics(ts, tmp, P, S, M, L, mech)
        acc[0] += _GAUSS_W[i] * mech[1]
        acc[1] += _GAUSS_W[i] * mech[2]
    acc[0] *= 0.5 * span
    acc[1] *= 0.5 * span


@njit(cache=True, inline="always", error_model="numpy")
def _audit_step(
    form: Form, buffers: Buffers, t: float, t_new: float, t_cut: float, outputs: Outputs, n_out: int
) -> None:
    """The energy audit over [t, t_cut] of the accepted step [t, t_new] (t_cut < t_new at an
    event): the running [W_ext, D] (J) at each output time in it into the ``outputs``' W
    from row n_out, then the running ``total`` (``buffers``) advanced to t_cut. GAUSS_NODES
    evaluations of ``mechanics`` per output time in it and once more; its dense output costs
    3 evaluations on every step (``_record_step``)."""
    times, W, total = outputs[0], outputs[2], buffers[7]
    h = t_new - t
    part = np.empty(2)
    j = n_out
    while j < times.shape[0] and times[j] <= t_cut:
        _power_integral(form, buffers, t, h, times[j] - t, part)
        W[j, 0] = total[0] + part[0]
        W[j, 1] = total[1] + part[1]
        j += 1
    _power_integral(form, buffers, t, h, t_cut - t, part)
    total[0] += part[0]
    total[1] += part[1]


@njit(cache=True, inline="always", error_model="numpy")
def _step_control(
    form: Form,
    t: float,
    t_bound: float,
    h_abs: float,
    buffers: Buffers,
    settings: Settings,
    cnt: Arr,
) -> tuple[int, float, float]:
    """Step attempts from (t, y) towards t_bound with Hairer's step-size control until one is
    accepted (its stages in K, its solution in y_new: ``buffers``). ``settings`` as in
    ``run``; ``cnt``: ``budget.counters``, updated. Returns (code, t of the accepted step's
    end, the next step size): ``OK``, or ``STEP_TOO_SMALL``, ``BUDGET``, ``WALL`` or
    ``NON_FINITE`` with t unchanged.

    An attempt whose stages are not finite (a step far beyond the stability limit of a stiff
    transient, e.g. just after a lock) is rejected and the step cut by MIN_FACTOR, as scipy's
    DOP853 does with its infinite error norm; a state whose attempts stay non-finite down to
    the smallest step is ``NON_FINITE`` (diverged), not ``STEP_TOO_SMALL``."""
    controls = settings[0]
    max_step = controls[2]
    min_step = smallest_step(t)
    h_abs = min(max(h_abs, min_step), max_step)
    rejected = False
    finite = True  # whether the last attempt's stages were finite
    while True:
        code, t_new = next_attempt(t, t_bound, h_abs, min_step, finite, controls, cnt)
        if code != OK:
            return code, t, h_abs
        h_abs = t_new - t
        err = _attempt(form, t, t_new, buffers, settings)
        cnt[0] += N_STAGES
        finite = np.isfinite(err)
        if finite and err < 1.0:
            factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err**ERROR_EXPONENT)
            if rejected:
                factor = min(1.0, factor)
            return OK, t_new, h_abs * factor
        h_abs *= max(MIN_FACTOR, SAFETY * err**ERROR_EXPONENT) if finite else MIN_FACTOR
        rejected = True


@njit(cache=True, inline="always", error_model="numpy")
def _record_step(
    form: Form,
    t: float,
    t_new: float,
    buffers: Buffers,
    outputs: Outputs,
    n_out: int,
    cnt: Arr,
    dense: bool,
) -> tuple[int, int, float]:
    """After the accepted step [t, t_new]: the events at its end (g_new, against g_old at
    its start); the dense output (unless the stepper wrote it: ``dense``) when an output time
    falls in it, the audit runs (W with rows: ``_audit_step``) or an event crosses; the
    crossing located (``dop853_events.locate``), then the outputs written and the audit
    advanced up to it. Returns (next output row, event index or -1, the time the step is cut
    at: the event's or t_new). ``buffers``, ``outputs``: the loop's (see ``run``);
    ``cnt[0]``: evaluations, updated."""
    y, y_new, F, g_old, g_new = buffers[0], buffers[1], buffers[3], buffers[9], buffers[10]
    times, W = outputs[0], outputs[2]
    crossing = False
    if form[4].shape[0] > 0:
        events_at(form, t_new, y_new, g_new)
        crossing = any_crossing(g_old, g_new, form[5])
    due = n_out < times.shape[0] and times[n_out] <= t_new
    audited = W.shape[0] > 0
    if not dense and (due or audited or crossing):
        _dense_coefficients(form, t, t_new, buffers)
        cnt[0] += 3
    index, t_cut = -1, t_new
    if crossing:
        index, t_cut = locate(form, F, y, t, t_new, (g_old, g_new), (buffers[4], buffers[8]))
    if audited:
        _audit_step(form, buffers, t, t_new, t_cut, outputs, n_out)
    if due:
        n_out = _write_outputs(buffers, t, t_new, t_cut, outputs, n_out)
    return n_out, index, t_cut


@njit(cache=True, inline="always")
def _buffers(y0: Arr, total: Arr, n_events: int) -> Buffers:
    """The loop's work arrays (``Buffers``), the state y0's copy and the audit's ``total``
    among them. O(N)."""
    N = y0.shape[0]
    return (
        y0.copy(),
        np.empty(N),
        np.empty((16, N)),
        np.empty((7, N)),
        np.empty(N),
        np.zeros(N),
        np.zeros(3),
        total,
        np.empty(n_events),
        np.empty(n_events),
        np.empty(n_events),
    )


@njit(cache=True, inline="always")
def _accept(buffers: Buffers) -> None:
    """The accepted step's end becomes the next step's start: y, its derivative K[0] and the
    events' values g_old. O(N)."""
    y, y_new, K, g_old, g_new = buffers[0], buffers[1], buffers[2], buffers[9], buffers[10]
    for i in range(y.shape[0]):
        y[i] = y_new[i]
        K[0, i] = K[N_STAGES, i]
    radau.copy_into(g_old, g_new)


@njit(cache=True, inline="always")
def _start(form: Form, t: float, buffers: Buffers, outputs: Outputs) -> int:
    """A run's start at t (s): the state y (``buffers``) at the output times <= t into the
    ``outputs``' Y, the events' values there into g_old. Returns the next output row."""
    y, g_old = buffers[0], buffers[9]
    times, Y = outputs[0], outputs[1]
    n_out = 0
    while n_out < times.shape[0] and times[n_out] <= t:
        radau.copy_into(Y[n_out], y)
        n_out += 1
    if form[4].shape[0] > 0:
        events_at(form, t, y, g_old)
    return n_out


@njit(cache=True, inline="always", error_model="numpy")
def _segment_start(
    form: Form,
    t: float,
    t_bound: float,
    buffers: Buffers,
    settings: Settings,
    cnt: Arr,
    stepper: Stepper,
    mode: tuple[bool, bool],
) -> float:
    """The derivative at a segment's start into K[0] and the first step size (s): the given
    one (controls[3] > 0) or ``_initial_step``'s for the stepper's order; 1 or 2
    evaluations, counted in cnt[0]. ``mode``: (implicit, switching): Radau IIA starts
    (``radau.start``) when implicit; else, when switching, the spectral radius is estimated
    (``stiffness.spectral_radius``)."""
    y, y_new, K, F, tmp = buffers[0], buffers[1], buffers[2], buffers[3], buffers[4]
    rw, sc, switch = stepper
    implicit, switching = mode
    rhs_at(form, t, y, K[0])
    cnt[0] += 1
    if not np.all(np.isfinite(K[0])):
        return 0.0
    if implicit:
        radau.start(form, t, y, K[0], rw, sc, cnt)
    elif switching:
        switch[stiffness.RHO] = stiffness.spectral_radius(form, t, y, K[0], y_new, F[3], tmp)
        cnt[0] += 2 * stiffness.POWER_ITERATIONS
    controls = settings[0]
    if controls[3] > 0:
        return float(min(controls[3], t_bound - t))
    cnt[0] += 1
    order = radau.ERROR_ORDER if implicit else 7
    return _initial_step(form, t, y, K[0], t_bound, settings, order, tmp, np.empty(y.shape[0]))


@njit(cache=True, inline="always", error_model="numpy")
def _advance(
    form: Form,
    t: float,
    t_bound: float,
    h_abs: float,
    buffers: Buffers,
    settings: Settings,
    cnt: Arr,
    stepper: Stepper,
    implicit: bool,
) -> tuple[int, float, float]:
    """One accepted step from (t, y) by the stepper in use (Radau IIA when ``implicit``,
    which also writes the dense output F): ``_step_control``'s or ``radau.step``'s return."""
    y, y_new, K, F = buffers[0], buffers[1], buffers[2], buffers[3]
    if implicit:
        state = (y, K[0], y_new, K[N_STAGES], F)
        return radau.step(form, t, t_bound, h_abs, state, settings, cnt, stepper[0], stepper[1])
    return _step_control(form, t, t_bound, h_abs, buffers, settings, cnt)


#: The loop's signature: a compiled form's arrays (P, S, M, L, E, directions), its functions
#: apart (numba would type a tuple holding functions in Python: 0.1 ms more per call).
_RUN_SIGNATURE = tuple_type(types.int64, types.int64, types.int64, types.int64, types.float64)(
    tuple_type(*FORM_TYPE.types[:6]),
    *FORM_TYPE.types[6:],
    _F1,
    _F1,
    tuple_type(_F1, _F1, _F1),
    tuple_type(_F1, _F2, _F2),
    tuple_type(_F1, _F1, _F1, _F1),
)


@njit(cache=True, error_model="numpy")  # compiled for _RUN_SIGNATURE only: ``loop``
def run(
    rows: tuple[Arr, ...],
    rhs: Kernel,
    mechanics: Kernel,
    events: Kernel,
    y0: Arr,
    edges: Arr,
    settings: Settings,
    outputs: Outputs,
    carry: tuple[Arr, Arr, Arr, Arr],
) -> tuple[int, int, int, int, float]:
    """Integrate the compiled form (``signature.FORM_TYPE``: ``rows``, then its functions)
    from (edges[0], y0) to edges[-1], restarting at each interior edge, writing the states at
    the ``outputs``' times into their Y, until the end or the first event. ``settings``:
    ``budget.Settings`` (controls[6], the stepper: ``DOP853_STEPPER``, ``RADAU_STEPPER`` or
    ``SWITCHING_STEPPER``, switching between them when N <= ``MAX_IMPLICIT_SIZE``,
    ``rodval.solvers.stiffness``). ``carry`` (over restarts): the guard's monitor
    (``guard_step`` after every accepted step, on ``mechanics``' (T, P_ext, P_diss) when
    guard[2] is finite), the audit's running [W_ext, D] (J), written into the ``outputs``' W
    (nt, 2; (0, 2): no audit) at the output times (``_audit_step``), the event's hit, the
    switching state. An event crossing in an accepted step is located on the dense output
    (``dop853_events.locate``), outputs and audit taken up to it: ``EVENT`` at its time, its
    index in hit[0], the state there in hit[1:] (the caller applies the jump).
    Returns (number of output times written, nfev, accepted steps, code, t reached)."""
    form = (rows[0], rows[1], rows[2], rows[3], rows[4], rows[5], rhs, mechanics, events)
    controls, N = settings[0], y0.shape[0]
    mon, total, hit, switch = carry
    buffers = _buffers(y0, total, form[4].shape[0])
    y, K, F = buffers[0], buffers[2], buffers[3]
    switching = controls[6] == SWITCHING_STEPPER and N <= MAX_IMPLICIT_SIZE
    implicit = controls[6] == RADAU_STEPPER or (switching and switch[stiffness.IMPLICIT] == 1.0)
    rw, sc = radau.work(N, implicit), np.zeros(7)  # Radau IIA's work and scalars
    cnt = counters()  # evaluations, and the clock reads' counts and time
    nsteps = 0
    t = edges[0]
    n_out = _start(form, t, buffers, outputs)
    for seg in range(edges.shape[0] - 1):
        t, t_bound = edges[seg], edges[seg + 1]
        stepper = (rw, sc, switch)
        mode = (implicit, switching)
        h_abs = _segment_start(form, t, t_bound, buffers, settings, cnt, stepper, mode)
        if not np.all(np.isfinite(K[0])):  # the derivative at an accepted state
            return n_out, cnt[0], nsteps, NON_FINITE, t
        while t < t_bound:
            code, t_new, h_abs = _advance(
                form, t, t_bound, h_abs, buffers, settings, cnt, stepper, implicit
            )
            nsteps += code == OK
            if code == OK:
                code = _check_state(form, t, t_new, buffers, settings, mon)
            if code != OK:
                return n_out, cnt[0], nsteps, code, t
            h = t_new - t
            flip = switching and _flip(switch, implicit, h, t_new, cnt[0], sc, N)
            n_out, index, t_cut = _record_step(
                form, t, t_new, buffers, outputs, n_out, cnt, implicit
            )
            if index >= 0:
                hit[0] = index
                interpolate(F, y, (t_cut - t) / h, hit[1:])
                return n_out, cnt[0], nsteps, EVENT, t_cut
            t = t_new
            _accept(buffers)
            if flip:  # the other stepper from here on (see above)
                implicit = not implicit
                if implicit:
                    rw = radau.work(N, True)
                    radau.start(form, t, y, K[0], rw, sc, cnt)
                stepper = (rw, sc, switch)
    return n_out, cnt[0], nsteps, OK, t


#: The key of the loop's background compilation (``signature.compile_in_background``).
_LOOP_KEY = "dop853.run"


def loop() -> Any:
    """``run`` compiled for ``_RUN_SIGNATURE``, its only signature: loaded from numba's
    cache after the background compilation of ``warm_up`` if any (else compiled here)."""
    if not run.signatures:
        wait_for(_LOOP_KEY)
        run.compile(_RUN_SIGNATURE)
        run.disable_compile()
    return run


def warm_up() -> None:
    """Compile ``run`` in a background process (once; ``background_allowed``) when numba's
    cache lacks it, while this process builds the system and compiles its kernels."""
    if run.signatures or not background_allowed() or in_cache(run, _RUN_SIGNATURE) is not False:
        return
    compile_in_background(_LOOP_KEY, "from rodval.solvers import dop853; dop853.loop()")


if in_cache(run, _RUN_SIGNATURE):  # loaded on import, as a study worker's warm-up expects
    loop()
