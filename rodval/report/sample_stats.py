"""Statistics of a sampled study (``[sample]``, ``rodval.study.sampling``): the distribution of
each model's results over the samples, as engineers read a deployment's reliability.

* ``lock_statistics``: per model, the probability that every latch locks (the fraction of
  samples whose run recorded a lock of each latch of its scene) and, per hinge, the fraction
  that locked and the percentiles of its lock time (s);
* ``discrepancy_percentiles``: per model pair and quantity, percentiles of max_abs and rms
  over the samples (the comparisons that were made);
* ``sample_section``: both as the study report's Sample statistics section;
* ``spread``: one quantity's distribution over the cases (min, percentiles, max, the worst
  case), which ``percentile_rows`` and the report's opening (``rodval.report.study_summary``)
  give.

Percentiles are numpy's linear interpolation (``numpy.percentile``) at ``PERCENTILES``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from rodval.analysis.agreement import latch_hinges, locked_hinges
from rodval.report.markdown import to_markdown

PERCENTILES = (5, 50, 95)


def lock_statistics(cases: pd.DataFrame, events: pd.DataFrame, models: list[str]) -> pd.DataFrame:
    """One row per model and latched hinge: model, hinge, samples, locked (fraction),
    p_all_locked (fraction of samples in which every latch of the scene locked, the same on
    every row of a model), t_pP (lock time percentiles, s, over the samples where it locked),
    t_min, t_max. ``cases`` needs columns case and latch_hinges (JSON list); O(events)."""
    hinges_of = {str(c): hs for c, hs in latch_hinges(cases).items()}
    samples = len(hinges_of)
    rows = []
    for model in models:
        own = events[events["model"] == model] if not events.empty else events
        times: dict[tuple[str, int], float] = {}
        for case, label, t in zip(own.get("case", []), own.get("label", []), own.get("t", [])):
            for h in locked_hinges(label):
                times.setdefault((str(case), h), float(t))
        every = sum(all((c, h) in times for h in hs) for c, hs in hinges_of.items() if hs)
        latched = sorted({h for hs in hinges_of.values() for h in hs})
        for h in latched:
            with_h = [c for c, hs in hinges_of.items() if h in hs]
            t = np.array([times[(c, h)] for c in with_h if (c, h) in times])
            row = {
                "model": model,
                "hinge": h,
                "samples": len(with_h),
                "locked": len(t) / len(with_h),
                "p_all_locked": every / samples if samples else np.nan,
            }
            for p in PERCENTILES:
                row[f"t_p{p}"] = float(np.percentile(t, p)) if t.size else np.nan
            row["t_min"] = float(t.min()) if t.size else np.nan
            row["t_max"] = float(t.max()) if t.size else np.nan
            rows.append(row)
    return pd.DataFrame(rows)


def discrepancy_percentiles(disc: pd.DataFrame) -> pd.DataFrame:
    """Per model, reference and quantity: the number of samples compared and the percentiles
    of max_abs and rms over them (rows whose comparison could not be made are left out)."""
    ok = disc[disc["status"] == "ok"] if "status" in disc else disc
    rows = []
    for (model, ref, q), part in ok.groupby(["model", "reference", "quantity"], sort=False):
        row = {"model": model, "reference": ref, "quantity": q, "samples": len(part)}
        for metric in ("max_abs", "rms"):
            vals = part[metric].astype(float).to_numpy()
            for p in PERCENTILES:
                row[f"{metric}_p{p}"] = float(np.percentile(vals, p))
        rows.append(row)
    return pd.DataFrame(rows)


def sample_section(
    meta: dict[str, Any], tables: dict[str, pd.DataFrame], events: pd.DataFrame
) -> list[str]:
    """The report's Sample statistics of a ``[sample]`` study (none for a grid study): latch
    locking and lock times when the scenes have latches (``events``: the events table), and
    the discrepancies (markdown lines)."""
    sample = meta.get("sample")
    if not sample:
        return []
    keys = ", ".join(f"`{k}` ({v['dist']})" for k, v in sample["keys"].items())
    lines = [
        "## Sample statistics\n",
        f"{sample['count']} samples, {sample['design']} design, seed {sample['seed']}, of "
        f"{keys}; percentiles {', '.join(str(p) for p in PERCENTILES)} over the samples.\n",
    ]
    models = [m["label"] for m in meta["models"]]
    locks = lock_statistics(tables["cases"], events, models)
    if not locks.empty:
        lines.append("### Latches\n")
        bullets = [
            f"- `{model}`: every latch locked by the end of the run in "
            f"{part['p_all_locked'].iloc[0]:.1%} of the samples"
            for model, part in locks.groupby("model", sort=False)
        ]
        lines += ["\n".join(bullets) + "\n", to_markdown(locks, floatfmt=".4g")]
    disc = discrepancy_percentiles(tables["discrepancies"])
    if not disc.empty:
        lines += ["### Discrepancies\n", to_markdown(disc, floatfmt=".3g")]
    return lines


#: The events' quantities whose distribution a sampled study's report gives per lock.
EVENT_QUANTITIES = ("t", "impulse", "energy_lost")


def spread(values: pd.Series, cases: pd.Series, absolute: bool = False) -> dict[str, Any]:
    """The distribution of ``values`` (one per case, in their unit; blank and non-numeric
    ones left out) over the cases ``cases`` (same index): ``count``, ``min``, ``pP`` for P in
    PERCENTILES, ``max``, and the worst: ``worst`` the largest value (the largest |value| when
    ``absolute``), ``worst_case`` its case. Only ``count`` (0) without values."""
    vals = pd.to_numeric(values, errors="coerce").dropna()
    if vals.empty:
        return {"count": 0}
    at = (vals.abs() if absolute else vals).idxmax()
    return {
        "count": len(vals),
        "min": float(vals.min()),
        **{f"p{p}": float(np.percentile(vals, p)) for p in PERCENTILES},
        "max": float(vals.max()),
        "worst": float(vals[at]),
        "worst_case": cases[at],
    }


def percentile_rows(
    df: pd.DataFrame, by: list[str], columns: tuple[str, ...], absolute: bool = False
) -> pd.DataFrame:
    """Per group of ``by``: the number of rows and, for each of ``columns``, its percentiles
    (PERCENTILES, over the group's non-blank values) and the case of its largest value (of
    its largest |value| when ``absolute``): ``spread``'s. O(rows)."""
    rows = []
    for key, part in df.groupby(by, sort=False):
        row = dict(zip(by, key if isinstance(key, tuple) else (key,)))
        row["samples"] = len(part)
        for col in columns:
            s = spread(part[col], part["case"], absolute)
            for p in PERCENTILES:
                row[f"{col}_p{p}"] = s.get(f"p{p}", np.nan)
            if s["count"]:
                row[f"{col}_worst"] = s["worst"]
                row[f"{col}_worst_case"] = s["worst_case"]
        rows.append(row)
    return pd.DataFrame(rows)


