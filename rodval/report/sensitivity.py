"""Sensitivity of a study's design quantities to its parameters (issue 58): first-order and
total Sobol indices (SALib), and each quantity against each parameter.

Definitions. For a quantity Y = f(X_1, ..., X_D) of D independent parameters X_i (a
``[sample]``'s keys, each with its distribution), the first-order index S1_i = Var(E[Y | X_i])
/ Var(Y) is the share of Var(Y) that X_i explains alone, the total index ST_i = E[Var(Y |
X_~i)] / Var(Y) its share with every interaction it takes part in (dimensionless); 0 <= S1_i
<= ST_i <= 1 and sum_i S1_i <= 1, = 1 for an additive f. They are estimated by SALib
(``SALib.analyze.sobol``: the estimators of Saltelli et al. 2010) on SALib's own scheme
(``SALib.sample.sobol``, Saltelli's extension of a scrambled Sobol' sequence, without second
order): N base samples, each a block of D + 2 consecutive cases (A, A with its column i taken
from B for i = 1..D, B), so ``count = N (D + 2)`` with N a power of 2 (``saltelli_count_error``:
the rule, checked when the study file is read). Each index has the half-width of its
``CONF_LEVEL`` confidence interval from SALib's bootstrap over the base samples (``RESAMPLES``
resamples).

The quantities of interest are the report's design quantities (``DESIGN_QUANTITIES``, one
entry each): lock time and lock impulse per latched hinge, peak hinge moment per hinge, the
base's final attitude where it is free. A run that failed (runtime.csv's status) or lacks a
value (a latch that never locked) leaves out its base sample's whole block; indices over fewer than
``MIN_BASE_SAMPLES`` base samples, or of a quantity constant over them, are refused with the
reason, never computed wrong.

Pure functions on arrays and frames (no I/O) but the two at the end: ``plot_against`` (the
scatter figures, drawn on ``matplotlib.figure.Figure`` as ``rodval.report.figures`` does) and
``sensitivity_section`` (the report's section).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rodval.analysis.agreement import locked_hinges
from rodval.analysis.events import is_lock
from rodval.core.status import STATUS_MESSAGES
from rodval.report.markdown import to_markdown
from rodval.report.tables import axis_columns

#: The design's name, as SALib names its scheme (``SALib.sample.saltelli``, now ``sobol``).
SALTELLI = "saltelli"
#: Fewest base samples the indices are computed over: SALib's bootstrap resamples the N base
#: samples with replacement, and below 8 its interval rests on a handful of distinct resamples
#: (the count rule asks at least this many too, so only failed runs can take a study below it).
MIN_BASE_SAMPLES = 8
#: Confidence level of the bootstrap intervals and the number of bootstrap resamples (the
#: half-width's own relative error is about 1 / sqrt(2 RESAMPLES) = 2 %).
CONF_LEVEL = 0.95
RESAMPLES = 1000
SUCCESS = STATUS_MESSAGES[0]


def block_size(dims: int) -> int:
    """Cases per base sample of Saltelli's scheme without second order: D + 2."""
    return dims + 2


def saltelli_count_error(count: int, dims: int) -> str:
    """Why ``count`` cases are not a Saltelli design of ``dims`` parameters ("" when they
    are): count = N (D + 2), N a power of 2 >= MIN_BASE_SAMPLES."""
    b, n = block_size(dims), count // block_size(dims)
    if count % b == 0 and n >= MIN_BASE_SAMPLES and not n & (n - 1):
        return ""
    low = max(MIN_BASE_SAMPLES, 1 << max(n.bit_length() - 1, 0))
    near = sorted({low * b, 2 * low * b} if low * b != count else {2 * low * b})
    return (
        f"design = 'saltelli' needs count = N (D + 2) = N x {b} (D = {dims} keys) with N a "
        f"power of 2 >= {MIN_BASE_SAMPLES}, got {count}; use " + " or ".join(str(c) for c in near)
    )


