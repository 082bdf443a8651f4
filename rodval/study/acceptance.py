"""A study's acceptance criteria (the ``[acceptance]`` table): what makes ``rodval study`` and
``rodval report`` exit 1, so that a study gates a CI pipeline.

    [acceptance]
    valid = true                 # every model run must keep its model's assumptions
    [[acceptance.bound]]         # one table per model and quantity
    model = "reduced"            # a model label; the pair is (model, the study's reference)
    quantity = "phi"
    max_abs = 1e-3               # bounds on the discrepancies table's metrics (the
    rms = 2e-4                   # quantity's unit); at least one of them

A bound holds in a case when that pair's comparison of the quantity was made (status "ok")
and each bounded metric is at most its bound; a comparison that could not be made breaks the
bound (nothing passes by being absent). Checked when the study file is read: every key, the
model label (not the reference), the quantity among the cases' outputs, the bounds finite
numbers > 0. Evaluated by ``rodval.report.acceptance``.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

from rodval.core.checks import check_keys
from rodval.report.acceptance import BOUND_METRICS

ACCEPTANCE_KEYS = {"valid", "bound"}
BOUND_KEYS = {"model", "quantity", "max_abs", "rms"}


def acceptance_spec(
    table: Any, labels: list[str], reference: str, quantities: set[str], where: str
) -> dict[str, Any] | None:
    """The checked ``[acceptance]`` table as ``{"valid": bool, "bounds": [...]}`` (each bound
    a dict with model, quantity and its metrics), or None without the table. ValueError
    naming ``acceptance.<key>`` and what is allowed otherwise."""
    if table is None:
        return None

    def err(key: str, msg: str) -> ValueError:
        return ValueError(f"{where} key 'acceptance{key}': {msg}")

    if not isinstance(table, dict):
        raise err("", "must be a table")
    check_keys(table, ACCEPTANCE_KEYS, where, path="acceptance")
    valid = table.get("valid", False)
    if not isinstance(valid, bool):
        raise err(".valid", f"must be true or false, got {valid!r}")
    raw = table.get("bound", [])
    if not isinstance(raw, list) or not all(isinstance(b, dict) for b in raw):
        raise err(".bound", "must be an array of tables [[acceptance.bound]]")
    if not raw and not valid:
        raise err("", "has nothing to check: give valid = true or [[acceptance.bound]] tables")
    others = [lb for lb in labels if lb != reference]
    bounds = []
    for i, b in enumerate(raw):
        key = f".bound[{i}]"
        check_keys(b, BOUND_KEYS, where, path=f"acceptance{key}")
        if b.get("model") not in others:
            raise err(
                f"{key}.model",
                f"must be a model label other than the reference {reference!r} "
                f"(one of {others}), got {b.get('model')!r}",
            )
        if b.get("quantity") not in quantities:
            raise err(
                f"{key}.quantity",
                f"must be a quantity the cases output ({', '.join(sorted(quantities))}), "
                f"got {b.get('quantity')!r}",
            )
        limits = {m: b[m] for m in BOUND_METRICS if m in b}
        if not limits:
            raise err(key, f"needs at least one of {', '.join(BOUND_METRICS)}")
        for m, v in limits.items():
            if isinstance(v, bool) or not isinstance(v, numbers.Real) or v <= 0 or not v < math.inf:
                raise err(f"{key}.{m}", f"must be a finite number > 0, got {v!r}")
        bounds.append({"model": b["model"], "quantity": b["quantity"], **limits})
    return {"valid": valid, "bounds": bounds}
