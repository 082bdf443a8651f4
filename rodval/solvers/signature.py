"""The numba types of a system's compiled functions (``CompiledForm``):

* ``RHS_TYPE`` (``.rhs``, ``.mechanics``): ``f(t, y, P, S, M, L, out)`` writing into ``out``;
* ``EVENTS_TYPE`` (``.events``): ``g(t, y, P, S, M, L, E, out)`` writing the value of each
  event function (one per row of the model's event table E) into ``out``.

Kept apart from the integrators so that kernels can declare them without loading the compiled
integrator loop. Kernels are decorated without a signature, so importing their module compiles
(or loads from numba's cache) none of them; ``first_class`` compiles the ones a run uses, as
the compiled integrators take them (issue 38: a run compiles what it needs).

A first run on an empty cache (issue 50, docs/performance.md "First run"): the compiled loop
(``dop853.run``, about half of the compile time of a first run) is compiled in a background
process (``compile_in_background``, started by ``dop853.warm_up`` when a native model's run
begins, ``OdeModel.run``), while this process builds the system and compiles its kernels; the
loop is then loaded from numba's cache (``dop853.loop`` waits for it). No kernel module
imports the loop: this module does not, so the loop stays out of the kernels' cache keys.
The machine code is the same as compiled here: same source, same signature, same cache key
(``rodval.core.jit_cache``)."""

from __future__ import annotations

import atexit
import os
import subprocess
import sys
from collections.abc import Callable
from typing import Any

import numpy as np
from numba import njit, types

F1 = types.float64[::1]
F2 = types.float64[:, ::1]
F3 = types.float64[:, :, ::1]
RHS_SIGNATURE = types.void(types.float64, F1, F2, F1, F3, F2, F1)
RHS_TYPE = types.FunctionType(RHS_SIGNATURE)
EVENTS_SIGNATURE = types.void(types.float64, F1, F2, F1, F3, F2, F2, F1)
EVENTS_TYPE = types.FunctionType(EVENTS_SIGNATURE)


def tuple_type(*items: Any) -> Any:
    """numba's type of a tuple of the numba types ``items``."""
    return types.Tuple(items)  # type: ignore[no-untyped-call]  # numba's types are untyped


#: A compiled form as the compiled integrators take it, one tuple: its arrays (P, S, M, L, E,
#: directions), then its functions (rhs, mechanics, events) (``CompiledForm``). Arrays
#: first: numba warns of a tuple that starts with a function as an experimental feature.
FORM_TYPE = tuple_type(F2, F1, F3, F2, F2, F1, RHS_TYPE, RHS_TYPE, EVENTS_TYPE)
#: An array argument of a compiled function, as mypy sees it.
Arr = np.ndarray
#: A compiled function, as mypy sees it.
Kernel = Callable[..., None]
#: ``FORM_TYPE`` as mypy sees it.
Form = tuple[Arr, Arr, Arr, Arr, Arr, Arr, Kernel, Kernel, Kernel]


@njit(cache=True, inline="always")
def rhs_at(form: Form, t: float, y: Arr, out: Arr) -> None:
    """The form's right-hand side y'(t, y) into ``out``. One evaluation."""
    form[6](t, y, form[0], form[1], form[2], form[3], out)


@njit(cache=True, inline="always")
def mechanics_at(form: Form, t: float, y: Arr, out: Arr) -> None:
    """The form's (T, P_ext, P_diss) at (t, y) into ``out`` (3,)."""
    form[7](t, y, form[0], form[1], form[2], form[3], out)


@njit(cache=True, inline="always")
def events_at(form: Form, t: float, y: Arr, out: Arr) -> None:
    """The form's event values g_i(t, y), one per row of E, into ``out``."""
    form[8](t, y, form[0], form[1], form[2], form[3], form[4], out)


#: Environment variable: "0" compiles everything in the process that needs it (set in the
#: background processes themselves, so that they start none).
BACKGROUND_ENV = "RODVAL_BACKGROUND_COMPILE"

#: The background compilations this process started, by key.
_BACKGROUND: dict[str, subprocess.Popen[bytes]] = {}


def first_class(kernel: Any, signature: Any) -> Any:
    """``kernel`` (a numba dispatcher) with ``signature`` compiled, or loaded from numba's
    cache, so that it passes as a first-class function of that type; returned for chaining.
    Cheap once compiled (a dictionary lookup)."""
    kernel.compile(signature)
    return kernel


def in_cache(kernel: Any, signature: Any) -> bool | None:
    """Whether numba's on-disk cache holds ``kernel`` (a dispatcher) compiled for
    ``signature``, read from its index without loading the code; None when unknown (no
    cache, or numba internals other than 0.5x-0.6x's: ``Cache._index_key``,
    ``_cache_file._load_index``)."""
    try:
        cache = kernel._cache
        key = cache._index_key(signature, kernel.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:  # noqa: BLE001 - NullCache or other internals: unknown
        return None


def background_allowed() -> bool:
    """Whether this process may compile in a background process: at least 2 CPUs available
    to it and not switched off (``BACKGROUND_ENV`` = "0")."""
    if os.environ.get(BACKGROUND_ENV, "1") == "0":
        return False
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cpus = os.cpu_count() or 1
    return cpus >= 2


def compile_in_background(key: str, code: str) -> None:
    """Run ``python -c code`` (a compilation into numba's cache) in a background process,
    once per ``key`` and process, with this process's environment (its NUMBA_CACHE_DIR) and
    ``BACKGROUND_ENV`` = "0"; its output is discarded. ``wait_for(key)`` waits for it."""
    if key in _BACKGROUND:
        return
    env = dict(os.environ, **{BACKGROUND_ENV: "0"})
    _BACKGROUND[key] = subprocess.Popen(
        [sys.executable, "-c", code],
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def wait_for(key: str) -> bool:
    """Wait for the background compilation ``key`` if this process started one; whether it
    ran and succeeded (else the caller compiles itself)."""
    process = _BACKGROUND.get(key)
    return process is not None and process.wait() == 0


@atexit.register
def _stop_background() -> None:
    """End the background compilations still running when this process ends (a run that
    did not need their result): none outlives the command that started it."""
    for process in _BACKGROUND.values():
        if process.poll() is None:
            process.terminate()
