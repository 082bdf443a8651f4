"""Scheduling a study's cases: warm worker processes on this machine, or a dask cluster.

Each case runs in a worker process (``rodval.study.worker``) that stays warm across cases, so
imports and compiled-kernel loading are paid once per worker, not once per case. A case that
exceeds its time limit, or whose worker crashes (even a segfault in a compiled library), kills
only that worker, which is replaced; its unfinished runs are recorded with status ``timeout``
or ``worker crashed``. On dask, every dask worker process keeps its own warm workers (one per
thread), so the same isolation and warm-up hold there.
"""

from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, as_completed
from typing import Any

from rodval.core.status import STATUS_CRASHED, STATUS_TIMEOUT
from rodval.study.worker import failed_run

BACKENDS = ("processes", "dask")

Payload = dict[str, Any]
Done = Callable[[Payload, list[dict[str, Any]]], None]


def complete_runs(
    payload: Payload, runs: list[dict[str, Any]], status: int, message: str
) -> list[dict[str, Any]]:
    """``runs`` plus a failed run (``status``, ``message``) for each model not in them."""
    done = {r["label"] for r in runs}
    name = payload["scene"].get("name", payload["case"])
    return runs + [
        failed_run(m, name, status, message) for m in payload["models"] if m["label"] not in done
    ]


class WarmWorker:
    """One persistent worker process; ``run`` sends a case and collects its runs."""

    _live: set[WarmWorker] = set()
    _live_lock = threading.Lock()

    def __init__(self) -> None:
        self.proc: subprocess.Popen[str] | None = None
        self.lines: queue.Queue[str | None] = queue.Queue()
        self.stderr = tempfile.TemporaryFile(mode="w+")

    def _start(self) -> None:
        self.lines = queue.Queue()
        self.stderr.seek(0)
        self.stderr.truncate()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "rodval.study.worker"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self.stderr,
            text=True,
            bufsize=1,
        )
        threading.Thread(target=self._read, args=(self.proc, self.lines), daemon=True).start()
        with WarmWorker._live_lock:
            WarmWorker._live.add(self)

    @staticmethod
    def _read(proc: subprocess.Popen[str], lines: queue.Queue[str | None]) -> None:
        assert proc.stdout is not None
        for line in proc.stdout:
            lines.put(line)
        lines.put(None)  # end of output: the process has exited

    def kill(self) -> None:
        if self.proc is not None:
            self.proc.kill()
            self.proc.wait()
            self.proc = None
        with WarmWorker._live_lock:
            WarmWorker._live.discard(self)

    def _crash_message(self) -> str:
        code = self.proc.wait() if self.proc is not None else None
        self.stderr.seek(0)
        tail = " | ".join(self.stderr.read().strip().splitlines()[-2:]) or "no message"
        return f"worker exited with code {code}: {tail}"

    def run(self, payload: Payload, timeout: float | None) -> list[dict[str, Any]]:
        """The case's run records; ``timeout`` (s) counts from sending the case."""
        if self.proc is None or self.proc.poll() is not None:
            self.kill()
            self._start()
            if self._next(None) is None:  # the "ready" line (imports done)
                message = self._crash_message()
                self.kill()
                return complete_runs(payload, [], STATUS_CRASHED, message)
        assert self.proc is not None and self.proc.stdin is not None
        deadline = None if timeout is None else time.monotonic() + timeout
        runs: list[dict[str, Any]] = []
        try:
            self.proc.stdin.write(json.dumps(payload) + "\n")
            self.proc.stdin.flush()
        except OSError:
            message = self._crash_message()
            self.kill()
            return complete_runs(payload, runs, STATUS_CRASHED, message)
        while True:
            try:
                line = self._next(deadline)
            except queue.Empty:
                self.kill()
                return complete_runs(
                    payload, runs, STATUS_TIMEOUT, f"case exceeded its time limit of {timeout:g} s"
                )
            if line is None:
                message = self._crash_message()
                self.kill()
                return complete_runs(payload, runs, STATUS_CRASHED, message)
            try:
                msg = json.loads(line)
            except json.JSONDecodeError:
                continue
            if "done" in msg:
                return runs
            if "label" in msg:
                runs.append(msg)

    def _next(self, deadline: float | None) -> str | None:
        if deadline is None:
            return self.lines.get()
        return self.lines.get(timeout=max(deadline - time.monotonic(), 0.0))

    @classmethod
    def kill_all(cls) -> None:
        with cls._live_lock:
            workers = list(cls._live)
        for w in workers:
            w.kill()


_local = threading.local()


def run_case_warm(payload: Payload, timeout: float | None = None) -> list[dict[str, Any]]:
    """Run a case on this thread's warm worker (started on first use, replaced after a
    timeout or crash). Used by the dask backend inside each dask worker."""
    worker = getattr(_local, "worker", None)
    if worker is None:
        worker = _local.worker = WarmWorker()
    return worker.run(payload, timeout)


def run_processes(payloads: list[Payload], done: Done, workers: int, timeout: float | None) -> None:
    """Run the cases on ``workers`` warm worker processes, calling ``done`` as each ends."""
    pool: queue.Queue[WarmWorker] = queue.Queue()
    for _ in range(min(workers, max(len(payloads), 1))):
        pool.put(WarmWorker())

    def task(payload: Payload) -> list[dict[str, Any]]:
        worker = pool.get()
        try:
            return worker.run(payload, timeout)
        finally:
            pool.put(worker)

    executor = ThreadPoolExecutor(max_workers=workers)
    try:
        futures = {executor.submit(task, p): p for p in payloads}
        for fut in as_completed(futures):
            done(futures[fut], fut.result())
    except BaseException:
        executor.shutdown(wait=False, cancel_futures=True)
        WarmWorker.kill_all()
        raise
    executor.shutdown()
    while not pool.empty():
        pool.get().kill()


def run_dask(payloads: list[Payload], done: Done, scheduler: str, timeout: float | None) -> None:
    """Run the cases on the dask.distributed cluster at ``scheduler``."""
    from dask.distributed import Client
    from dask.distributed import as_completed as dask_completed

    with Client(scheduler) as client:
        futures = client.map(run_case_warm, payloads, timeout=timeout, pure=False)
        by_key = {f.key: p for f, p in zip(futures, payloads)}
        for fut in dask_completed(futures):
            payload = by_key[fut.key]
            try:
                runs = fut.result()
            except Exception as exc:  # noqa: BLE001 - the task itself failed
                runs = complete_runs(
                    payload, [], STATUS_CRASHED, f"dask task failed: {type(exc).__name__}: {exc}"
                )
            done(payload, runs)


def default_workers() -> int:
    return os.cpu_count() or 1
