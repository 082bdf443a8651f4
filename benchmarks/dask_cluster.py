"""Start a dask.distributed LocalCluster for ``rodval study --backend dask`` and keep it up.

Prints the scheduler address (and writes it to --address-file), then waits until Ctrl-C or
SIGTERM and closes the cluster. Each dask worker is a process with ``--threads`` threads;
every thread runs its cases on its own warm rodval worker process (rodval.study.schedule),
so W = workers x threads cases run at once.

Run: OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/dask_cluster.py --workers 2 \\
         --address-file /tmp/dask_address
     rodval study studies/scale_study_10k.toml --out DIR --backend dask \\
         --scheduler "$(cat /tmp/dask_address)"

On several machines, start ``dask scheduler`` on one and ``dask worker tcp://HOST:8786`` on
each of the others instead (docs/studies.md).
"""

from __future__ import annotations

import argparse
import signal
import threading
from pathlib import Path

from dask.distributed import LocalCluster


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2, help="dask worker processes")
    ap.add_argument("--threads", type=int, default=1, help="threads per dask worker")
    ap.add_argument("--port", type=int, default=0, help="scheduler port (0: any free)")
    ap.add_argument("--address-file", type=Path, help="write the scheduler address here")
    args = ap.parse_args()
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    with LocalCluster(
        n_workers=args.workers,
        threads_per_worker=args.threads,
        processes=True,
        scheduler_port=args.port,
        dashboard_address=None,
    ) as cluster:
        print(cluster.scheduler_address, flush=True)
        if args.address_file:
            args.address_file.write_text(cluster.scheduler_address + "\n")
        try:
            while not stop.wait(1.0):
                pass
        except KeyboardInterrupt:
            pass


if __name__ == "__main__":
    main()
