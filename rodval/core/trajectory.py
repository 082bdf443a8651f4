"""What a simulation returns: requested quantities at requested times, and how the run ended."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from rodval.core.run_result import SolverStats
from rodval.core.status import STATUS_SUCCESS

if TYPE_CHECKING:
    import pandas as pd

#: ``SolverStats`` (the run's result, ``rodval.core.run_result``) is named here too, where a
#: trajectory's readers have always imported it.
__all__ = [
    "RESULT_KEYS",
    "RUN_SETTINGS",
    "SolverStats",
    "Trajectory",
    "UnknownQuantity",
    "finish",
    "result_fields",
]


class UnknownQuantity(KeyError, ValueError):
    """A quantity a trajectory does not hold (a KeyError for ``traj[q]``, a ValueError for
    rodval's one-line error reporting); its message names it and the available ones."""

    def __str__(self) -> str:
        return str(self.args[0])


@dataclass
class Trajectory:
    """Requested quantities of one run.

    ``values[q]`` is an array of shape (len(times), n_k) for quantity q; ``k_index[q]`` gives
    the k label of each column (rods 1..n for phi/dphi/alpha/beta, nodes 0..n for x/y, 0 for
    energies). ``times`` holds only the output times the run actually reached: a failed run
    returns its partial history and never NaN padding.
    """

    model: str
    scene_name: str
    times: np.ndarray
    values: dict[str, np.ndarray]
    k_index: dict[str, np.ndarray]
    stats: SolverStats
    #: The integrator settings as the run used them (for "auto": the method that ran, and
    #: ``requested_method``); a reference model's own integrator (method, step).
    settings: dict[str, Any] = field(default_factory=dict)
    #: The model's options (e.g. coefficients, kernel; exudyn's discretization).
    options: dict[str, Any] = field(default_factory=dict)
    #: State events in time order (e.g. latches locking), each a plain dict with "t" (s),
    #: "label" and the model's own measures.
    events: list[Any] = field(default_factory=list)
    #: The rodval.Scene the run simulated (set by ``Model.simulate``; None for trajectories
    #: read from files or records, whose scene is in run.json / the case record). ``compare``
    #: refuses two runs of different scenes. Not part of equality or of ``to_dict``.
    scene: Any = field(default=None, compare=False, repr=False)

    @classmethod
    def failed(
        cls,
        model: str,
        scene_name: str,
        stats: SolverStats,
        *,
        settings: dict[str, Any] | None = None,
        options: dict[str, Any] | None = None,
    ) -> Trajectory:
        """The trajectory of a run that produced no output time (a set-up error, a timeout, a
        crashed worker): no times, no values; ``stats`` says how it ended. The one
        constructor of a failed run, for every model and the study runner (through
        ``finish``)."""
        return finish(stats, model=model, scene_name=scene_name, settings=settings, options=options)

    @property
    def success(self) -> bool:
        return self.stats.success

    def __getitem__(self, quantity: str) -> np.ndarray:
        """Values (nt, nk) of ``quantity``; UnknownQuantity (a KeyError) naming it and the
        available quantities when the run does not hold it."""
        if not isinstance(quantity, str) or quantity not in self.values:
            raise UnknownQuantity(
                f"quantity {quantity!r} is not in this trajectory (available: "
                f"{', '.join(self.values) or 'none'}; a scene's outputs choose them)"
            )
        return self.values[quantity]

    @property
    def quantities(self) -> tuple[str, ...]:
        return tuple(self.values)

    def at(self, quantity: str, t: float, k: int) -> float:
        """Value of ``quantity`` for index k at output time t (s, exact match of t within
        1e-12 s); ValueError naming t or k when the trajectory has no such output time or
        label, UnknownQuantity for a quantity it does not hold."""
        values = self[quantity]
        i = np.flatnonzero(np.isclose(self.times, t, rtol=0, atol=1e-12))
        if i.size == 0:
            raise ValueError(
                f"t = {t!r} s is not an output time of this trajectory "
                f"({self.times.size} times in [{self.times.min(initial=0):g}, "
                f"{self.times.max(initial=0):g}] s; the scene's times choose them)"
            )
        j = np.flatnonzero(self.k_index[quantity] == k)
        if j.size == 0:
            raise ValueError(
                f"k = {k!r} is not a label of {quantity!r} "
                f"(allowed: {', '.join(map(str, self.k_index[quantity]))})"
            )
        return float(values[i[0], j[0]])

    def result_dict(self) -> dict[str, Any]:
        """The run's result (``RESULT_KEYS``: model, options, settings, stats, events), plain
        and JSON-ready: what ``to_dict`` (a study's case record) and run.json
        (``rodval.report.run_files.write_run``) hold alike; read back by ``result_fields``."""
        return {
            "model": self.model,
            "options": self.options,
            "settings": self.settings,
            "stats": self.stats.to_dict(),
            "events": self.events,
        }

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready form (lists and numbers); inverse of ``from_dict``."""
        return {
            "scene_name": self.scene_name,
            "times": self.times.tolist(),
            "values": {q: v.tolist() for q, v in self.values.items()},
            "k_index": {q: k.tolist() for q, k in self.k_index.items()},
            **self.result_dict(),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Trajectory:
        times = np.asarray(d["times"], dtype=float)
        k_index = {q: np.asarray(k, dtype=int) for q, k in d["k_index"].items()}
        return cls(
            model=d["model"],
            scene_name=d["scene_name"],
            times=times,
            values={
                q: np.asarray(v, dtype=float).reshape(times.size, k_index[q].size)
                for q, v in d["values"].items()
            },
            k_index=k_index,
            **result_fields(d),
        )

    @classmethod
    def from_frame(cls, frame: pd.DataFrame, model: str, scene_name: str = "scene") -> Trajectory:
        """Inverse of ``to_frame`` (columns t, quantity, k, value; every (t, k) of a quantity
        present). The stats are not in the frame: they are left at their defaults."""
        times = np.unique(frame["t"].to_numpy(float))
        values, k_index = {}, {}
        for q, part in frame.groupby("quantity", sort=False):
            wide = part.pivot(index="t", columns="k", values="value")
            if wide.shape[0] != times.size or wide.isna().to_numpy().any():
                raise ValueError(f"frame of quantity {q!r} does not cover every (t, k)")
            values[q] = wide.to_numpy(float)
            k_index[q] = wide.columns.to_numpy(int)
        return cls(
            model=model,
            scene_name=scene_name,
            times=times,
            values=values,
            k_index=k_index,
            stats=SolverStats(),
        )

    def to_frame(self, wide: bool = False) -> pd.DataFrame:
        """Tidy table with columns t, quantity, k, value; ``wide=True``: one row per output
        time, a column t (s) and one column ``quantity[k]`` per quantity and index, in the
        trajectory's order (units: ``rodval.core.scene.UNITS``)."""
        if not isinstance(wide, bool):
            raise ValueError(f"wide must be True or False, got {wide!r}")
        import pandas as pd  # imported by the tables that need it, not by every run

        if wide:
            columns = {"t": self.times}
            for q, arr in self.values.items():
                for j, k in enumerate(self.k_index[q]):
                    columns[f"{q}[{int(k)}]"] = arr[:, j]
            return pd.DataFrame(columns)
        parts = []
        for q, arr in self.values.items():
            nt, nk = arr.shape
            parts.append(
                pd.DataFrame(
                    {
                        "t": np.repeat(self.times, nk),
                        "quantity": q,
                        "k": np.tile(self.k_index[q], nt),
                        "value": arr.ravel(),
                    }
                )
            )
        if not parts:
            return pd.DataFrame(columns=["t", "quantity", "k", "value"])
        return pd.concat(parts, ignore_index=True)


#: The integrator settings that change what a run computes (``Trajectory.settings``; the
#: ones that only stop a run, budgets and the divergence guard, are not among them): every
#: table of runs shows each (a study's runtime.csv, its report's Models table), so that a run
#: is never read without them (a run with ``error_control = "per-block"`` takes fewer
#: evaluations and leaves a larger energy residual than a uniform one, issue 54).
RUN_SETTINGS = (
    "method",
    "rtol",
    "atol",
    "max_step",
    "first_step",
    "error_control",
    "block_frequency",
    "bending_scale",
)

#: The fields of a run's result, the same in memory, in a case record and in run.json.
RESULT_KEYS = ("model", "options", "settings", "stats", "events")


def result_fields(d: dict[str, Any]) -> dict[str, Any]:
    """The result fields ``Trajectory.result_dict`` wrote (a case record's trajectory or a
    run.json), as ``Trajectory`` fields: stats (``SolverStats.from_dict``), settings, options
    and events (the model is read with the outputs it names)."""
    return {
        "stats": SolverStats.from_dict(d["stats"]),
        "settings": dict(d.get("settings", {})),
        "options": dict(d.get("options", {})),
        "events": list(d.get("events", [])),
    }


def finish(
    stats: SolverStats,
    *,
    model: str,
    scene_name: str,
    times: np.ndarray | None = None,
    observed: dict[str, tuple[np.ndarray, np.ndarray]] | None = None,
    settings: dict[str, Any] | None = None,
    options: dict[str, Any] | None = None,
    events: list[Any] | None = None,
) -> Trajectory:
    """The one end of every run, native (``rodval.solvers.driver.integrate``), exudyn
    (``reference_models.exudyn_chain``) and failed (``Trajectory.failed``): the trajectory of
    the output ``times`` (s) reached and the ``observed`` quantities (name -> (values
    (nt, nk), k labels)), with ``stats`` as the run left it. Its status was set on the way by
    ``rodval.core.status.update_status`` alone; a run still at success here reached t_end,
    and its message says so."""
    if stats.status == STATUS_SUCCESS:
        stats.message = "reached t_end"
    observed = observed or {}
    return Trajectory(
        model=model,
        scene_name=scene_name,
        times=np.zeros(0) if times is None else times,
        values={q: v for q, (v, _) in observed.items()},
        k_index={q: k for q, (_, k) in observed.items()},
        stats=stats,
        settings=dict(settings or {}),
        options=dict(options or {}),
        events=list(events or []),
    )
