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

import math
from typing import NamedTuple

import numpy as np
from numba import njit, types
from scipy.integrate._ivp import dop853_coefficients as dc

from rodval.solvers import radau, stiffness
from rodval.solvers.audit import GAUSS_NODES
from rodval.solvers.budget import EVENT, NON_FINITE, OK, counters, next_attempt, smallest_step
from rodval.solvers.dop853_events import any_crossing, interpolate, locate, no_events
from rodval.solvers.guard import GuardSpec, guard_step, new_monitor
from rodval.solvers.limits import MAX_IMPLICIT_SIZE
from rodval.solvers.signature import (
    EVENTS_TYPE,
    RHS_TYPE,
    background_allowed,
    compile_in_background,
    in_cache,
    wait_for,
)
from rodval.solvers.signature import F1 as _F1
from rodval.solvers.signature import F2 as _F2
from rodval.solvers.signature import F3 as _F3

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


@njit(cache=True, inline="always", error_model="numpy")
def _combine(out, base, K, coef, count, h):
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
def _rms(x):
    return np.sqrt(np.mean(x * x))


@njit(cache=True, error_model="numpy")
def _initial_step(rhs, P, S, M, L, t0, y0, f0, t_bound, rtol, atol, max_step, order, tmp, f1):
    """scipy's select_initial_step (Hairer, Sec. II.4) for a method of the given order (``atol``:
    one per coordinate); uses one evaluation."""
    scale = atol + np.abs(y0) * rtol
    d0 = _rms(y0 / scale)
    d1 = _rms(f0 / scale)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, t_bound - t0)
    for i in range(y0.shape[0]):  # a loop: a slice assignment compiles numba's shape check
        tmp[i] = y0[i] + h0 * f0[i]
    rhs(t0 + h0, tmp, P, S, M, L, f1)
    d2 = _rms((f1 - f0) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1.0))
    return min(100.0 * h0, h1, t_bound - t0, max_step)


@njit(cache=True, inline="always", error_model="numpy")
def _attempt(rhs, P, S, M, L, t, t_new, y, K, y_new, tmp, rtol, atol):
    """One DOP853 step from (t, y) to t_new (s): the stages into K, the solution into y_new;
    returns Hairer's error norm (< 1: accepted) with the scale atol[i] + rtol max(|y_i|,
    |y_new_i|) (``atol``: one per coordinate). 12 evaluations, O(N) each combination."""
    N = y.shape[0]
    h = t_new - t
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
    return h * err5 / np.sqrt((err5 + 0.01 * err3) * N)


@njit(cache=True, inline="always", error_model="numpy")
def _check_state(mechanics, P, S, M, L, t, t_new, y_new, guard, mon, mech):
    """The accepted state y_new at t_new (step from t): ``NON_FINITE`` if it is not finite,
    else the guard's code (``guard_step``; the mechanics evaluated when it checks energy)."""
    if not np.all(np.isfinite(y_new)):
        return NON_FINITE
    guarded = np.isfinite(guard[2])
    if guarded:
        mechanics(t_new, y_new, P, S, M, L, mech)
    return guard_step(guard, mon, t_new - t, mech, guarded)


@njit(cache=True, inline="always")
def _flip(sw, implicit, h, t_new, evaluations, sc, N):
    """Whether the switching stepper changes stepper after the accepted step h (s) ending at
    t_new (s) (``stiffness.watch_explicit``/``watch_implicit`` on the cost so far; sc:
    Radau's scalars, for its factorizations and Newton iterations)."""
    if implicit:
        cost = stiffness.implicit_cost(evaluations, sc[radau.NLU], sc[radau.NITER], N)
        return stiffness.watch_implicit(sw, t_new, cost)
    return stiffness.watch_explicit(sw, h, t_new, float(evaluations))


@njit(cache=True, inline="always", error_model="numpy")
def _dense_coefficients(rhs, P, S, M, L, t, t_new, y, y_new, K, F, tmp, zero):
    """The 7th-order interpolant's coefficients F over the accepted step [t, t_new]: three
    extra stages (3 evaluations), O(N) each combination (``zero``: N zeros)."""
    N = y.shape[0]
    h = t_new - t
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
def _write_outputs(F, y, t, t_new, t_cut, times, n_out, Y):
    """The interpolated states at every output time in (t, t_cut] (t_cut <= t_new, the
    step's end) into Y from row n_out; returns the next row."""
    nt = times.shape[0]
    h = t_new - t
    while n_out < nt and times[n_out] <= t_cut:
        interpolate(F, y, (times[n_out] - t) / h, Y[n_out])
        n_out += 1
    return n_out


