"""Resource checks before any work: the memory a run or a study will need, refused above a limit.

A run's memory is dominated by its outputs: the driver keeps the state at every output time
(``nt x state``) and the trajectory holds every asked quantity at every output time
(``nt x (n + 1)`` doubles each); the full model's state is 6 n doubles (phi, alpha, beta and
their rates), the reduced model's 2 n. The default (native, compiled) path is O(n) otherwise.
Dense matrices (``n_state^2`` doubles, a few of them) are built only for ``kernel="numpy"``
and for the Jacobians of implicit methods (Radau, BDF, LSODA).

The limit is ``RODVAL_MAX_MEMORY_GB`` (environment, GB = 1e9 bytes), default
``DEFAULT_LIMIT_GB``; ``inf`` disables the check. The message gives the estimate and what it
is made of, so that the user can cut output times, quantities or rods.
"""

from __future__ import annotations

import math
import os
from typing import Any

#: Default memory limit of one run (GB = 1e9 bytes): well below the RAM of a workstation.
DEFAULT_LIMIT_GB = 4.0
ENV_LIMIT = "RODVAL_MAX_MEMORY_GB"
#: Doubles of state per rod: the full model (phi, alpha, beta and rates); the largest.
STATE_PER_ROD = {"full": 6, "reduced": 2}
#: Dense n_state x n_state matrices held at once on a dense path (mass, stiffness, Jacobian
#: and an LU factor).
DENSE_MATRICES = 4
#: Bytes of one output value in a JSON case record (text of a double, separators).
JSON_BYTES_PER_VALUE = 24


def memory_limit_bytes() -> float:
    """The limit from ``RODVAL_MAX_MEMORY_GB`` (ValueError naming it when it is not a number
    > 0), ``DEFAULT_LIMIT_GB`` when unset."""
    raw = os.environ.get(ENV_LIMIT, "").strip()
    if not raw:
        return DEFAULT_LIMIT_GB * 1e9
    try:
        value = float(raw)
    except ValueError:
        value = math.nan
    if not value > 0:
        raise ValueError(f"{ENV_LIMIT} must be a number of GB > 0 (inf: no limit), got {raw!r}")
    return value * 1e9


def output_values(n: int, num_times: int, quantities: tuple[str, ...]) -> int:
    """Output values of a run: every trajectory quantity at every output time, n + 1 per
    quantity at most (x, y have n + 1 nodes; energies one)."""
    return num_times * (n + 1) * len(quantities)


def estimate_run_bytes(
    n: int,
    num_times: int,
    quantities: tuple[str, ...],
    *,
    model: str = "full",
    dense: bool = False,
) -> dict[str, float]:
    """The memory (bytes) a run will need, by part: ``outputs`` (the stored states and the
    trajectory's quantities), ``dense`` (dense matrices, when ``dense``) and ``total``.
    ``model``: "full", "reduced", or any other name (estimated as the full model)."""
    state = STATE_PER_ROD.get(model, STATE_PER_ROD["full"]) * n
    outputs = 8.0 * (num_times * state + output_values(n, num_times, quantities))
    dense_bytes = 8.0 * DENSE_MATRICES * state * state if dense else 0.0
    return {"outputs": outputs, "dense": dense_bytes, "total": outputs + dense_bytes}


def _gb(b: float) -> str:
    return f"{b / 1e9:.3g} GB"


#: Doubles per rod that any run holds besides its outputs, at the least: the chain's seven
#: per-rod arrays and the compiled DOP853 loop's work arrays (16 stages, 7 dense-output rows
#: and 4 vectors) on the smallest state, the reduced model's 2 per rod.
CHAIN_ARRAYS = 7
DOP853_WORK_ROWS = 27
MIN_DOUBLES_PER_ROD = CHAIN_ARRAYS + DOP853_WORK_ROWS * STATE_PER_ROD["reduced"]


def check_rods(n: int) -> float:
    """The least memory (bytes) a chain of n rods needs for any run
    (``MIN_DOUBLES_PER_ROD`` doubles per rod), or ValueError naming n and the limit, checked
    before any n-sized array exists (n = 1e8 took 48 s and 6.6 GB to be refused; n = 1e13
    ended in numpy's out-of-memory error)."""
    est = 8.0 * MIN_DOUBLES_PER_ROD * n
    limit = memory_limit_bytes()
    if est > limit:
        raise ValueError(
            f"n = {n} rods would need at least {_gb(est)} of memory (the chain's data and the "
            f"integrator's work arrays, {8 * MIN_DOUBLES_PER_ROD} bytes per rod), more than "
            f"the limit of {_gb(limit)}; ask for at most {int(limit // (8 * MIN_DOUBLES_PER_ROD))} "
            f"rods, or raise the limit with the environment variable {ENV_LIMIT}"
        )
    return est


def check_run_memory(
    n: int,
    num_times: int,
    quantities: tuple[str, ...],
    *,
    model: str = "full",
    dense: bool = False,
    what: str = "this run",
) -> dict[str, float]:
    """``estimate_run_bytes``, or ValueError when it exceeds the limit (the message has the
    estimate, its parts and how to change the limit)."""
    est = estimate_run_bytes(n, num_times, quantities, model=model, dense=dense)
    limit = memory_limit_bytes()
    if est["total"] > limit:
        parts = (
            f"{num_times} output times x {len(quantities)} quantities x n + 1 = {n + 1} "
            f"values and the {model} model's state: {_gb(est['outputs'])}"
        )
        if dense:
            parts += f"; dense matrices of the {n}-rod system: {_gb(est['dense'])}"
        raise ValueError(
            f"{what} would need about {_gb(est['total'])} of memory ({parts}), more than the "
            f"limit of {_gb(limit)}; ask for fewer output times, quantities or rods, or raise "
            f"the limit with the environment variable {ENV_LIMIT}"
        )
    return est


def dense_path(model: str, options: dict[str, Any], method: str) -> bool:
    """Whether a native model's run builds dense n_state^2 matrices: the numpy kernel, or an
    implicit method's Jacobian."""
    return options.get("kernel") == "numpy" or method in ("Radau", "BDF", "LSODA")


#: Memory per output value while a study's tables are built (the case records' values as
#: Python floats and arrays, then a row of the long trajectories table: case, model, t,
#: quantity, k, value, and pandas' copies while concatenating).
TABLE_BYTES_PER_VALUE = 100


def check_study_memory(values: int, cases: int, what: str = "the study") -> float:
    """The memory (bytes) building a study's tables will need for ``values`` output values
    over ``cases`` cases, or ValueError above the limit."""
    est = float(values) * TABLE_BYTES_PER_VALUE
    limit = memory_limit_bytes()
    if est > limit:
        raise ValueError(
            f"{what} would need about {_gb(est)} of memory for its tables ({values} output "
            f"values over {cases} cases and their models, ~{TABLE_BYTES_PER_VALUE} bytes "
            f"each), more than the limit of {_gb(limit)}; ask for fewer output times, "
            f"quantities, rods or cases, or raise the limit with {ENV_LIMIT}"
        )
    return est