def sample_events_section(
    meta: dict[str, Any], tables: dict[str, pd.DataFrame], events: pd.DataFrame
) -> list[str]:
    """A sampled study's Deployment section: per model and lock, the percentiles of its
    time (s), impulse (N m s) and energy lost (J) over the samples, and of its gaps to the
    reference (dt s, impulse_rel), each with its worst case; every event stays in
    ``events.csv`` (markdown lines, as long for 10 samples as for 10,000)."""
    from rodval.analysis.events import event_discrepancies

    have = [c for c in EVENT_QUANTITIES if c in events]
    lines = [
        "## Deployment: locks, impulses and residual vibration\n",
        "Over the samples, per model and lock: percentiles of the lock time t (s), the lock "
        "impulse (N m s) and the energy lost (J), and the sample of the largest value "
        "(`_worst`, `_worst_case`); every event of every sample: `events.csv` "
        "(docs/deployment.md defines each column).\n",
        to_markdown(percentile_rows(events, ["model", "label"], tuple(have)), ".4g"),
    ]
    disc = event_discrepancies(events, meta["reference"])
    if not disc.empty:
        lines += [
            f"Gaps to `{meta['reference']}` at each lock over the samples (dt s, impulse_rel "
            "= |dS| / |S_ref|), with the sample of the largest |gap|:\n",
            to_markdown(
                percentile_rows(disc, ["model", "label"], ("dt", "impulse_rel"), absolute=True),
                ".3g",
            ),
        ]
    return lines
