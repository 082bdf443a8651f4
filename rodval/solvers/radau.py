"""Radau IIA (order 5, three stages; Hairer & Wanner, Solving ODEs II, Sec. IV.8) as one
compiled (numba) loop: the implicit method of rodval's compiled path, for stiff scenes.

The same method, constants, simplified Newton iteration, error estimate, step-size control
(Gustafsson's predictive controller), Jacobian reuse and cubic dense output as
``scipy.integrate.Radau``, with three differences of means, not of method: the Jacobian is
formed by forward differences inside the loop (one evaluation per state component, Hairer's
increment sqrt(eps max(1e-5, |y_j|))), the dense LU factorizations are rodval's own
(``lu_factor``/``lu_solve``: partial pivoting, no BLAS, so a run is the same on every
machine), and the previous step's ``h_abs`` is kept for the controller (scipy keeps the one
before it). The loop itself (outputs, events, guard, audit, budgets) is ``dop853.loop``:
the dense output is written in that loop's interpolant form.

Cost per accepted step: 3 evaluations per Newton iteration (at most ``NEWTON_MAXITER``),
one at the step's end, and, when the step size changes by more than 20 % or Newton
converges slowly, a Jacobian (N evaluations, O(N^2)) and two LU factorizations (one real,
one complex: O(N^3)); the dense linear algebra makes it the method for small N (the paper's
chains, deployments: N <= a few hundred), which is how ``rodval.solvers.stiffness`` prices it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from rodval.solvers.budget import OK, Settings, next_attempt, smallest_step
from rodval.solvers.dop853_events import interpolate
from rodval.solvers.signature import Arr, Form, rhs_at

#: The stepper's buffers (``work``).
Work = tuple[Arr, ...]
#: A step's arrays, the loop's: (y, f = rhs(t, y), y_new, f_new, F: the dense output).
Step = tuple[Arr, Arr, Arr, Arr, Arr]

S6 = 6.0**0.5
#: Collocation nodes (fractions of the step).
C = np.array([(4.0 - S6) / 10.0, (4.0 + S6) / 10.0, 1.0])
#: Error-estimate combination of the stage increments.
E = np.array([-13.0 - 7.0 * S6, -13.0 + 7.0 * S6, -1.0]) / 3.0
#: Eigenvalues of the inverse of the Butcher matrix: one real, one complex pair.
MU_REAL = 3.0 + 3.0 ** (2.0 / 3.0) - 3.0 ** (1.0 / 3.0)
MU_COMPLEX = (
    3.0
    + 0.5 * (3.0 ** (1.0 / 3.0) - 3.0 ** (2.0 / 3.0))
    - 0.5j * (3.0 ** (5.0 / 6.0) + 3.0 ** (7.0 / 6.0))
)
#: The transformation that diagonalises the Butcher matrix, and its inverse.
T = np.array(
    [
        [0.09443876248897524, -0.14125529502095421, 0.03002919410514742],
        [0.25021312296533332, 0.20412935229379994, -0.38294211275726192],
        [1.0, 1.0, 0.0],
    ]
)
TI = np.array(
    [
        [4.17871859155190428, 0.32768282076106237, 0.52337644549944951],
        [-4.17871859155190428, -0.32768282076106237, 0.47662355450055044],
        [0.50287263494578682, -2.57192694985560522, 0.59603920482822492],
    ]
)
#: Dense output: y(t + x h) = y + sum_k (Z^T P)[:, k] x^(k+1).
P = np.array(
    [
        [13.0 / 3.0 + 7.0 * S6 / 3.0, -23.0 / 3.0 - 22.0 * S6 / 3.0, 10.0 / 3.0 + 5.0 * S6],
        [13.0 / 3.0 - 7.0 * S6 / 3.0, -23.0 / 3.0 + 22.0 * S6 / 3.0, 10.0 / 3.0 - 5.0 * S6],
        [1.0 / 3.0, -8.0 / 3.0, 10.0 / 3.0],
    ]
)

NEWTON_MAXITER = 6
MIN_FACTOR, MAX_FACTOR = 0.2, 10.0
#: The method's order for the initial step (scipy's choice for Radau: its error estimate's).
ERROR_ORDER = 3
_EPS = np.finfo(float).eps

#: Slots of the stepper's scalars (``start``): the last accepted step (s; 0: none), its error
#: norm, whether the Jacobian is current (1/0), whether the LU factors are valid (1/0),
#: whether a previous step's dense output exists to predict from (1/0), pairs of LU
#: factorizations and Newton iterations so far (never reset: the cost the switching stepper
#: counts).
H_OLD, ERR_OLD, CURRENT_JAC, LU_VALID, HAVE_SOL, NLU, NITER = range(7)


@njit(cache=True, inline="always")
def copy_into(dst: Arr, src: Arr) -> None:
    """dst[:] = src (1-D, same size), as a loop: a slice assignment compiles numba's shape
    check and its message (about 2 s on each first compile, ``benchmarks/first_run.py``)."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@njit(cache=True, error_model="numpy")
