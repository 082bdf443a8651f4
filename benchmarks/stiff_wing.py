"""The 6-panel latched wing of issue 37 (``exudyn_speed.wing_scene``: 1.2 m, 8 kg panels,
folded zig-zag, latches on hinges 1..5) over 10 s on the default settings, with stiff panels:
EI 2e4 (the user's wing, the yardstick), 1e8 and 1e9, undamped and with 1 % bending damping
(``bending_damping = { ratio = 0.01 }``, ``rodval.core.damping``), full and reduced models.
Prints wall time, time reached, evaluations, lock times and how each run ended.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/stiff_wing.py
"""

from __future__ import annotations

import time

from exudyn_speed import wing_scene

from rodval.core.damping import bending_damping_for_ratio
from rodval.models import simulate


def main() -> None:
    print("| EI | ratio | model | wall (s) | t reached (s) | evaluations | locks (s) | ended |")
    print("|---|---|---|---|---|---|---|---|")
    for EI in (2e4, 1e8, 1e9):
        for ratio in (0.0, 0.01):
            base = wing_scene(10.0)
            chain = base.chain.with_(EI=EI)
            c = bending_damping_for_ratio(ratio, chain.l, chain.m, chain.EI)
            scene = base.with_(chain=chain.with_(bending_damping=c))
            for model in ("full", "reduced"):
                start = time.perf_counter()
                tr = simulate(scene, model)
                wall = time.perf_counter() - start
                st = tr.stats
                locks = ", ".join(f"{ev['t']:.4f}" for ev in tr.events)
                ended = st.message.split(";")[0]
                print(
                    f"| {EI:g} | {ratio:g} | {model} | {wall:.1f} | {st.t_reached:.3f} | "
                    f"{st.nfev} | {locks} | {ended} |"
                )


if __name__ == "__main__":
    main()
