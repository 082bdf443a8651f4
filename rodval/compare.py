"""Discrepancy metrics between two trajectories of the same scene.

Both trajectories must hold the same output times and, per quantity, the same k labels (the
same scene run by two models). For a quantity q with values v (nt, nk) and reference values
r (nt, nk), the error is e = v - r (in the quantity's units: rad, rad/s, m, J) and

* ``max_abs``   = max over t and k of |e|; ``t_at_max`` (s) and ``k_at_max`` locate it;
* ``rms``       = sqrt(mean over t and k of e^2);
* ``final_abs`` = max over k of |e| at the last output time;
* ``max_rel``   = max over k of (max_t |e[:, k]|) / (max_t |r[:, k]|): each column's error
  relative to that reference column's own scale, so values passing through zero do not blow
  it up. Columns whose reference is identically zero carry no scale and are left out; if every
  column is zero, ``max_rel`` is NaN (meaning "no relative scale", not a failure).
"""
from __future__ import annotations

from typing import Iterable

import numpy as np
import pandas as pd

from .trajectory import Trajectory

METRICS = ("max_abs", "rms", "final_abs", "max_rel", "k_at_max", "t_at_max")


def error_metrics(times: np.ndarray, k: np.ndarray, values: np.ndarray,
                  reference: np.ndarray) -> dict[str, float]:
    """The metrics of one quantity: ``values`` and ``reference`` (nt, nk) at ``times`` (nt,)
    with column labels ``k`` (nk,). See the module docstring for the definitions."""
    values = np.asarray(values, dtype=float)
    reference = np.asarray(reference, dtype=float)
    if values.shape != reference.shape or values.ndim != 2 or values.size == 0:
        raise ValueError(f"values and reference must be equal non-empty (nt, nk) arrays, "
                         f"got {values.shape} and {reference.shape}")
    err = np.abs(values - reference)
    i, j = np.unravel_index(int(np.argmax(err)), err.shape)
    col_err = err.max(axis=0)
    col_scale = np.abs(reference).max(axis=0)
    scaled = col_scale > 0
    max_rel = float(np.max(col_err[scaled] / col_scale[scaled])) if scaled.any() else float("nan")
    return {"max_abs": float(err[i, j]), "rms": float(np.sqrt(np.mean(err * err))),
            "final_abs": float(err[-1].max()), "max_rel": max_rel,
            "k_at_max": int(k[j]), "t_at_max": float(times[i])}


def common_quantities(traj: Trajectory, reference: Trajectory) -> tuple[str, ...]:
    """Quantities present in both trajectories, in the reference's order."""
    return tuple(q for q in reference.quantities if q in traj.values)


def check_comparable(traj: Trajectory, reference: Trajectory, quantities: Iterable[str]) -> None:
    """Raise ValueError unless both trajectories have the same times and k labels."""
    if traj.times.shape != reference.times.shape or not np.allclose(
            traj.times, reference.times, rtol=0, atol=1e-12):
        raise ValueError(f"trajectories {traj.model!r} and {reference.model!r} have different "
                         f"output times ({traj.times.size} and {reference.times.size} times)")
    for q in quantities:
        if not np.array_equal(traj.k_index[q], reference.k_index[q]):
            raise ValueError(f"quantity {q!r}: k labels differ between {traj.model!r} and "
                             f"{reference.model!r}")


def discrepancies(traj: Trajectory, reference: Trajectory,
                  quantities: Iterable[str] | None = None) -> pd.DataFrame:
    """One row per quantity: quantity, max_abs, rms, final_abs, max_rel, k_at_max, t_at_max.

    ``quantities`` defaults to those both trajectories hold; a quantity missing from either
    is a ValueError.
    """
    qs = common_quantities(traj, reference) if quantities is None else tuple(quantities)
    missing = [q for q in qs if q not in traj.values or q not in reference.values]
    if missing:
        raise ValueError(f"quantities {missing} are not in both trajectories")
    check_comparable(traj, reference, qs)
    rows = [{"quantity": q, **error_metrics(reference.times, reference.k_index[q],
                                            traj.values[q], reference.values[q])} for q in qs]
    return pd.DataFrame(rows, columns=["quantity", *METRICS])
