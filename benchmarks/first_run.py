"""The first run of each kind of scene with numba's cache empty, against D (issue 50).

Each row is one ``rodval simulate`` in a fresh process; D is a process importing numpy,
scipy.integrate, pandas and numba (``benchmarks/startup.py``), measured in the same run
(``--repeats`` times, median), so the ratios hold on a loaded machine too. Rows:

    cold        the scene's first run with an empty cache (NUMBA_CACHE_DIR a new folder)
    after full  the scene's first run after one ``simulate paper --model full`` filled the
                cache (a second kind of scene after the first)
    warm        the scene again on the filled cache (its run speed)

Scenes: the paper example (full, reduced), the latched wing with a stop
(``studies/scenes/wing_stop_latches.toml`` over 2 s: "auto" takes the exact kinematics),
the latched wing on a free 800 kg body (``studies/scenes/wing6_spacecraft.toml`` over 2 s:
exact kinematics on a free base). Targets: cold paper full, cold free-base and cold
exact-kinematics within 10 D, "after full" within 5 D.

``--kernels SCENE`` instead prints, for one cold run in this process, the seconds numba spent
compiling each function (its ``numba:compile`` events: exclusive of the functions it compiled
while typing it, then inclusive), largest first.

    .venv/bin/python benchmarks/first_run.py [--repeats 3] [--root SRC]
    .venv/bin/python benchmarks/first_run.py --kernels paper-full

(``--root SRC`` runs the rodval package found in SRC, e.g. a copy of an older tree.)
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PYTHON = sys.executable
REPO = Path(__file__).resolve().parents[1]
SCENES: dict[str, list[str]] = {
    "paper-full": ["paper", "--model", "full"],
    "paper-reduced": ["paper", "--model", "reduced"],
    "latched-wing": [str(REPO / "studies/scenes/wing_stop_latches.toml"), "--model", "full"],
    "free-wing": [str(REPO / "studies/scenes/wing6_spacecraft.toml"), "--model", "full"],
}
TWO_SECONDS = ["--t-end", "2"]
TARGETS = {"cold paper-full": 10.0, "cold latched-wing": 10.0, "cold free-wing": 10.0}
D_COMMAND = [PYTHON, "-c", "import numpy, scipy.integrate, pandas, numba"]


def simulate_command(scene: str, out: Path) -> list[str]:
    """``python -m rodval simulate`` of ``scene`` (a key of SCENES) into ``out``."""
    extra = TWO_SECONDS if scene in ("latched-wing", "free-wing") else []
    return [PYTHON, "-m", "rodval", "simulate", *SCENES[scene], *extra, "--out", str(out)]


def wall(cmd: list[str], env: dict[str, str]) -> float:
    """Seconds of one run of ``cmd`` in a fresh process (its output discarded)."""
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    return time.perf_counter() - t0


def environment(cache: Path, root: Path | None) -> dict[str, str]:
    """The process environment: numba's cache in ``cache``, rodval from ``root`` if given."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    env.setdefault("OMP_NUM_THREADS", "1")
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    if root is not None:
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(root), env.get("PYTHONPATH")]))
    return env


def measure(tmp: Path, repeats: int, root: Path | None) -> dict[str, float]:
    """Seconds of every row (D the median of ``repeats``), each cold row on a new cache."""
    times: dict[str, float] = {}
    d_times = []
    for k, scene in enumerate(SCENES):
        d_times.append(wall(D_COMMAND, environment(tmp / "d", root)))
        cache = tmp / f"cache-{k}"
        env = environment(cache, root)
        times[f"cold {scene}"] = wall(simulate_command(scene, tmp / f"out-{k}"), env)
        times[f"warm {scene}"] = wall(simulate_command(scene, tmp / f"out-{k}"), env)
    for scene in ("latched-wing", "free-wing", "paper-reduced"):
        cache = tmp / f"after-{scene}"
        env = environment(cache, root)
        wall(simulate_command("paper-full", tmp / f"first-{scene}"), env)
        times[f"after full {scene}"] = wall(simulate_command(scene, tmp / f"out-{scene}"), env)
    d_times += [wall(D_COMMAND, environment(tmp / "d", root)) for _ in range(repeats)]
    times["D"] = statistics.median(d_times)
    return times


