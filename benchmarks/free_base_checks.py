"""The free base's figures that docs/base.md quotes: the first integrals of a free flexible
chain against its bending stiffness, the heavy-body limit and the three panels deploying from
a 1000 kg body in the native full model, and exudyn's first integrals and its three panels
beside the native model's (the settings of tests/test_exudyn_free_base.py).

    PYTHONPATH=. python benchmarks/free_base_checks.py
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np

from rodval import Base, paper_scene, simulate
from rodval.core.scene_file import scene_from_dict

STUDIES = Path(__file__).resolve().parents[1] / "studies"
TIGHT = dict(rtol=1e-10, atol=1e-12)


def drift(values: np.ndarray) -> float:
    """max |v - v(0)| / max |v(0)|: a first integral's relative drift."""
    return float(np.abs(values - values[0]).max() / np.abs(values[0]).max())


def free_chain() -> None:
    print("free 3-rod paper chain, no load, 1 s, rtol 1e-10 (50 kg, 20 kg m^2 body)")
    print(f"{'EI':>8} {'P drift':>10} {'H_c drift':>10} {'max|alpha|':>11}")
    body = Base(
        kind="free",
        mass=50.0,
        inertia=20.0,
        hinge_offset=[0.5, 0.2],
        rate=0.3,
        velocity=[0.1, -0.2],
    )
    for EI in (1e5, 1e7):
        s = paper_scene(3, t_end=1.0)
        s = s.with_(
            chain=s.chain.with_(EI=EI),
            loads=(),
            outputs=("alpha", "angular_momentum", "momentum"),
            base=body,
        )
        tr = simulate(s, "full", **TIGHT)
        H = tr["angular_momentum"][:, 1]
        print(
            f"{EI:8.0e} {drift(tr['momentum']):10.2e} {drift(H):10.2e} "
            f"{np.abs(tr['alpha']).max():11.2e}"
        )


def heavy_body() -> None:
    print("heavy body -> pinned: max |phi - phi_pinned| (rad), paper chain n = 3, 1 s")
    scene = paper_scene(3, t_end=1.0)
    ref = simulate(scene, "full", **TIGHT)["phi"]
    for mass in (1e3, 1e6, 1e9):
        tr = simulate(scene.with_(base=Base(kind="free", mass=mass, inertia=mass)), "full", **TIGHT)
        print(f"  body {mass:7.0e} kg: {np.abs(tr['phi'] - ref).max():.3e}")


def three_panels() -> None:
    doc = tomllib.loads((STUDIES / "companion_three_panel_free.toml").read_text())["scene"]
    tr = simulate(scene_from_dict(doc), "full", **TIGHT)
    H = tr["angular_momentum"][:, 1]
    print("three panels on a 1000 kg, 2000 kg m^2 body, 6 s (companion_three_panel_free)")
    print("  locks:", [(round(ev["t"], 4), ev["label"]) for ev in tr.events])
    print(
        f"  final attitude {tr['base_attitude'][-1, 0]:.6f} rad, drift {tr['base_position'][-1]} m"
    )
    print(f"  P drift {drift(tr['momentum']):.2e}; H_c {H[0]:.3f} -> {H[-1]:.3f} N m s")
    print(f"  largest bending after the locks {np.abs(tr['alpha']).max():.2e} rad")


def exudyn_side() -> None:
    body = Base(
        kind="free",
        mass=50.0,
        inertia=20.0,
        hinge_offset=[0.5, 0.2],
        rate=0.3,
        velocity=[0.1, -0.2],
    )
    outputs = ("angular_momentum", "momentum", "base")
    scene = paper_scene(3, t_end=1.0).with_(loads=(), outputs=outputs, base=body)
    print("exudyn, the same free chain (EI 1e5), 1 s: drift of P, H_c")
    for label, options in (
        ("default Newton tolerance", {}),
        ("EA 1e8, Newton 1e-6 N", {"EA": 1e8, "newton_atol_per_EA": 1e-14}),
    ):
        tr = simulate(scene, "exudyn", **options)
        H = tr["angular_momentum"][:, 1]
        print(f"  {label:26s} {drift(tr['momentum']):.2e} {drift(H):.2e}")
    doc = tomllib.loads((STUDIES / "companion_three_panel_free.toml").read_text())["scene"]
    panels = scene_from_dict(doc)
    native = simulate(panels, "full", **TIGHT)
    ex = simulate(panels, "exudyn", elements=2, step=1e-3, spectral_radius=0.0)
    print("three panels, exudyn (2 elements, 1e-3 s) against native full")
    for name, tr in (("exudyn", ex), ("native", native)):
        print(
            f"  {name}: final attitude {tr['base_attitude'][-1, 0]:.6f} rad, drift "
            f"{tr['base_position'][-1] - tr['base_position'][0]} m, H_c drift "
            f"{drift(tr['angular_momentum'][:, 1]):.1e}"
        )


if __name__ == "__main__":
    free_chain()
    heavy_body()
    three_panels()
    exudyn_side()
