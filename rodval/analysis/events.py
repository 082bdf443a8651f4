"""Lock events compared across models: one definition for the study report, a study's
``[acceptance]`` and ``rodval compare``.

Every model records one event dict per lock (``Trajectory.events``: t, label, hinge, impulse,
impulse_window, rigid_impulse, kinetic_before, kinetic_after, ...; docs/deployment.md).
``events_frame`` puts the runs' events in one table (one row per event, with the derived
energy_lost and impulse_to_rigid); ``event_discrepancies`` compares each model's events with the
reference's of the same case and label; ``lock_comparison`` puts one model's locks and the
reference's side by side, locks that only one of them has included. ``comparability`` says why
a lock cannot be compared pointwise with the reference's (blank when it can).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
import pandas as pd

from rodval.mechanics.lock_window import MIN_WINDOW_STEPS

#: The leading columns of an events table (after the columns that name the run: case columns
#: and model); the keys the native and exudyn latch records share.
EVENT_COLUMNS = (
    *("t", "label", "hinge", "impulse", "impulse_window", "rigid_impulse", "impulse_to_rigid"),
    *("kinetic_before", "kinetic_after", "energy_lost", "instant_energy_loss", "hinge_before"),
    *("bending_before", "kinetic_window_end", "hinge_window_end", "bending_window_end"),
    *("work_window_end", "dissipated_window_end", "energy_residual_window_end"),
)

#: A lock is compared pointwise with the reference's when every earlier lock of the case came
#: within this time (s) of the reference's and its kinetic plus bending energy before the
#: lock (``state_energies``) is within this fraction of the reference's: otherwise the models
#: reach it in different states.
COMPARABLE_DT_S = 1e-3
COMPARABLE_ENERGY = 0.05
#: A lock is grazing when the rigid-panel lock of the chords just before it would take less
#: than this fraction of the rigid chain's kinetic energy (``rodval.mechanics.rigid``): its hinge
#: approaches the latch angle so slowly that its time and impulse hang on small differences
#: of state, and a model may not lock at all.
GRAZING_LOSS = 0.01


def event_row(lead: Mapping[str, Any], ev: Mapping[str, Any]) -> dict[str, Any]:
    """One row of an events table: the columns naming the run (``lead``: case columns,
    model), the event's keys, energy_lost = kinetic_before - kinetic_after (J) and
    impulse_to_rigid = impulse / rigid_impulse, where the record has them."""
    row = {**lead, **ev}
    before, after = ev.get("kinetic_before"), ev.get("kinetic_after")
    if isinstance(before, (int, float)) and isinstance(after, (int, float)):
        row["energy_lost"] = before - after
    if ev.get("rigid_impulse") and ev.get("impulse") is not None:
        row["impulse_to_rigid"] = ev["impulse"] / ev["rigid_impulse"]
    return row


def events_frame(
    runs: Iterable[tuple[Mapping[str, Any], Iterable[Mapping[str, Any]]]],
    lead_columns: Iterable[str] = ("case", "model"),
) -> pd.DataFrame:
    """The events table of ``runs`` ((lead, events) pairs: the columns naming a run, e.g.
    {"case": ..., "model": ...}, and its list of event dicts): one row per event
    (``event_row``), columns ``lead_columns``, then EVENT_COLUMNS, then the union of the
    models' own keys in first-seen order (blank where a model lacks one)."""
    rows = [event_row(lead, ev) for lead, events in runs for ev in events]
    lead = [*lead_columns, *EVENT_COLUMNS]
    extra = [c for c in dict.fromkeys(k for row in rows for k in row) if c not in lead]
    return pd.DataFrame(rows).reindex(columns=[*lead, *extra])


def rigid_loss_fraction(ev: pd.Series) -> float:
    """The fraction of the rigid chain's kinetic energy the rigid-panel lock takes out (nan
    where the record lacks the rigid-panel energies, e.g. a stop event)."""
    before, after = ev.get("rigid_kinetic_before"), ev.get("rigid_kinetic_after")
    if before is None or after is None or not float(before) > 0:
        return float("nan")
    return (float(before) - float(after)) / float(before)