@njit(cache=True, inline="always", error_model="numpy")
def _power_integral(mechanics, P, S, M, L, F, y, t, h, span, tmp, mech, acc):
    """[int P_ext, int P_diss] (J) over [t, t + span] inside the step [t, t + h] into acc[:2]:
    Gauss-Legendre with ``rodval.solvers.audit.GAUSS_NODES`` nodes on the dense output (the
    scipy path's ``step_integral``). GAUSS_NODES evaluations of ``mechanics``, O(N) each."""
    acc[0] = 0.0
    acc[1] = 0.0
    if span <= 0.0:
        return
    for i in range(_GAUSS_X.shape[0]):
        ts = t + 0.5 * span * (_GAUSS_X[i] + 1.0)
        interpolate(F, y, (ts - t) / h, tmp)
        mechanics(ts, tmp, P, S, M, L, mech)
        acc[0] += _GAUSS_W[i] * mech[1]
        acc[1] += _GAUSS_W[i] * mech[2]
    acc[0] *= 0.5 * span
    acc[1] *= 0.5 * span


@njit(cache=True, inline="always", error_model="numpy")
def _audit_step(mechanics, P, S, M, L, F, y, t, t_new, t_cut, times, n_out, tmp, mech, total, W):
    """The energy audit over [t, t_cut] of the accepted step [t, t_new] (t_cut < t_new at an
    event): the running [W_ext, D] (J) at each output time in it into W's rows from n_out,
    then ``total`` advanced to t_cut."""
    h = t_new - t
    part = np.empty(2)
    j = n_out
    while j < times.shape[0] and times[j] <= t_cut:
        _power_integral(mechanics, P, S, M, L, F, y, t, h, times[j] - t, tmp, mech, part)
        W[j, 0] = total[0] + part[0]
        W[j, 1] = total[1] + part[1]
        j += 1
    _power_integral(mechanics, P, S, M, L, F, y, t, h, t_cut - t, tmp, mech, part)
    total[0] += part[0]
    total[1] += part[1]


@njit(cache=True, inline="always", error_model="numpy")
def _step_control(
    rhs, P, S, M, L, t, t_bound, h_abs, y, K, y_new, tmp, controls, atol, reporting, cnt
):
    """Step attempts from (t, y) towards t_bound with Hairer's step-size control until one is
    accepted (its stages in K, its solution in y_new). ``controls``, ``atol`` as in ``run``; ``cnt``:
    ``budget.counters``, updated. Returns (code, t
    of the accepted step's end, the next step size): ``OK``, or ``STEP_TOO_SMALL``,
    ``BUDGET``, ``WALL`` or ``NON_FINITE`` with t unchanged.

    An attempt whose stages are not finite (a step far beyond the stability limit of a stiff
    transient, e.g. just after a lock) is rejected and the step cut by MIN_FACTOR, as scipy's
    DOP853 does with its infinite error norm; a state whose attempts stay non-finite down to
    the smallest step is ``NON_FINITE`` (diverged), not ``STEP_TOO_SMALL``."""
    rtol, max_step = controls[0], controls[2]
    min_step = smallest_step(t)
    h_abs = min(max(h_abs, min_step), max_step)
    rejected = False
    finite = True  # whether the last attempt's stages were finite
    while True:
        code, t_new = next_attempt(t, t_bound, h_abs, min_step, finite, controls, reporting, cnt)
        if code != OK:
            return code, t, h_abs
        h_abs = t_new - t
        err = _attempt(rhs, P, S, M, L, t, t_new, y, K, y_new, tmp, rtol, atol)
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
def _record_step(rhs, mechanics, events, arrays, t, t_new, buffers, times, n_out, Y, W, cnt, dense):
    """After the accepted step [t, t_new]: the events at its end (g_new, against g_old at
    its start); the dense output (unless the stepper wrote it: ``dense``) when an output time
    falls in it, the audit runs (W with rows: ``_audit_step``) or an event crosses; the
    crossing located
    (``dop853_events.locate``), then the outputs written and the audit advanced up to it.
    Returns (next output row, event index or -1, the time the step is cut at: the event's
    or t_new). ``arrays``: the form's (P, S, M, L, E, directions); ``buffers``: the loop's
    (see ``run``); ``cnt[0]``: evaluations, updated."""
    P, S, M, L, E, directions = arrays
    y, y_new, K, F, tmp, zero, mech, total, g, g_old, g_new = buffers
    crossing = False
    if E.shape[0] > 0:
        events(t_new, y_new, P, S, M, L, E, g_new)
        crossing = any_crossing(g_old, g_new, directions)
    outputs = n_out < times.shape[0] and times[n_out] <= t_new
    audited = W.shape[0] > 0
    if not dense and (outputs or audited or crossing):
        _dense_coefficients(rhs, P, S, M, L, t, t_new, y, y_new, K, F, tmp, zero)
        cnt[0] += 3
    index, t_cut = -1, t_new
    if crossing:
        index, t_cut = locate(
            events, P, S, M, L, E, directions, F, y, t, t_new, g_old, g_new, tmp, g
        )
    if audited:
        _audit_step(mechanics, P, S, M, L, F, y, t, t_new, t_cut, times, n_out, tmp, mech, total, W)
    if outputs:
        n_out = _write_outputs(F, y, t, t_new, t_cut, times, n_out, Y)
    return n_out, index, t_cut


