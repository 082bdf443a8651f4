"""Where a run's states go: the scene's output times (the trajectory) and the probe times of the
lock windows (``LockWindows``: the integrals a latch's lock record needs over the window after
the lock, ``rodval.mechanics.lock_window``).

Probe times are output times the integrators interpolate on their dense output like the
scene's own (every path: scipy's steps and the compiled loop): they never change a step, so a
run's trajectory is the same with or without them. A probe's state goes to its window at once,
while the system is still in the mode of that time. The audit grid (``AuditGrid``: a fixed
grid of [0, t_end]) is recorded beside the output times, on the same dense output: the
momentum and energy audits are read there, so that their residuals are the run's and not the
output grid's. The peak grid (``PeakGrid``: a finer fixed grid of [0, t_end]) and the lock
windows' probes give the states the run's peaks are read on (``SolverStats.peaks``), likewise
independent of the output times.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rodval.core.quantities import impulsive_locks, peak_values
from rodval.mechanics.lock_window import window_energies, window_nodes
from rodval.solvers.audit import audit_times
from rodval.solvers.system import OdeSystem

#: Intervals of the peak grid (``peak_times``): a run's peaks are read on PEAK_INTERVALS + 1
#: evenly spaced times of [0, t_end] of its dense output and on its lock windows' probes
#: (``rodval.mechanics.lock_window.window_nodes``: 256 in each window, the first bending period
#: after a lock), whatever the output times.
PEAK_INTERVALS = 4000
#: The most state values (doubles) the peak grid's states may hold: a system of N states
#: gets min(PEAK_INTERVALS, PEAK_MAX_VALUES // N) intervals (160 MB at most).
PEAK_MAX_VALUES = 20_000_000


def _add(total: float, terms: np.ndarray) -> float:
    """total + terms[0] + terms[1] + ... added left to right (a cumulative sum is
    sequential), as a loop of ``+=`` over the terms would."""
    if not terms.size:
        return total
    return float(np.cumsum(np.concatenate([[total], terms]))[-1])


class _Window:
    """One lock's window: its probes (the quadrature nodes of ``window_nodes`` and its end),
    the running sums of the lock record's impulses and the energy accounts at its end."""

    def __init__(self, record: dict[str, Any]):
        self.record = record
        self.t0 = float(record["t"])
        self.w = float(record["impulse_window"])
        self.hinge = int(record["hinge"])
        times, taper, mean = window_nodes(self.t0, self.w)
        # the window's end: a probe with zero weights, for the energies there
        self.times = np.append(times, self.t0 + self.w)
        self.taper, self.mean = np.append(taper, 0.0), np.append(mean, 0.0)
        self.i = 0
        #: mu + int lambda (1 - s/w) ds, mean H_out, int finite (1 - s/w) ds
        self.impulse = float(record["impulse_instant"])
        self.H = 0.0
        self.finite = 0.0
        self.taken = 0.0
        #: int P_ext ds, the lock's and later events' losses + int P_diss ds (J)
        self.work = 0.0
        self.dissipated = float(record.get("instant_energy_loss", 0.0))
        self.energies: tuple[float, ...] = ()

    def later_event(self, record: dict[str, Any]) -> None:
        """A later event inside the window: a lock adds its instantaneous impulse on this
        hinge, weighted by the taper at its time; any event its instantaneous energy loss."""
        s = float(record["t"]) - self.t0
        if not 0 <= s < self.w:
            return
        self.dissipated += float(record.get("instant_energy_loss", 0.0))
        held = record.get("held_hinges", [])
        if self.hinge in held:
            mu = record["angular_impulses"][held.index(self.hinge)]
            self.impulse += float(mu) * (1.0 - s / self.w)

    def take(self, system: OdeSystem, Y: np.ndarray) -> None:
        """The states Y (m, N) at the window's next m probes, all in the system's current
        mode: their integrands in one ``window_rows`` call, added to the running sums in
        probe order (``_add``: the same sums, term by term, as one probe at a time)."""
        m = len(Y)
        if not m:
            return
        probes = slice(self.i, self.i + m)
        terms = system.window_rows(self.times[probes], Y, self.hinge)
        taper, mean = self.taper[probes], self.mean[probes]
        self.impulse = _add(self.impulse, taper * terms[:, 0])
        self.H = _add(self.H, mean * terms[:, 1])
        self.finite = _add(self.finite, taper * terms[:, 2])
        self.taken = _add(self.taken, mean)
        self.work = _add(self.work, self.w * mean * terms[:, 3])
        self.dissipated = _add(self.dissipated, self.w * mean * terms[:, 4])
        self.i += m
        if self.i == self.times.size:  # the window's end
            self.energies = system.energy_parts(float(self.times[-1]), Y[-1])

    def finish(self) -> None:
        """Write the window's measures into the lock record (a window the run did not reach
        to its end: the impulses over the part reached, ``window_closed`` False, no energy
        accounts)."""
        rec = self.record
        rec["impulse"] = float(self.impulse)
        # mean over the window of H_out(tau) - H_out(0-) - int_0^tau finite ds
        rec["impulse_momentum"] = float(
            self.H - self.taken * rec["outboard_momentum_before"] - self.finite
        )
        rec["window_closed"] = self.i == self.times.size
        if rec["window_closed"]:
            rec.update(window_energies(rec, self.energies, self.work, self.dissipated))