def _number(value: Any) -> float:
    """``value`` as a float (nan for a blank, None or text)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def _ratio(a: float, b: float) -> float:
    """a / b (nan where b is 0)."""
    return a / b if b != 0 else math.nan


def _compliant(record: Any) -> bool:
    """Whether an event record is a compliant latch's engagement (no impact, no impulse)."""
    flag = record.get("compliant")
    return isinstance(flag, bool | np.bool_) and bool(flag)


def is_lock(label: Any) -> bool:
    """Whether an event's label names a lock ("latch ..."): the one test the tables use."""
    return str(label).startswith("latch")


def overlapping_lock(ev: pd.Series, run: pd.DataFrame) -> tuple[str, float] | None:
    """(label, t s) of a lock of the same run (``run``: its events) that lies inside the lock
    ``ev``'s window [t, t + impulse_window], or inside whose window ``ev`` lies (an earlier
    lock's); None when there is none or the records carry no window. Such windowed impulses
    hold each other's reactions: they are not separable."""
    t, w = _number(ev.get("t")), _number(ev.get("impulse_window"))
    for idx, other in run.iterrows():
        if idx == ev.name or not is_lock(other.get("label")):
            continue
        t_o, w_o = _number(other.get("t")), _number(other.get("impulse_window"))
        inside = t <= t_o <= t + w if w >= 0 else False
        before = t_o <= t <= t_o + w_o if w_o >= 0 else False
        if inside or before:
            return str(other["label"]), t_o
    return None


def comparability(
    ev: pd.Series,
    r: pd.Series,
    earlier: list[tuple[str, float]],
    own_run: pd.DataFrame | None = None,
    ref_run: pd.DataFrame | None = None,
) -> str:
    """Why the lock ``ev`` is not comparable pointwise with the reference's ``r`` ("" when it
    is); ``earlier``: (label, |dt| s) of the case's earlier locks (nan: the model lacks it);
    ``own_run``, ``ref_run``: the events of ev's run and of r's (for overlapping windows).

    In order: a window that overlaps another lock of the same run (``overlapping_lock``, the
    model's or the reference's), an exudyn window of fewer than MIN_WINDOW_STEPS steps
    (``window_steps``), a grazing lock (``GRAZING_LOSS``), an earlier lock of the case more
    than COMPARABLE_DT_S apart, a kinetic plus bending energy before the lock more than
    COMPARABLE_ENERGY apart (``state_energies``). A lock whose record has no finite impulse
    (a damaged or edited run record: rodval records every ideal lock's; a compliant latch's
    engagement, ``compliant``, has none: no impact) says so first."""
    for who, record in (("its", ev), ("the reference's", r)):
        impulse = _number(record.get("impulse"))
        if is_lock(record.get("label")) and not _compliant(record) and not math.isfinite(impulse):
            return f"{who} record has no finite lock impulse (a damaged run record)"
    for who, record, run in (("its", ev, own_run), ("the reference's", r, ref_run)):
        if run is None or not is_lock(record.get("label")):
            continue
        hit = overlapping_lock(record, run)
        if hit is not None:
            return (
                f"{who} window overlaps the lock of {hit[0]} at t = {hit[1]:.6g} s "
                "(the impulses are not separable)"
            )
    for who, record in (("", ev), ("the reference's ", r)):
        steps = _number(record.get("window_steps"))
        if steps < MIN_WINDOW_STEPS:
            return (
                f"{who}exudyn's window holds {steps:.3g} steps (< {MIN_WINDOW_STEPS}); "
                "refine its step"
            )
    for who, record in (("its", ev), ("the reference's", r)):
        loss = rigid_loss_fraction(record)
        if loss < GRAZING_LOSS:
            return (
                f"grazing: {who} rigid-panel lock takes {loss:.2%} of the kinetic energy "
                f"(< {GRAZING_LOSS:.0%})"
            )
    for label, dt in earlier:
        if not dt <= COMPARABLE_DT_S:
            return f"after {label}, whose lock time differs by {dt * 1e3:.3g} ms"
    energy, what = state_energies(ev, r)
    if energy[1] > 0:
        gap = abs(energy[0] / energy[1] - 1.0)
        if not gap <= COMPARABLE_ENERGY:
            return f"{what} before it differs by {gap:.0%}: a different state"
    return ""


