"""How far a model agrees with the study's reference, where it parts and why: the answer a
study report opens with (docs/deployment.md, "The answer").

Definitions (one place; the report and docs/deployment.md quote them):

* **scale** of a quantity q: s_q = max over output times and k of |q_ref| (the reference's
  largest magnitude, ``relative_error``'s "all" group).
* **gap** of q at an output time t: g_q(t) = max over k of |q_m(t, k) - q_ref(t, k)| / s_q.
* **agreement horizon** t_h: the first output time at which g_q(t) > tol + e_ref for some
  watched quantity q (``AgreementSettings``: ``tol``, default ``DEFAULT_TOL``; the watched
  ``quantities``, default ``DEFAULT_QUANTITIES``; e_ref = ``reference_rel``, the reference's
  own error bar as a fraction of the scale when the study gives one, else 0). The model
  agrees with the reference on [0, t_h); no horizon (None) when it agrees at every common
  output time.
* **parting lock**: walking the reference's locks in time order, the first whose lock the
  model lacks, reaches in another order (the model's i-th lock is another hinge's) or reaches
  more than lock_dt + e_dt away (``lock_dt``, default ``COMPARABLE_DT_S``; e_dt =
  ``reference_dt``, the reference's error bar on lock times); a lock only the model has
  parts too.
* **predictability horizon**: the agreement horizon of the reference's twin (the reference
  run again on the scene with one initial chord angle moved by a perturbation far below the
  tolerance) against the reference.
* **beyond the horizon** (what stays meaningful once the trajectories part): the lock order
  (``lock_order``: "same", or the first lock where the model's sequence of lock labels
  differs from the reference's); how many of the reference's locks the model reaches in
  order within lock_dt + e_dt (``locks_within``, "k/N"); the **deployed state**: each run's
  chord angles (and a free base's attitude) averaged over the output times after the later
  of the two runs' last locks (``rodval.analysis.convergence.deployed_mean``, the definition
  ``rodval reference`` converges), and their largest difference, rad (``deployed_gap``;
  ``attitude_gap``), against the reference's band: e_ref x the scale for the angles, the
  reference's ``attitude`` error bar for the attitude. A run is **deployed** when every
  latch of its case locked within it; ``never_locked`` names those that did not (the state
  after the last lock is then a partly folded structure's, and the report says so).
* **cause** of a model's parting, measured: (a) ``out of domain``: the model's own verdict
  on its run broke one of its checks (its ``invalid_because``); (b) ``unpredictable``: the
  twin parts as much: at the model's parting lock the twin's |dt| is at least
  ``AS_MUCH`` of the model's |dt| (or the twin parts there or earlier), or, when the model
  parts by its trajectories only, the predictability horizon is no later than the agreement
  horizon; (c) ``model difference``: neither (a) nor (b), with a twin run to measure (b);
  without a twin run (b) is "not measured". (a) and (b) may hold together.

Pure functions over arrays and the study's tidy tables (trajectories, events, runtime).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from rodval.analysis.convergence import deployed_mean
from rodval.analysis.events import COMPARABLE_DT_S, is_lock, lock_comparison

#: Default tolerance of the agreement horizon: a fraction of each watched quantity's scale.
DEFAULT_TOL = 0.02
#: The quantities the agreement horizon watches by default: the chord angles (the motion).
DEFAULT_QUANTITIES = ("phi",)
#: The twin "parts as much" as the model when its lock-time gap is at least this fraction
#: of the model's.
AS_MUCH = 0.5
#: The cause labels.
OUT_OF_DOMAIN, UNPREDICTABLE, MODEL_DIFFERENCE = (
    "out of domain",
    "unpredictable",
    "model difference",
)


@dataclass(frozen=True)
class AgreementSettings:
    """A study's [agreement] settings (``tol``: fraction of the scale; ``quantities``: the
    watched ones; ``lock_dt``: s; ``reference_rel``, ``reference_dt``, ``reference_impulse``:
    the reference's own error bars (fraction of the scale, s, fraction of |S_ref|), 0 when
    the study gives none; ``reference_attitude``: rad, a free base's attitude; ``twin``: the
    twin's perturbation {"rod": k, "angle": rad} or None)."""

    tol: float = DEFAULT_TOL
    quantities: tuple[str, ...] = DEFAULT_QUANTITIES
    lock_dt: float = COMPARABLE_DT_S
    reference_rel: float = 0.0
    reference_dt: float = 0.0
    reference_impulse: float = 0.0
    reference_attitude: float = 0.0
    twin: Mapping[str, Any] | None = None

    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | None) -> AgreementSettings:
        """The settings of a checked [agreement] table (study.json's), defaults for None."""
        d = d or {}
        ref = d.get("reference_error") or {}
        return cls(
            tol=float(d.get("tol", DEFAULT_TOL)),
            quantities=tuple(d.get("quantities", DEFAULT_QUANTITIES)),
            lock_dt=float(d.get("lock_dt", COMPARABLE_DT_S)),
            reference_rel=float(ref.get("rel", 0.0)),
            reference_dt=float(ref.get("lock_dt", 0.0)),
            reference_impulse=float(ref.get("impulse_rel", 0.0)),
            reference_attitude=float(ref.get("attitude", 0.0)),
            twin=d.get("twin"),
        )