class LockWindows:
    """The open lock windows of one run of ``system``."""

    def __init__(self, system: OdeSystem):
        self.system = system
        self.open: list[_Window] = []

    def event(self, record: dict[str, Any]) -> None:
        """After an event: its instantaneous impulses and losses go to the windows still
        open; a lock whose record declares an ``impulse_window`` opens one."""
        for win in self.open:
            win.later_event(record)
        if "impulse_window" in record:
            self.open.append(_Window(record))

    def pending(self) -> np.ndarray:
        """The probe times not yet taken, sorted."""
        if not self.open:
            return np.zeros(0)
        return np.sort(np.concatenate([w.times[w.i :] for w in self.open]))

    def take(self, times: np.ndarray, Y: np.ndarray) -> None:
        """The states Y (m, N) at probe times ``times`` (sorted, all in the system's current
        mode) to every window probing there: each window takes the run of its next probes
        found among ``times`` (a probe two windows share is one state for both)."""
        if not len(times):
            return
        for win in list(self.open):
            pending = win.times[win.i :]
            at = np.searchsorted(times, pending)
            found = at < len(times)
            found[found] = times[at[found]] == pending[found]
            m = int(np.argmin(found)) if not found.all() else found.size  # leading run
            win.take(self.system, Y[at[:m]])
            if win.i == win.times.size:
                win.finish()
                self.open.remove(win)

    def close(self) -> None:
        """At the end of the run: the windows not completed are written over the part
        reached."""
        for win in self.open:
            win.finish()
        self.open = []


class AuditGrid:
    """The audit grid (``audit.audit_times``: evenly spaced in [0, t_end]): times at which
    ``Outputs`` records a state like an output time (from the dense output: no step
    changes), and the energy audit's running [W_ext, D] with it (``audit.PowerLedger``). The
    momentum and energy audits read their residuals there (``Outputs.audit_rows``), so that
    a run's residuals do not depend on its output grid: read at the output times, one run's
    momentum residual was 0.067 with 11 output times and 0.052 with 201, its energy
    residual 0.0486 and 0.0510 (issue 47)."""

    def __init__(self, t_end: float):
        self.times = audit_times(t_end)


