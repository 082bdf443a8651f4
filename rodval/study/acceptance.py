"""A study's acceptance criteria (the ``[acceptance]`` table): what makes ``rodval study`` and
``rodval report`` exit 1, so that a study gates a CI pipeline.

    [acceptance]
    valid = true                 # every model run must keep its model's assumptions
    [[acceptance.bound]]         # one table per model and quantity
    model = "reduced"            # a model label; the pair is (model, the study's reference)
    quantity = "phi"
    max_abs = 1e-3               # bounds on the discrepancies table's metrics (the
    rms = 2e-4                   # quantity's unit); at least one of them

    [[acceptance.event]]         # lock events, one table per model
    model = "reduced"            # a model label other than the reference
    lock_time = 2e-3             # s: max |dt| of the model's locks against the reference's
    impulse = 0.05               # relative: max impulse_rel; at least one of the two
    [acceptance]                 # (the same table) top-level keys:
    all_latched = 0.95           # per model: fraction of cases in which every latch locked
    energy_residual = 1e-2       # max |energy_residual| of every run (runtime.csv)
    momentum_residual = 1e-6     # max |momentum_residual| of every audited run

A bound holds in a case when that pair's comparison of the quantity was made (status "ok")
and each bounded metric is at most its bound; a comparison that could not be made breaks the
bound (nothing passes by being absent). Checked when the study file is read: every key, the
model label (not the reference), the quantity among the cases' outputs, the bounds finite
numbers > 0. An event bound holds in a case when every lock of the model and of the reference
has its partner (a lock only one has breaks it) and every lock comparable pointwise keeps the
bounds (``rodval.analysis.events.comparability``; the others are skipped and named).
``all_latched`` lies in (0, 1], the other keys are finite numbers > 0. Evaluated by
``rodval.report.acceptance``.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

from rodval.core.checks import check_keys
from rodval.report.acceptance import BOUND_METRICS, EVENT_METRICS, SCALAR_KEYS

ACCEPTANCE_KEYS = {"valid", "bound", "event", *SCALAR_KEYS}
BOUND_KEYS = {"model", "quantity", "max_abs", "rms"}
EVENT_KEYS = {"model", *EVENT_METRICS}


def acceptance_spec(
    table: Any, labels: list[str], reference: str, quantities: set[str], where: str
) -> dict[str, Any] | None:
    """The checked ``[acceptance]`` table as ``{"valid": bool, "bounds": [...], "events":
    [...], "all_latched": ..., "energy_residual": ..., "momentum_residual": ...}`` (each bound
    a dict with model, quantity and its metrics, each event bound a dict with model and its
    metrics; the scalar keys the study gives), or None without the table. ValueError naming
    ``acceptance.<key>`` and what is allowed otherwise."""
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
    raw_events = table.get("event", [])
    if not isinstance(raw_events, list) or not all(isinstance(b, dict) for b in raw_events):
        raise err(".event", "must be an array of tables [[acceptance.event]]")
    scalars = {}
    for key in SCALAR_KEYS:
        if key not in table:
            continue
        v = table[key]
        upper = 1.0 if key == "all_latched" else math.inf
        number = not isinstance(v, bool) and isinstance(v, (int, float))
        if not number or not 0 < float(v) <= upper or not float(v) < math.inf:
            allowed = "a number in (0, 1]" if key == "all_latched" else "a finite number > 0"
            raise err(f".{key}", f"must be {allowed}, got {v!r}")
        scalars[key] = float(v)
    if not raw and not valid and not raw_events and not scalars:
        raise err(
            "",
            "has nothing to check: give valid = true, [[acceptance.bound]] or "
            f"[[acceptance.event]] tables, or one of {', '.join(SCALAR_KEYS)}",
        )
    others = [lb for lb in labels if lb != reference]
    bounds = []
    for i, b in enumerate(raw):
        key = f".bound[{i}]"
        check_keys(b, BOUND_KEYS, where, path=f"acceptance{key}")
        _check_model(b, key, others, reference, err)
        if b.get("quantity") not in quantities:
            raise err(
                f"{key}.quantity",
                f"must be a quantity the cases output ({', '.join(sorted(quantities))}), "
                f"got {b.get('quantity')!r}",
            )
        limits = _limits(b, key, BOUND_METRICS, err)
        bounds.append({"model": b["model"], "quantity": b["quantity"], **limits})
    events = _event_bounds(raw_events, others, reference, where, err)
    return {"valid": valid, "bounds": bounds, "events": events, **scalars}


def _event_bounds(
    raw: list[dict[str, Any]], others: list[str], reference: str, where: str, err: Any
) -> list[dict[str, Any]]:
    """The checked [[acceptance.event]] tables (model and its metrics); ``err(key, msg)``
    makes the one-line ValueError naming ``acceptance<key>``."""
    events = []
    for i, b in enumerate(raw):
        key = f".event[{i}]"
        check_keys(b, EVENT_KEYS, where, path=f"acceptance{key}")
        _check_model(b, key, others, reference, err)
        limits = _limits(b, key, EVENT_METRICS, err)
        events.append({"model": b["model"], **{m: float(v) for m, v in limits.items()}})
    return events


def _check_model(b: dict[str, Any], key: str, others: list[str], reference: str, err: Any) -> None:
    """The table's ``model`` must be a label other than the reference's."""
    if b.get("model") not in others:
        raise err(
            f"{key}.model",
            f"must be a model label other than the reference {reference!r} "
            f"(one of {others}), got {b.get('model')!r}",
        )


def _limits(b: dict[str, Any], key: str, metrics: tuple[str, ...], err: Any) -> dict[str, Any]:
    """The table's bounds among ``metrics``: at least one, each a finite number > 0."""
    limits = {m: b[m] for m in metrics if m in b}
    if not limits:
        raise err(key, f"needs at least one of {', '.join(metrics)}")
    for m, v in limits.items():
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or v <= 0 or not v < math.inf:
            raise err(f"{key}.{m}", f"must be a finite number > 0, got {v!r}")
    return limits