def lu_factor(A: Arr, piv: Arr) -> None:
    """A = P L U in place (Doolittle, partial pivoting), row swaps in piv. O(N^3), real or
    complex. A singular pivot leaves a zero on U's diagonal: the solve gives inf/NaN, which
    the Newton iteration treats as non-convergence."""
    n = A.shape[0]
    for k in range(n):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big = abs(A[i, k])
                p = i
        piv[k] = p
        if p != k:
            for j in range(n):
                A[k, j], A[p, j] = A[p, j], A[k, j]
        d = A[k, k]
        if d == 0.0:
            continue
        for i in range(k + 1, n):
            m = A[i, k] / d
            A[i, k] = m
            if m != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= m * A[k, j]


@njit(cache=True, error_model="numpy")
def lu_solve(A: Arr, piv: Arr, b: Arr) -> None:
    """Solve (P L U) x = b in place in b with ``lu_factor``'s A and piv. O(N^2)."""
    n = A.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            b[k], b[p] = b[p], b[k]
    for i in range(n):
        acc = b[i]
        for j in range(i):
            acc -= A[i, j] * b[j]
        b[i] = acc
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, n):
            acc -= A[i, j] * b[j]
        b[i] = acc / A[i, i]


@njit(cache=True, error_model="numpy")
def jacobian(form: Form, t: float, y: Arr, f: Arr, J: Arr, tmp: Arr, f1: Arr) -> None:
    """The Jacobian df/dy at (t, y) by forward differences into J (f = rhs(t, y)): column j
    from an increment sqrt(eps max(1e-5, |y_j|)) (Hairer's RADAU5). N evaluations, O(N^2)."""
    N = y.shape[0]
    for i in range(N):
        tmp[i] = y[i]
    P_, S, M, L, rhs = form[0], form[1], form[2], form[3], form[6]  # once, not per evaluation
    for j in range(N):
        delta = np.sqrt(_EPS * max(1e-5, abs(y[j])))
        tmp[j] = y[j] + delta
        rhs(t, tmp, P_, S, M, L, f1)
        tmp[j] = y[j]
        for i in range(N):
            J[i, j] = (f1[i] - f[i]) / delta


@njit(cache=True, error_model="numpy")
def _factor(J: Arr, h: float, LUr: Arr, pr: Arr, LUc: Arr, pc: Arr) -> None:
    """The iteration matrices MU_REAL/h I - J and MU_COMPLEX/h I - J, factorized. O(N^3)."""
    N = J.shape[0]
    mr = MU_REAL / h
    mc = MU_COMPLEX / h
    for i in range(N):
        for j in range(N):
            LUr[i, j] = -J[i, j]
            LUc[i, j] = -J[i, j]
        LUr[i, i] += mr
        LUc[i, i] += mc
    lu_factor(LUr, pr)
    lu_factor(LUc, pc)


@njit(cache=True, error_model="numpy")
def _norm(x: Arr, scale: Arr) -> float:
    """rms of x / scale over all entries (scipy's ``norm``): x (N,) or (3, N), scale (N,)."""
    rows = x.reshape((-1, scale.shape[0]))
    acc = 0.0
    for r in range(rows.shape[0]):
        for i in range(scale.shape[0]):
            acc += (rows[r, i] / scale[i]) ** 2
    return float(np.sqrt(acc / rows.size))