def table(times: dict[str, float]) -> list[str]:
    """The markdown rows: seconds, ratio to D, target, whether it holds."""
    d = times["D"]
    lines = ["| run | wall (s) | / D | target | holds |", "|---|---|---|---|---|"]
    for name, seconds in times.items():
        target = TARGETS.get(name, 5.0 if name.startswith("after full") else None)
        goal = "" if target is None else f"<= {target:g} D"
        holds = "" if target is None else ("yes" if seconds / d <= target else "NO")
        lines.append(f"| {name} | {seconds:.1f} | {seconds / d:.1f} | {goal} | {holds} |")
    return lines


def kernel_seconds(argv: list[str]) -> tuple[float, dict[str, list[float]]]:
    """Run ``rodval`` with ``argv`` in this process; per compiled function: [compilations,
    exclusive s, inclusive s] from numba's compile events, and the wall time."""
    from numba.core import event

    rows: dict[str, list[float]] = {}
    stack: list[list] = []

    class Listener(event.Listener):
        def on_start(self, ev: event.Event) -> None:
            func = getattr(ev.data.get("dispatcher"), "py_func", None)
            name = f"{func.__module__}.{func.__qualname__}" if func else "?"
            stack.append([time.perf_counter(), 0.0, name])

        def on_end(self, ev: event.Event) -> None:
            t0, inner, name = stack.pop()
            spent = time.perf_counter() - t0
            if stack:
                stack[-1][1] += spent
                if not name.startswith("rodval"):  # numba's own: charged to its rodval caller
                    outer = next((s[2] for s in reversed(stack) if s[2].startswith("rodval")), "")
                    name = f"{name.split('.<locals>')[0]} (in {outer.rsplit('.', 1)[-1]})"
            row = rows.setdefault(name, [0, 0.0, 0.0])
            row[0] += 1
            row[1] += spent - inner
            row[2] += spent

    event.register("numba:compile", Listener())
    from rodval.cli import main

    t0 = time.perf_counter()
    main(argv)
    return time.perf_counter() - t0, rows


def print_kernels(scene: str, tmp: Path) -> None:
    """The per-function compile table of one cold run of ``scene`` (this process)."""
    if "numba" in sys.modules:
        raise ValueError("--kernels must run before numba is imported")
    os.environ["NUMBA_CACHE_DIR"] = str(tmp / "cache")
    extra = TWO_SECONDS if scene in ("latched-wing", "free-wing") else []
    argv = ["simulate", *SCENES[scene], *extra, "--out", str(tmp / "out")]
    seconds, rows = kernel_seconds(argv)
    total = sum(row[1] for row in rows.values())
    print(f"{scene}: wall {seconds:.1f} s, of which compiling {total:.1f} s")
    print("| function | compilations | exclusive (s) | inclusive (s) |")
    print("|---|---|---|---|")
    for name, (count, exclusive, inclusive) in sorted(rows.items(), key=lambda kv: -kv[1][1]):
        if exclusive >= 0.2:
            print(f"| {name} | {count:.0f} | {exclusive:.2f} | {inclusive:.2f} |")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="extra runs of D (default 3)")
    parser.add_argument("--root", type=Path, default=None, help="folder holding rodval/")
    parser.add_argument("--kernels", choices=sorted(SCENES), default=None)
    args = parser.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="rodval-first-run-"))
    try:
        if args.kernels is not None:
            print_kernels(args.kernels, tmp)
            return 0
        times = measure(tmp, args.repeats, args.root)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    print(
        f"python {sys.version.split()[0]}, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}; "
        f"D = import numpy, scipy.integrate, pandas, numba = {times['D']:.2f} s (median)"
    )
    print()
    print("\n".join(table(times)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