def state_energies(ev: pd.Series, r: pd.Series) -> tuple[tuple[float, float], str]:
    """((the model's, the reference's) energy (J) that says whether they reach a lock in the
    same state, what it is): kinetic_before + bending_before where both records carry the
    bending energy, kinetic_before alone where not (nan where a record has none). Rods that ring
    after an earlier lock trade energy between kinetic and bending twice per period of the
    ring, so the kinetic energy alone follows the ring's phase, which a shift of the lock
    time by a fraction of that period turns over (the six-panel wing against exudyn, hinge
    2: 0.34 ms and 0.04 % apart in time and impulse, kinetic 806.7 against 856.5 J, 6 %;
    with the bending 994.2 against 998.4 J, 0.4 %); their sum does not follow it."""
    kinetic = (_number(ev.get("kinetic_before")), _number(r.get("kinetic_before")))
    bending = (_number(ev.get("bending_before")), _number(r.get("bending_before")))
    if all(math.isfinite(b) for b in bending):
        return (kinetic[0] + bending[0], kinetic[1] + bending[1]), "kinetic plus bending energy"
    return kinetic, "kinetic energy"


#: Columns of ``event_discrepancies``.
DISCREPANCY_COLUMNS = (
    *("case", "label", "model", "reference", "dt", "impulse_abs", "impulse_rel", "rigid_rel"),
    *("dE_lost", "not_comparable"),
)


def _numbered(events: pd.DataFrame) -> pd.DataFrame:
    """``events`` with ``nth``: the k-th event of its case, model and label (0-based, by t)."""
    nth = events.sort_values("t", kind="stable").groupby(["case", "model", "label"]).cumcount()
    return events.assign(nth=nth)  # aligned on the index


def _shown_label(label: Any, nth: int) -> str:
    return str(label) + (f" #{nth + 1}" if nth else "")


def event_discrepancies(events: pd.DataFrame, reference: str) -> pd.DataFrame:
    """Each model's events against the reference's event of the same case and label (the
    k-th of a repeated label, e.g. a stop's k-th contact, against the reference's k-th;
    labelled "#k" from the second on): time difference dt (s, model - reference), lock
    impulse difference and its ratio to the reference's |impulse| (impulse_rel), the same
    ratio of the rigid-panel impulses (rigid_rel, where recorded), energy_lost difference
    (J), and ``not_comparable``: why the lock cannot be compared pointwise
    (``comparability``, grazing and overlapping locks included; blank when it can). Events
    the reference lacks are listed with blanks (``lock_comparison`` also lists the
    reference's locks a model lacks)."""
    cols = list(DISCREPANCY_COLUMNS)
    if events.empty:
        return pd.DataFrame(columns=cols)
    # the k-th event of a label (a stop's contacts repeat) is compared with the reference's k-th
    events = _numbered(events)
    ref = events[events["model"] == reference].set_index(["case", "label", "nth"])
    runs = {key: part for key, part in events.groupby(["case", "model"], sort=False)}
    rows = []
    for _, ev in events[events["model"] != reference].iterrows():
        key = (ev["case"], ev["label"], ev["nth"])
        row = {
            "case": ev["case"],
            "label": _shown_label(ev["label"], ev["nth"]),
            "model": ev["model"],
            "reference": reference,
        }
        if key in ref.index:
            ref_run = runs[(ev["case"], reference)]
            # the record as a row of its run (its index names it in the overlap check)
            r = ref_run[(ref_run["label"] == ev["label"]) & (ref_run["nth"] == ev["nth"])].iloc[0]
            row["dt"] = float(ev["t"]) - float(r["t"])
            if "impulse" in events:
                d = _number(ev["impulse"]) - _number(r["impulse"])
                row["impulse_abs"] = d
                row["impulse_rel"] = _ratio(abs(d), abs(_number(r["impulse"])))
            if "rigid_impulse" in events:
                d = _number(ev["rigid_impulse"]) - _number(r["rigid_impulse"])
                row["rigid_rel"] = _ratio(abs(d), abs(_number(r["rigid_impulse"])))
            if "energy_lost" in events:
                row["dE_lost"] = _number(ev["energy_lost"]) - _number(r["energy_lost"])
            row["not_comparable"] = comparability(
                ev,
                r,
                earlier_gaps(events, ev, reference, float(r["t"])),
                runs.get((ev["case"], ev["model"])),
                ref_run,
            )
        rows.append(row)
    return pd.DataFrame(rows).reindex(columns=cols)


