"""Every error measure of rodval, defined once and named for what it measures.

Discrepancy metrics between two trajectories of the same scene (studies, ``rodval compare``):

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

Relative errors scaled by the reference's own magnitude (``relative_error``): max |e| over a
group of entries divided by max |r| over the same group. The group is one choice of
``scale``: ``"all"`` (every time and column: the work-precision benchmarks), ``"time"`` (each
output time across columns: Table 1 columns, where the group is the rods at one time) or
``"column"`` (each column across time: ``max_rel`` above and the cross-check's dphi gap).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import numpy as np
import pandas as pd

from rodval.core.checks import check_type
from rodval.core.scene import trajectory_quantities
from rodval.core.scene_file import scene_differences, scene_to_dict
from rodval.core.status import STATUS_MESSAGES
from rodval.core.trajectory import Trajectory

METRICS = ("max_abs", "rms", "final_abs", "max_rel", "k_at_max", "t_at_max")
SCALES = ("all", "time", "column")


def relative_error(values: np.ndarray, reference: np.ndarray, scale: str = "all") -> np.ndarray:
    """max |values - reference| / max |reference| over the groups of ``scale`` (see the module
    docstring), for (nt, nk) arrays: a scalar array for "all", one value per time for "time",
    per column for "column". A group whose reference is all zero gives NaN."""
    if scale not in SCALES:
        raise ValueError(f"scale must be one of {SCALES}, got {scale!r}")
    err = np.abs(np.asarray(values, float) - np.asarray(reference, float))
    ref = np.abs(np.asarray(reference, float))
    axis = {"all": None, "time": 1, "column": 0}[scale]
    top, norm = err.max(axis=axis), ref.max(axis=axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(norm > 0, top / np.where(norm > 0, norm, 1.0), np.nan)


def error_metrics(
    times: np.ndarray, k: np.ndarray, values: np.ndarray, reference: np.ndarray
) -> dict[str, float]:
    """The metrics of one quantity: ``values`` and ``reference`` (nt, nk) at ``times`` (nt,)
    with column labels ``k`` (nk,). See the module docstring for the definitions."""
    values = np.asarray(values, dtype=float)
    reference = np.asarray(reference, dtype=float)
    if values.shape != reference.shape or values.ndim != 2 or values.size == 0:
        raise ValueError(
            f"values and reference must be equal non-empty (nt, nk) arrays, "
            f"got {values.shape} and {reference.shape}"
        )
    err = np.abs(values - reference)
    i, j = np.unravel_index(int(np.argmax(err)), err.shape)
    per_column = relative_error(values, reference, "column")
    max_rel = float(np.nanmax(per_column)) if np.isfinite(per_column).any() else float("nan")
    return {
        "max_abs": float(err[i, j]),
        "rms": float(np.sqrt(np.mean(err * err))),
        "final_abs": float(err[-1].max()),
        "max_rel": max_rel,
        "k_at_max": int(k[j]),
        "t_at_max": float(times[i]),
    }


def common_quantities(traj: Trajectory, reference: Trajectory) -> tuple[str, ...]:
    """Quantities present in both trajectories, in the reference's order."""
    return tuple(q for q in reference.quantities if q in traj.values)


def check_comparable(traj: Trajectory, reference: Trajectory, quantities: Iterable[str]) -> None:
    """Raise ValueError unless both trajectories have the same times and k labels."""
    if traj.times.shape != reference.times.shape or not np.allclose(
        traj.times, reference.times, rtol=0, atol=1e-12
    ):
        raise ValueError(
            f"trajectories {traj.model!r} and {reference.model!r} have different "
            f"output times ({traj.times.size} and {reference.times.size} times)"
        )
    for q in quantities:
        if not np.array_equal(traj.k_index[q], reference.k_index[q]):
            raise ValueError(
                f"quantity {q!r}: k labels differ between {traj.model!r} and {reference.model!r}"
            )


def discrepancies(
    traj: Trajectory,
    reference: Trajectory,
    quantities: Iterable[str] | None = None,
    *,
    allow_different_scenes: bool = False,
) -> pd.DataFrame:
    """One row per quantity: quantity, max_abs, rms, final_abs, max_rel, k_at_max, t_at_max.

    ``quantities`` defaults to those both trajectories hold; a quantity missing from either
    is a ValueError. Two runs of different scenes (both known: ``Trajectory.scene``) are
    refused, naming the scene keys that differ, unless ``allow_different_scenes`` (the table
    then mixes a model's error with the change of scene). Arguments of another type are
    refused up front (ValueError).
    """
    check_type("traj", traj, Trajectory, "a rodval.Trajectory (what simulate returns)")
    check_type("reference", reference, Trajectory, "a rodval.Trajectory (what simulate returns)")
    check_type("allow_different_scenes", allow_different_scenes, bool, "True or False")
    if not allow_different_scenes:
        check_same_scene(traj, reference)
    if isinstance(quantities, str) or not isinstance(quantities, Iterable | None):
        raise ValueError(
            f"quantities must be a list of quantity names such as ['phi'] or None (all), "
            f"got {quantities!r}"
        )
    qs = common_quantities(traj, reference) if quantities is None else tuple(quantities)
    missing = [q for q in qs if q not in traj.values or q not in reference.values]
    if missing:
        raise ValueError(f"quantities {missing} are not in both trajectories")
    check_comparable(traj, reference, qs)
    rows = [
        {
            "quantity": q,
            **error_metrics(
                reference.times, reference.k_index[q], traj.values[q], reference.values[q]
            ),
        }
        for q in qs
    ]
    return pd.DataFrame(rows, columns=["quantity", *METRICS])