@njit(cache=True, inline="always")
def _buffers(y0, total, n_events):
    """The loop's buffers: state, trial state, stages, interpolant, scratch, zeros, mechanics,
    the audit's totals, event values (scratch, at the step's start, at its end). O(N)."""
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


@njit(cache=True, inline="always", error_model="numpy")
def _segment_start(rhs, P, S, M, L, t, t_bound, buffers, controls, atol, cnt, stepper, mode):
    """The derivative at a segment's start into K[0] and the first step size (s): the given
    one (controls[3] > 0) or ``_initial_step``'s for the stepper's order; 1 or 2
    evaluations, counted in cnt[0]. ``stepper``: (Radau's work, its scalars, the switching
    state); ``mode``: (implicit, switching): Radau IIA starts (``radau.start``) when
    implicit; else, when switching, the spectral radius is estimated
    (``stiffness.spectral_radius``)."""
    y, y_new, K, F, tmp = buffers[0], buffers[1], buffers[2], buffers[3], buffers[4]
    rw, sc, switch = stepper
    implicit, switching = mode
    rhs(t, y, P, S, M, L, K[0])
    cnt[0] += 1
    if not np.all(np.isfinite(K[0])):
        return 0.0
    if implicit:
        radau.start(rhs, P, S, M, L, t, y, K[0], rw, sc, cnt)
    elif switching:
        switch[stiffness.RHO] = stiffness.spectral_radius(
            rhs, P, S, M, L, t, y, K[0], y_new, F[3], tmp
        )
        cnt[0] += 2 * stiffness.POWER_ITERATIONS
    if controls[3] > 0:
        return min(controls[3], t_bound - t)
    cnt[0] += 1
    rtol, max_step = controls[0], controls[2]
    order = radau.ERROR_ORDER if implicit else 7
    return _initial_step(
        rhs, P, S, M, L, t, y, K[0], t_bound, rtol, atol, max_step, order, tmp, np.empty(y.shape[0])
    )


@njit(cache=True, inline="always", error_model="numpy")
def _advance(rhs, P, S, M, L, args):
    """One accepted step from (t, y) by the stepper in use (Radau IIA when ``implicit``,
    which also writes the dense output F): ``_step_control``'s or ``radau.step``'s return.
    ``args``: (t, t_bound, h_abs, buffers, controls, atol, reporting, cnt, rw, sc, implicit)."""
    t, t_bound, h_abs, buffers, controls, atol, reporting, cnt, rw, sc, implicit = args
    y, y_new, K, F, tmp = buffers[0], buffers[1], buffers[2], buffers[3], buffers[4]
    if implicit:
        return radau.step(
            rhs, P, S, M, L, t, t_bound, h_abs, y, K[0], y_new, K[N_STAGES], F,
            controls, atol, reporting, cnt, rw, sc,
        )  # fmt: skip
    return _step_control(
        rhs, P, S, M, L, t, t_bound, h_abs, y, K, y_new, tmp, controls, atol, reporting, cnt
    )


#: A compiled form's arrays as the loop takes them: (P, S, M, L, E, directions) (its functions
#: are separate arguments: numba warns of tuples of first-class functions as experimental).
_ARRAYS = types.Tuple((_F2, _F1, _F3, _F2, _F2, _F1))

_RUN_SIGNATURE = types.Tuple((types.int64, types.int64, types.int64, types.int64, types.float64))(
    RHS_TYPE,
    RHS_TYPE,
    EVENTS_TYPE,
    _ARRAYS,
    _F1,
    _F1,
    _F1,
    _F1,
    _F1,
    _F1,
    types.boolean,
    _F2,
    _F2,
    types.Tuple((_F1, _F1, _F1, _F1)),
)