def twin_label(reference: str) -> str:
    """The label of the reference's twin run."""
    return f"{reference} twin"


def gap_series(values: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """g(t) = max_k |values - reference| / max |reference| for (nt, nk) arrays (module
    docstring); nan everywhere when the reference is identically zero (no scale)."""
    v, r = np.asarray(values, float), np.asarray(reference, float)
    scale = float(np.max(np.abs(r))) if r.size else 0.0
    if not scale > 0:
        return np.full(v.shape[0], np.nan)
    return np.asarray(np.max(np.abs(v - r), axis=1) / scale)


def agreement_horizon(
    times: np.ndarray,
    values: Mapping[str, np.ndarray],
    reference: Mapping[str, np.ndarray],
    tol: float,
    reference_rel: float = 0.0,
) -> tuple[float | None, str | None]:
    """(t_h, q): the first output time where a quantity's gap exceeds tol + reference_rel,
    and that quantity (the first in ``values``' order at that time); (None, None) when none
    does. ``values`` and ``reference``: quantity -> (nt, nk) arrays at ``times`` (nt,)."""
    bound = tol + reference_rel
    first: tuple[float | None, str | None] = (None, None)
    for q, v in values.items():
        above = np.flatnonzero(gap_series(v, reference[q]) > bound)
        if above.size and (first[0] is None or times[above[0]] < first[0]):
            first = (float(times[above[0]]), q)
    return first


def parting_lock(
    model: Sequence[tuple[str, float]], ref: Sequence[tuple[str, float]], tol_dt: float
) -> dict[str, Any] | None:
    """The first lock where ``model`` parts from ``ref`` (both (label, t) in time order):
    {"label", "dt" (s, model - reference; nan when the model lacks it), "why"}; None when
    every lock agrees in order and within ``tol_dt`` s and neither has an extra lock."""
    own: dict[str, float] = {}
    for label, t in model:
        own.setdefault(label, t)
    for i, (label, t_ref) in enumerate(ref):
        if label not in own:
            return {"label": label, "dt": math.nan, "why": "no such lock in the model"}
        dt = own[label] - t_ref
        if i >= len(model) or model[i][0] != label:
            return {"label": label, "dt": dt, "why": f"out of order (lock {i + 1})"}
        if not abs(dt) <= tol_dt:
            return {"label": label, "dt": dt, "why": f"{'late' if dt > 0 else 'early'}"}
    if len(model) > len(ref):
        label, _ = model[len(ref)]
        return {"label": label, "dt": math.nan, "why": "a lock the reference lacks"}
    return None


def lock_order(model: Sequence[tuple[str, float]], ref: Sequence[tuple[str, float]]) -> str:
    """ "same" when the model's locks carry the reference's labels in the reference's order
    (both (label, t) in time order), else the first differing position in words."""
    for i, ((label, _), (own, _)) in enumerate(zip(ref, model)):
        if own != label:
            return f"lock {i + 1}: {own} where the reference has {label}"
    if len(model) != len(ref):
        return f"{len(model)} locks, the reference {len(ref)}"
    return "same"


def locks_within(
    model: Sequence[tuple[str, float]], ref: Sequence[tuple[str, float]], tol_dt: float
) -> str:
    """ "k/N": of the reference's N locks, how many the model reaches at the same position in
    its lock order and within ``tol_dt`` s."""
    hits = sum(
        1
        for (label, t_ref), (own, t) in zip(ref, model)
        if own == label and abs(t - t_ref) <= tol_dt
    )
    return f"{hits}/{len(ref)}"


def deployed_gap(
    times: tuple[np.ndarray, np.ndarray], values: tuple[np.ndarray, np.ndarray], since: float
) -> float:
    """The largest difference (the values' unit) between the model's and the reference's
    deployed states: ``deployed_mean`` of each run's (nt, nk) ``values`` over its output
    ``times`` at or after ``since`` (s); nan when either run has no output time there."""
    (t_m, t_r), (v_m, v_r) = times, values
    if not (t_m >= since).any() or not (t_r >= since).any():
        return math.nan
    return float(np.max(np.abs(deployed_mean(t_m, v_m, since) - deployed_mean(t_r, v_r, since))))


def twin_parts_as_much(
    model_part: Mapping[str, Any],
    twin_locks: Sequence[tuple[str, float]],
    ref_locks: Sequence[tuple[str, float]],
    tol_dt: float,
) -> bool:
    """Whether the twin parts from the reference as much as the model does at the model's
    parting lock ``model_part`` (``parting_lock``'s dict): the twin parts there or earlier,
    or its |dt| at that lock is at least AS_MUCH of the model's."""
    twin_part = parting_lock(twin_locks, ref_locks, tol_dt)
    order = [label for label, _ in ref_locks]
    if twin_part is not None and model_part["label"] in order and twin_part["label"] in order:
        if order.index(twin_part["label"]) <= order.index(model_part["label"]):
            return True
    own = dict(twin_locks)
    ref = dict(ref_locks)
    label = model_part["label"]
    if label not in own or label not in ref or math.isnan(model_part["dt"]):
        return False
    return bool(abs(own[label] - ref[label]) >= AS_MUCH * abs(model_part["dt"]))


def check_names(invalid_because: Any) -> str:
    """The names of the checks a verdict broke ("small bending", "energy balance"), from its
    invalid_because text ("... (small bending); fix: ..."); the text itself when it names none."""
    text = str(invalid_because or "")
    names = re.findall(r"\(([a-z][a-z -]+)\); fix", text)
    return ", ".join(dict.fromkeys(names)) or text


def _twin_text(twin: Mapping[str, Any], part: Mapping[str, Any] | None) -> str:
    """What the twin measured, in words: its lock-time gap at the parting lock, or its
    predictability horizon."""
    if part is not None:
        dt = twin.get("dt", math.nan)
        moved = "lacks it" if math.isnan(dt) else f"moves it by {dt * 1e3:+.3g} ms"
        return f"the twin {moved}"
    horizon = twin["horizon"]
    return (
        "the twin agrees to the end"
        if horizon is None
        else f"predictability horizon {horizon:.4g} s"
    )


def cause(
    invalid_because: str,
    part: Mapping[str, Any] | None,
    horizon: float | None,
    twin: Mapping[str, Any] | None,
) -> str:
    """The measured cause of a model's parting (module docstring), "" when it does not part.
    ``invalid_because``: its broken checks ("" when valid); ``part``: its parting lock or
    None; ``horizon``: its agreement horizon; ``twin``: None without a twin run, else
    {"parts_as_much": bool (at ``part``), "dt": the twin's dt at that lock (s, nan if it
    lacks it), "horizon": the predictability horizon or None}."""
    if part is None and horizon is None:
        return ""
    causes = []
    if invalid_because:
        causes.append(f"{OUT_OF_DOMAIN} ({check_names(invalid_because)})")
    if twin is None:
        causes.append("predictability not measured (no twin run)")
        return "; ".join(causes)
    if part is not None:
        unpredictable = bool(twin["parts_as_much"])
    else:
        unpredictable = twin["horizon"] is not None and horizon is not None
        unpredictable = unpredictable and twin["horizon"] <= horizon
    measured = _twin_text(twin, part)
    if unpredictable:
        causes.append(f"{UNPREDICTABLE} ({measured})")
    else:
        if not invalid_because:
            causes.append(MODEL_DIFFERENCE)
        causes.append(f"predictable ({measured})")
    return "; ".join(causes)


# ---- over the study's tables -------------------------------------------------------------


def run_arrays(
    traj: pd.DataFrame, quantities: Sequence[str]
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """One run's output times and its (nt, nk) arrays of ``quantities`` (those it has) from
    its rows of a tidy trajectories table (t, quantity, k, value)."""
    times = np.sort(traj["t"].unique())
    out = {}
    for q in quantities:
        part = traj[traj["quantity"] == q]
        if not part.empty:
            wide = part.pivot_table(index="t", columns="k", values="value", sort=True)
            out[q] = wide.reindex(times).to_numpy(float)
    return times, out


def pair_horizon(
    run: pd.DataFrame, ref: pd.DataFrame, settings: AgreementSettings
) -> tuple[float | None, str | None, float]:
    """(t_h, quantity, t_common_end) of one run against the reference's (tidy rows of each):
    the agreement horizon over their common output times and the last of them."""
    qs = settings.quantities
    t_m, v_m = run_arrays(run, qs)
    t_r, v_r = run_arrays(ref, qs)
    common = np.intersect1d(t_m, t_r)
    watched = [q for q in qs if q in v_m and q in v_r]
    if not common.size or not watched:
        return None, None, math.nan
    im, ir = np.searchsorted(t_m, common), np.searchsorted(t_r, common)
    t_h, q = agreement_horizon(
        common,
        {q: v_m[q][im] for q in watched},
        {q: v_r[q][ir] for q in watched},
        settings.tol,
        settings.reference_rel,
    )
    return t_h, q, float(common[-1])


def lock_list(events: pd.DataFrame, case: Any, model: str) -> list[tuple[str, float]]:
    """The (label, t) of one run's locks in time order ([] for a run without any)."""
    if events.empty:
        return []
    own = events[(events["case"] == case) & (events["model"] == model)]
    # a boolean array, not a Series: an empty Series of labels maps to an empty str Series,
    # which pandas reads as a list of column names (a frame without columns, no "t")
    own = own[own["label"].map(is_lock).to_numpy(bool)].sort_values("t", kind="stable")
    return [(str(lab), float(t)) for lab, t in zip(own["label"], own["t"])]


def locked_hinges(label: str) -> list[int]:
    """The hinges a lock event's label names ("latch hinge 2", "latch hinge 1, 3")."""
    if not str(label).startswith("latch hinge"):
        return []
    return [int(h) for h in re.findall(r"\d+", str(label))]


def never_locked(latched: Sequence[int], locks: Sequence[tuple[str, float]]) -> str:
    """The latches of ``latched`` (a case's hinges, cases.csv's latch_hinges) that none of a
    run's ``locks`` ((label, t), ``lock_list``) names, "latch hinge 1, latch hinge 3" ("" when
    every one locked): latches that never locked within the run, which is not deployed."""
    done = {h for label, _ in locks for h in locked_hinges(label)}
    return ", ".join(f"latch hinge {h}" for h in latched if h not in done)


def latch_hinges(cases: pd.DataFrame) -> dict[Any, list[int]]:
    """Case -> the hinges its scene latches (cases.csv's ``latch_hinges``, a JSON list; no
    entry for a case without the column)."""
    if "latch_hinges" not in cases:
        return {}
    return {
        case: [int(h) for h in re.findall(r"\d+", str(hs))] if pd.notna(hs) else []
        for case, hs in zip(cases["case"], cases["latch_hinges"])
    }


#: Columns of ``agreement_table``.
AGREEMENT_COLUMNS = (
    *("case", "model", "role", "status", "valid", "out_of_domain", "horizon"),
    *("horizon_quantity", "compared_to", "part_lock", "part_dt", "part_why", "cause"),
    *("worst_dt", "worst_dt_lock", "worst_impulse_rel", "worst_impulse_lock", "lock_order"),
    *("locks_within", "never_locked", "deployed_gap", "deployed_band", "attitude_gap"),
    *("attitude_band", "wall_s"),
)


def _text(value: Any) -> bool:
    """Whether a table cell holds text (not blank, not nan)."""
    return isinstance(value, str) and bool(value.strip())


def domain_reason(invalid_because: Any) -> str:
    """The broken checks of a run's verdict without their fixes ("" for a valid run)."""
    if not _text(invalid_because):
        return ""
    return "; ".join(part.split("; fix:")[0].strip() for part in invalid_because.split(" | "))


def worst_gaps(events: pd.DataFrame, model: str, reference: str, case: Any) -> dict[str, Any]:
    """The largest |dt| (s, signed) and impulse_rel over the locks both runs of ``case`` have
    (``lock_comparison``), with the locks' labels; nan without common locks."""
    out: dict[str, Any] = {
        "worst_dt": math.nan,
        "worst_dt_lock": "",
        "worst_impulse_rel": math.nan,
        "worst_impulse_lock": "",
    }
    if events.empty:
        return out
    locks = lock_comparison(events[events["case"] == case], model, reference)
    both = locks.dropna(subset=["dt"])
    if both.empty:
        return out
    i = both["dt"].abs().idxmax()
    out.update(worst_dt=float(both.loc[i, "dt"]), worst_dt_lock=str(both.loc[i, "label"]))
    imp = both.dropna(subset=["impulse_rel"])
    if not imp.empty:
        j = imp["impulse_rel"].idxmax()
        out.update(
            worst_impulse_rel=float(imp.loc[j, "impulse_rel"]),
            worst_impulse_lock=str(imp.loc[j, "label"]),
        )
    return out


def _run_row(run: pd.Series, role: str) -> dict[str, Any]:
    """The verdict columns of one runtime row."""
    valid = run.get("valid")
    return {
        "case": run["case"],
        "model": run["model"],
        "role": role,
        "status": run.get("status", ""),
        "valid": None if pd.isna(valid) else str(valid) == "True",
        "out_of_domain": domain_reason(run.get("invalid_because")),
        "_checks": check_names(run.get("invalid_because"))
        if _text(run.get("invalid_because"))
        else "",
        "wall_s": float(run.get("wall_s", math.nan)),
    }


def _pair_columns(
    row: dict[str, Any],
    runs: dict[str, pd.DataFrame],
    events: pd.DataFrame,
    reference: str,
    settings: AgreementSettings,
) -> dict[str, Any]:
    """The agreement columns of ``row``'s run against the reference (``runs``: model ->
    tidy trajectory rows of its case)."""
    model, case = row["model"], row["case"]
    t_h, q, t_end = pair_horizon(runs[model], runs[reference], settings)
    ref_locks = lock_list(events, case, reference)
    own_locks = lock_list(events, case, model)
    tol_dt = settings.lock_dt + settings.reference_dt
    part = parting_lock(own_locks, ref_locks, tol_dt)
    return {
        "horizon": math.nan if t_h is None else t_h,
        "horizon_quantity": q or "",
        "compared_to": t_end,
        "part_lock": "" if part is None else part["label"],
        "part_dt": math.nan if part is None else part["dt"],
        "part_why": "" if part is None else part["why"],
        "_part": part,
        **worst_gaps(events, model, reference, case),
        "lock_order": lock_order(own_locks, ref_locks) if ref_locks or own_locks else "",
        "locks_within": locks_within(own_locks, ref_locks, tol_dt) if ref_locks else "",
        **_deployed_columns(runs[model], runs[reference], own_locks, ref_locks, settings),
    }


def _deployed_columns(
    run: pd.DataFrame,
    ref: pd.DataFrame,
    own_locks: Sequence[tuple[str, float]],
    ref_locks: Sequence[tuple[str, float]],
    settings: AgreementSettings,
) -> dict[str, float]:
    """``deployed_gap`` (chord angles, rad) and ``attitude_gap`` (a free base's attitude,
    rad; nan without it) of one run against the reference's, after the later last lock, and
    the reference's bands: ``deployed_band`` = reference_rel x max |phi_ref| (rad; the scale
    of ``gap_series``), ``attitude_band`` = reference_attitude (rad)."""
    since = max((t for _, t in [*own_locks, *ref_locks]), default=0.0)
    _, phi_ref = run_arrays(ref, ("phi",))
    scale = float(np.max(np.abs(phi_ref["phi"]))) if "phi" in phi_ref else math.nan
    out = {
        "deployed_band": settings.reference_rel * scale,
        "attitude_band": settings.reference_attitude,
    }
    for column, q in (("deployed_gap", "phi"), ("attitude_gap", "base_attitude")):
        t_m, v_m = run_arrays(run, (q,))
        t_r, v_r = run_arrays(ref, (q,))
        out[column] = (
            deployed_gap((t_m, t_r), (v_m[q], v_r[q]), since) if q in v_m and q in v_r else math.nan
        )
    return out


def agreement_table(
    traj: pd.DataFrame,
    events: pd.DataFrame,
    runtime: pd.DataFrame,
    reference: str,
    settings: AgreementSettings,
    latches: Mapping[Any, Sequence[int]] | None = None,
) -> pd.DataFrame:
    """One row per case and run (AGREEMENT_COLUMNS): its role (reference, twin, model), how
    it ended, its verdict (valid; out_of_domain: the checks it broke), ``never_locked``: the
    case's latches (``latches``: case -> hinges, ``latch_hinges``) the run never locked
    ("latch hinge 1, latch hinge 3"; "" when every one locked; nan for a case without
    latches or when ``latches`` is not given), its agreement horizon
    against the reference (s; nan: agrees at every common output time, up to
    ``compared_to``) and the quantity that parts there, the first lock where it parts
    (label, dt s, why), the measured cause, the worst lock-time gap (s) and impulse gap
    (fraction of |S_ref|) over the locks both have, and its integration wall time (s). The
    twin's horizon is the predictability horizon. O(rows of the tables)."""
    twin = twin_label(reference)
    rows = []
    for case, runs_rt in runtime.groupby("case", sort=False):
        runs = {m: part for m, part in traj[traj["case"] == case].groupby("model", sort=False)}
        twin_row: dict[str, Any] | None = None
        ordered = sorted(
            (r for _, r in runs_rt.iterrows()),
            key=lambda r: (r["model"] != reference, r["model"] != twin),
        )
        for run in ordered:
            role = (
                "reference"
                if run["model"] == reference
                else "twin"
                if run["model"] == twin
                else "model"
            )
            row = _run_row(run, role)
            if latches and latches.get(case):
                row["never_locked"] = never_locked(
                    latches[case], lock_list(events, case, run["model"])
                )
            if role != "reference" and run["model"] in runs and reference in runs:
                row.update(_pair_columns(row, runs, events, reference, settings))
            if role == "twin":
                twin_row = row
            elif role == "model":
                row["cause"] = _row_cause(row, twin_row, events, reference, settings)
            rows.append(row)
    return pd.DataFrame(rows).reindex(columns=list(AGREEMENT_COLUMNS))


def _row_cause(
    row: dict[str, Any],
    twin_row: dict[str, Any] | None,
    events: pd.DataFrame,
    reference: str,
    settings: AgreementSettings,
) -> str:
    """``cause`` of a model's row (its broken checks' names in ``_checks``), measured with
    the twin's row (None: no twin run)."""
    part = row.get("_part")
    horizon = None if pd.isna(row.get("horizon", math.nan)) else float(row["horizon"])
    twin = None
    if twin_row is not None and "horizon" in twin_row:
        t_h, case = twin_row["horizon"], row["case"]
        twin_list = lock_list(events, case, str(twin_row["model"]))
        ref_list = lock_list(events, case, reference)
        twin_locks, ref_locks = dict(twin_list), dict(ref_list)
        label = part["label"] if part is not None else ""
        tol_dt = settings.lock_dt + settings.reference_dt
        twin = {
            "horizon": None if pd.isna(t_h) else float(t_h),
            "dt": twin_locks[label] - ref_locks[label]
            if label in twin_locks and label in ref_locks
            else math.nan,
            "parts_as_much": part is not None
            and twin_parts_as_much(part, twin_list, ref_list, tol_dt),
        }
    return cause(row["_checks"], part, horizon, twin)
