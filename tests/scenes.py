"""Scenes shared by the test modules (no test module imports another)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rodval.core.scene import Chain, InitialState, Latch, Scene


def two_rod_latch(EI: float, window: float | None = None) -> Scene:
    """The exudyn deployment tests' two-rod scene (tests/test_exudyn_deployment.py): l = 1.5
    m, m = 3 kg/m, mu = 0.5 kg, hinge 0 free, hinge 1 stowed at pi - 0.05 rad unfolding on a
    50 N m/rad spring, latch at 0 (its lock window ``window`` s, None: the latch's default,
    the locked pair's first bending period, 2.28 ms at EI = 1e7); the lock comes at t =
    0.404 s."""
    chain = Chain.uniform(2, l=1.5, m=3.0, EI=EI, mu=0.5, kappa=[0.0, 50.0], nu=0.0)
    return Scene(
        chain=chain,
        t_end=0.42,
        times=np.linspace(0.0, 0.42, 43),
        outputs=("phi", "dphi"),
        initial=InitialState(phi=[0.0, math.pi - 0.05], dphi=[1.0, 1.0]),
        latches=(Latch(1, 0.0, window=window),),
    )


#: Kelvin-Voigt bending damping (N m^2 s) of the stiff damped two-rod scene: zeta = c omega /
#: (2 EI) = 0.1 on the locked pair's first bending mode (2756 rad/s at EI = 1e7).
DAMPING = 700.0


def stiff_damped_latch() -> Scene:
    """``two_rod_latch`` at EI 1e7 with bending damping DAMPING; outputs phi, dphi and the
    angular momentum."""
    scene = two_rod_latch(1e7)
    chain = scene.chain.with_(bending_damping=DAMPING)
    return dataclasses.replace(scene, chain=chain, outputs=("phi", "dphi", "angular_momentum"))


def latch3_toml(
    table: str = "", outputs: tuple[str, ...] = ("phi",), latches: tuple[int, ...] = (1, 2)
) -> str:
    """The latched three-rod deployment (benchmarks/exudyn_speed.py ``latch3_scene``) as scene
    TOML: 3 rods (l = 1.5 m, m = 3 kg/m, EI = 1e5 N m^2, mu = 0.5 kg), hinge 0 free, hinges 1
    and 2 stowed at +-(pi - 0.05) rad unfolding on 50 N m/rad springs, a latch at 0 on each of
    ``latches``; 0.8 s, 81 output times, ``outputs``. Under ``[table]`` (a study's "scene")
    when given, else a scene file's top level."""
    p = f"{table}." if table else ""
    head = f"[{table}]\n" if table else ""
    quoted = ", ".join(f'"{q}"' for q in outputs)
    locks = "".join(f"\n[[{p}latches]]\nhinge = {h}\nangle = 0.0\n" for h in latches)
    return (
        f"{head}n = 3\nt_end = 0.8\ntimes = {{ num = 81 }}\noutputs = [{quoted}]\nloads = []\n\n"
        f"[{p}chain]\nl = 1.5\nm = 3.0\nEI = 1e5\nmu = 0.5\nkappa = [0.0, 50.0, 50.0]\n"
        f"nu = 0.0\n\n[{p}initial]\nphi = [0.0, 3.0915926535897933, 0.0]\n{locks}"
    )