@njit(cache=True, error_model="numpy")
def _collocation(
    form: Form, t: float, y: Arr, h: float, Z: Arr, scale: Arr, tol: float, work: Work
) -> tuple[bool, int, float]:
    """The collocation system by simplified Newton (scipy's ``solve_collocation_system``):
    Z (3, N) holds the guess on entry, the solution on exit. Returns (converged, iterations,
    rate: -1 before two iterations, inf when stage values are not finite); 3 evaluations per
    iteration."""
    LUr, pr, LUc, pc, Wt, Fs, dW, fr, fc, tmp = work
    N = y.shape[0]
    mr = MU_REAL / h
    mc = MU_COMPLEX / h
    for a in range(3):
        for i in range(N):
            Wt[a, i] = TI[a, 0] * Z[0, i] + TI[a, 1] * Z[1, i] + TI[a, 2] * Z[2, i]
    dW_norm_old = -1.0
    rate = -1.0
    P_, S, M, L, rhs = form[0], form[1], form[2], form[3], form[6]  # once, not per evaluation
    for k in range(NEWTON_MAXITER):
        for a in range(3):
            for i in range(N):
                tmp[i] = y[i] + Z[a, i]
            rhs(t + C[a] * h, tmp, P_, S, M, L, Fs[a])
        if not np.all(np.isfinite(Fs)):
            return False, k + 1, np.inf
        for i in range(N):
            fr[i] = TI[0, 0] * Fs[0, i] + TI[0, 1] * Fs[1, i] + TI[0, 2] * Fs[2, i] - mr * Wt[0, i]
            re = TI[1, 0] * Fs[0, i] + TI[1, 1] * Fs[1, i] + TI[1, 2] * Fs[2, i]
            im = TI[2, 0] * Fs[0, i] + TI[2, 1] * Fs[1, i] + TI[2, 2] * Fs[2, i]
            fc[i] = complex(re, im) - mc * complex(Wt[1, i], Wt[2, i])
        lu_solve(LUr, pr, fr)
        lu_solve(LUc, pc, fc)
        for i in range(N):
            dW[0, i] = fr[i]
            dW[1, i] = fc[i].real
            dW[2, i] = fc[i].imag
        dW_norm = _norm(dW, scale)
        if not np.isfinite(dW_norm):  # a singular iteration matrix
            return False, k + 1, np.inf
        if dW_norm_old >= 0.0:
            rate = dW_norm / dW_norm_old
        if rate >= 0.0 and (
            rate >= 1.0 or rate ** (NEWTON_MAXITER - k) / (1.0 - rate) * dW_norm > tol
        ):
            return False, k + 1, rate
        for a in range(3):
            for i in range(N):
                Wt[a, i] += dW[a, i]
        for a in range(3):
            for i in range(N):
                Z[a, i] = T[a, 0] * Wt[0, i] + T[a, 1] * Wt[1, i] + T[a, 2] * Wt[2, i]
        if dW_norm == 0.0 or (rate >= 0.0 and rate / (1.0 - rate) * dW_norm < tol):
            return True, k + 1, rate
        dW_norm_old = dW_norm
    return False, NEWTON_MAXITER, rate


@njit(cache=True, error_model="numpy")
def _predict_factor(
    h_abs: float, h_abs_old: float, error_norm: float, error_norm_old: float
) -> float:
    """Gustafsson's predictive step-size factor (scipy's ``predict_factor``)."""
    if error_norm_old <= 0.0 or h_abs_old <= 0.0 or error_norm == 0.0:
        multiplier = 1.0
    else:
        multiplier = h_abs / h_abs_old * (error_norm_old / error_norm) ** 0.25
    if error_norm == 0.0:
        return MAX_FACTOR
    return float(min(1.0, multiplier) * error_norm**-0.25)


@njit(cache=True, error_model="numpy")
def dense_coefficients(Z: Arr, F: Arr) -> None:
    """The step's cubic dense output (y + sum_k (Z^T P)[:, k] x^(k+1)) in ``dop853``'s
    interpolant form F (7, N): F0 = a1 + a2 + a3, F1 = -(a2 + a3), F2 = -a3, the rest 0,
    so that ``dop853_events.interpolate`` evaluates it. O(N)."""
    N = Z.shape[1]
    for i in range(N):
        a1 = P[0, 0] * Z[0, i] + P[1, 0] * Z[1, i] + P[2, 0] * Z[2, i]
        a2 = P[0, 1] * Z[0, i] + P[1, 1] * Z[1, i] + P[2, 1] * Z[2, i]
        a3 = P[0, 2] * Z[0, i] + P[1, 2] * Z[1, i] + P[2, 2] * Z[2, i]
        F[0, i] = a1 + a2 + a3
        F[1, i] = -(a2 + a3)
        F[2, i] = -a3
        for r in range(3, 7):
            F[r, i] = 0.0