def peak_times(t_end: float, size: int) -> np.ndarray:
    """The peak grid (s): evenly spaced times of [0, t_end], PEAK_INTERVALS intervals, fewer
    for a system of ``size`` states whose grid would hold more than PEAK_MAX_VALUES values
    (at least one interval)."""
    intervals = max(1, min(PEAK_INTERVALS, PEAK_MAX_VALUES // max(size, 1)))
    return np.linspace(0.0, float(t_end), intervals + 1)


class PeakGrid:
    """The states a run's peaks are read on: the peak grid's (``peak_times``) and the lock
    windows' probes, taken from the dense output as ``Outputs`` writes them (never a step
    changed), and observed after the run (``read``) in the mode in effect at each time."""

    def __init__(self, t_end: float, size: int):
        self.times = peak_times(t_end, size)
        self.i = 0  # the grid times taken
        self._t: list[np.ndarray] = []
        self._Y: list[np.ndarray] = []

    def pending(self) -> np.ndarray:
        """The grid times not yet taken."""
        return self.times[self.i :]

    def take(self, times: np.ndarray, Y: np.ndarray, grid: int) -> None:
        """States Y (m, N) at ``times`` (s), of which ``grid`` are the next grid times."""
        if len(times):
            self._t.append(np.array(times, float))
            self._Y.append(np.array(Y, float))
        self.i += grid

    def read(
        self, system: OdeSystem, t_reached: float, events: list[dict[str, Any]]
    ) -> dict[str, Any]:
        """The run's peaks (``SolverStats.peaks``): ``peak_values`` of ``system.observe`` (the
        outputs' own quantity functions) at the states taken up to ``t_reached`` (s), in time
        order. A system without bending coordinates (``bending_mask`` None: the reduced and
        rigid chains) locks its chords plastically: a hinge that locked reports the lock's
        impulse, not a peak (``impulsive_locks``, from the run's ``events``)."""
        times = np.concatenate(self._t) if self._t else np.zeros(0)
        Y = np.concatenate(self._Y) if self._Y else np.zeros((0, 0))
        order = np.argsort(times, kind="stable")
        keep = order[times[order] <= t_reached]
        observed = system.observe(times[keep], Y[keep]) if keep.size else {}
        values = peak_values(times[keep], observed)
        if system.bending_mask() is None:
            impulsive_locks(values, events)
        grid = self.times.size - 1
        how = f"dense output ({grid} intervals, lock windows)"
        return {"read_on": how, "values": values}


def _recorded(scene: np.ndarray, grid: np.ndarray) -> tuple[np.ndarray, ...]:
    """(times, is-scene, is-grid) of the recorded rows: the scene's output times and the
    grid's, sorted, a time in both once."""
    times, inverse = np.unique(np.concatenate([scene, grid]), return_inverse=True)
    is_scene, is_grid = np.zeros(times.size, bool), np.zeros(times.size, bool)
    is_scene[inverse[: scene.size]] = True
    is_grid[inverse[scene.size :]] = True
    return times, is_scene, is_grid


#: The kinds of the times ``Outputs`` plans: a recorded row (an output or audit-grid time), a
#: lock window's probe, a peak-grid time.
RECORDED, PROBE, PEAK = 0, 1, 2


class Outputs:
    """States at the recorded times ``times``, rows of Y filled in time order: the scene's
    output times and the audit grid's (``audit``; ``scene_rows``, ``audit_rows`` split
    them), and at the lock windows' probe times (handed to ``windows``, not recorded) and
    the peak grid's (``peaks``: the probes' states and its own go there, not recorded)."""

    def __init__(
        self,
        times: np.ndarray,
        size: int,
        windows: LockWindows | None = None,
        audit: AuditGrid | None = None,
        peaks: PeakGrid | None = None,
    ):
        grid = audit.times if audit is not None else np.zeros(0)
        if grid.size:
            self.times, self.is_scene, self.is_grid = _recorded(np.asarray(times, float), grid)
        else:
            self.times = times
            self.is_scene = np.ones(times.size, bool)
            self.is_grid = np.zeros(times.size, bool)
        self.Y = np.empty((self.times.size, size))
        self.n = 0
        self.windows = windows
        self.peaks = peaks

    def scene_rows(self) -> np.ndarray:
        """Indices of the recorded rows reached that are scene output times."""
        return np.flatnonzero(self.is_scene[: self.n])

    def audit_rows(self) -> np.ndarray:
        """Indices of the recorded rows reached that are audit-grid times."""
        return np.flatnonzero(self.is_grid[: self.n])

    def _merged(self, recorded: np.ndarray, t: float = np.inf) -> tuple[np.ndarray, np.ndarray]:
        """(times, kind) of ``recorded`` times (kind RECORDED), the lock windows' probes
        (PROBE) and the peak grid's times not yet taken (PEAK) up to ``t`` (s), sorted."""
        probes = self.windows.pending() if self.windows is not None else np.zeros(0)
        grid = self.peaks.pending() if self.peaks is not None else np.zeros(0)
        grid = grid[: int(np.searchsorted(grid, t, side="right"))]  # one step's, not all
        times = np.concatenate([recorded, probes, grid])
        kind = np.repeat([RECORDED, PROBE, PEAK], [recorded.size, probes.size, grid.size])
        order = np.argsort(times, kind="stable")
        return times[order], kind[order]

    def upto(self, t: float) -> np.ndarray:
        """The recorded, probe and peak-grid times not yet written that are <= t, sorted."""
        end = int(np.searchsorted(self.times, t, side="right"))
        times, kind = self._merged(self.times[self.n : end], t)
        keep = times <= t
        self._plan = times[keep], kind[keep]
        return self._plan[0]

    def remaining(self) -> np.ndarray:
        """All recorded, probe and peak-grid times not yet written, sorted (for a loop that
        writes them in order, ``write`` after it)."""
        self._plan = self._merged(self.times[self.n :])
        return self._plan[0]

    def write(self, values: np.ndarray) -> np.ndarray:
        """values (k, N) for the first k times of the last ``upto`` / ``remaining``; returns
        the mask of those that are recorded times (output or audit grid: the rows an audit's
        ledger records)."""
        times, kind = self._plan[0][: len(values)], self._plan[1][: len(values)]
        mask: np.ndarray = kind == RECORDED
        kept = values[mask]
        self.Y[self.n : self.n + len(kept)] = kept
        self.n += len(kept)
        if self.windows is not None:
            self.windows.take(times[~mask], values[~mask])
        if self.peaks is not None:
            self.peaks.take(times[~mask], values[~mask], int(np.count_nonzero(kind == PEAK)))
        return mask