def earlier_gaps(
    events: pd.DataFrame, ev: pd.Series, reference: str, t_ref: float
) -> list[tuple[str, float]]:
    """(label, |dt| s) of the reference's locks of ev's case before t_ref against the same
    model's (nan where the model lacks one)."""
    case = events[
        (events["case"] == ev["case"]) & events["label"].astype(str).str.startswith("latch")
    ]
    own = case[case["model"] == ev["model"]].set_index("label")["t"]
    out = []
    for _, r in case[(case["model"] == reference) & (case["t"] < t_ref)].iterrows():
        t = own.get(r["label"])
        t = float(t.iloc[0]) if isinstance(t, pd.Series) else t
        out.append((str(r["label"]), abs(float(t) - float(r["t"])) if t is not None else np.nan))
    return out


#: Columns of ``lock_comparison`` (``_m``: the model's, ``_ref``: the reference's).
LOCK_COLUMNS = (
    *("case", "label", "t_m", "t_ref", "dt", "impulse_m", "impulse_ref", "impulse_rel"),
    *("impulse_to_rigid_m", "impulse_to_rigid_ref", "not_comparable"),
)


def lock_comparison(events: pd.DataFrame, model: str, reference: str) -> pd.DataFrame:
    """The locks (events labelled "latch ...") of ``model`` and ``reference`` side by side,
    one row per case and label (the k-th of a repeated label with the reference's k-th, as
    ``event_discrepancies``, whose dt, impulse_rel and not_comparable it shows): both lock
    times (s) and dt = t_m - t_ref, both impulses (N m s) and impulse_rel, both
    impulse_to_rigid; a lock only one of them has is listed with blanks and
    not_comparable "only in <model>" or "only in <reference>". Case order, then time."""
    cols = list(LOCK_COLUMNS)
    locks = events[events["label"].map(is_lock)] if not events.empty else events
    locks = locks[locks["model"].isin([model, reference])] if not locks.empty else locks
    if locks.empty:
        return pd.DataFrame(columns=cols)
    locks = _numbered(locks)
    disc = event_discrepancies(locks.drop(columns="nth"), reference)
    disc = disc[disc["model"] == model].set_index(["case", "label"])
    rows = []
    keys: dict[tuple[Any, str], dict[str, Any]] = {}
    for _, ev in locks.sort_values("t", kind="stable").iterrows():
        key = (ev["case"], _shown_label(ev["label"], int(ev["nth"])))
        row = keys.get(key)
        if row is None:
            row = keys[key] = {"case": key[0], "label": key[1]}
            rows.append(row)
        side = "m" if ev["model"] == model else "ref"
        row[f"t_{side}"] = float(ev["t"])
        row[f"impulse_{side}"] = _number(ev.get("impulse"))
        row[f"impulse_to_rigid_{side}"] = _number(ev.get("impulse_to_rigid"))
    for row in rows:
        has_m, has_ref = "t_m" in row, "t_ref" in row
        if has_m and has_ref:
            d = disc.loc[(row["case"], row["label"])]
            d = d.iloc[0] if isinstance(d, pd.DataFrame) else d
            row["dt"] = float(d["dt"])
            row["impulse_rel"] = _number(d.get("impulse_rel"))
            row["not_comparable"] = str(d.get("not_comparable") or "")
        else:
            row["not_comparable"] = f"only in {model if has_m else reference}"
    order = {c: i for i, c in enumerate(dict.fromkeys(locks["case"]))}
    out = pd.DataFrame(rows).reindex(columns=cols)
    return out.sort_values(by="case", key=lambda s: s.map(order), kind="stable").reset_index(
        drop=True
    )
