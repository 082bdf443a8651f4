"""Assertions and runners shared by the test modules (no test module imports another): a
command's one-line refusal, running the CLI in-process, a hang guard."""

from __future__ import annotations

import signal
import subprocess
import time

from rodval.cli import main


def assert_refused(proc: subprocess.CompletedProcess, words: list[str]) -> None:
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    for w in words:
        assert w in lines[0], (w, lines[0])


def run_main(capsys, *args: str) -> subprocess.CompletedProcess:
    try:
        code = main(list(args))
    except SystemExit as exc:
        code = exc.code
    out = capsys.readouterr()
    return subprocess.CompletedProcess(args, code, out.out, out.err)


def one_line(capsys) -> str:
    """The one line a refused command printed on stderr (no traceback, no internal error)."""
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err and "internal error" not in err, err
    return lines[0]


class TimeLimit:
    """Fails the test when the block takes longer than ``seconds``: a SIGALRM for Python code,
    and the elapsed time afterwards for compiled loops (which a signal cannot interrupt)."""

    def __init__(self, seconds: float):
        self.seconds = seconds

    def __enter__(self):
        def alarm(signum, frame):
            raise AssertionError(f"hang: more than {self.seconds:g} s")

        self.old = signal.signal(signal.SIGALRM, alarm)
        signal.setitimer(signal.ITIMER_REAL, self.seconds)
        self.start = time.perf_counter()
        return self

    def __exit__(self, *exc):
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, self.old)
        assert time.perf_counter() - self.start < self.seconds, "hang"
        return False