@njit(cache=True, error_model="numpy")  # compiled for _RUN_SIGNATURE only: ``loop``
def run(
    rhs, mechanics, events, arrays, y0, edges, times, controls, atol, guard, reporting, Y, W, carry
):
    """Integrate from edges[0] to edges[-1], restarting at each interior edge (breakpoint),
    writing the state at ``times`` into Y, until the end or the first event. ``rhs``,
    ``mechanics``, ``events`` and ``arrays`` (P, S, M, L, E, directions): a
    ``CompiledForm``'s functions and arrays. ``controls``: [rtol, atol, max_step (s),
    first_step (s; <= 0 selects it), max_nfev, deadline (a ``time.perf_counter()`` value, s;
    inf: none), stepper (``DOP853_STEPPER``, or ``RADAU_STEPPER``, its own dense output)];
    ``atol`` (N,): each coordinate's absolute tolerance (controls[1] is not read); the budgets'
    codes: ``budget.exhausted``; the time reached goes to the progress reporter if ``reporting``.
    ``carry``: (mon, total, hit, switch), over restarts. ``guard``: ``GuardSpec.as_array()``,
    checked by ``guard_step`` after every accepted step (``mon``: its monitor); ``mechanics(t,
    y, ...)`` writes (T, P_ext, P_diss), for the guard when guard[2] is finite.
    ``W`` (nt, 2), or (0, 2) for no audit: the audit's running [W_ext, D] (J) at the output
    times from the running ``total`` (``_audit_step``: 3 evaluations for the dense output on
    every step, GAUSS_NODES evaluations of ``mechanics`` per step and per output time).
    Events (E has rows): a crossing at an accepted step located on the dense output
    (``dop853_events.locate``), outputs and audit taken up to it; returns ``EVENT`` at its
    time, its index in hit[0] and the state there in hit[1:] (the caller applies the jump).

    The ``SWITCHING_STEPPER`` (N <= ``MAX_IMPLICIT_SIZE``) runs DOP853, switches to Radau
    IIA when its steps are limited by stability and back when Radau IIA proves dearer
    (``rodval.solvers.stiffness``; ``switch``: its state, ``stiffness.new_state``).

    Returns (number of output times written, nfev, accepted steps, code, t reached)."""
    P, S, M, L, E, directions = arrays
    N = y0.shape[0]
    mon, total, hit, switch = carry
    buffers = _buffers(y0, total, E.shape[0])
    y, y_new, K, F, tmp, zero, mech, total, g, g_old, g_new = buffers
    switching = controls[6] == SWITCHING_STEPPER and N <= MAX_IMPLICIT_SIZE
    implicit = controls[6] == RADAU_STEPPER or (switching and switch[stiffness.IMPLICIT] == 1.0)
    rw = radau.work(N, implicit)
    sc = np.zeros(7)
    n_out = 0
    cnt = counters()  # evaluations, and the clock reads' counts and time
    nsteps = 0
    t = edges[0]
    while n_out < times.shape[0] and times[n_out] <= t:
        radau.copy_into(Y[n_out], y)
        n_out += 1
    if E.shape[0] > 0:
        events(t, y, P, S, M, L, E, g_old)
    for seg in range(edges.shape[0] - 1):
        t, t_bound = edges[seg], edges[seg + 1]
        stepper, mode = (rw, sc, switch), (implicit, switching)
        h_abs = _segment_start(
            rhs, P, S, M, L, t, t_bound, buffers, controls, atol, cnt, stepper, mode
        )
        if not np.all(np.isfinite(K[0])):  # the derivative at an accepted state
            return n_out, cnt[0], nsteps, NON_FINITE, t
        while t < t_bound:
            args = (t, t_bound, h_abs, buffers, controls, atol, reporting, cnt, rw, sc, implicit)
            code, t_new, h_abs = _advance(rhs, P, S, M, L, args)
            nsteps += code == OK
            if code == OK:
                code = _check_state(mechanics, P, S, M, L, t, t_new, y_new, guard, mon, mech)
            if code != OK:
                return n_out, cnt[0], nsteps, code, t
            h = t_new - t
            flip = switching and _flip(switch, implicit, h, t_new, cnt[0], sc, N)
            n_out, index, t_cut = _record_step(
                rhs, mechanics, events, arrays, t, t_new, buffers, times, n_out, Y, W, cnt, implicit
            )
            if index >= 0:
                hit[0] = index
                interpolate(F, y, (t_cut - t) / h, hit[1:])
                return n_out, cnt[0], nsteps, EVENT, t_cut
            t = t_new
            for i in range(N):
                y[i] = y_new[i]
                K[0, i] = K[N_STAGES, i]
            radau.copy_into(g_old, g_new)
            if flip:  # the other stepper from here on (see above)
                implicit = not implicit
                if implicit:
                    rw = radau.work(N, True)
                    radau.start(rhs, P, S, M, L, t, y, K[0], rw, sc, cnt)
    return n_out, cnt[0], nsteps, OK, t


