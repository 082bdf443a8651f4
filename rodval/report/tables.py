"""The study tables as the report reads them: their names, the columns a grid axis becomes,
checked reading of the CSV files, and the Table-1-like sample of values at report times.

The tables themselves are written by ``rodval.study.tables``; this module is what a reader of
a study folder needs (the report, ``rodval report``), so it lies below the study layer.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from rodval.analysis.metrics import METRICS
from rodval.core.checks import as_path

TABLES = ("cases", "trajectories", "discrepancies", "runtime")
#: The report's error budget (``rodval.report.error_budget``): ``error_budget.csv``, ``.md``.
ERROR_BUDGET = "error_budget"
#: Every table a study may write (``<name>.csv``, some also ``<name>.md``): the four above,
#: events and modes tables when runs record them, and the report's error budget
#: (``rodval.report.error_budget``) when the study runs the full model's ladder.
ALL_TABLES = (*TABLES, "events", "modes", "mac", "mode_shapes", ERROR_BUDGET)
#: The report's figure folder in a study folder (the PNG files report.md links).
FIGURES = "figures"
#: Columns each table must have (every column ``rodval.study.tables`` writes but the grid
#: axes, which depend on the study).
REQUIRED = {
    "cases": ("case", "n", "horizon", "l"),
    "trajectories": ("case", "model", "t", "quantity", "k", "value"),
    "discrepancies": tuple(
        "case n horizon model reference quantity max_abs rms final_abs max_rel status".split()
    ),
    "runtime": tuple(
        "case n horizon model method rtol atol wall_s setup_s nfev nsteps t_reached status "
        "message".split()
    ),
}
#: The tables' fixed columns: a grid axis labelled like one keeps its full path as its column.
FIXED = frozenset(
    [*(c for cols in REQUIRED.values() for c in cols), "max_step", "step", "njev", "nlu"]
    + ["fingerprint", *METRICS]
)


def unreadable(path: Path, exc: Exception) -> str:
    """ "<path>: unreadable (...)" in rodval's words, not Python's: a file that is not UTF-8
    text, not JSON (where the parse stopped), or not readable (the system's reason)."""
    if isinstance(exc, UnicodeDecodeError):
        why = f"not UTF-8 text: byte {exc.object[exc.start]:#04x} at position {exc.start}"
    elif isinstance(exc, json.JSONDecodeError):
        why = f"not JSON: {exc.msg} at line {exc.lineno}, column {exc.colno}"
    elif isinstance(exc, OSError):
        why = exc.strerror or type(exc).__name__
    else:
        why = str(exc) or type(exc).__name__
    return f"{path}: unreadable ({why})"


def _parse_error(exc: Exception) -> str:
    """Why pandas could not read a CSV file, in one line."""
    if isinstance(exc, UnicodeDecodeError):
        return f"byte {exc.start} is not UTF-8 text; the file is damaged or not a table the study wrote"
    first = str(exc).splitlines()[0] if str(exc) else ""
    return f"{type(exc).__name__}: {first}"


def axis_columns(meta: dict[str, Any]) -> dict[str, str]:
    """Case parameter label -> table column. scene.n and scene.t_end are the n and horizon
    columns already; a label clashing with a fixed column keeps its full grid path."""
    cols = {}
    for path, label in meta["labels"].items():
        if path in ("scene.n", "scene.t_end"):
            continue
        cols[label] = path if label in FIXED else label
    return cols


def read_tables(out: str | Path) -> dict[str, pd.DataFrame]:
    """The study tables in the folder ``out`` (str or Path), checked: every file present,
    readable as CSV and with the columns the report needs, consistent (cases, complete
    trajectories, a value of each metric for every comparison made) and the very files the
    study wrote (``MANIFEST``). ValueError naming the file and what is wrong otherwise."""
    out = as_path("out", out)
    tables = {}
    for name in TABLES:
        path = out / f"{name}.csv"
        if not path.is_file():
            raise ValueError(
                f"{out} is not a complete study folder: {path.name} is missing "
                "(run `rodval study FILE --out DIR` first)"
            )
        try:
            df = pd.read_csv(path)
        except (pd.errors.ParserError, pd.errors.EmptyDataError, ValueError) as exc:
            raise ValueError(_unparsed(out, name, exc)) from None
        missing = [c for c in REQUIRED[name] if c not in df.columns]
        if missing:
            raise ValueError(
                f"{path}: column {missing[0]!r} is missing (needed: {', '.join(REQUIRED[name])})"
            )
        if df.empty:  # a header only (e.g. no model pairs): typed, nothing to check
            df = df.astype({col: float for col in NUMERIC.get(name, ())})
        for col in NUMERIC.get(name, ()):
            if not pd.api.types.is_numeric_dtype(df[col]):
                bad = next((v for v in df[col] if pd.isna(pd.to_numeric(v, errors="coerce"))), None)
                raise ValueError(f"{path}: column {col!r} must hold numbers, got {bad!r}")
        if df["case"].isna().any():
            raise ValueError(f"{path}: a row has no case id")
        tables[name] = df
    cases = tables["cases"]
    if cases["case"].duplicated().any():
        dup = cases["case"][cases["case"].duplicated()].iloc[0]
        raise ValueError(f"{out / 'cases.csv'}: case {dup!r} is listed twice")
    known = set(cases["case"].astype(str))
    for name in ("runtime", "discrepancies", "trajectories"):
        unknown = sorted(set(tables[name]["case"].astype(str)) - known)
        if unknown:
            raise ValueError(f"{out / (name + '.csv')}: case {unknown[0]!r} is not in cases.csv")
    _check_trajectories(tables["trajectories"], out / "trajectories.csv")
    _check_compared(tables["discrepancies"], out / "discrepancies.csv")
    check_manifest(out)
    return tables


#: Beside the tables: each CSV table's size and SHA-256 as the study wrote it
#: (``rodval.study.tables.write_tables``), so that a truncated or edited table is refused.
MANIFEST = "tables.json"
#: The discrepancy metrics every comparison that was made (status "ok") has a value of
#: (max_rel may be NaN: a reference that is identically zero has no relative scale).
COMPARED = ("max_abs", "rms", "final_abs")


def table_digest(path: Path) -> dict[str, Any]:
    """A file's size (bytes) and SHA-256 (hex), as the manifest records them."""
    sha = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            sha.update(block)
    return {"bytes": path.stat().st_size, "sha256": sha.hexdigest()}


def _rewrite(out: Path) -> str:
    return f"run `rodval study FILE --out {out}` again to rewrite the tables from the case records"


def _written(out: Path) -> dict[str, tuple[int, str]]:
    """The manifest: table name -> (bytes, SHA-256) as the study wrote it; ValueError when it
    is missing or unreadable."""
    path = out / MANIFEST
    if not path.is_file():
        raise ValueError(
            f"{path} is missing, so the tables cannot be checked against what the study "
            f"wrote; {_rewrite(out)}"
        )
    try:
        manifest = json.loads(path.read_text())
        return {str(name): (int(e["bytes"]), str(e["sha256"])) for name, e in manifest.items()}
    except (OSError, UnicodeDecodeError, ValueError, TypeError, KeyError, AttributeError) as exc:
        raise ValueError(f"{unreadable(path, exc)}; {_rewrite(out)}") from None


def _damage(table: Path, size: int, sha: str) -> str:
    """How ``table`` differs from the file the study wrote (``size`` bytes, SHA-256 ``sha``):
    '' when it does not."""
    got = table_digest(table)
    if got["bytes"] != size:
        return f"{got['bytes']} bytes, the study wrote {size} (the file is truncated or was edited)"
    if got["sha256"] != sha:
        return "checksum mismatch with what the study wrote (the file was edited or damaged)"
    return ""


def check_manifest(out: Path) -> None:
    """Every table the manifest lists is the file the study wrote (same size and SHA-256);
    ValueError naming the file and what is wrong otherwise."""
    wrote = _written(out)
    missing = [name for name in TABLES if name not in wrote]
    if missing:
        raise ValueError(f"{out / MANIFEST}: table {missing[0]!r} is not listed; {_rewrite(out)}")
    for name, (size, sha) in wrote.items():
        table = out / f"{name}.csv"
        if not table.is_file():
            raise ValueError(f"{table} is missing (the study wrote it); {_rewrite(out)}")
        damage = _damage(table, size, sha)
        if damage:
            raise ValueError(f"{table}: {damage}; {_rewrite(out)}")


def _unparsed(out: Path, name: str, exc: Exception) -> str:
    """The one line for a table pandas could not read: why, and, when the manifest can tell,
    how the file differs from what the study wrote (where a cut lands decides the parser's
    complaint: inside a quoted message or between rows; the manifest's does not)."""
    path = out / f"{name}.csv"
    line = f"{path}: not a readable CSV table ({_parse_error(exc)})"
    try:
        wrote = _written(out)
    except ValueError:
        return line
    damage = _damage(path, *wrote[name]) if name in wrote else ""
    return f"{line}; {damage}; {_rewrite(out)}" if damage else line


def _check_compared(disc: pd.DataFrame, path: Path) -> None:
    """A comparison that was made (status "ok") has a value of each COMPARED metric; one
    that could not be made says why in its status."""
    made = disc[disc["status"] == "ok"]
    for col in COMPARED:
        bad = made[made[col].isna()]
        if not bad.empty:
            row = bad.iloc[0]
            raise ValueError(
                f"{path}: case {row['case']!r}, model {row['model']!r}, {row['quantity']}: "
                f"{col} is NaN although status is 'ok' (a comparison that could not be made "
                "says why in its status; the table was edited or damaged)"
            )


#: Columns that must be numeric in each table.
NUMERIC = {
    "cases": ("n", "horizon"),
    "trajectories": ("t", "k", "value"),
    "discrepancies": ("n", "horizon", "max_abs", "max_rel"),
    "runtime": ("n", "horizon", "wall_s", "setup_s", "nfev", "nsteps", "t_reached"),
}


def _check_trajectories(traj: pd.DataFrame, path: Path) -> None:
    """Every (case, model, quantity) of the trajectories table covers each of its output
    times at each of its k once (a truncated or edited table does not)."""
    keys = ["case", "model", "quantity"]
    if traj.duplicated(keys + ["t", "k"]).any():
        row = traj[traj.duplicated(keys + ["t", "k"])].iloc[0]
        raise ValueError(
            f"{path}: case {row['case']!r}, model {row['model']!r}, {row['quantity']}: "
            f"t = {row['t']:g}, k = {row['k']:g} appears twice"
        )
    grouped = traj.groupby(keys, sort=False).agg(
        rows=("value", "size"), nt=("t", "nunique"), nk=("k", "nunique")
    )
    short = grouped[grouped["rows"] != grouped["nt"] * grouped["nk"]]
    if not short.empty:
        (case, model, q), row = next(iter(short.iterrows()))
        raise ValueError(
            f"{path}: case {case!r}, model {model!r}, {q}: {row['rows']} values for "
            f"{row['nt']} output times x {row['nk']} values of k (the table is incomplete)"
        )
    runs = grouped.reset_index().groupby(["case", "model"], sort=False)["nt"].nunique()
    if (runs > 1).any():
        case, model = runs[runs > 1].index[0]
        raise ValueError(
            f"{path}: case {case!r}, model {model!r}: the output times differ between "
            "quantities (the table is incomplete)"
        )


def trajectory_samples(
    traj: pd.DataFrame, meta: dict[str, Any], cases: pd.DataFrame
) -> pd.DataFrame:
    """The report cases' values at the report times (nearest output time) for the report rods
    and quantities, one column per model: a small table like the paper's Table 1; a
    ``case`` column when the study has more than one case (``IDENTITY_COLUMNS``)."""
    rep = meta["report"]
    parts = []
    for cid in rep["cases"]:
        sub = traj[traj["case"] == cid]
        if sub.empty:
            continue
        horizon = float(cases.loc[cases["case"] == cid, "horizon"].iloc[0])
        rods = report_rods(rep, int(cases.loc[cases["case"] == cid, "n"].iloc[0]))
        snapped = snapped_times(sub, rep["times"], horizon, QUARTERS)
        pick = sub[
            sub["t"].isin(snapped) & sub["k"].isin(rods) & sub["quantity"].isin(rep["quantities"])
        ]
        wide = pick.pivot_table(
            index=["quantity", "k", "t"], columns="model", values="value", sort=False
        ).reset_index()
        if len(cases) > 1:
            wide.insert(0, "case", cid)
        parts.append(wide)
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()


#: The report times of a case whose [report] gives none: these fractions of its horizon.
QUARTERS = (0.25, 0.5, 0.75, 1.0)


def report_rods(rep: dict[str, Any], n: int) -> list[int]:
    """The rods the report (``rep``: study.json's ``report``) draws of a chain of ``n`` rods,
    "last" as n, in order, each once."""
    return sorted({n if r == "last" else int(r) for r in rep["rods"] if r == "last" or int(r) <= n})


def snapped_times(
    sub: pd.DataFrame, times: list[float] | None, horizon: float, fractions: Sequence[float]
) -> list[float]:
    """The output times of ``sub`` (rows of the trajectories table) nearest to the report's
    ``times`` (s; default: the ``fractions`` of the ``horizon``), those within the horizon,
    sorted and distinct."""
    out_t = np.unique(sub["t"].to_numpy())
    want = times or [horizon * f for f in fractions]
    return sorted({float(out_t[np.abs(out_t - t).argmin()]) for t in want if t <= horizon})


def read_events(out: Path) -> pd.DataFrame:
    """``out/events.csv`` (empty frame if the study recorded no events)."""
    path = out / "events.csv"
    if not path.is_file():
        return pd.DataFrame(columns=["case", "model", "t", "label"])
    try:
        events = pd.read_csv(path)
    except (OSError, ValueError, pd.errors.ParserError) as exc:
        raise ValueError(unreadable(path, exc)) from None
    missing = [c for c in ("case", "model", "t", "label") if c not in events]
    if missing:
        raise ValueError(f"{path}: column {missing[0]!r} is missing")
    return events


#: Columns that name a case or a comparison: a report table leaves out any of them that is
#: constant over it (``drop_constant``); the report states their values once.
IDENTITY_COLUMNS = ("case", "n", "horizon", "reference")


def drop_constant(df: pd.DataFrame, columns: tuple[str, ...] = IDENTITY_COLUMNS) -> pd.DataFrame:
    """``df`` without those of ``columns`` (identity columns by default) that hold one value
    over all of its rows (a table of one row keeps ``case`` only when the study has several
    cases: pass the columns to drop)."""
    drop = [c for c in columns if c in df.columns and len(df) and df[c].nunique(dropna=False) <= 1]
    return df.drop(columns=drop)


def study_constants(cases: pd.DataFrame, reference: str) -> dict[str, Any]:
    """The identity columns constant over the whole study (column -> its one value): case in
    a one-case study, n and horizon when no case changes them, and the reference."""
    out: dict[str, Any] = {}
    for col in ("case", "n", "horizon"):
        if col in cases and len(cases) and cases[col].nunique() == 1:
            out[col] = cases[col].iloc[0]
    out["reference"] = reference
    return out


def drop_study_constants(df: pd.DataFrame, constants: dict[str, Any]) -> pd.DataFrame:
    """``df`` without the columns constant over the whole study (``study_constants``)."""
    return df.drop(columns=[c for c in constants if c in df.columns])
