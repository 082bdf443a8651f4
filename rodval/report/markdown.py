"""The one markdown writer: GitHub pipe tables from pandas DataFrames."""

from __future__ import annotations

import pandas as pd


def to_markdown(df: pd.DataFrame, floatfmt: str = ".3g") -> str:
    """A GitHub pipe table ("|" inside cells escaped); ``_(no rows)_`` for an empty frame."""
    if df.empty:
        return "_(no rows)_\n"
    safe = df.copy()
    for col in safe.columns:
        if safe[col].dtype == object:
            safe[col] = safe[col].map(
                lambda v: str(v).replace("|", "\\|") if isinstance(v, str) else v
            )
    return safe.to_markdown(index=False, tablefmt="pipe", floatfmt=floatfmt) + "\n"