#: The key of the loop's background compilation (``signature.compile_in_background``).
_LOOP_KEY = "dop853.run"


def loop():
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


class CompiledRun(NamedTuple):
    """What ``integrate_compiled`` returns."""

    n_out: int  #: output times written
    nfev: int  #: right-hand-side evaluations
    nsteps: int  #: accepted steps
    code: int  #: how the loop ended (OK, STEP_TOO_SMALL, ..., EVENT)
    t: float  #: time reached (s): the event's time for EVENT
    monitor: np.ndarray  #: the guard's figures (``guard_step``)
    work: np.ndarray  #: the audit's [W_ext, D] (J) at the output times written, (n_out, 2)
    event: int  #: the event's index (EVENT), else -1
    y: np.ndarray  #: the state at the event (before its jump; EVENT), else empty
    #: the switching stepper's state (``stiffness.new_state``; carried over restarts)
    switch: np.ndarray


def start_monitor(form, t: float, y: np.ndarray, guard: GuardSpec) -> np.ndarray:
    """The guard's monitor for a run of ``form`` from (t, y): the load power there in it
    when the guard checks energy (``rodval.solvers.guard.new_monitor``)."""
    if form.mechanics is None or not guard.checks_energy:
        return new_monitor()
    mech = np.zeros(3)
    form.mechanics(t, np.array(y, float), form.P, form.S, form.M, form.L, mech)
    return new_monitor(mech[1])


def integrate_compiled(
    form,
    y0: np.ndarray,
    edges: np.ndarray,
    times: np.ndarray,
    rtol: float,
    atol: float | np.ndarray,
    max_step: float,
    first_step: float | None,
    max_nfev: int,
    guard: GuardSpec,
    Y: np.ndarray,
    deadline: float = math.inf,
    reporting: bool = False,
    audit: bool = False,
    monitor: np.ndarray | None = None,
    total: np.ndarray | None = None,
    stepper: int = DOP853_STEPPER,
    switch: np.ndarray | None = None,
) -> CompiledRun:
    """Run ``run`` on a CompiledForm (see ``run``; without ``form.mechanics`` there is no
    blow-up check and no audit; ``deadline``: a ``time.perf_counter()`` value, s;
    ``reporting``: report progress; ``audit``: integrate the load and damper powers;
    ``stepper``: ``DOP853_STEPPER``, ``RADAU_STEPPER`` or ``SWITCHING_STEPPER``, see ``run``;
    ``switch``: the switching state, carried on like ``monitor``; ``atol``: one absolute
    tolerance for every coordinate, or one per coordinate (N,), e.g.
    ``rodval.solvers.compiled.atol_vector``'s).
    A run continued after an event passes the guard's ``monitor`` and the audit's running
    ``total`` [W_ext, D] (J) on (both updated in place); new ones start from (edges[0], y0)."""
    g = guard.as_array()
    if form.mechanics is None:
        g[2] = math.inf
        if audit:
            raise ValueError("an energy audit needs the compiled form's mechanics")
    mechanics = form.mechanics if form.mechanics is not None else form.rhs
    events = form.events if form.events is not None else no_events
    first = -1.0 if first_step is None else first_step
    y0 = np.array(y0, float)
    atol_v = np.array(np.broadcast_to(np.asarray(atol, float), y0.shape))
    controls = np.array([rtol, atol_v.max(), max_step, first, max_nfev, deadline, stepper], float)
    mon = start_monitor(form, float(edges[0]), y0, guard) if monitor is None else monitor
    total = np.zeros(2) if total is None else total
    W = np.zeros((len(times) if audit else 0, 2))
    hit = np.zeros(y0.size + 1)
    switch = stiffness.new_state() if switch is None else switch
    n_out, nfev, nsteps, code, t = loop()(
        form.rhs,
        mechanics,
        events,
        (form.P, form.S, form.M, form.L, form.E, form.directions),
        y0,
        np.array(edges, float),
        np.array(times, float),
        controls,
        atol_v,
        g,
        bool(reporting),
        Y,
        W,
        (mon, total, hit, switch),
    )
    event = int(hit[0]) if code == EVENT else -1
    y_event = hit[1:].copy() if code == EVENT else np.zeros(0)
    return CompiledRun(
        int(n_out),
        int(nfev),
        int(nsteps),
        int(code),
        float(t),
        mon,
        W[:n_out],
        event,
        y_event,
        switch,
    )