def saltelli_unit_design(count: int, dims: int, seed: int) -> np.ndarray:
    """(count, dims) points of [0, 1)^dims in Saltelli's scheme (``SALib.sample.sobol``,
    scrambled, seeded; blocks of D + 2 rows), for a count ``saltelli_count_error`` accepts."""
    from SALib.sample import sobol as salib_sample

    problem = {"num_vars": dims, "names": [f"x{i}" for i in range(dims)], "bounds": [[0, 1]] * dims}
    n = count // block_size(dims)
    points: np.ndarray = salib_sample.sample(problem, n, calc_second_order=False, seed=seed)
    return points


def complete_blocks(y: np.ndarray, dims: int) -> tuple[np.ndarray, int]:
    """``y`` (values in the scheme's order, NaN where a run failed or has no value) without
    the blocks that hold a NaN, and how many blocks were left out. ValueError when ``y`` is
    not a whole number of blocks (the scheme's cases are not all there)."""
    b = block_size(dims)
    if y.size % b:
        raise ValueError(
            f"{y.size} values are not whole blocks of D + 2 = {b} (the Saltelli scheme's "
            "cases are not all there)"
        )
    blocks = y.reshape(-1, b)
    keep = np.isfinite(blocks).all(axis=1)
    return blocks[keep].ravel(), int((~keep).sum())


def sobol_indices(y: np.ndarray, names: Sequence[str], seed: int) -> pd.DataFrame:
    """First-order and total Sobol indices of ``y`` (finite values in the Saltelli scheme's
    order, whole blocks of D + 2 = len(names) + 2) against each parameter of ``names``: one
    row each with S1, S1_conf, ST, ST_conf (dimensionless; ``_conf`` the CONF_LEVEL
    half-width of SALib's bootstrap, seeded by ``seed`` >= 0). ValueError with the reason
    when they cannot be computed: not whole blocks, fewer than MIN_BASE_SAMPLES base samples,
    a non-finite value, or ``y`` constant (Var(Y) = 0: the indices are 0 / 0)."""
    from SALib.analyze import sobol as salib_analyze

    dims = len(names)
    b = block_size(dims)
    if y.size % b:
        raise ValueError(f"{y.size} values are not whole blocks of D + 2 = {b}")
    n = y.size // b
    if n < MIN_BASE_SAMPLES:
        raise ValueError(f"{n} base samples, fewer than the {MIN_BASE_SAMPLES} the indices need")
    if not np.isfinite(y).all():
        raise ValueError("a value is not finite (leave its block out: complete_blocks)")
    if np.ptp(y) == 0:
        raise ValueError(f"constant over the {n} base samples (Var = 0: no index is defined)")
    problem = {"num_vars": dims, "names": list(names), "bounds": [[0, 1]] * dims}
    # SALib draws unseeded resamples for seed 0 (``if seed:``): seed + 1 keeps them repeatable
    si = salib_analyze.analyze(
        problem,
        np.asarray(y, float),
        calc_second_order=False,
        num_resamples=RESAMPLES,
        conf_level=CONF_LEVEL,
        seed=seed + 1,
    )
    return pd.DataFrame(
        {
            "parameter": list(names),
            "S1": si["S1"],
            "S1_conf": si["S1_conf"],
            "ST": si["ST"],
            "ST_conf": si["ST_conf"],
        }
    )


# --- the design quantities: one entry of DESIGN_QUANTITIES each ---------------------------

#: Columns of every quantity reader's frame (value in the quantity's unit).
VALUE_COLUMNS = ["case", "model", "k", "value"]


def _frame(rows: list[dict[str, Any]]) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=VALUE_COLUMNS)


def _values(rows: pd.DataFrame, k: str, value: str) -> pd.DataFrame:
    """A reader's frame (``VALUE_COLUMNS``) of ``rows``: its case (as text) and model, its
    column ``k`` as k and ``value`` as the value."""
    return pd.DataFrame(
        {
            "case": rows["case"].astype(str),
            "model": rows["model"],
            "k": rows[k].astype(int),
            "value": rows[value].astype(float),
        }
    )


