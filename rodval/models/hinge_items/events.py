"""A native system's hinge items as events (docs/deployment_native.md): the current mode's
latches and stops as rows (``event_rows``: the Python event functions, ``event_specs``, and
the compiled event table read them in one order) and what one does when it fires
(``switch``: a stop switching, a latch locking with its plastic impact,
``lock_records.lock_record``, a compliant latch engaging and arming its two stops). The system is a
``rodval.models.systems.paper_system.PaperSystem`` (which imports this module)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from rodval.models.hinge_items import deployment, lock_records
from rodval.solvers.system import EventRecord, EventSpec


class EventRow(NamedTuple):
    """One event of the current mode: a "latch", "compliant latch" or "stop" (``kind``;
    ``item``: its index among the system's latches, compliant latches or stops), on ``hinge``,
    g = D_hinge - ``angle`` (rad) crossing in ``direction``."""

    kind: str
    item: int
    hinge: int
    angle: float
    direction: int


def directions(latches: Any, D0: np.ndarray) -> tuple[int, ...]:
    """Each latch's direction (+1, -1): its own, or (None) towards its angle from D0 (rad)."""
    return tuple(
        int(np.sign(la.angle - D0[la.hinge])) if la.direction is None else la.direction
        for la in latches
    )


def system_stops(scene: Any, D0: np.ndarray) -> tuple[tuple[Any, ...], tuple[bool, ...]]:
    """A system's stops: the scene's, then each compliant latch's two (``engaged_stops``:
    latch j's upper and lower), dormant until it engages (``armed``); and which act at the
    initial hinge angles D0 (rad): the scene's the initial state is beyond, no latch's."""
    own = tuple(scene.stops)
    latched = tuple(st for la in scene.compliant_latches for st in la.engaged_stops())
    initial = tuple(bool(st.acts(D0[st.hinge])) for st in own) + (False,) * len(latched)
    return own + latched, initial


def armed(system: Any, i: int) -> bool:
    """Whether the system's stop ``i`` can switch: a scene's stop (the first
    ``len(scene.stops)``), or a compliant latch's once it has engaged."""
    own = i - len(system.scene.stops)
    return own < 0 or own // 2 in system.engaged


def event_rows(system: Any) -> tuple[EventRow, ...]:
    """The current mode's events: latches not yet locked and compliant latches not yet
    engaged (g = D_k - angle in the latch's direction), and limit stops on hinges not locked,
    a compliant latch's once it has engaged (g = D_k - angle in the direction that
    switches the stop: into its side while it is off, out of it while it acts; a root found
    again just after the switch, where g may sit a rounding error on the old side, then
    cannot fire twice)."""
    rows = []
    held = {system.latches[j].hinge for j in system.locked}
    for j, la in enumerate(system.latches):
        if j not in system.locked:
            rows.append(EventRow("latch", j, la.hinge, la.angle, system.latch_dir[j]))
    for j, la in enumerate(system.compliant):
        if j not in system.engaged:
            rows.append(EventRow("compliant latch", j, la.hinge, la.angle, system.compliant_dir[j]))
    for i, st in enumerate(system.stops):
        if st.hinge in held or not armed(system, i):
            continue
        entering = 1 if st.side == "upper" else -1
        direction = -entering if system.stop_active[i] else entering
        rows.append(EventRow("stop", i, st.hinge, st.angle, direction))
    return tuple(rows)


def _hinge_crossing(system: Any, hinge: int, angle: float) -> Callable[[float, np.ndarray], float]:
    """The event function g(t, y) = D_hinge - angle (rad) of a latch or stop."""

    def g(t: float, y: np.ndarray) -> float:
        return float(system.hinge_angles_at(t, y)[hinge] - angle)

    return g


def event_specs(system: Any) -> tuple[EventSpec, ...]:
    """The current mode's events (``event_rows``) as g(t, y) = D_k - angle."""
    return tuple(
        EventSpec(
            g=_hinge_crossing(system, r.hinge, r.angle),
            direction=r.direction,
            label=f"{r.kind} hinge {r.hinge}",
        )
        for r in event_rows(system)
    )


def switch(system: Any, index: int, t: float, y: np.ndarray) -> tuple[np.ndarray, EventRecord]:
    """Event ``index`` of ``event_rows`` at (t, y): the system's new mode, the state after the
    jump and the record."""
    row = event_rows(system)[index]
    kind, j = row.kind, row.item
    if kind == "stop":
        st = system.stops[j]
        on = not system.stop_active[j]  # the event looks for the crossing that switches
        active = list(system.stop_active)
        active[j] = on
        for i, other in enumerate(system.stops):  # one root: leaving one side enters the other
            twin = other.hinge == st.hinge and other.angle == st.angle and other.side != st.side
            if twin and armed(system, i):
                active[i] = not on
        system.set_mode((tuple(active), system.locked, system.engaged), t)
        return y.copy(), EventRecord(
            t,
            f"stop hinge {st.hinge} {'on' if on else 'off'}",
            {"hinge": st.hinge, "active": on},
        )
    if kind == "compliant latch":
        return y.copy(), _engage(system, j, t)
    D = system.hinge_angles_at(t, y)
    group = [j] + [
        i
        for i, la in enumerate(system.latches)
        if i != j
        and i not in system.locked
        and abs(D[la.hinge] - la.angle) <= deployment.SIMULTANEOUS_RAD
    ]
    locked = system.locked + tuple(group)
    y_new, data = lock_records.lock_record(system, t, y, locked, tuple(group))
    system.set_mode((system.stop_active, locked, system.engaged), t)
    hinges = [system.latches[i].hinge for i in group]
    label = "latch hinge " + ", ".join(str(h) for h in hinges)
    return y_new, EventRecord(t, label, data)


def _engage(system: Any, j: int, t: float) -> EventRecord:
    """Compliant latch ``j`` engaging at time t (s), without a jump: its two stops are armed,
    the one on the side the hinge moves into acting at once when it has no play (the hinge
    is at its angle), neither with play (the hinge is inside it). The record is a lock's
    ("latch hinge k", ``analysis.events.is_lock``) without an impulse: no impact."""
    la = system.compliant[j]
    first = len(system.scene.stops) + 2 * j  # its upper stop, then its lower one
    active = list(system.stop_active)
    if la.play == 0.0:
        active[first if system.compliant_dir[j] > 0 else first + 1] = True
    system.set_mode((tuple(active), system.locked, system.engaged + (j,)), t)
    data = {"hinge": la.hinge, "hinges": [la.hinge], "compliant": True}
    return EventRecord(t, f"latch hinge {la.hinge}", data)
