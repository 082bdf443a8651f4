"""Energy audit through stop contacts and locks (issue 19; docs/deployment_native.md, "Energy
through events").

The scene: studies/scenes/wing_stop_latches.toml (a six-panel wing with undamped rods, a
damped stop on the tip hinge, latches on hinges 1-4) at three EI. Each native model runs it
twice with the same settings: the second time with output times 1e-7 s either side of every event of the
first (output times never change a step), so the audit residual R = E - E0 - W + D is read
just before and just after each event.

Printed per model, EI and tolerance (every energy relative to the scale max(E, |W|)):
  * ``event``: the largest jump of R across one event: what an event changes that the audit
    does not book (the audit books each event's ``instant_energy_loss``: a lock's plastic
    loss, the reduced model's quasi-static bending re-equilibrating when a moment switches);
  * ``locks``, ``switches``: the booked instantaneous losses, J (switches: the stops' on/off
    events; negative: energy the event added); ``first on``: the energy the first stop
    switch-on added, J (the reduced model's quasi-static bending jump);
  * ``contacts``, ``elsewhere``: R accumulated inside the stop contacts and outside them;
  * ``R_end``, ``max|R|``: the run's residual.
Two tolerances tell integration from the model's own residual; three EI tell the quasi-static
(1/EI) residual from the full model's kinematic residual in the bending vibration the locks
leave (independent of EI: the vibration energy is set by the lock); the last rows damp that
vibration (bending damping 200 and 1000 N m^2 s).

Run:  PYTHONPATH=. python benchmarks/energy_events.py   (about a minute)
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from tabulate import tabulate

from rodval import Scene, load_scene, simulate

#: Output times either side of an event (s): R changes by at most |P| 2 DELTA in between.
DELTA = 1e-7


SCENE = Path(__file__).resolve().parents[1] / "studies" / "scenes" / "wing_stop_latches.toml"


def wing(EI: float, times: np.ndarray, damping: float = 0.0) -> Scene:
    """The scene file's wing with bending stiffness EI (N m^2), bending damping ``damping``
    (N m^2 s) and output times ``times``."""
    scene = load_scene(SCENE)
    chain = scene.chain.with_(EI=EI, bending_damping=damping)
    return dataclasses.replace(scene, chain=chain, times=times)


def audit_row(model: str, EI: float, rtol: float, damping: float = 0.0) -> list:
    base = np.linspace(0.0, 2.5, 501)
    first = simulate(wing(EI, base, damping), model, rtol=rtol, atol=rtol * 1e-2)
    t_ev = np.array([ev["t"] for ev in first.events])
    times = np.unique(np.concatenate([base, t_ev - DELTA, t_ev + DELTA]))
    tr = simulate(wing(EI, times, damping), model, rtol=rtol, atol=rtol * 1e-2)
    assert [ev["t"] for ev in tr.events] == list(t_ev), "output times changed the events"
    E, W, R = (tr[q][:, 0] for q in ("energy", "work", "energy_residual"))
    scale = max(float(np.max(np.abs(E))), float(np.max(np.abs(W))))

    def at(t: float) -> float:
        return float(R[np.searchsorted(times, t)])

    jumps = [at(t + DELTA) - at(t - DELTA) for t in t_ev]
    losses = {"latch": 0.0, "stop": 0.0}
    first_on = next(0.0 - ev["instant_energy_loss"] for ev in tr.events if ev.get("active"))
    contacts, on = 0.0, None
    for ev in tr.events:
        losses[ev["label"].split()[0]] += ev["instant_energy_loss"]
        if ev["label"].startswith("stop") and ev["active"]:
            on = ev["t"]
        elif ev["label"].startswith("stop") and on is not None:
            contacts += at(ev["t"] - DELTA) - at(on + DELTA)
            on = None
    return [
        model if damping == 0 else f"{model}, bending damping {damping:g}",
        f"{EI:g}",
        rtol,
        len(t_ev),
        max(map(abs, jumps)) / scale,
        losses["latch"],
        losses["stop"],
        first_on,
        contacts / scale,
        (R[-1] - contacts) / scale,
        R[-1] / scale,
        float(np.max(np.abs(R))) / scale,
    ]


def main() -> None:
    rows = [
        audit_row(model, EI, rtol)
        for model in ("full", "reduced")
        for EI in (1e5, 1e6, 1e7)
        for rtol in (1e-8, 1e-10)
    ]
    rows += [audit_row("full", 1e5, 1e-8, damping) for damping in (200.0, 1000.0)]
    head = ["model", "EI", "rtol", "events", "event", "locks J", "switches J", "first on J"]
    print(
        tabulate(rows, headers=[*head, "contacts", "elsewhere", "R_end", "max|R|"], floatfmt=".3g")
    )


if __name__ == "__main__":
    main()
