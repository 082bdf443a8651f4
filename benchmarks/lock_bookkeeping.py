"""Lock bookkeeping at compiled speed (issue 50): the reduced model's latched four-panel
deployment (``rodval.bench.fast_path.four_panel_wing``, the scene of studies/deployment.toml)
and the rigid two-rod latch (``rodval.bench.stiffness.rigid_latch``), side by side.

Per scene: the integration wall (``stats.wall_s``, best of ``--repeats`` after one warm-up
run, so numba compilation is excluded), the locks and lock-window probes of the run, and the
Python cost of the lock bookkeeping per lock: the lock records (``lock_records.lock_record``,
inside the event's jump) plus the windows' integrands (``LockWindows.take``), timed by
wrapping them (best repeat). Then cProfile's top entries by cumulative time over the repeats
of the wing.

With ``--against DIR`` the same measurement runs on the rodval tree in DIR (e.g. an earlier
commit's, ``git archive <commit> rodval | tar -x -C DIR``) in a subprocess, repeats
interleaved with this tree's, and the ratios before / after are printed: one run, one
machine.

Run:  OMP_NUM_THREADS=1 python benchmarks/lock_bookkeeping.py [--repeats 7] [--against DIR]
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import os
import pstats
import subprocess
import sys
import time
from typing import Any

SCENES = ("four_panel_wing", "rigid_latch")


def _scene(name: str):
    from rodval.bench.fast_path import four_panel_wing
    from rodval.bench.stiffness import rigid_latch

    return four_panel_wing() if name == "four_panel_wing" else rigid_latch()


class _Clock:
    """Wall seconds spent inside wrapped functions (not nested)."""

    def __init__(self) -> None:
        self.total = 0.0
        self.depth = 0
        self.wrapped: list[tuple[Any, str, Any]] = []

    def wrap(self, owner: Any, name: str) -> None:
        inner = getattr(owner, name)

        def timed(*args, **kwargs):
            self.depth += 1
            start = time.perf_counter()
            try:
                return inner(*args, **kwargs)
            finally:
                self.depth -= 1
                if self.depth == 0:
                    self.total += time.perf_counter() - start

        setattr(owner, name, timed)
        self.wrapped.append((owner, name, inner))

    def restore(self) -> None:
        """Put the wrapped functions back."""
        for owner, name, inner in self.wrapped:
            setattr(owner, name, inner)
        self.wrapped = []


def measure(repeats: int) -> dict[str, dict[str, float]]:
    """Per scene: best wall (s), locks, probes, bookkeeping per lock (s) on this process's
    rodval."""
    from rodval.models.hinge_items import lock_records
    from rodval.models.registry import simulate
    from rodval.solvers import outputs

    clock = _Clock()
    clock.wrap(lock_records, "lock_record")
    clock.wrap(outputs.LockWindows, "take")
    out = {}
    for name in SCENES:
        scene = _scene(name)
        simulate(scene, "reduced")  # warm-up: compilation
        walls, books = [], []
        for _ in range(repeats):
            clock.total = 0.0
            tr = simulate(scene, "reduced")
            walls.append(tr.stats.wall_s)
            books.append(clock.total)
        locks = [e for e in tr.events if "impulse_window" in e]
        probes = sum(257 for _ in locks)  # WINDOW_PANELS * WINDOW_NODES + the window's end
        out[name] = {
            "wall_s": min(walls),
            "locks": len(locks),
            "probes": probes,
            "bookkeeping_per_lock_s": min(books) / max(len(locks), 1),
        }
    clock.restore()
    return out


def profile(repeats: int, top: int = 12) -> str:
    """cProfile's top entries (cumulative) over ``repeats`` runs of the wing, after a warm-up."""
    from rodval.models.registry import simulate

    scene = _scene("four_panel_wing")
    simulate(scene, "reduced")
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(repeats):
        simulate(scene, "reduced")
    prof.disable()
    text = io.StringIO()
    pstats.Stats(prof, stream=text).sort_stats("cumtime").print_stats(top)
    return text.getvalue()


def _subprocess(tree: str, repeats: int) -> dict[str, dict[str, float]]:
    env = dict(os.environ, PYTHONPATH=tree, OMP_NUM_THREADS="1")
    cmd = [sys.executable, __file__, "--json", "--repeats", str(repeats)]
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _merge(runs: list[dict[str, dict[str, float]]]) -> dict[str, dict[str, float]]:
    """The best of several measurements, per scene and figure (counts from the first)."""
    best = {}
    for name in SCENES:
        best[name] = dict(runs[0][name])
        for key in ("wall_s", "bookkeeping_per_lock_s"):
            best[name][key] = min(r[name][key] for r in runs)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds with --against")
    parser.add_argument("--against", help="an earlier rodval tree (a folder holding rodval/)")
    parser.add_argument("--json", action="store_true", help="print this tree's figures as JSON")
    args = parser.parse_args()
    if args.repeats < 1:
        raise SystemExit(f"--repeats must be >= 1, got {args.repeats}")
    if args.json:
        print(json.dumps(measure(args.repeats)))
        return
    import rodval

    here = os.path.dirname(os.path.dirname(os.path.abspath(rodval.__file__)))
    if args.against:
        before, after = [], []
        for _ in range(args.rounds):
            before.append(_subprocess(args.against, args.repeats))
            after.append(_subprocess(here, args.repeats))
        old, new = _merge(before), _merge(after)
    else:
        old, new = None, measure(args.repeats)
    print(f"rodval: {here}" + (f"   before: {args.against}" if old else ""))
    head = f"{'scene (reduced)':<18}{'locks':>6}{'probes':>7}{'wall_s':>10}{'per_lock_s':>12}"
    if old:
        head += f"{'wall_before':>13}{'per_lock_before':>17}{'wall_ratio':>12}{'lock_ratio':>12}"
    print(head)
    for name in SCENES:
        r = new[name]
        line = (
            f"{name:<18}{r['locks']:>6}{r['probes']:>7}{r['wall_s']:>10.4f}"
            f"{r['bookkeeping_per_lock_s']:>12.5f}"
        )
        if old:
            o = old[name]
            line += (
                f"{o['wall_s']:>13.4f}{o['bookkeeping_per_lock_s']:>17.5f}"
                f"{o['wall_s'] / r['wall_s']:>12.2f}"
                f"{o['bookkeeping_per_lock_s'] / r['bookkeeping_per_lock_s']:>12.2f}"
            )
        print(line)
    print()
    print(profile(args.repeats))


if __name__ == "__main__":
    main()
