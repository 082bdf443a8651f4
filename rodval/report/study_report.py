"""The study report: ``OUT/report.md`` and ``OUT/figures/*.png`` rebuilt from the saved tables
(``cases.csv``, ``trajectories.csv``, ``discrepancies.csv``, ``runtime.csv``, and
``events.csv`` when some run recorded events: the deployment section) and the study's
``study.json`` / ``provenance.json``; nothing is recomputed."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rodval.analysis.metrics import left_out_quantities
from rodval.core.modal import Modes
from rodval.core.trajectory import Trajectory
from rodval.core.validity import ENERGY_RESIDUAL_BOUND, SMALL_BENDING_RAD
from rodval.models import get_model
from rodval.models.registry import uses_integrator
from rodval.report.acceptance import acceptance_section
from rodval.report.figures import (
    plot_configurations,
    plot_deployment,
    plot_discrepancy_vs,
    plot_modes,
    plot_runtime_vs,
    plot_speedup_vs,
    plot_time_histories,
    speedups,
)
from rodval.report.markdown import to_markdown
from rodval.report.sample_stats import (
    PERCENTILES,
    discrepancy_percentiles,
    lock_statistics,
)
from rodval.report.tables import FIGURES, axis_columns, read_tables, trajectory_samples


def varying_params(cases: pd.DataFrame, params: list[str]) -> list[str]:
    """Case parameters with more than one value, all numeric and finite: the x axes of the
    figures (an axis such as max_step = [inf, 1e-7] has no place on a plot axis)."""
    return [
        p
        for p in params
        if pd.api.types.is_numeric_dtype(cases[p])
        and cases[p].nunique() > 1
        and np.isfinite(cases[p].to_numpy(float)).all()
    ]


def _case_figures(
    out: Path, fig_dir: Path, meta: dict, tables: dict[str, pd.DataFrame]
) -> list[str]:
    rep, lines = meta["report"], []
    traj, cases = tables["trajectories"], tables["cases"]
    labels = [m["label"] for m in meta["models"]]
    for cid in rep["cases"]:
        sub = traj[traj["case"] == cid]
        row = cases[cases["case"] == cid].iloc[0]
        n, horizon, l = int(row["n"]), float(row["horizon"]), np.asarray(json.loads(row["l"]))
        trajs = {
            lab: Trajectory.from_frame(sub[sub["model"] == lab], lab, cid)
            for lab in labels
            if (sub["model"] == lab).any()
        }
        lines.append(f"### Case `{cid}` (n = {n}, horizon = {horizon:g} s)\n")
        if not trajs:
            lines.append("_No model produced output for this case._\n")
            continue
        rods = sorted(
            {n if r == "last" else int(r) for r in rep["rods"] if r == "last" or int(r) <= n}
        )
        qs = [q for q in rep["quantities"] if (sub["quantity"] == q).any()]
        slug = cid.replace(",", "_").replace("=", "")
        hist = plot_time_histories(
            trajs, qs, rods, fig_dir / f"history_{slug}.png", title=f"case {cid}: all models"
        )
        lines.append(f"![time histories, case {cid}](figures/{hist.name})\n")
        if "phi" in qs or (sub["quantity"] == "phi").any():
            out_t = np.unique(sub["t"].to_numpy())
            want = rep["times"] or [horizon * f for f in (0.25, 0.5, 0.75, 1.0)]
            snapped = sorted(
                {float(out_t[np.abs(out_t - t).argmin()]) for t in want if t <= horizon}
            )
            conf = plot_configurations(
                trajs,
                snapped,
                l,
                fig_dir / f"configurations_{slug}.png",
                title=f"case {cid}: chain at t = " + ", ".join(f"{t:.4g}" for t in snapped) + " s",
            )
            lines.append(f"![configurations, case {cid}](figures/{conf.name})\n")
    samples = trajectory_samples(traj, meta, cases)
    if not samples.empty:
        lines += ["Values at the report times (rad, rad/s):\n", to_markdown(samples, ".6g")]
    return lines


def _stability_map(runtime: pd.DataFrame, params: list[str]) -> list[str]:
    """Case x model: how each run ended, its cost and (when audited) its energy residual."""

    def cell(row) -> str:
        text = f"{row['status']}, {row['wall_s']:.3g} s"
        if row["status"] != "success":
            text += f", t = {row['t_reached']:.3g} s"
        res = row.get("energy_residual")
        if res is not None and pd.notna(res):
            text += f", R = {res:.2g}"
        return text

    grid = runtime.assign(cell=runtime.apply(cell, axis=1)).pivot_table(
        index=["case", *params], columns="model", values="cell", aggfunc="first", sort=False
    )
    return [
        "## Stability map\n",
        "Each run: status, integration wall time, the time reached if it did not finish, "
        "and R = max |E - E(0) - W_ext + D| / max(E, |W_ext|), the energy balance "
        "residual (see docs/stability.md), when the scene asks for energy.\n",
        to_markdown(grid.reset_index()),
    ]


def left_out_table(traj: pd.DataFrame, reference: str) -> pd.DataFrame:
    """Per case and model: the quantities left out of its comparison with the reference
    because only one of the two runs outputs them (``left_out_quantities``), with why.
    Columns case, model, quantity, why. O(rows of the trajectories table)."""
    have = traj.groupby(["case", "model"], sort=False)["quantity"].unique()
    rows = []
    for (case, model), qs in have.items():
        if model == reference or (case, reference) not in have.index:
            continue
        ref_qs = have[(case, reference)]
        for q in left_out_quantities(qs, ref_qs):
            lacking = model if q in ref_qs else reference
            rows.append(
                {"case": case, "model": model, "quantity": q, "why": f"not output by {lacking}"}
            )
    return pd.DataFrame(rows, columns=["case", "model", "quantity", "why"])


def _summary_tables(meta: dict, tables: dict[str, pd.DataFrame], params: list[str]) -> list[str]:
    # a union of grids ([[grid]]) leaves some parameters unset in some cases
    disc, runtime = (
        tables[k].fillna({p: "-" for p in params}) for k in ("discrepancies", "runtime")
    )
    ref = meta["reference"]
    lines = []
    failed = runtime[runtime["status"] != "success"]
    invalid = runtime[runtime["valid"].astype(str) == "False"] if "valid" in runtime else failed[:0]
    left = left_out_table(tables["trajectories"], ref)
    not_made = disc[disc["status"] != "ok"]
    lines.append(
        f"## Outcome\n\n{runtime['case'].nunique()} cases, {len(runtime)} model runs, "
        f"{len(failed)} failed, {len(invalid)} invalid; "
        f"{(disc['status'] == 'ok').sum()} comparisons made (case, model, quantity), "
        f"{len(not_made) + len(left)} could not be made.\n"
    )
    reasons = pd.concat(
        [not_made[["status"]], pd.DataFrame({"status": left["why"]}) if len(left) else None]
    )
    if len(reasons):
        why = (
            reasons.groupby("status", sort=False)
            .size()
            .reset_index(name="comparisons")
            .rename(columns={"status": "reason"})
        )
        lines += ["Comparisons not made, by reason:\n", to_markdown(why)]
    if not failed.empty:
        lines += [
            "Failed runs:\n",
            to_markdown(failed[["case", "model", "status", "t_reached", "message"]]),
        ]
    lines.append(
        "Validity: a run is invalid when it broke an assumption of its model (small bending, "
        f"largest |alpha|, |beta| <= {SMALL_BENDING_RAD:g} rad, in the paper models; an "
        f"energy-audit residual <= {ENERGY_RESIDUAL_BOUND:g} where audited; see "
        "docs/stability.md), whether or not it reached its end; its results are not those of "
        "the model's premise." + (" Invalid runs:\n" if len(invalid) else "\n")
    )
    if len(invalid):
        lines.append(to_markdown(invalid[["case", "model", "status", "invalid_because"]]))
    lines.append(f"## Discrepancies against `{ref}`\n")
    if len(meta["models"]) == 1:
        lines.append(f"The study has one model (`{ref}`): nothing to compare.\n")
    else:
        lines.append(
            "Largest absolute difference over all output times and rods (`max_abs`; rad, "
            "rad/s) and the same relative to each reference rod's largest value "
            "(`max_rel`); see `discrepancies.csv` for rms, final value and where the "
            "maximum occurs.\n"
        )
    for model, part in disc.groupby("model", sort=False):
        ok = part[part["status"] == "ok"]
        lines.append(f"### `{model}` against `{ref}`\n")
        if ok.empty:
            lines.append(f"_No comparison: {part['status'].iloc[0]}._\n")
            continue
        mine = left[left["model"] == model] if len(left) else left
        if len(mine):
            names = ", ".join(
                f"`{q}` ({w})" for q, w in dict.fromkeys(zip(mine["quantity"], mine["why"]))
            )
            lines.append(
                f"_Left out of this comparison: {names}; the other quantities are compared._\n"
            )
        wide = ok.pivot_table(
            index=["case", *params], columns="quantity", values=["max_abs", "max_rel"], sort=False
        )
        wide.columns = [f"{q} {m}" for m, q in wide.columns]
        order = [f"{q} {m}" for q in dict.fromkeys(ok["quantity"]) for m in ("max_abs", "max_rel")]
        lines.append(to_markdown(wide[order].reset_index()))
    lines.append("## Run time\n")
    lines.append(
        "Integration wall time in s (without model set-up); speed-up = wall time of "
        f"`{ref}` / wall time of the model.\n"
    )
    ok = runtime[runtime["status"] == "success"]
    wall = ok.pivot_table(index=["case", *params], columns="model", values="wall_s", sort=False)
    speed = speedups(runtime, ref, params)
    if not speed.empty:
        sp = speed.pivot_table(
            index=["case", *params], columns="model", values="speedup", sort=False
        )
        wall = wall.join(sp.add_prefix("speed-up "))
    lines.append("Failed runs are left out.\n")
    lines.append(to_markdown(wall.reset_index()))
    if not failed.empty or (
        "energy_residual" in runtime and runtime["energy_residual"].notna().any()
    ):
        lines += _stability_map(runtime, params)
    return lines


def _param_figures(
    fig_dir: Path, meta: dict, tables: dict[str, pd.DataFrame], params: list[str]
) -> list[str]:
    labels = [m["label"] for m in meta["models"]]
    ref, lines = meta["reference"], []
    speed = speedups(tables["runtime"], ref, params)
    for x in varying_params(tables["cases"], params):
        others = [p for p in varying_params(tables["cases"], params) if p != x]
        logx = (
            x != "horizon"
            and tables["cases"][x].min() > 0
            and tables["cases"][x].max() / tables["cases"][x].min() >= 8
        )
        lines.append(f"### Against {x}\n")
        if not tables["discrepancies"].empty:
            d = plot_discrepancy_vs(
                tables["discrepancies"],
                x,
                others,
                labels,
                fig_dir / f"discrepancy_vs_{x}.png",
                logx=logx,
            )
            lines.append(f"![discrepancy against {x}](figures/{d.name})\n")
        r = plot_runtime_vs(
            tables["runtime"], x, others, labels, fig_dir / f"runtime_vs_{x}.png", logx=logx
        )
        lines.append(f"![run time against {x}](figures/{r.name})\n")
        if not speed.empty:
            s = plot_speedup_vs(
                speed, x, others, labels, ref, fig_dir / f"speedup_vs_{x}.png", logx=logx
            )
            lines.append(f"![speed-up against {x}](figures/{s.name})\n")
    return lines


#: Columns of the events table shown in the report, when present.
EVENT_REPORT_COLUMNS = (
    "case",
    "model",
    "label",
    "t",
    "angular_impulse",
    "kinetic_before",
    "kinetic_after",
    "energy_lost",
    "peak_moment",
    "lock_duration",
    "angular_momentum_root_jump",
)


def read_events(out: Path) -> pd.DataFrame:
    """``out/events.csv`` (empty frame if the study recorded no events)."""
    path = out / "events.csv"
    if not path.is_file():
        return pd.DataFrame(columns=["case", "model", "t", "label"])
    try:
        events = pd.read_csv(path)
    except (OSError, ValueError, pd.errors.ParserError) as exc:
        raise ValueError(f"{path}: unreadable ({type(exc).__name__}: {exc})") from None
    missing = [c for c in ("case", "model", "t", "label") if c not in events]
    if missing:
        raise ValueError(f"{path}: column {missing[0]!r} is missing")
    return events


def event_discrepancies(events: pd.DataFrame, reference: str) -> pd.DataFrame:
    """Each model's events against the reference's event of the same case and label: lock
    time difference dt (s, model - reference), angular impulse difference and its ratio to
    the reference's |impulse| (impulse_rel), energy_lost difference (J). Events the reference
    lacks (or the model lacks) are listed with blanks."""
    cols = ["case", "label", "model", "reference", "dt", "impulse_abs", "impulse_rel", "dE_lost"]
    if events.empty:
        return pd.DataFrame(columns=cols)
    ref = events[events["model"] == reference].set_index(["case", "label"])
    rows = []
    for _, ev in events[events["model"] != reference].iterrows():
        key = (ev["case"], ev["label"])
        row = {
            "case": ev["case"],
            "label": ev["label"],
            "model": ev["model"],
            "reference": reference,
        }
        if key in ref.index:
            r = ref.loc[key]
            r = r.iloc[0] if isinstance(r, pd.DataFrame) else r
            row["dt"] = float(ev["t"]) - float(r["t"])
            if "angular_impulse" in events:
                d = float(ev["angular_impulse"]) - float(r["angular_impulse"])
                row["impulse_abs"] = d
                row["impulse_rel"] = abs(d) / abs(float(r["angular_impulse"]))
            if "energy_lost" in events:
                row["dE_lost"] = float(ev["energy_lost"]) - float(r["energy_lost"])
        rows.append(row)
    return pd.DataFrame(rows).reindex(columns=cols)


def residual_vibration(
    traj: pd.DataFrame, events: pd.DataFrame, cases: pd.DataFrame
) -> pd.DataFrame:
    """Per case and model, after its last lock (t_last + lock_duration where recorded): the
    tip's y amplitude (max - min) / 2 and mean (m), the largest |alpha| and |beta| (rad), and
    the chord angles' spread max - min of phi over the rods at the last output time (rad, 0
    for a straight chain). Models without events are measured after the last lock of any
    model of the case."""
    rows = []
    for (case, model), part in traj.groupby(["case", "model"], sort=False):
        evs = events[events["case"] == case]
        own = evs[evs["model"] == model]
        use = own if not own.empty else evs
        if use.empty:
            continue
        ends = use["t"].astype(float)
        if "lock_duration" in use:
            ends = ends + use["lock_duration"].astype(float).fillna(0.0)
        t_last = float(ends.max())
        after = part[part["t"] > t_last]
        row = {"case": case, "model": model, "last_lock_end": t_last, "locks": len(own)}
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


def peak_hinge_moments(traj: pd.DataFrame, events: pd.DataFrame) -> pd.DataFrame:
    """Largest |hinge moment| (N m) per case, model and hinge: from the "hinge_moment"
    trajectories when recorded, else the events' peak_moment (the lock window's peak)."""
    hm = traj[traj["quantity"] == "hinge_moment"]
    if not hm.empty:
        g = hm.assign(abs_value=hm["value"].abs()).groupby(["case", "model", "k"], sort=False)
        out = g["abs_value"].max().reset_index().rename(columns={"k": "hinge"})
        return out.rename(columns={"abs_value": "peak_moment"}).assign(source="hinge_moment")
    if "peak_moment" in events and events["peak_moment"].notna().any():
        cols = ["case", "model", "hinge", "peak_moment"]
        part = events.dropna(subset=["peak_moment"])[[c for c in cols if c in events]]
        return part.assign(source="lock window")
    return pd.DataFrame()


def _deployment_section(
    out: Path, fig_dir: Path, meta: dict, tables: dict[str, pd.DataFrame]
) -> list[str]:
    events = read_events(out)
    if events.empty:
        return []
    ref, labels = meta["reference"], [m["label"] for m in meta["models"]]
    lines = [
        "## Deployment: locks, impulses and residual vibration\n",
        "Every recorded event (`events.csv`): lock time t (s), angular impulse of the latch "
        "(N m s, on the outboard rod, counter-clockwise positive), kinetic energy before and "
        "after the lock and their difference (J); exudyn adds the lock window's peak hinge "
        "moment (N m), its duration (s) and the jump of the angular momentum about the root "
        "through it (N m s; an internal impulse leaves it unchanged). See docs/deployment.md "
        "for how each model measures them.\n",
        to_markdown(events[[c for c in EVENT_REPORT_COLUMNS if c in events]], ".5g"),
    ]
    silent = [lab for lab in labels if not (events["model"] == lab).any()]
    if silent:
        lines.append(
            "No events from " + ", ".join(f"`{s}`" for s in silent) + ": those runs did not "
            "latch (a model without latch support ignores the scene's latches).\n"
        )
    disc = event_discrepancies(events, ref)
    if not disc.empty:
        lines += [
            f"Lock discrepancies against `{ref}` (dt in s, impulse_rel = |dS| / |S_ref|, "
            "dE_lost in J):\n",
            to_markdown(disc, ".3g"),
        ]
    peaks = peak_hinge_moments(tables["trajectories"], events)
    if not peaks.empty:
        lines += ["Peak hinge moments (N m):\n", to_markdown(peaks, ".4g")]
    resid = residual_vibration(tables["trajectories"], events, tables["cases"])
    if not resid.empty:
        lines += [
            "Residual vibration after the last lock (tip y amplitude and mean in m, largest "
            "|alpha|, |beta| in rad, spread of the chord angles at the end in rad):\n",
            to_markdown(resid, ".4g"),
        ]
    traj, cases = tables["trajectories"], tables["cases"]
    for cid in meta["report"]["cases"]:
        sub = traj[traj["case"] == cid]
        if sub.empty or not (sub["quantity"] == "phi").any():
            continue
        row = cases[cases["case"] == cid].iloc[0]
        l = np.asarray(json.loads(row["l"]))
        trajs = {
            lab: Trajectory.from_frame(sub[sub["model"] == lab], lab, cid)
            for lab in labels
            if (sub["model"] == lab).any()
        }
        out_t = np.unique(sub["t"].to_numpy())
        horizon = float(row["horizon"])
        want = meta["report"]["times"] or [horizon * f for f in (0.0, 0.25, 0.5, 0.75, 1.0)]
        snapped = sorted({float(out_t[np.abs(out_t - t).argmin()]) for t in want if t <= horizon})
        slug = cid.replace(",", "_").replace("=", "")
        fig = plot_deployment(
            trajs,
            events[events["case"] == cid],
            snapped,
            l,
            fig_dir / f"deployment_{slug}.png",
            title=f"case {cid}: deployment sequence and tip y (dotted: lock times)",
        )
        lines.append(f"![deployment, case {cid}](figures/{fig.name})\n")
    return lines


def _sample_section(out: Path, meta: dict, tables: dict[str, pd.DataFrame]) -> list[str]:
    """Percentiles over the samples of a ``[sample]`` study (``rodval.report.sample_stats``):
    latch locking and lock times when the scenes have latches, and the discrepancies."""
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
    locks = lock_statistics(tables["cases"], read_events(out), models)
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


def model_row(m: dict[str, Any]) -> dict[str, Any]:
    """A study model's row of the report's Models table: its options as the model runs them
    (defaults included) and the integrator settings that apply to it; "n/a" for a model that
    integrates itself (exudyn: the study's [integrator] does not apply, its own step does)."""
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
        **{k: settings[k] if uses else "n/a" for k in ("method", "rtol", "atol")},
    }


