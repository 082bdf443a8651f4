"""The study report: ``OUT/report.md`` and ``OUT/figures/*.png`` rebuilt from the saved tables
(``cases.csv``, ``trajectories.csv``, ``discrepancies.csv``, ``runtime.csv``, and
``events.csv`` when some run recorded events: the deployment section) and the study's
``study.json`` / ``provenance.json``; nothing is recomputed.

``build_report`` puts the sections in order: the title and the Answer (``study_summary.
answer_section``: each model against the reference, from ``rodval.analysis.agreement``), the
header (study, models, machine), Acceptance
(``rodval.report.acceptance``), Outcome, Discrepancies, Run time and Stability map
(``study_summary``), the Error budget of the full model's ladder when the study runs its
rungs (``error_budget``: also ``error_budget.csv`` and ``.md``), the figures against the grid
parameters (``study_figures``), Sample statistics (``sample_stats``), the Deployment section
(here, with the events tables), Modes (``study_modes``) and the report cases' time histories
and configurations (``study_figures``). The tables leave out the identity columns constant
over the study (``rodval.report.tables.study_constants``: case in a one-case study, n,
horizon, reference), stated once in the header. A sampled study's report gives
distributions and worst cases instead of per-case tables (``sample_stats``), so its length
does not grow with the number of samples.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pandas as pd

from rodval.analysis.agreement import latch_hinges, lock_list, never_locked
from rodval.analysis.events import (
    COMPARABLE_DT_S,
    COMPARABLE_ENERGY,
    EVENT_COLUMNS,
    GRAZING_LOSS,
    event_discrepancies,
)
from rodval.core.out_paths import STUDY_SCHEMA, is_stamped, write_file
from rodval.core.quantities import models_with
from rodval.core.trajectory import RUN_SETTINGS
from rodval.mechanics.lock_window import MIN_WINDOW_STEPS
from rodval.models import get_model
from rodval.models.registry import uses_integrator
from rodval.report.acceptance import acceptance_section
from rodval.report.error_budget import error_budget
from rodval.report.markdown import to_markdown
from rodval.report.sample_stats import sample_events_section, sample_section
from rodval.report.sensitivity import sensitivity_section
from rodval.report.study_figures import case_figures, deployment_figures, param_figures
from rodval.report.study_modes import modes_section
from rodval.report.study_summary import opening_section, summary_sections
from rodval.report.tables import (
    ERROR_BUDGET,
    FIGURES,
    axis_columns,
    drop_study_constants,
    read_events,
    read_tables,
    study_constants,
    unreadable,
)

#: Columns of the events table shown in the report, when present: the run, the lock and its
#: impulse and energies (``EVENT_COLUMNS``' impulse ... energy_lost, the window's end), its
#: window's state and the root's angular momentum jump.
EVENT_REPORT_COLUMNS = (
    *("case", "model", "label", "t", *EVENT_COLUMNS[3:10], *EVENT_COLUMNS[-2:]),
    *("window_closed", "angular_momentum_root_jump"),
)


def residual_vibration(
    traj: pd.DataFrame, events: pd.DataFrame, cases: pd.DataFrame
) -> pd.DataFrame:
    """Per case and model, after its last lock's window (t_last + impulse_window): the
    tip's y amplitude (max - min) / 2 and mean (m), the largest |alpha| and |beta| (rad), and
    the chord angles' spread max - min of phi over the rods at the last output time (rad, 0
    for a straight chain). Models without events are measured after the last lock of any
    model of the case. ``never_locked``: the case's latches (cases.csv's latch_hinges) the
    run never locked: it is not deployed (a run that locked none has that column only)."""
    rows = []
    hinges = latch_hinges(cases)
    for (case, model), part in traj.groupby(["case", "model"], sort=False):
        evs = events[events["case"] == case]
        own = evs[evs["model"] == model]
        use = own if not own.empty else evs
        missed = never_locked(hinges.get(case, []), lock_list(events, case, model))
        unlocked = {"never_locked": missed} if missed else {}
        if use.empty:
            if missed:
                rows.append({"case": case, "model": model, "locks": 0, **unlocked})
            continue
        ends = use["t"].astype(float)
        if "impulse_window" in use:
            ends = ends + use["impulse_window"].astype(float).fillna(0.0)
        t_last = float(ends.max())
        after = part[part["t"] > t_last]
        row = {"case": case, "model": model, "last_lock_end": t_last, "locks": len(own), **unlocked}
        n = int(cases.loc[cases["case"] == case, "n"].iloc[0]) if not cases.empty else None
        tip = after[(after["quantity"] == "y") & (after["k"] == n)]["value"]
        if not tip.empty:
            row["tip_y_amplitude"] = 0.5 * float(tip.max() - tip.min())
            row["tip_y_mean"] = float(tip.mean())
        for q in ("alpha", "beta"):
            vals = after[after["quantity"] == q]["value"]
            if not vals.empty:
                row[f"max_abs_{q}"] = float(vals.abs().max())
        phi = part[part["quantity"] == "phi"]
        if not phi.empty:
            last = phi[phi["t"] == phi["t"].max()]["value"]
            row["final_phi_spread"] = float(last.max() - last.min())
        rows.append(row)
    return pd.DataFrame(rows)


def recorded_peaks(runtime: pd.DataFrame, quantity: str = "hinge_moment") -> pd.DataFrame:
    """The runs' recorded peaks of ``quantity`` (runtime.csv's ``peaks``, each run's
    ``SolverStats.peaks``, read between its output times): one row per case, model and k
    with ``peak`` (|value|, the quantity's unit, blank where it is an impulse), ``t_peak``
    (s), ``impulse`` (N m s, a hinge whose moment is an impulse at its lock) and ``source``
    (what the peak was read on: ``peaks_read_on``). Empty without recorded peaks."""
    rows = []
    if "peaks" in runtime:
        for _, run in runtime.dropna(subset=["peaks"]).iterrows():
            for e in json.loads(str(run["peaks"])).get(quantity, []):
                rows.append(
                    {
                        "case": run["case"],
                        "model": run["model"],
                        "k": int(e["k"]),
                        "peak": e["peak"],
                        "t_peak": e["t"],
                        "impulse": e.get("impulse"),
                        "source": str(run.get("peaks_read_on", "")),
                    }
                )
    cols = ["case", "model", "k", "peak", "t_peak", "impulse", "source"]
    return pd.DataFrame(rows, columns=cols).astype(
        {"peak": float, "t_peak": float, "impulse": float}
    )


def peak_hinge_moments(
    traj: pd.DataFrame,
    events: pd.DataFrame,
    models: list[dict[str, Any]] | None = None,
    runtime: pd.DataFrame | None = None,
) -> pd.DataFrame:
    """Largest |hinge moment| (N m) per case, model and hinge, one row each: ``peak_moment``
    the run's, read between its output times (``recorded_peaks`` of ``runtime``, its time
    ``t_peak``, ``source`` what it was read on; a hinge whose moment is an impulse at its
    lock: no peak, its ``impulse`` N m s); a run without a recorded peak (a study of an older
    rodval) gives the peak over the output times of its "hinge_moment" trajectory
    (``source`` "hinge_moment"), for every model that outputs it
    (``rodval.core.quantities.models_with``; ``models``: the study's ``[{"label", "model"}]``,
    None: every model in ``traj``). Beside it ``window_peak``, the lock windows' peak where the
    model's lock records carry one (``peak_moment`` of events.csv: exudyn's, over every step
    of the window). A model with only the lock records gives their peak (``source`` "lock
    window")."""
    keys = ["case", "model", "hinge"]
    hm = traj[traj["quantity"] == "hinge_moment"]
    if models is not None:
        labels = {m["label"] for m in models if models_with("hinge_moment", [m["model"]])}
        hm = hm[hm["model"].isin(labels)]
    rec = recorded_peaks(runtime if runtime is not None else pd.DataFrame())
    rec = rec.rename(columns={"k": "hinge", "peak": "peak_moment"})
    runs = set(zip(rec["case"].astype(str), rec["model"]))
    hm = hm[[(str(c), m) not in runs for c, m in zip(hm["case"], hm["model"])]]
    peaks = rec[[*keys, "peak_moment", "t_peak", "source", "impulse"]]
    if not hm.empty:
        g = hm.assign(abs_value=hm["value"].abs()).groupby(["case", "model", "k"], sort=False)
        at = g["abs_value"].idxmax()
        grid = pd.DataFrame(
            {
                "case": [c for c, _, _ in at.index],
                "model": [m for _, m, _ in at.index],
                "hinge": [int(k) for _, _, k in at.index],
                "peak_moment": hm["value"].abs()[at.to_numpy()].to_numpy(),
                "t_peak": hm["t"][at.to_numpy()].to_numpy(),
                "source": "hinge_moment",
            }
        )
        peaks = pd.concat([peaks, grid], ignore_index=True) if not peaks.empty else grid
    window = pd.DataFrame(columns=[*keys, "window_peak"])
    if "peak_moment" in events and events["peak_moment"].notna().any():
        part = events.dropna(subset=["peak_moment"])
        window = part.groupby(keys, sort=False)["peak_moment"].max().reset_index()
        window = window.rename(columns={"peak_moment": "window_peak"})
        window["hinge"] = window["hinge"].astype(int)
    cols = [*keys, "peak_moment", "t_peak", "source", "impulse", "window_peak"]
    if window.empty:
        return peaks.reindex(columns=cols) if not peaks.empty else pd.DataFrame()
    if peaks.empty:
        return window.assign(peak_moment=window["window_peak"], source="lock window").reindex(
            columns=cols
        )
    out = peaks.merge(window, on=keys, how="outer")
    only = out["source"].isna()
    out["source"] = out["source"].where(~only, "lock window")
    out["peak_moment"] = out["peak_moment"].where(~only, out["window_peak"])
    return out.reindex(columns=cols)


def _blanks(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` with its missing float values as None, which the markdown table shows blank (a
    record's None, e.g. the root's angular momentum jump once hinge 0 is held, is read back
    from events.csv as nan)."""
    out = df.copy()
    for col in out.columns:
        if pd.api.types.is_float_dtype(out[col]) and out[col].isna().any():
            out[col] = out[col].astype(object).where(out[col].notna(), None)
    return out


#: What the Deployment section's events table holds, in words.
EVENTS_TEXT = (
    "Every recorded event (`events.csv`): lock time t (s); the lock impulse (N m s, on the "
    "outboard rod, counter-clockwise positive), one definition in every model: the latch "
    "reaction's impulse, instantaneous part included, averaged over the lock window of "
    "`impulse_window` s after the lock (the first bending period of the locked segment, the "
    "rods joined through held hinges, unless the scene sets it; `window_closed` false: the "
    "run ended inside it); `rigid_impulse`, the plastic lock of rigid rods with the model's "
    "chord angles and rates just before the lock (`rodval.mechanics.rigid`), and "
    "`impulse_to_rigid`, their ratio (1 in the rigid-panel limit); the kinetic energy just "
    "before and just after the lock's instantaneous part and their difference (J: the full "
    "model's tangent impact takes out little, the reduced model's chord impact the whole "
    "rigid-panel loss, exudyn's is taken two steps after the lock); the energy dissipated "
    "from just before the lock to the window's end (instantaneous losses and dampers) and the "
    "residual of that window's energy balance (J: exudyn's is its integrator's numerical "
    "dissipation; the kinetic, hinge and bending parts are in `events.csv`); the jump of the "
    "angular momentum about the root through the lock (N m s; an internal impulse leaves it "
    "unchanged while hinge 0 is free; blank once hinge 0 is held, where the ground's or the "
    "base's holding moment makes it meaningless). docs/deployment.md defines each.\n"
)


def _deployment_section(
    fig_dir: Path,
    meta: dict[str, Any],
    tables: dict[str, pd.DataFrame],
    events: pd.DataFrame,
    constants: dict[str, Any],
) -> list[str]:
    """The Deployment section when runs recorded events (``events``): the events, the lock
    discrepancies against the reference, peak hinge moments, residual vibration after the
    last lock, and the report cases' deployment figures (markdown lines); a sampled study's
    gives their distributions instead (``sample_events_section``). ``constants``: the
    columns left out of every table (``study_constants``)."""
    if events.empty:
        return []
    if meta.get("sample"):
        return sample_events_section(meta, tables, events)
    keep = _keep(constants)
    shown = events[[c for c in EVENT_REPORT_COLUMNS if c in events]]
    lines = [
        "## Deployment: locks, impulses and residual vibration\n",
        EVENTS_TEXT,
        to_markdown(_blanks(keep(shown)), ".5g"),
    ]
    silent = [m["label"] for m in meta["models"] if not (events["model"] == m["label"]).any()]
    if silent:
        lines.append(
            "No events from " + ", ".join(f"`{s}`" for s in silent) + ": those runs did not "
            "latch (a model without latch support ignores the scene's latches).\n"
        )
    lines += _discrepancy_lines(event_discrepancies(events, meta["reference"]), meta, keep)
    lines += peak_moment_lines(tables, events, meta["models"], keep)
    lines += _residual_lines(tables, events, keep)
    return [*lines, *deployment_figures(fig_dir, meta, tables, events)]


def _discrepancy_lines(
    disc: pd.DataFrame, meta: dict[str, Any], keep: Callable[[pd.DataFrame], pd.DataFrame]
) -> list[str]:
    """The lock discrepancies against the reference (``event_discrepancies``) as markdown
    lines, with when a lock is compared pointwise; none without any."""
    if disc.empty:
        return []
    return [
        f"Lock discrepancies against `{meta['reference']}` (dt in s, impulse_rel = |dS| / "
        "|S_ref| of the lock impulses, rigid_rel = the same of the rigid-panel impulses; "
        "dE_lost in J, of different quantities, see above). A lock is compared pointwise "
        "only when the models reach it in the same state: every earlier lock within "
        f"{COMPARABLE_DT_S * 1e3:g} ms of the reference's and the kinetic plus bending "
        f"energy before it within {COMPARABLE_ENERGY:.0%}, and neither lock grazing (its "
        f"rigid-panel lock taking less than {GRAZING_LOSS:.0%} of the kinetic energy: the "
        "hinge creeps onto the latch angle, and its time hangs on small differences of "
        "state), neither lock's window overlapping another lock of its run (the windowed "
        "impulses are not separable) and neither an exudyn window of fewer than "
        f"{MIN_WINDOW_STEPS} steps of its fixed step; `not_comparable` says why otherwise: "
        "the two runs reach that lock in different states, so its pointwise gap adds up the "
        "earlier differences. Whether such a gap is a model's error or the motion's own "
        "sensitivity is measured, not assumed: the Answer above compares it with the "
        "reference's twin run when the study has one:\n",
        to_markdown(keep(disc), ".3g"),
    ]


def _residual_lines(
    tables: dict[str, pd.DataFrame],
    events: pd.DataFrame,
    keep: Callable[[pd.DataFrame], pd.DataFrame],
) -> list[str]:
    """The residual vibration after the last lock (``residual_vibration``) as markdown lines;
    none when no run locked."""
    resid = residual_vibration(tables["trajectories"], events, tables["cases"])
    if resid.empty:
        return []
    never = (
        "; `never_locked`: the latches that did not lock within the run, which is then not "
        "deployed: its motion after the last lock is a partly folded structure's, not a "
        "deployed one's residual vibration"
    )
    return [
        "Residual vibration after the last lock (tip y amplitude and mean in m, largest "
        "|alpha|, |beta| in rad, spread of the chord angles at the end in rad"
        + (never if "never_locked" in resid else "")
        + "):\n",
        to_markdown(keep(resid), ".4g"),
    ]


def peak_moment_lines(
    tables: dict[str, pd.DataFrame],
    events: pd.DataFrame,
    models: list[dict[str, Any]],
    keep: Any,
) -> list[str]:
    """The peak hinge moments' table (``peak_hinge_moments`` of the study's trajectories and
    runtime ``tables``) as markdown lines; none when no model recorded a hinge moment."""
    traj = tables["trajectories"]
    peaks = peak_hinge_moments(traj, events, models, tables.get("runtime"))
    if peaks.empty:
        return []
    lines = [
        "Peak hinge moments (N m): `peak_moment` is each run's largest |hinge_moment|, at "
        "`t_peak` (s), read between the output times as `source` says (the native models on "
        "their dense output: a fixed grid of [0, t_end] and the lock windows; exudyn on every "
        "recorded step), so the same run gives the same peak whatever its output times; "
        "`source` `hinge_moment`: over the output times only (a run that recorded no peak); "
        "a hinge whose moment is an impulse at its lock (an ideal latch on rigid chords: the "
        "reduced and rigid models) has no finite peak: `impulse` gives the lock's (N m s); "
        "`window_peak` over every step of a lock window where the model's lock records carry "
        "it:\n",
        to_markdown(_blanks(keep(peaks)), ".4g"),
    ]
    recorded = set(traj.loc[traj["quantity"] == "hinge_moment", "model"])
    unrecorded = [
        m["label"]
        for m in models
        if models_with("hinge_moment", [m["model"]]) and m["label"] not in recorded
    ]
    if unrecorded:
        lines.append(
            "Without `hinge_moment` among the [scene] outputs the peaks of "
            + ", ".join(f"`{label}`" for label in unrecorded)
            + " are not recorded: add it there to compare every model's.\n"
        )
    return lines


def _keep(constants: dict[str, Any]) -> Callable[[pd.DataFrame], pd.DataFrame]:
    """A function that drops the study's constant columns from a table."""
    return lambda df: drop_study_constants(df, constants)


def _error_budget_section(
    out: Path, meta: dict[str, Any], tables: dict[str, pd.DataFrame]
) -> list[str]:
    """The Error budget section and ``out/error_budget.csv``, ``.md`` when the study runs the
    rungs the split needs (``rodval.report.error_budget``); nothing otherwise (and a stale
    budget of an earlier report of the folder is removed)."""
    budget = error_budget(tables["discrepancies"], meta, tables["runtime"])
    files = [out / f"{ERROR_BUDGET}.{ext}" for ext in ("csv", "md")]
    if budget is None:
        for path in files:
            path.unlink(missing_ok=True)
        return []
    write_file(files[0], budget.to_csv(index=False))
    table = to_markdown(_blanks(budget), ".3g")
    write_file(files[1], table)
    p_max = int(budget["p_max"].iloc[0])
    ref = meta["reference"]
    return [
        "## Error budget of the model ladder\n",
        f"Each case group's gap to `{ref}` (the Discrepancies' `max_abs` of each rung of the "
        "full model, over all output times and rods, in the quantity's unit) split into "
        'parts (docs/model.md, "The model ladder"): `kinematics` = gap(first-order, p = 1) '
        "- gap(exact, p = 1), what the paper's first-order kinematics costs; `shapes` = "
        f"gap(exact, 1) - gap(exact, {p_max}), what one cubic shape per rod costs; `base` = "
        f"gap(exact, {p_max}) - the same gap of the pinned case, what a free base adds, when "
        "the study varies the base kind (else blank, `base_note` says why); `remainder` = "
        f"gap(exact, {p_max}) - base: the reference's own discretization error and what no "
        "rung carries (the inextensible chord). The parts add up to the paper rung's gap; a "
        "negative part means the rungs' errors cancel (a rung closer to the reference "
        "because its error offsets another), not that relaxing an assumption hurts. Also "
        f"`{ERROR_BUDGET}.csv` and `{ERROR_BUDGET}.md`.\n",
        table,
    ]


def model_row(m: dict[str, Any]) -> dict[str, Any]:
    """A study model's row of the report's Models table: its options as the model runs them
    (defaults included: the full model's kinematics and shapes, exudyn's step) and every
    integrator setting that changes what runs (``rodval.core.trajectory.RUN_SETTINGS``: the
    method, tolerances, steps, error control); "n/a" for a model that integrates itself
    (exudyn: the study's [integrator] does not apply, its own step does)."""
    try:
        options = get_model(m["model"], **m["options"]).options()
        uses = uses_integrator(m["model"])
    except ValueError:  # the model is not available here: what the study gave
        options, uses = m["options"], True
    settings = m["settings"]
    return {
        "label": m["label"],
        "model": m["model"],
        "options": json.dumps(options) if options else "",
        **{k: _setting(settings.get(k)) if uses else "n/a" for k in RUN_SETTINGS},
    }


def _setting(value: Any) -> Any:
    """A setting as the Models table shows it: None (the integrator chooses, e.g. the first
    step) blank."""
    return "" if value is None else value


def study_file(meta: dict[str, Any]) -> str:
    """The study file's path relative to the study folder (where report.md lies), as the
    study recorded it when it ran (``source_path``); the name it was given when it recorded
    none (a study built in Python, or an older study.json)."""
    return str(meta.get("source_path") or meta["source"])


def _design(meta: dict[str, Any]) -> str:
    """The grid (its axes and values) or the sample (its count and keys) in a few words."""
    sample = meta.get("sample")
    if sample:
        keys = ", ".join(f"`{k}`" for k in sample["keys"])
        return f"Sample: {sample['count']} cases ({sample['design']}) of {keys}"
    axes = "; ".join(f"`{p}` = {v}" for p, v in meta["axes"].items()) or "none (one case)"
    return f"Grid: {axes}"


def _header(meta: dict[str, Any], prov: dict[str, Any], constants: dict[str, Any]) -> list[str]:
    """The report's description, study file (relative to the study folder), grid or
    sample, reference, the columns constant over the study (``constants``), the Models table
    and the machine and packages it ran on (``prov``: provenance.json)."""
    models = pd.DataFrame([model_row(m) for m in meta["models"]])
    mach = prov["machine"]
    pkgs = ", ".join(f"{k} {v}" for k, v in prov["packages"].items() if v)
    units = {"horizon": " s"}
    compared = len(meta["models"]) > 1  # one model: no reference to name
    same = ", ".join(
        f"{k} = {v:g}{units.get(k, '')}" if isinstance(v, float) else f"{k} = {v}"
        for k, v in constants.items()
        if k != "reference"
    )
    return [
        "## Study\n",
        f"{meta['description']}\n" if meta["description"] else "",
        f"Study file: `{study_file(meta)}` (copied to `study.toml`). {_design(meta)}."
        + (f" Reference model: `{meta['reference']}`." if compared else "")
        + (
            f" Left out of the tables as the same throughout: {same}"
            + (" and the reference." if compared else ".")
            if same
            else ""
        )
        + "\n",
        "Models:\n",
        to_markdown(models),
        f"Machine: {mach['processor']}, {mach['cpu_count']} cores, {mach['platform']}, "
        f"Python {mach['python']}. Packages: {pkgs}.\n",
    ]


def _read_json(path: Path, keys: tuple[str, ...]) -> dict[str, Any]:
    """A JSON object with ``keys``; ValueError naming the file otherwise."""
    if not path.is_file():
        raise ValueError(f"{path.parent} is not a study folder: {path.name} is missing")
    try:
        doc = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(unreadable(path, exc)) from None
    if not isinstance(doc, dict) or any(k not in doc for k in keys):
        missing = next((k for k in keys if not isinstance(doc, dict) or k not in doc), "")
        raise ValueError(f"{path}: key {missing!r} is missing")
    return doc


def build_report(out: str | Path) -> Path:
    """Write ``out/report.md`` and ``out/figures/`` from the saved tables; returns the path."""
    out = Path(out)
    meta: dict[str, Any] = _read_json(
        out / "study.json", ("name", "models", "reference", "labels", "axes", "report")
    )
    if not is_stamped(meta, STUDY_SCHEMA):
        raise ValueError(
            f"{out} is not a study folder of rodval: its study.json carries no rodval schema "
            "and checksum (another program's file, edited, or from an older rodval), so "
            "rodval report will not write report.md there"
        )
    prov = _read_json(out / "provenance.json", ("machine", "packages"))
    tables = read_tables(out)
    params = ["n", "horizon", *axis_columns(meta).values()]
    fig_dir = out / FIGURES
    fig_dir.mkdir(exist_ok=True)
    events = read_events(out)
    constants = study_constants(tables["cases"], meta["reference"])
    peaks = peak_hinge_moments(tables["trajectories"], events, meta["models"], tables["runtime"])
    lines = [f"# Study `{meta['name']}`\n", *opening_section(meta, tables, events, peaks)]
    lines += _header(meta, prov, constants)
    lines += acceptance_section(meta, tables, events)
    lines += summary_sections(meta, tables, params, constants)
    lines += _error_budget_section(out, meta, tables)
    figs = param_figures(fig_dir, meta, tables, params)
    if figs:
        lines += ["## Discrepancy, run time and speed-up against the grid parameters\n", *figs]
    lines += sample_section(meta, tables, events)
    lines += sensitivity_section(fig_dir, meta, tables, events, peaks)
    lines += _deployment_section(fig_dir, meta, tables, events, constants)
    lines += modes_section(out, fig_dir, meta)
    lines += ["## Time histories and configurations\n", *case_figures(fig_dir, meta, tables)]
    path = out / "report.md"
    write_file(path, "\n".join(x for x in lines if x))
    return path
