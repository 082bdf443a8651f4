"""Progress of a single run: the driver reports the time reached after each accepted step to
the reporter set for the current context (none by default, so library calls print nothing);
the compiled loop at its clock reads (``budget.read_interval``: at most every
``WALL_CHECK_EVALUATIONS`` evaluations) when a reporter is set.

``progress_bar`` is the CLI's reporter: a tqdm bar over [0, t_end] s on stderr that appears
only when the run lasts more than ``delay`` seconds and only on a terminal.
"""

from __future__ import annotations

import contextvars
from collections.abc import Callable, Iterator
from contextlib import contextmanager

Reporter = Callable[[float], None]
_reporter: contextvars.ContextVar[Reporter | None] = contextvars.ContextVar(
    "rodval_progress", default=None
)


def reporting() -> bool:
    """Whether a reporter is set for the current context (the compiled loop then reports)."""
    return _reporter.get() is not None


def report(t: float) -> None:
    """Tell the current reporter (if any) that the run reached time t (s)."""
    reporter = _reporter.get()
    if reporter is not None:
        reporter(t)


@contextmanager
def progress_bar(t_end: float, *, enabled: bool, delay: float = 2.0) -> Iterator[None]:
    """A progress bar for the runs inside the block (nothing when not ``enabled``)."""
    if not enabled:
        yield
        return
    from tqdm import tqdm

    bar = tqdm(
        total=t_end,
        unit="s",
        delay=delay,
        leave=False,
        bar_format="{l_bar}{bar}| t = {n:.4g} / {total:.4g} s [{elapsed}]",
    )

    def update(t: float) -> None:
        bar.update(max(t - bar.n, 0.0))

    token = _reporter.set(update)
    try:
        yield
    finally:
        _reporter.reset(token)
        bar.close()