@njit(cache=True, inline="always")
def work(N: int, implicit: bool) -> Work:
    """The stepper's buffers for N states (all empty unless ``implicit``): [0] Jacobian,
    [1-4] real and complex LU factors and pivots, [5] stage increments Z (3, N), [6-10]
    Newton work (W, stage derivatives, increments (3, N each), real and complex right-hand
    sides), [11-12] scratch, [13] the previous step's start state, [14] the tolerance scale
    atol + rtol |y|, [15] error. O(N^2) memory when implicit."""
    n = N if implicit else 0
    return (
        np.empty((n, n)),
        np.empty((n, n)),
        np.empty(n, np.int64),
        np.empty((n, n), np.complex128),
        np.empty(n, np.int64),
        np.empty((3, n)),
        np.empty((3, n)),
        np.empty((3, n)),
        np.empty((3, n)),
        np.empty(n),
        np.empty(n, np.complex128),
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty(n),
    )


@njit(cache=True, error_model="numpy")
def start(form: Form, t: float, y: Arr, f: Arr, rw: Work, sc: Arr, cnt: Arr) -> None:
    """A segment's start from (t, y) with f = rhs(t, y): the Jacobian there (N evaluations,
    counted in cnt[0]), no LU factors, no previous step. O(N^2)."""
    J, tmp, f1 = rw[0], rw[11], rw[12]
    jacobian(form, t, y, f, J, tmp, f1)
    cnt[0] += y.shape[0]
    sc[H_OLD], sc[ERR_OLD], sc[CURRENT_JAC], sc[LU_VALID], sc[HAVE_SOL] = 0.0, 0.0, 1.0, 0.0, 0.0


@njit(cache=True, inline="always", error_model="numpy")
def _predict(t: float, h: float, y: Arr, F: Arr, rw: Work, sc: Arr) -> None:
    """The Newton guess Z (3, N): the previous step's dense output extrapolated to the
    collocation times t + C h, minus y (zero without a previous step)."""
    Z, tmp, yp = rw[5], rw[11], rw[13]
    N = y.shape[0]
    if sc[HAVE_SOL] == 0.0:
        Z[:] = 0.0
        return
    h_old = sc[H_OLD]
    for a in range(3):
        interpolate(F, yp, (t + C[a] * h - (t - h_old)) / h_old, tmp)
        for i in range(N):
            Z[a, i] = tmp[i] - y[i]


@njit(cache=True, inline="always", error_model="numpy")
def _error(
    form: Form, t: float, h: float, state: Step, rw: Work, settings: Settings, again: bool, cnt: Arr
) -> float:
    """Hairer's error estimate of the step h (s) from (t, y) to y_new (``state``) (its
    norm): (MU_REAL/h I - J)^-1 (f + Z^T E / h), filtered once more through the right-hand
    side when ``again`` (after a rejection; one evaluation); scaled by atol[i] + rtol
    max(|y_i|, |y_new_i|) (``settings``' atol: one per coordinate)."""
    LUr, pr, Z, tmp, f1, err = rw[1], rw[2], rw[5], rw[11], rw[12], rw[15]
    y, f, y_new = state[0], state[1], state[2]
    rtol, atol = settings[0][0], settings[1]
    N = y.shape[0]
    for i in range(N):
        err[i] = f[i] + (E[0] * Z[0, i] + E[1] * Z[1, i] + E[2] * Z[2, i]) / h
    lu_solve(LUr, pr, err)
    for i in range(N):
        tmp[i] = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
    norm = _norm(err, tmp)
    if again and norm > 1.0:
        for i in range(N):
            f1[i] = y[i] + err[i]
        rhs_at(form, t, f1, err)
        cnt[0] += 1
        for i in range(N):
            err[i] += (E[0] * Z[0, i] + E[1] * Z[1, i] + E[2] * Z[2, i]) / h
        lu_solve(LUr, pr, err)
        norm = _norm(err, tmp)
    return norm


@njit(cache=True, inline="always", error_model="numpy")
def _newton(
    form: Form, t: float, h: float, state: Step, tol: float, rw: Work, sc: Arr, cnt: Arr
) -> tuple[bool, int, float]:
    """The collocation system of the step h (s) from (t, y) (``state``: y, f = rhs(t, y),
    the previous step's dense output F) from the predicted guess, with
    the iteration matrices factorized when they are not valid, and once more with a fresh
    Jacobian when Newton fails on an old one (scipy's inner loop). Returns
    ``_collocation``'s (converged, iterations, rate); evaluations counted in cnt[0]."""
    J, LUr, pr, LUc, pc, Z = rw[0], rw[1], rw[2], rw[3], rw[4], rw[5]
    tmp, f1, scale = rw[11], rw[12], rw[14]
    y, f, F = state[0], state[1], state[4]
    newton = (LUr, pr, LUc, pc, rw[6], rw[7], rw[8], rw[9], rw[10], tmp)
    while True:
        if sc[LU_VALID] == 0.0:
            _factor(J, h, LUr, pr, LUc, pc)
            sc[LU_VALID] = 1.0
            sc[NLU] += 1.0
        _predict(t, h, y, F, rw, sc)
        converged, n_iter, rate = _collocation(form, t, y, h, Z, scale, tol, newton)
        cnt[0] += 3 * n_iter
        sc[NITER] += n_iter
        if converged or sc[CURRENT_JAC] == 1.0:
            return converged, n_iter, rate
        jacobian(form, t, y, f, J, tmp, f1)
        cnt[0] += y.shape[0]
        sc[CURRENT_JAC], sc[LU_VALID] = 1.0, 0.0