def lock_times(t: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """Each run's first lock time of each hinge (s), from events.csv's lock labels."""
    ev = t["events"]
    rows: dict[tuple[str, str, int], float] = {}
    for case, model, label, time in zip(ev["case"], ev["model"], ev["label"], ev["t"]):
        for h in locked_hinges(str(label)):
            rows.setdefault((str(case), str(model), h), float(time))
    return _frame([{"case": c, "model": m, "k": h, "value": v} for (c, m, h), v in rows.items()])


def lock_impulses(t: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """Each run's lock impulse of each hinge at its first lock (N m s, events.csv's
    ``impulse``: the lock window's, docs/deployment.md)."""
    ev = t["events"]
    if "impulse" not in ev or "hinge" not in ev or ev.empty:
        return _frame([])
    locks = ev[ev["label"].map(is_lock).to_numpy(bool)].sort_values("t", kind="stable")
    return _values(locks.drop_duplicates(["case", "model", "hinge"]), "hinge", "impulse")


def peak_moments(t: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """Each run's largest |hinge moment| per hinge (N m): the report's peak table (``peaks``:
    runtime.csv's recorded peak, else the output times' maximum, as its ``source`` says;
    blank for a hinge whose moment is an impulse at its lock)."""
    p = t["peaks"]
    return _frame([]) if p.empty else _values(p, "hinge", "peak_moment")


def final_attitude(t: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """The deployed attitude of a free base: base_attitude at the run's last output time
    (rad), for the cases whose base is free (cases.csv's base_kind)."""
    cases, traj = t["cases"], t["trajectories"]
    if "base_kind" not in cases:
        return _frame([])
    free = set(cases.loc[cases["base_kind"] == "free", "case"].astype(str))
    att = traj[(traj["quantity"] == "base_attitude") & traj["case"].astype(str).isin(free)]
    if att.empty:
        return _frame([])
    return _values(
        att[att["t"] == att.groupby(["case", "model"])["t"].transform("max")], "k", "value"
    )


@dataclass(frozen=True)
class DesignQuantity:
    """A design quantity: its name in the tables and figures, unit, definition and reader
    (the study's tables -> case, model, k, value)."""

    name: str
    unit: str
    definition: str
    read: Callable[[dict[str, pd.DataFrame]], pd.DataFrame]


#: The design quantities, one entry each (the minimum clearance would be one more).
DESIGN_QUANTITIES = (
    DesignQuantity("t_lock", "s", "first lock time of hinge k", lock_times),
    DesignQuantity("impulse", "N m s", "lock impulse of hinge k at its first lock", lock_impulses),
    DesignQuantity("peak_moment", "N m", "largest |hinge moment| of hinge k", peak_moments),
    DesignQuantity("final_attitude", "rad", "a free base's attitude at t_end", final_attitude),
)


def design_values(t: dict[str, pd.DataFrame]) -> pd.DataFrame:
    """Every design quantity of every run: case, model, quantity, k, value (NaN for a run
    that did not succeed: runtime.csv's status). ``t``: the study tables (cases,
    trajectories, runtime) with ``events`` and ``peaks`` (the report's peak table)."""
    parts = [q.read(t).assign(quantity=q.name) for q in DESIGN_QUANTITIES]
    empty = _frame([]).assign(quantity=pd.Series(dtype=str))
    values = pd.concat([p for p in parts if not p.empty] or [empty], ignore_index=True)
    rt = t["runtime"][t["runtime"]["status"] != SUCCESS]
    failed = set(zip(rt["case"].astype(str), rt["model"]))
    bad = [(str(c), m) in failed for c, m in zip(values["case"], values["model"])]
    values.loc[bad, "value"] = np.nan
    return values[["case", "model", "quantity", "k", "value"]]


def _lost(y: np.ndarray, names: Sequence[str]) -> str:
    """The note " (k of N base samples left out)" on the blocks of ``y`` that hold a NaN."""
    b = block_size(len(names))
    lost = np.isnan(y[: y.size - y.size % b]).reshape(-1, b).any(axis=1)
    return f" ({lost.sum()} of {lost.size} base samples left out)" if lost.any() else ""


def indices_table(
    values: pd.DataFrame, cases: Sequence[str], names: Sequence[str], seed: int
) -> tuple[pd.DataFrame, list[str]]:
    """Sobol indices of every (model, quantity, k) of ``values`` (``design_values``) over the
    Saltelli scheme's ``cases`` (ids in the scheme's order) against ``names``: rows model,
    quantity, k, parameter, S1, S1_conf, ST, ST_conf, samples (base samples used), left_out
    (base samples left out: a failed run or no value); and one line per quantity whose
    indices were refused, with the reason."""
    rows, refused = [], []
    order = pd.Index([str(c) for c in cases])
    for (model, q, k), part in values.groupby(["model", "quantity", "k"], sort=False):
        y = pd.Series(part["value"].to_numpy(float), index=part["case"].astype(str))
        full = y.reindex(order).to_numpy(float)
        try:
            kept, left = complete_blocks(full, len(names))
            table = sobol_indices(kept, names, seed)
        except ValueError as exc:
            refused.append(f"`{model}` {q} k = {k}: not computed: {exc}{_lost(full, names)}")
            continue
        n = kept.size // block_size(len(names))
        for row in table.to_dict("records"):
            rows.append(
                {"model": model, "quantity": q, "k": k, **row, "samples": n, "left_out": left}
            )
    return pd.DataFrame(rows), refused


# --- the figures and the section ------------------------------------------------------------


def plot_against(wide: pd.DataFrame, x: str, columns: Sequence[str], path: Path) -> Path:
    """One panel per design quantity (``columns`` of ``wide``), its value in every run
    against the parameter ``x`` (a column of ``wide``), one colour per model (``model``);
    drawn on a ``matplotlib.figure.Figure`` and written as PNG (110 dpi) like every figure of
    ``rodval.report.figures``."""
    from matplotlib.figure import Figure

    from rodval.core.out_paths import write_figure
    from rodval.report.figures import model_styles

    styles = model_styles(list(dict.fromkeys(wide["model"].astype(str))))
    ncols = min(3, len(columns))
    nrows = -(-len(columns) // ncols)
    fig = Figure(figsize=(3.6 * ncols, 2.8 * nrows))
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    for ax, col in zip(axes, columns):
        for model, part in wide.groupby("model", sort=False):
            ax.scatter(part[x], part[col], s=9, color=styles[str(model)]["color"], label=model)
        ax.set_xlabel(x)
        ax.set_ylabel(col)
        ax.grid(alpha=0.3)
    for ax in axes[len(columns) :]:
        ax.set_visible(False)
    axes[0].legend(fontsize=7)
    fig.suptitle(f"design quantities against {x}")
    fig.tight_layout()
    write_figure(fig, path, dpi=110)
    return path


def quantity_columns(values: pd.DataFrame, cases: pd.DataFrame, params: list[str]) -> pd.DataFrame:
    """One row per case and model: the ``params`` columns of ``cases`` and one column per
    design quantity and k of ``values`` (``design_values``), named "t_lock_1, s"."""
    unit = {q.name: q.unit for q in DESIGN_QUANTITIES}
    named = values.assign(
        column=[f"{q}_{k}, {unit[q]}" for q, k in zip(values["quantity"], values["k"])]
    )
    wide = named.pivot_table(index=["case", "model"], columns="column", values="value", sort=False)
    return wide.reset_index().merge(cases[["case", *params]].astype({"case": str}), on="case")


def sensitivity_section(
    fig_dir: Path,
    meta: dict[str, Any],
    tables: dict[str, pd.DataFrame],
    events: pd.DataFrame,
    peaks: pd.DataFrame,
) -> list[str]:
    """The report's Sensitivity section (markdown lines; none without a varied parameter or a
    design quantity): for a Saltelli sample the Sobol indices of every design quantity,
    model and k against each sampled key (``indices_lines``); for any sample or grid the
    scatter figures of each quantity against each varied parameter, written to ``fig_dir``.
    ``peaks``: the report's peak hinge moments
    (``rodval.report.study_report.peak_hinge_moments``)."""
    # imported here, not at the top: reading a study file (sampling.py) needs no matplotlib
    from rodval.report.study_figures import axis_names, varying_params

    cases, sample = tables["cases"], meta.get("sample")
    labels = list(axis_columns(meta).values())
    params = varying_params(cases, labels if sample else ["n", "horizon", *labels])
    if not params:
        return []
    values = design_values({**tables, "events": events, "peaks": peaks})
    drawn = values.dropna(subset=["value"])
    if drawn.empty:
        return []
    lines = [
        "## Sensitivity of the design quantities\n",
        "Design quantities, per model and k (`rodval.report.sensitivity.DESIGN_QUANTITIES`): "
        + "; ".join(f"`{q.name}` ({q.unit}), {q.definition}" for q in DESIGN_QUANTITIES)
        + ".\n",
    ]
    if "source" in peaks and (peaks["source"] == "hinge_moment").any():
        lines.append(
            "Some runs recorded no peak (runtime.csv's `peaks`): their `peak_moment` is the "
            "largest |hinge_moment| over the output times only.\n"
        )
    if sample and sample["design"] == SALTELLI:
        lines += indices_lines(meta, tables, values)
    elif sample:
        lines.append(
            f'Sobol indices need SALib\'s scheme (`design = "{SALTELLI}"`, count = N (D + 2)); '
            f"this sample's design is `{sample['design']}`: the figures only.\n"
        )
    names = axis_names(meta)
    wide = quantity_columns(drawn, cases, params)
    columns = [c for c in wide.columns if c not in ("case", "model", *params)]
    for x in params:
        shown = names.get(x, x)
        path = fig_dir / f"sensitivity_vs_{shown.replace('*', 'all')}.png"
        plot_against(wide.rename(columns={x: shown}), shown, columns, path)
        lines.append(f"![design quantities against {shown}](figures/{path.name})\n")
    return lines


def indices_lines(
    meta: dict[str, Any], tables: dict[str, pd.DataFrame], values: pd.DataFrame
) -> list[str]:
    """A Saltelli sample's Sobol indices (``indices_table`` of ``values``, in the order of
    cases.csv, which is the scheme's) as markdown lines, with the runs that failed and the
    quantities refused and why."""
    from rodval.report.study_figures import axis_names  # as in sensitivity_section

    sample, columns, shown = meta["sample"], axis_columns(meta), axis_names(meta)
    names = [shown.get(c, c) for c in (columns[meta["labels"][p]] for p in sample["keys"])]
    cases = tables["cases"]["case"].astype(str).tolist()
    table, refused = indices_table(values, cases, names, int(sample["seed"]))
    b = block_size(len(names))
    lines = [
        "First-order (`S1`) and total (`ST`) Sobol indices (SALib on Saltelli's scheme: "
        f"{len(cases) // b} base samples of {b} cases) of each quantity against each sampled "
        f"key; `_conf`: the half-width of the {CONF_LEVEL:.0%} interval of SALib's bootstrap "
        f"({RESAMPLES} resamples); `samples`: the base samples used, `left_out`: those left "
        "out (a run that failed or has no value, e.g. a latch that did not lock, takes out "
        "its whole block of cases).\n",
    ]
    for model, part in tables["runtime"].groupby("model", sort=False):
        failed = part[part["status"] != SUCCESS]
        if not failed.empty:
            lines.append(
                f"`{model}`: {len(failed)} of {len(part)} runs failed "
                f"({', '.join(sorted(set(failed['status'].astype(str))))}): their blocks are "
                "left out of the indices.\n"
            )
    if not table.empty:
        lines.append(to_markdown(table, ".3g"))
    if refused:
        lines.append("\n".join(f"- {r}" for r in refused) + "\n")
    return lines