def check_same_scene(traj: Trajectory, reference: Trajectory) -> None:
    """ValueError naming the differing scene keys (``scene_differences``) when both runs know
    their scene and the scenes differ. O(n) (the scenes' arrays)."""
    a, b = traj.scene, reference.scene
    if a is None or b is None or a is b:
        return
    differ = scene_differences(scene_to_dict(a), scene_to_dict(b))
    if differ:
        raise ValueError(
            f"traj and reference are runs of different scenes ({', '.join(differ)} differ); "
            "pass allow_different_scenes=True to compare them anyway"
        )


def scaled_errors(values: np.ndarray, reference: np.ndarray) -> dict[str, float]:
    """Errors of (nt, nk) ``values`` scaled by the reference's largest magnitude
    s = max |reference| over all times and columns: ``final`` = max_k |e(t_last)| / s,
    ``rms`` = RMS(e) / s, ``max`` = max |e| / s (= ``relative_error(..., "all")``)."""
    e = np.asarray(values, float) - np.asarray(reference, float)
    s = float(np.max(np.abs(reference)))
    return {
        "final": float(np.max(np.abs(e[-1])) / s),
        "rms": float(np.sqrt(np.mean(e * e)) / s),
        "max": float(relative_error(values, reference, "all")),
    }


def left_out_quantities(
    model_quantities: Iterable[str], reference_quantities: Iterable[str]
) -> list[str]:
    """Quantities only one run of a pair outputs (e.g. the energy audit's work, dissipated
    and energy_residual, which only audited native runs record), in order: they are left out
    of that pair's comparison (``compare_runs``), the rest compared; reports name them."""
    a, b = tuple(model_quantities), tuple(reference_quantities)
    return [q for q in b if q not in a] + [q for q in a if q not in b]


def compare_runs(
    trajectories: dict[str, Trajectory], reference: str, outputs: Iterable[str]
) -> list[dict[str, Any]]:
    """Discrepancy rows of every trajectory against the one labelled ``reference``, one row
    per quantity (``discrepancies`` plus model, reference, status). When either run failed,
    the metrics are absent (NaN in tables) and ``status`` says which run failed. A quantity
    that only one run of a successful pair outputs is left out of that pair's comparison
    (``left_out_quantities``; the study report names it and counts it), the others are
    compared: a pair is never dropped for lack of a common quantity."""
    ref = trajectories[reference]
    quantities = ref.quantities if ref.success else trajectory_quantities(outputs)
    rows: list[dict[str, Any]] = []
    for label, traj in trajectories.items():
        if label == reference:
            continue
        base = {"model": label, "reference": reference}
        if not ref.success:
            status = f"reference failed ({STATUS_MESSAGES[ref.stats.status]})"
        elif not traj.success:
            status = f"model failed ({STATUS_MESSAGES[traj.stats.status]})"
        else:
            try:
                rows += _pair_rows(traj, ref, quantities, base)
                continue
            except ValueError as exc:
                status = f"not comparable: {exc}"
        rows += [{**base, "quantity": q, "status": status} for q in quantities]
    return rows


def _pair_rows(
    traj: Trajectory, ref: Trajectory, quantities: Iterable[str], base: dict[str, Any]
) -> list[dict[str, Any]]:
    """The rows of one successful pair: the quantities both runs output, compared ("ok");
    those only one of them outputs are left out (``left_out_quantities``). ValueError when
    the runs cannot be compared at all."""
    both = [q for q in quantities if q in traj.values]
    compared = discrepancies(traj, ref, both).to_dict("records") if both else []
    return [{**base, **r, "status": "ok"} for r in compared]


def pareto_front(cost: np.ndarray, err: np.ndarray) -> np.ndarray:
    """Indices of the points not dominated in (cost, error), by increasing cost: along the
    front the error decreases strictly as the cost grows (a monotone front)."""
    order = np.argsort(cost, kind="stable")
    front, best = [], math.inf
    for i in order:
        if np.isfinite(err[i]) and err[i] < best:
            front.append(i)
            best = err[i]
    return np.array(front, dtype=int)
