"""Kane, Ryan and Banerjee's spin-up benchmark (1987): a 10 m cantilever (rho A = 1.2 kg/m,
EI = 1.4e4 N m^2, EA = 2.8e7 N) clamped to a hub at its axis whose angle follows the smooth
spin-up law to omega_s over T_s = 15 s (``rodval.core.base.Motion("spin_up")``), here as a
chain of n rods on a prescribed base, every hinge held from t = 0 (``Latch(k, 0, held=True)``:
hinge 0 clamps rod 1 to the hub, the others make the rods one continuous beam).

The tip's transverse deflection in the hub frame, v(t) = (r_n - r_0) . (-sin theta, cos theta),
for the first-order and exact kinematics, n = 1..8 rods, p = 1, against exudyn (elements per
rod refined): the table prints min v, v at t_end and the run's verdict.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/spin_up.py [--omega 4 10] [--n 1 2 4 8]
        [--t-end 20] [--no-exudyn]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rodval.core.base import Base, Motion
from rodval.core.hinges import Latch
from rodval.core.scene import Chain, InitialState, Scene
from rodval.models import simulate

#: The benchmark's beam and law.
LENGTH, RHO_A, EI, EA, RAMP = 10.0, 1.2, 1.4e4, 2.8e7, 15.0


def spin_up_scene(n: int, omega: float, t_end: float = 20.0, samples: int = 401) -> Scene:
    """The beam as n equal rods, clamped to the hub spun up to ``omega`` (rad/s)."""
    chain = Chain.uniform(n, l=LENGTH / n, m=RHO_A, EI=EI, mu=0.0, kappa=0.0, nu=0.0)
    hub = Base(
        kind="prescribed",
        hinge_offset=(0.0, 0.0),
        motion={"attitude": Motion("spin_up", (omega, RAMP))},
    )
    return Scene(
        chain=chain,
        t_end=t_end,
        times=np.linspace(0.0, t_end, samples),
        outputs=("phi", "x", "y", "base"),
        initial=InitialState(phi=[0.0] * n),
        latches=tuple(Latch(k, 0.0, held=True) for k in range(n)),
        base=hub,
        name=f"spin_up_{n}_{omega:g}",
    )


def tip_deflection(tr) -> np.ndarray:
    """v(t) (m): the tip's transverse deflection in the hub frame."""
    theta = tr["base_attitude"][:, 0]
    x, y = tr["x"], tr["y"]
    dx, dy = x[:, -1] - x[:, 0], y[:, -1] - y[:, 0]
    return -np.sin(theta) * dx + np.cos(theta) * dy


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--omega", type=float, nargs="+", default=[4.0, 10.0])
    parser.add_argument("--n", type=int, nargs="+", default=[1, 2, 4, 8])
    parser.add_argument("--t-end", type=float, default=20.0)
    parser.add_argument("--no-exudyn", action="store_true")
    args = parser.parse_args()
    print(
        "| omega_s (rad/s) | model | n | min v (m) | t at min (s) | v(t_end) (m) | wall (s) | verdict |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for omega in args.omega:
        runs = [("full", n, {"kinematics": k}) for k in ("first-order", "exact") for n in args.n]
        if not args.no_exudyn:
            runs += [
                ("exudyn", max(args.n), {"elements": e, "step": h, "EA": EA})
                for e, h in ((2, 1e-3), (4, 5e-4))
            ]
        for model, n, options in runs:
            scene = spin_up_scene(n, omega, args.t_end)
            start = time.perf_counter()
            tr = simulate(scene, model, **options)
            wall = time.perf_counter() - start
            st = tr.stats
            verdict = "valid" if st.valid else "INVALID" if st.valid is False else "-"
            if tr.times.size < 2:
                print(
                    f"| {omega:g} | {model} {options} | {n} | - | - | - | {wall:.1f} | {st.message[:60]} |"
                )
                continue
            v = tip_deflection(tr)
            i = int(np.argmin(v))
            label = model + "".join(f", {k} = {val}" for k, val in options.items())
            print(
                f"| {omega:g} | {label} | {n} | {v[i]:.4f} | {tr.times[i]:.2f} | {v[-1]:.4f} | "
                f"{wall:.1f} | {verdict}, {st.message[:50]} |"
            )


if __name__ == "__main__":
    main()
