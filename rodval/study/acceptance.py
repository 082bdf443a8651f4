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
``all_latched`` lies in (0, 1], the other keys are finite numbers > 0.

Absolute requirements bound a model's own results, not its gap to the reference:

    [[acceptance.require]]       # one table per model (any label, the reference's too)
    model = "full"
    locked_by = 5.0              # s: every latch of the scene locked at or before this time
    lock_time = { hinge = 1, min = 1.9, max = 2.2 }   # s: the hinge's lock time in [min, max]
    impulse = { hinge = 1, max = 12.0 }               # N m s: |lock impulse| in [min, max]
    peak_hinge_moment = 300.0    # N m: the run's max |hinge_moment|, every hinge (or
                                 # { hinge = 0, max = 300.0 }); needs "hinge_moment"
    final = { quantity = "phi", k = 4, min = -0.01, max = 0.01 }   # the value at t_end

``lock_time``, ``impulse`` and ``final`` take one table or an array of them (one per hinge or
quantity); each has ``min``, ``max`` or both (finite, min <= max; a lock time and an impulse
>= 0). The hinge is a latched hinge of every case (not a held one), the final quantity one
the cases output (a scene's ``"energy"`` yields ``kinetic``, ``potential`` and ``energy``)
and its k one that quantity has (``rodval.core.quantities.quantity_k``),
``peak_hinge_moment`` needs ``"hinge_moment"`` among the outputs: each refused when the file
is read, naming the key and what is allowed. ``locked_by`` and a lock time's bounds lie
within the cases' shortest horizon (a lock after t_end is never seen). A peak is the run's,
read between its output times (``SolverStats.peaks``; a hinge whose moment is an impulse at
its lock, in the reduced and rigid models, has none, and a peak requirement on it breaks
saying so). Evaluated by ``rodval.report.acceptance``; a requirement on a run that did not
reach t_end breaks.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any

from rodval.core.checks import check_keys
from rodval.core.quantities import quantity_k
from rodval.core.scene import EXPANDS, QUANTITIES, Scene
from rodval.report.acceptance import BOUND_METRICS, EVENT_METRICS, REQUIRE_ITEMS, SCALAR_KEYS

ACCEPTANCE_KEYS = {"valid", "bound", "event", "require", *SCALAR_KEYS}
BOUND_KEYS = {"model", "quantity", "max_abs", "rms"}
EVENT_KEYS = {"model", *EVENT_METRICS}
REQUIRE_KEYS = {"model", *REQUIRE_ITEMS}
#: The keys of each requirement table: what it names, and its bounds.
ITEM_KEYS = {
    "lock_time": {"hinge", "min", "max"},
    "impulse": {"hinge", "min", "max"},
    "peak_hinge_moment": {"hinge", "max"},
    "final": {"quantity", "k", "min", "max"},
}


def acceptance_spec(
    table: Any,
    labels: list[str],
    reference: str,
    quantities: set[str],
    where: str,
    scenes: Sequence[Scene] = (),
) -> dict[str, Any] | None:
    """The checked ``[acceptance]`` table as ``{"valid": bool, "bounds": [...], "events":
    [...], "requires": [...], "all_latched": ..., "energy_residual": ...,
    "momentum_residual": ...}`` (each bound a dict with model, quantity and its metrics, each
    event bound a dict with model and its metrics, each requirement as
    ``requirement_tables`` gives it; the scalar keys the study gives), or None without the
    table. ``scenes``: the cases' scenes, against which a requirement's hinge, k and times
    are checked (none given: not checked). ValueError naming ``acceptance.<key>`` and what is
    allowed otherwise."""
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
    raw, raw_events = _tables(table, "bound", err), _tables(table, "event", err)
    scalars = _scalars(table, err)
    raw_requires = _tables(table, "require", err)
    if not raw and not valid and not raw_events and not raw_requires and not scalars:
        raise err(
            "",
            "has nothing to check: give valid = true, [[acceptance.bound]], "
            "[[acceptance.event]] or [[acceptance.require]] tables, or one of "
            f"{', '.join(SCALAR_KEYS)}",
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
    requires = requirement_tables(raw_requires, labels, quantities, scenes, where, err)
    return {"valid": valid, "bounds": bounds, "events": events, "requires": requires, **scalars}


def _tables(table: dict[str, Any], key: str, err: Any) -> list[dict[str, Any]]:
    """The [[acceptance.KEY]] tables (none: []), an array of tables or the error."""
    raw = table.get(key, [])
    if not isinstance(raw, list) or not all(isinstance(b, dict) for b in raw):
        raise err(f".{key}", f"must be an array of tables [[acceptance.{key}]]")
    return raw


def _scalars(table: dict[str, Any], err: Any) -> dict[str, float]:
    """The [acceptance] table's scalar keys it gives (SCALAR_KEYS), checked: all_latched in
    (0, 1], the others finite numbers > 0."""
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
    return scalars


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


def requirement_tables(
    raw: list[dict[str, Any]],
    labels: list[str],
    quantities: set[str],
    scenes: Sequence[Scene],
    where: str,
    err: Any,
) -> list[dict[str, Any]]:
    """The checked [[acceptance.require]] tables: each ``{"model": label, item: value}`` with
    ``locked_by`` a float, ``lock_time``, ``impulse`` and ``final`` lists of dicts,
    ``peak_hinge_moment`` a dict (``hinge`` absent: every hinge); ``err(key, msg)`` makes the
    one-line ValueError naming ``acceptance<key>``."""
    out = []
    for i, b in enumerate(raw):
        key = f".require[{i}]"
        check_keys(b, REQUIRE_KEYS, where, path=f"acceptance{key}")
        if b.get("model") not in labels:
            raise err(
                f"{key}.model", f"must be one of the model labels {labels}, got {b.get('model')!r}"
            )
        items = [m for m in REQUIRE_ITEMS if m in b]
        if not items:
            raise err(key, f"needs at least one of {', '.join(REQUIRE_ITEMS)}")
        req: dict[str, Any] = {"model": b["model"]}
        for item in items:
            req[item] = _requirement(item, b[item], f"{key}.{item}", quantities, scenes, err)
        out.append(req)
    return out


def _horizon(scenes: Sequence[Scene]) -> float:
    """The cases' shortest horizon t_end (s); inf when no scene is given."""
    return min((float(s.t_end) for s in scenes), default=math.inf)


def _within_horizon(v: float, key: str, scenes: Sequence[Scene], err: Any) -> float:
    """A time ``v`` (s) a run must see: at most the cases' shortest horizon."""
    horizon = _horizon(scenes)
    if v > horizon:
        raise err(
            key,
            f"must be <= the cases' horizon t_end = {horizon:g} s (a lock after t_end is "
            f"never seen), got {v:g}",
        )
    return v


def _requirement(
    item: str, value: Any, key: str, quantities: set[str], scenes: Sequence[Scene], err: Any
) -> Any:
    """One checked requirement of a [[acceptance.require]] table (see ``requirement_tables``)."""
    if item == "locked_by":
        if not scenes_latch(scenes):
            raise err(key, "needs latches: the cases' scenes have none that is not held")
        return _within_horizon(_number(value, key, err, low=0.0), key, scenes, err)
    if item == "peak_hinge_moment":
        if "hinge_moment" not in quantities:
            raise err(key, 'needs "hinge_moment" among the [scene] outputs: add it there')
        table = {"max": value} if not isinstance(value, dict) else value
        return _item_table(item, table, key, quantities, scenes, err)
    if isinstance(value, dict):
        value = [value]
    if not isinstance(value, list) or not value or not all(isinstance(v, dict) for v in value):
        raise err(key, "must be a table or a non-empty array of tables")
    many = len(value) > 1
    return [
        _item_table(item, v, f"{key}[{j}]" if many else key, quantities, scenes, err)
        for j, v in enumerate(value)
    ]


def _item_table(
    item: str,
    table: dict[str, Any],
    key: str,
    quantities: set[str],
    scenes: Sequence[Scene],
    err: Any,
) -> dict[str, Any]:
    """A requirement table's names (hinge, or quantity and k) and bounds (min, max), checked."""
    unknown = sorted(set(table) - ITEM_KEYS[item])
    if unknown:
        allowed = ", ".join(sorted(ITEM_KEYS[item]))
        raise err(f"{key}.{unknown[0]}", f"is not a key of {item} (allowed: {allowed})")
    out: dict[str, Any] = {}
    if item in ("lock_time", "impulse"):
        out["hinge"] = _latched_hinge(table.get("hinge"), f"{key}.hinge", scenes, err)
    elif item == "peak_hinge_moment" and "hinge" in table:
        n = min((s.n for s in scenes), default=None)
        out["hinge"] = _index(table["hinge"], f"{key}.hinge", range(n) if n else None, err)
    elif item == "final":
        q = table.get("quantity")
        if q not in quantities:
            raise err(f"{key}.quantity", _not_output(q, quantities))
        n = min((s.n for s in scenes), default=None)
        out["quantity"] = q
        out["k"] = _index(table.get("k"), f"{key}.k", quantity_k(q, n) if n else None, err)
    low = 0.0 if item != "final" else -math.inf
    for bound in ("min", "max"):
        if bound in table:
            out[bound] = _number(table[bound], f"{key}.{bound}", err, low=low)
            if item == "lock_time":
                _within_horizon(out[bound], f"{key}.{bound}", scenes, err)
    if "min" not in out and "max" not in out:
        raise err(key, "needs min, max or both" if item != "peak_hinge_moment" else "needs max")
    if out.get("min", -math.inf) > out.get("max", math.inf):
        raise err(f"{key}.min", f"must be <= max = {out['max']:g}, got {out['min']:g}")
    return out


def _not_output(q: Any, quantities: set[str]) -> str:
    """Why ``q`` cannot be required: not among the cases' quantities (and the output that
    would yield it, when one does)."""
    source = next((o for o, parts in EXPANDS.items() if q in parts), q)
    fix = f': add "{source}" to the [scene] outputs' if source in QUANTITIES else ""
    return f"must be a quantity the cases output ({', '.join(sorted(quantities))}), got {q!r}{fix}"


def _number(v: Any, key: str, err: Any, low: float) -> float:
    """``v`` as a float when it is a finite number (> 0 when ``low`` is 0, else any), else
    the one-line error naming ``key``."""
    finite = not isinstance(v, bool) and isinstance(v, numbers.Real) and math.isfinite(v)
    if not finite or (low == 0.0 and v < 0):
        allowed = "a finite number >= 0" if low == 0.0 else "a finite number"
        raise err(key, f"must be {allowed}, got {v!r}")
    return float(v)


def _index(v: Any, key: str, allowed: range | None, err: Any) -> int:
    """``v`` as an int within ``allowed`` (None: any >= 0), else the one-line error."""
    ok = not isinstance(v, bool) and isinstance(v, numbers.Integral) and int(v) >= 0
    if not ok or (allowed is not None and int(v) not in allowed):
        span = f"{allowed.start}..{allowed.stop - 1}" if allowed is not None else ">= 0"
        raise err(key, f"must be an integer in {span}, got {v!r}")
    return int(v)


def scenes_latch(scenes: Sequence[Scene]) -> bool:
    """Whether the scenes latch at all (True when none is given: not checked)."""
    return not scenes or any(la for s in scenes for la in s.latches if not la.held)


def _latched_hinge(v: Any, key: str, scenes: Sequence[Scene], err: Any) -> int:
    """``v`` as a hinge every scene latches (a latch that is not held), else the error."""
    hinge = _index(v, key, None, err)
    if scenes:
        common = set.intersection(*({la.hinge for la in s.latches if not la.held} for s in scenes))
        if hinge not in common:
            allowed = ", ".join(map(str, sorted(common))) or "none"
            raise err(key, f"must be a hinge every case latches ({allowed}), got {v!r}")
    return hinge