def _header(meta: dict, prov: dict) -> list[str]:
    models = pd.DataFrame([model_row(m) for m in meta["models"]])
    mach = prov["machine"]
    pkgs = ", ".join(f"{k} {v}" for k, v in prov["packages"].items() if v)
    axes = "; ".join(f"`{p}` = {v}" for p, v in meta["axes"].items()) or "none (one case)"
    return [
        f"# Study `{meta['name']}`\n",
        f"{meta['description']}\n" if meta["description"] else "",
        f"Study file: `{meta['source']}` (copied to `study.toml`). Grid: {axes}. "
        f"Reference model: `{meta['reference']}`.\n",
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
        raise ValueError(f"{path}: unreadable ({type(exc).__name__}: {exc})") from None
    if not isinstance(doc, dict) or any(k not in doc for k in keys):
        missing = next((k for k in keys if not isinstance(doc, dict) or k not in doc), "")
        raise ValueError(f"{path}: key {missing!r} is missing")
    return doc


def modes_from_tables(freq: pd.DataFrame, shapes: pd.DataFrame, case: str, model: str) -> Modes:
    """One model's modes of one case rebuilt from the modes and mode_shapes tables."""
    f = freq[(freq["case"] == case) & (freq["model"] == model)].sort_values("mode")
    sh = shapes[(shapes["case"] == case) & (shapes["model"] == model)]

    def arr(kind: str, mode: int) -> np.ndarray:
        part = sh[(sh["kind"] == kind) & (sh["mode"] == mode)].sort_values("k")
        return part["value"].to_numpy(float)

    x0, y0 = arr("node_x0", 0), arr("node_y0", 0)
    modes = [int(m) for m in f["mode"]]
    return Modes(
        model=model,
        about="",
        omega=f["omega_rad_s"].to_numpy(float),
        damping=f["damping_ratio"].to_numpy(float),
        dx=np.array([arr("node_dx", m) for m in modes]),
        dy=np.array([arr("node_dy", m) for m in modes]),
        hinge=np.array([arr("hinge", m) for m in modes]),
        phi0=np.arctan2(np.diff(y0), np.diff(x0)),
        l=np.hypot(np.diff(x0), np.diff(y0)),
    )


def _modes_section(out: Path, fig_dir: Path, meta: dict) -> list[str]:
    """Frequencies of every model, the MAC pairing against the reference and mode-shape
    figures of the report cases, when the study asked for modes ([modes])."""
    if not (out / "modes.csv").is_file():
        return []
    freq = pd.read_csv(out / "modes.csv")
    lines = [
        "## Modes\n",
        "Linearized natural frequencies (rad/s) of every model "
        "(`modes.csv`; damping ratios there), and each model's modes paired by shape with "
        f"`{meta['reference']}`'s (modal assurance criterion, `mac.csv`).\n",
    ]
    if "omega_rad_s" in freq:
        ok = freq[freq["omega_rad_s"].notna()]
        wide = ok.pivot_table(
            index=["case", "mode"], columns="model", values="omega_rad_s", sort=False
        )
        lines.append(to_markdown(wide.reset_index(), ".6g"))
    if "error" in freq and freq["error"].notna().any():
        failed = freq[freq["error"].notna()][["case", "model", "error"]]
        lines += ["Modal analyses that failed:\n", to_markdown(failed)]
    mac_path = out / "mac.csv"
    if mac_path.is_file() and mac_path.stat().st_size > 1:
        mac = pd.read_csv(mac_path)
        cols = [
            c
            for c in (
                "case",
                "model",
                "reference",
                "mode_a",
                "mode_b",
                "omega_a",
                "omega_b",
                "rel_gap",
                "mac",
            )
            if c in mac
        ]
        lines.append(to_markdown(mac[cols], ".4g"))
    shapes_path = out / "mode_shapes.csv"
    if shapes_path.is_file() and "omega_rad_s" in freq:
        shapes = pd.read_csv(shapes_path)
        for cid in meta["report"]["cases"]:
            have = set(freq[(freq["case"] == cid) & freq["omega_rad_s"].notna()]["model"])
            model = meta["reference"] if meta["reference"] in have else next(iter(have), None)
            if model is None:
                continue
            m = modes_from_tables(freq, shapes, cid, model)
            slug = cid.replace(",", "_").replace("=", "")
            fig = plot_modes(
                m, fig_dir / f"modes_{slug}.png", title=f"case {cid}: {model}, first modes"
            )
            lines.append(f"![mode shapes, case {cid}](figures/{fig.name})\n")
    return lines


def build_report(out: str | Path) -> Path:
    """Write ``out/report.md`` and ``out/figures/`` from the saved tables; returns the path."""
    out = Path(out)
    meta: dict[str, Any] = _read_json(
        out / "study.json", ("name", "models", "reference", "labels", "axes", "report")
    )
    prov = _read_json(out / "provenance.json", ("machine", "packages"))
    tables = read_tables(out)
    params = ["n", "horizon", *axis_columns(meta).values()]
    fig_dir = out / FIGURES
    fig_dir.mkdir(exist_ok=True)
    lines = _header(meta, prov)
    lines += acceptance_section(meta, tables)
    lines += _summary_tables(meta, tables, params)
    figs = _param_figures(fig_dir, meta, tables, params)
    if figs:
        lines += ["## Discrepancy, run time and speed-up against the grid parameters\n", *figs]
    lines += _sample_section(out, meta, tables)
    lines += _deployment_section(out, fig_dir, meta, tables)
    lines += _modes_section(out, fig_dir, meta)
    lines += ["## Time histories and configurations\n", *_case_figures(out, fig_dir, meta, tables)]
    path = out / "report.md"
    path.write_text("\n".join(x for x in lines if x))
    return path
