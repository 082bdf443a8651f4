"""Start-up cost of rodval's front door against its dependencies (issue 38).

Each command runs in a fresh process, ``--repeats`` times (default 5), round-robin so that a
slow spell of the shared machine falls on all of them; the table gives the min and median
wall time and each as a ratio to D, the import of the dependencies themselves:

    D         python -c "import numpy, scipy.integrate, pandas, numba"
    import    python -c "import rodval"
    --help    rodval --help
    --version rodval --version
    simulate  rodval simulate paper --model reduced --out TMP   (warm: numba's cache filled
              by a first, untimed run of the same command)

Targets (issue 38): --help and --version within 0.5 D, import rodval within 1.2 D, the warm
reduced simulate within 1.5 D (ratios of the medians). Run:

    .venv/bin/python benchmarks/startup.py [--repeats 5]
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
RODVAL = str(Path(PYTHON).with_name("rodval"))
SIMULATE = "rodval simulate paper --model reduced (warm)"
TARGETS = {"import rodval": 1.2, "rodval --help": 0.5, "rodval --version": 0.5, SIMULATE: 1.5}


def commands(out: Path) -> dict[str, list[str]]:
    return {
        "D": [PYTHON, "-c", "import numpy, scipy.integrate, pandas, numba"],
        "import rodval": [PYTHON, "-c", "import rodval"],
        "rodval --help": [RODVAL, "--help"],
        "rodval --version": [RODVAL, "--version"],
        SIMULATE: [RODVAL, "simulate", "paper", "--model", "reduced", "--out", str(out)],
    }


def wall(cmd: list[str]) -> float:
    """Seconds of one run of ``cmd`` in a fresh process (its output discarded)."""
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="timed runs of each (default 5)")
    args = parser.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="rodval-startup-"))
    try:
        cmds = commands(tmp / "run")
        env_note = os.environ.get("OMP_NUM_THREADS", "unset")
        wall(cmds[SIMULATE])  # fills numba's cache (compiles after a source change)
        times: dict[str, list[float]] = {name: [] for name in cmds}
        for _ in range(args.repeats):
            for name, cmd in cmds.items():
                times[name].append(wall(cmd))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    d_min, d_med = min(times["D"]), statistics.median(times["D"])
    print(
        f"python {sys.version.split()[0]}, {os.cpu_count()} CPUs, OMP_NUM_THREADS={env_note}; "
        f"{args.repeats} fresh processes each; D = import numpy, scipy.integrate, pandas, numba"
    )
    print()
    print("| command | min (s) | median (s) | min / D | median / D | target | holds |")
    print("|---|---|---|---|---|---|---|")
    for name, ts in times.items():
        lo, med = min(ts), statistics.median(ts)
        target = TARGETS.get(name)
        goal = "" if target is None else f"<= {target} D"
        holds = "" if target is None else ("yes" if med / d_med <= target else "NO")
        print(
            f"| {name} | {lo:.2f} | {med:.2f} | {lo / d_min:.2f} | {med / d_med:.2f} "
            f"| {goal} | {holds} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
