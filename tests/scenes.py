"""Scenes shared by the test modules (no test module imports another)."""

from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path

import numpy as np

from rodval.core.loads import harmonic
from rodval.core.scene import Chain, InitialState, Latch, Motor, Scene
from rodval.core.scene_file import scene_from_dict

STUDIES = Path(__file__).resolve().parents[1] / "studies"


def two_rod_latch(
    EI: float = 1e7,
    window: float | None = None,
    t_end: float = 0.42,
    num: int = 43,
    outputs: tuple[str, ...] = ("phi", "dphi"),
) -> Scene:
    """The exudyn deployment tests' two-rod scene (tests/test_exudyn_deployment.py): l = 1.5
    m, m = 3 kg/m, mu = 0.5 kg, hinge 0 free, hinge 1 stowed at pi - 0.05 rad unfolding on a
    50 N m/rad spring, latch at 0 (its lock window ``window`` s, None: the latch's default,
    the locked pair's first bending period, 2.28 ms at EI = 1e7); the lock comes at t =
    0.404 s; over ``t_end`` s at ``num`` output times, ``outputs``."""
    chain = Chain.uniform(2, l=1.5, m=3.0, EI=EI, mu=0.5, kappa=[0.0, 50.0], nu=0.0)
    return Scene(
        chain=chain,
        t_end=t_end,
        times=np.linspace(0.0, t_end, num),
        outputs=outputs,
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


def spun_damped_latch() -> Scene:
    """Two rods spun up from rest-free initial rates (phi = [0, -2.5] rad, dphi = [1, 1.5]
    rad/s; l = 1 m, m = 1 kg/m, EI = 1e7 N m^2, bending damping 700 N m^2 s, mu = 0.5 kg,
    hinge 1 on a 5 N m/rad spring) onto a latch at 0 on hinge 1, over 0.8 s: the lock
    records' stiff damped scene (not ``stiff_damped_latch``, which unfolds from stowed)."""
    chain = Chain.uniform(2, l=1.0, m=1.0, EI=1e7, mu=0.5, kappa=[0.0, 5.0], nu=0.0)
    return Scene(
        name="spun_damped_latch",
        chain=chain.with_(bending_damping=700.0),
        t_end=0.8,
        times=np.linspace(0.0, 0.8, 9),
        initial=InitialState(phi=[0.0, -2.5], dphi=[1.0, 1.5]),
        latches=(Latch(1, 0.0),),
        outputs=("phi", "dphi", "angular_momentum"),
    )


def three_rods_loaded() -> Scene:
    """tests/test_deployment.py's three rods (two latches, hinge dampers) with a harmonic
    tip force acting through the windows: the loads' terms of the window integrands."""
    chain = Chain.uniform(3, l=1.0, m=1.0, EI=1e4, mu=0.3, kappa=[0.0, 4.0, 6.0], nu=0.02)
    return Scene(
        name="three_rods_loaded",
        chain=chain,
        t_end=1.5,
        times=np.linspace(0.0, 1.5, 16),
        initial=InitialState(phi=[0.0, -2.0, -3.5], dphi=[0.5, 0.0, 0.0]),
        latches=(Latch(1, 0.0), Latch(2, 0.0)),
        loads=(harmonic(3, X=0.3, Y=-0.5, omega=7.0),),
        outputs=("phi", "hinge_angle"),
    )


def three_panel_free_scene(mass: float = 1000.0, inertia: float = 2000.0) -> Scene:
    """The companion paper's three panels (studies/companion_three_panel.toml, every hinge
    latching) deploying from a free body of ``mass`` kg and ``inertia`` kg m^2 (1000, 2000 by
    default), hinge 0 at 1 m from its centre of mass; outputs phi, hinge angles, momenta and
    the body."""
    doc = tomllib.loads((STUDIES / "companion_three_panel.toml").read_text())["scene"]
    doc["outputs"] = ["phi", "hinge_angle", "angular_momentum", "momentum", "base"]
    doc["base"] = {"kind": "free", "mass": mass, "inertia": inertia, "hinge_offset": [1.0, 0.0]}
    return scene_from_dict(doc)


def motor_wing(t_end: float = 3.0, num: int = 61, EI: float = 1e4) -> Scene:
    """A three-panel wing deployed by motors (issue 55): panels l = 1 m, m = 2 kg/m, EI
    N m^2, no hinge springs, hinge 0 free (the root panel turns on its pin), hinges 1 and 2
    stowed at -1.2 rad, each driven by a torque-speed motor (stall 4 N m, no-load speed 2
    rad/s) to a latch at 0 rad; both lock inside 2.5 s."""
    chain = Chain.uniform(3, l=1.0, m=2.0, EI=EI, mu=0.0, kappa=0.0, nu=0.0)
    return Scene(
        chain=chain,
        t_end=t_end,
        times=np.linspace(0.0, t_end, num),
        outputs=("phi", "hinge_angle", "hinge_moment", "energy"),
        initial=InitialState(phi=[0.0, -1.2, -2.4]),
        latches=(Latch(1, 0.0), Latch(2, 0.0)),
        motors=tuple(Motor(k, stall_torque=4.0, no_load_speed=2.0) for k in (1, 2)),
    )