@njit(cache=True, inline="always", error_model="numpy")
def _derivative_at_end(
    form: Form, t_new: float, state: Step, rw: Work, sc: Arr, refresh: bool, cnt: Arr
) -> None:
    """At the accepted step's end: f_new = rhs(t_new, y_new) (``state``) and, when
    ``refresh``, the Jacobian there (marked current, else marked old); evaluations counted
    in cnt[0]."""
    y_new, f_new = state[2], state[3]
    rhs_at(form, t_new, y_new, f_new)
    cnt[0] += 1
    if refresh:
        jacobian(form, t_new, y_new, f_new, rw[0], rw[11], rw[12])
        cnt[0] += y_new.shape[0]
        sc[CURRENT_JAC] = 1.0
    else:
        sc[CURRENT_JAC] = 0.0


@njit(cache=True, error_model="numpy")
def step(
    form: Form,
    t: float,
    t_bound: float,
    h_abs: float,
    state: Step,
    settings: Settings,
    cnt: Arr,
    rw: Work,
    sc: Arr,
) -> tuple[int, float, float]:
    """Attempts from (t, y) (``state``: y, f = rhs(t, y), y_new, f_new, F) to t_bound until
    one is accepted (scipy's ``Radau._step_impl``): y_new, f_new there, the dense output into
    F; ``settings``, ``cnt`` as in ``dop853.run``, ``rw``: ``work``, ``sc``: the scalars.
    Returns (code, t, next step): OK, or STEP_TOO_SMALL, BUDGET, WALL, NON_FINITE, t kept."""
    Z, scale = rw[5], rw[14]
    y, y_new, F = state[0], state[2], state[4]
    controls, atol = settings[0], settings[1]
    rtol, max_step = controls[0], controls[2]
    N = y.shape[0]
    tol = max(10.0 * _EPS / rtol, min(0.03, rtol**0.5))
    min_step = smallest_step(t)
    h_old, err_old = sc[H_OLD], sc[ERR_OLD]
    if h_abs > max_step or h_abs < min_step:
        h_abs = max_step if h_abs > max_step else min_step
        h_old, err_old = 0.0, 0.0
    rejected = False
    finite = True  # whether the last attempt's stages were finite
    while True:
        code, t_new = next_attempt(t, t_bound, h_abs, min_step, finite, controls, cnt)
        if code != OK:
            return code, t, h_abs
        h = t_new - t
        h_abs = h
        for i in range(N):
            scale[i] = atol[i] + abs(y[i]) * rtol
        converged, n_iter, rate = _newton(form, t, h, state, tol, rw, sc, cnt)
        finite = rate < np.inf
        if not converged:
            h_abs *= 0.5
            sc[LU_VALID] = 0.0
            continue
        for i in range(N):
            y_new[i] = y[i] + Z[2, i]
        error_norm = _error(form, t, h, state, rw, settings, rejected, cnt)
        safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
        if error_norm > 1.0 or not np.isfinite(error_norm):
            finite = np.isfinite(error_norm)
            factor = _predict_factor(h_abs, h_old, error_norm, err_old) if finite else 0.0
            h_abs *= max(MIN_FACTOR, safety * factor)
            sc[LU_VALID] = 0.0
            rejected = True
            continue
        break
    recompute_jac = n_iter > 2 and rate > 1e-3
    factor = min(MAX_FACTOR, safety * _predict_factor(h_abs, h_old, error_norm, err_old))
    if not recompute_jac and factor < 1.2:
        factor = 1.0
    else:
        sc[LU_VALID] = 0.0
    _derivative_at_end(form, t_new, state, rw, sc, recompute_jac, cnt)
    sc[H_OLD], sc[ERR_OLD], sc[HAVE_SOL] = h_abs, error_norm, 1.0
    copy_into(rw[13], y)
    dense_coefficients(Z, F)
    return OK, t_new, h_abs * factor
