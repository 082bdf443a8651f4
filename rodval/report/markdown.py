"""The one markdown writer: GitHub pipe tables from pandas DataFrames."""

from __future__ import annotations

import pandas as pd


def to_markdown(df: pd.DataFrame, floatfmt: str = ".3g") -> str:
    """A GitHub pipe table ("|" inside cells escaped, None blank); ``_(no rows)_`` for an
    empty frame."""
    if df.empty:
        return "_(no rows)_\n"
    safe = df.copy()
    for col in safe.columns:
        if safe[col].dtype == object or pd.api.types.is_string_dtype(safe[col]):
            safe[col] = pd.Series(
                [str(v).replace("|", "\\|") if isinstance(v, str) else v for v in safe[col]],
                index=safe.index,
                dtype=object,
            )
    # None (a value that does not apply) is shown blank
    text: str = safe.to_markdown(index=False, tablefmt="pipe", floatfmt=floatfmt, missingval="")
    return text + "\n"
