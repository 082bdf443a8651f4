"""The reduced model at scale, phase by phase: the paper chain of n rods (pulse at the last
node), 0..2 s, rtol 1e-6, atol 1e-8, output phi at t = 0, 1, 2 s, compiled DOP853 ("auto").

Phases (s, each measured once after a warm-up run at n = 64 in the same process, so that
loading the kernels from numba's cache is excluded): scene (``paper_scene``), set-up
(``ReducedSystem``: per-rod constants, the first evaluation), integration (the driver's
``stats.wall_s``), observation (the rest of ``integrate``: the guard's set-up, the
trajectory); beside them, not summed: the per-rod constants alone (``banded_constants``) and
the banded LU's equilibration (since this change run only on the banded LU's first use,
``reduced_band_lu.equilibrate``; before it, part of the constants). ``--command`` adds the
whole ``rodval simulate`` command in a fresh process (imports, reading, writing included).

``--before REV`` runs the same phases in a subprocess on ``git archive REV`` (read-only;
numba compiles that tree's kernels once, excluded by the warm-up), so that before and after
are measured in one run on the same machine; ratios = before / after.

Run: OMP_NUM_THREADS=1 .venv/bin/python benchmarks/reduced_scale.py 10000 100000 1000000 \\
         --before HEAD --before-max-n 100000 --command
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from io import BytesIO
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
TIMES = (0.0, 1.0, 2.0)
PHASES = ("scene_s", "setup_s", "integration_s", "observation_s")


def phases(n: int) -> dict:
    """One run of the scale scene at n rods, timed phase by phase (module docstring)."""
    from rodval.core.scene import paper_scene
    from rodval.core.settings import IntegratorSettings
    from rodval.models.bending import reduced_band_lu as lu
    from rodval.models.bending import reduced_banded as rb
    from rodval.models.presets.reduced import ReducedSystem
    from rodval.solvers.driver import integrate

    clock = time.perf_counter
    row: dict = {"n": n}
    start = clock()
    scene = paper_scene(n, times=TIMES, outputs=("phi",))
    row["scene_s"] = clock() - start
    start = clock()
    system = ReducedSystem(scene)
    row["setup_s"] = clock() - start
    settings = IntegratorSettings("auto", rtol=1e-6, atol=1e-8)
    start = clock()
    traj = integrate(system, scene, settings, model="reduced")
    total = clock() - start
    row["integration_s"] = traj.stats.wall_s
    row["observation_s"] = total - traj.stats.wall_s
    row["whole_s"] = sum(row[p] for p in PHASES)
    row["nfev"] = traj.stats.nfev
    start = clock()
    Cst = rb.banded_constants(system.cc, scene.chain)
    row["constants_s"] = clock() - start
    if hasattr(lu, "equilibrate"):  # this change: the equilibration on the LU's first use
        start = clock()
        lu.equilibrate(Cst)
        row["equilibration_s"] = clock() - start
    else:  # before: inside banded_constants
        start = clock()
        lu.ruiz_equilibrate(lu.band_magnitudes(Cst), np.ones(7 * n), np.ones(7 * n), 20)
        row["equilibration_s"] = clock() - start
    row["phi_tip_2s"] = float(np.asarray(traj["phi"])[-1, -1])
    return row


def measure(n_values: list[int]) -> list[dict]:
    phases(64)  # warm-up: loads (or compiles) every kernel of the path
    return [phases(n) for n in n_values]


def command_s(n: int, out: Path) -> float:
    """Wall time of the whole ``rodval simulate`` command in a fresh process."""
    args = [sys.executable, "-m", "rodval", "simulate", "paper", "--model", "reduced"]
    args += ["--set", f"n={n}", "--set", 'outputs=["phi"]', "--rtol", "1e-6", "--atol", "1e-8"]
    args += ["--times", ",".join(f"{t:g}" for t in TIMES), "--out", str(out)]
    start = time.perf_counter()
    subprocess.run(args, check=True, cwd=ROOT, capture_output=True)
    return time.perf_counter() - start


def before_rows(rev: str, n_values: list[int]) -> list[dict]:
    """``measure`` on ``git archive rev`` in a subprocess."""
    tree = Path(tempfile.mkdtemp(prefix="rodval_before_"))
    blob = subprocess.run(["git", "archive", rev], cwd=ROOT, check=True, capture_output=True)
    with tarfile.open(fileobj=BytesIO(blob.stdout)) as tar:
        tar.extractall(tree, filter="data")
    env = dict(os.environ, PYTHONPATH=str(tree))
    code = (
        f"import json, sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); "
        "import reduced_scale as r; "
        f"print(json.dumps(r.measure({n_values!r})))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=tree, env=env, check=True, capture_output=True
    )
    return json.loads(done.stdout.decode().strip().splitlines()[-1])


def table(after: list[dict], before: list[dict], commands: dict[int, float]) -> str:
    old = {r["n"]: r for r in before}
    cols = [*PHASES, "whole_s", "constants_s", "equilibration_s"]
    head = ["n", "nfev"] + [c[:-2] for c in cols] + (["command"] if commands else [])
    lines = ["| " + " | ".join(head) + " |", "|" + "---:|" * len(head)]
    for r in after:
        cells = [str(r["n"]), str(r["nfev"])]
        for c in cols:
            cell = f"{r[c]:.3g}"
            if r["n"] in old:
                cell += f" ({old[r['n']][c]:.3g}, {old[r['n']][c] / max(r[c], 1e-9):.3g}x)"
            cells.append(cell)
        if commands:
            cells.append(f"{commands[r['n']]:.3g}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n", type=int, nargs="*", default=[10000, 100000, 1000000])
    parser.add_argument("--before", help="git revision to measure alongside (e.g. HEAD)")
    parser.add_argument("--before-max-n", type=int, default=10**9, help="largest n of --before")
    parser.add_argument("--command", action="store_true", help="time rodval simulate too")
    opts = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    before: list[dict] = []
    if opts.before:
        small = [n for n in opts.n if n <= opts.before_max_n]
        before = before_rows(opts.before, small)
    after = measure(opts.n)
    commands = {}
    if opts.command:
        with tempfile.TemporaryDirectory() as tmp:
            command_s(64, Path(tmp) / "warm")
            commands = {n: command_s(n, Path(tmp) / f"n{n}") for n in opts.n}
    for r in after:
        o = next((b for b in before if b["n"] == r["n"]), None)
        same = ""
        if o is not None:
            same = f"; phi(2 s, tip) before - after = {o['phi_tip_2s'] - r['phi_tip_2s']:.1e}"
        print(f"n = {r['n']}: whole {r['whole_s']:.3f} s{same}")
    print("\nseconds after the change (before, before/after)\n")
    print(table(after, before, commands))


if __name__ == "__main__":
    main()
