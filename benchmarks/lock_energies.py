"""Where the lock energy goes, in every model, and exudyn's numerical dissipation (issue 19;
docs/deployment.md, "Where the lock energy goes").

Part 1: the stiff damped two-rod lock of tests/test_lock_impulse.py (EI 1e7, bending damping
700 N m^2 s: zeta 0.1 on the locked pair's first bending mode). Per model, from its lock
record (J): the energy just before the lock (E0 = kinetic + hinge + bending), its
instantaneous loss, the energy dissipated from just before the lock to the window's end,
the kinetic, hinge and bending energy at the window's end, the balance's residual
E(end) - E0 - work + dissipated, and ``ring left``: the energy at the window's end above the
rigid-panel lock's kinetic energy after it, over the rigid-panel loss (exp(-4 pi zeta) =
0.285 for one mode of the pair ringing down over one period). exudyn at three steps.

Part 2: exudyn's energy audit on the paper example (default settings) without and with rod
bending damping: max |R| over the energy scale and R(t_end) = -numerical dissipation (J),
beside the dissipated energy.

Run:  PYTHONPATH=.:tests python benchmarks/lock_energies.py   (about half a minute)
"""

from __future__ import annotations

import dataclasses

from tabulate import tabulate
from test_lock_impulse import stiff_damped_latch

from rodval import paper_scene, simulate

PARTS = ("kinetic", "hinge", "bending")


def lock_row(label: str, ev: dict) -> list:
    E0 = sum(ev[f"{p}_before"] for p in PARTS)
    end = [ev[f"{p}_window_end"] for p in PARTS]
    lock = ev["rigid_kinetic_before"] - ev["rigid_kinetic_after"]
    ring = (sum(end) - ev["rigid_kinetic_after"]) / lock
    return [
        label,
        E0,
        ev["instant_energy_loss"],
        ev["dissipated_window_end"],
        *end,
        ev["energy_residual_window_end"],
        ring,
    ]


def main() -> None:
    scene = stiff_damped_latch()
    rows = [lock_row(m, simulate(scene, m).events[0]) for m in ("full", "reduced")]
    for step in (1e-4, 5e-5, 2.5e-5):
        tr = simulate(scene, "exudyn", elements=2, step=step)
        rows.append(lock_row(f"exudyn h={step:g}", tr.events[0]))
    head = ["model", "E0", "instant", "dissipated", "T end", "hinge end", "bending end"]
    print(tabulate(rows, headers=[*head, "residual", "ring left"], floatfmt=".4g"))
    print()
    rows = []
    for c in (0.0, 1000.0):
        base = paper_scene()
        chain = base.chain.with_(bending_damping=c)
        tr = simulate(
            dataclasses.replace(base, chain=chain, outputs=(*base.outputs, "energy")), "exudyn"
        )
        D, R = tr.values["dissipated"][-1, 0], tr.values["energy_residual"][-1, 0]
        rows.append([c, tr.stats.energy_residual, R, tr.settings["numerical_dissipation"], D])
    print(
        tabulate(
            rows,
            headers=[
                "bending damping",
                "max|R|/scale",
                "R end (J)",
                "numerical dissipation (J)",
                "D end (J)",
            ],
            floatfmt=".4g",
        )
    )


if __name__ == "__main__":
    main()
