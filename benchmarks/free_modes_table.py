"""The free-spacecraft modes table of docs/modes.md ("Free base"): the full model's flexible
frequencies on rungs p = 1..5 against exudyn (16 elements per rod, EA 1e8 N), relative gaps
native - exudyn and the smallest MAC of modes 1-8, on the scene of tests/test_free_modes.py
(3 rods l = 1.5 m, m = 3 kg/m, EI = 1e5 N m^2, mu = 0.5 kg, kappa = 50 N m/rad, a 50 kg,
20 kg m^2 body, hinge offset (0.5, 0) m), plus the rigid modes' omegas.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/free_modes_table.py
"""

from __future__ import annotations

from rodval import Base, paper_scene
from rodval.analysis.modes import model_modes, pair_modes

BODY = dict(kind="free", mass=50.0, inertia=20.0, hinge_offset=(0.5, 0.0))


def main() -> None:
    s = paper_scene(3, t_end=1.0)
    scene = s.with_(
        chain=s.chain.with_(l=1.5, m=3.0, EI=1e5, mu=0.5, kappa=50.0), loads=(), base=Base(**BODY)
    )
    ref = model_modes(scene, "exudyn", elements=16, count=8)
    print("exudyn rigid omegas (rad/s):", ref.omega[:3].tolist())
    print("exudyn flexible omegas (rad/s):", [f"{w:.7g}" for w in ref.flexible().omega[:8]])
    print("| p | gaps of modes 1-8 (native - exudyn) / exudyn | MAC min | native rigid omegas |")
    print("|---:|---|---:|---|")
    for p in range(1, 6):
        native = model_modes(scene, "full", shapes=p, count=8)
        pairs = pair_modes(native, ref)  # rel_gap = (exudyn - native) / native
        gaps = ", ".join(
            f"{(a - b) / b:.2g}" for a, b in zip(pairs["omega_a"][:8], pairs["omega_b"][:8])
        )
        print(f"| {p} | {gaps} | {pairs['mac'][:8].min():.4f} | {native.omega[:3].tolist()} |")


if __name__ == "__main__":
    main()
