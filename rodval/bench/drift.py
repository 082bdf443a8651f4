"""Benchmarks that guard themselves: a fresh run of a benchmark against the table it recorded,
by ratios, naming each figure that drifted beyond the machine's noise (issue 50;
``benchmarks/drift_check.py``, docs/performance.md, "Drift").

Two kinds of figures are compared, each row matched by its ``keys`` columns:

* **ratios measured in one run** (e.g. ``speedup``: scipy's wall time over the default
  method's, the two runs side by side): machine speed cancels, so a ratio that moved by more
  than the factor ``noise`` (fresh / recorded outside [1 / noise, noise]) is a drift of the
  code, not of the machine; ``noise`` is the spread of the same ratio between runs of one
  commit on the machine (docs/performance.md states the one measured);
* **counts** (e.g. ``auto_nfev``: evaluations): deterministic for a given code path; a change
  beyond ``count_tol`` (relative) means the path changed (another method, step sequence or
  event handling), which is reported whatever its direction.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

#: The columns of ``drift_table``.
DRIFT_COLUMNS = ("figure", "recorded", "fresh", "factor", "verdict")


def drift_table(
    recorded: pd.DataFrame,
    fresh: pd.DataFrame,
    keys: Sequence[str],
    ratios: Sequence[str],
    counts: Sequence[str] = (),
    noise: float = 1.5,
    count_tol: float = 0.02,
) -> pd.DataFrame:
    """One row per key and compared column (the keys' columns, then DRIFT_COLUMNS): the
    recorded and fresh values, factor = fresh / recorded and the verdict: "slower" / "faster"
    (a ratio beyond ``noise``; "slower" when the fresh ratio is smaller), "changed" (a count
    beyond ``count_tol``), "within noise", "missing" (a recorded row the fresh run lacks).
    ``noise`` > 1, ``count_tol`` >= 0 (ValueError otherwise). O(rows)."""
    if not noise > 1:
        raise ValueError(f"noise must be a factor > 1, got {noise!r}")
    if not count_tol >= 0:
        raise ValueError(f"count_tol must be >= 0, got {count_tol!r}")
    keys = list(keys)
    rec = recorded.astype({k: str for k in keys}).set_index(keys)
    new = fresh.astype({k: str for k in keys}).set_index(keys)
    rows = []
    for key, row in rec.iterrows():
        key = key if isinstance(key, tuple) else (key,)
        for column, kind in [*((c, "ratio") for c in ratios), *((c, "count") for c in counts)]:
            old = float(row[column])
            now = float(new.loc[key, column]) if key in new.index else np.nan
            factor = now / old if old else np.nan
            rows.append(
                {
                    **dict(zip(keys, key)),
                    "figure": column,
                    "recorded": old,
                    "fresh": now,
                    "factor": factor,
                    "verdict": _verdict(kind, factor, noise, count_tol),
                }
            )
    return pd.DataFrame(rows, columns=[*keys, *DRIFT_COLUMNS])


def _verdict(kind: str, factor: float, noise: float, count_tol: float) -> str:
    """A figure's verdict from fresh / recorded (``drift_table``)."""
    if not np.isfinite(factor):
        return "missing"
    if kind == "count":
        return "changed" if abs(factor - 1.0) > count_tol else "within noise"
    if factor < 1.0 / noise:
        return "slower"
    if factor > noise:
        return "faster"
    return "within noise"


def drifted(table: pd.DataFrame) -> pd.DataFrame:
    """The rows of a ``drift_table`` whose verdict is not "within noise"."""
    return table[table["verdict"] != "within noise"]
