"""What a simulation returns: requested quantities at requested times, and how the run ended."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from rodval.core.status import STATUS_SUCCESS, Status

if TYPE_CHECKING:
    import pandas as pd


@dataclass
class SolverStats:
    """Cost and outcome of one run. ``wall_s`` is the integration's own wall time (s), without
    imports, model set-up or one-time compilation. ``status`` is always a ``Status`` (an int
    given to it is converted; ValueError for a number that is no status)."""

    status: int = STATUS_SUCCESS  # always a Status at run time (see __setattr__)
    message: str = ""
    t_reached: float = 0.0
    nfev: int = 0
    njev: int = 0
    nlu: int = 0
    nsteps: int = 0
    wall_s: float = 0.0
    #: max |E - E(0) - W_ext + D| / max(max E, max |W_ext|) over the output times, when the
    #: scene asks for "energy" (see rodval.solvers.audit); None otherwise.
    energy_residual: float | None = None
    #: max |H - H(0)| / max G over the output times, where angular momentum is conserved
    #: (``rodval.core.validity.momentum_point``: a free base or a free root, no loads); None
    #: otherwise.
    momentum_residual: float | None = None
    #: Largest |alpha|, |beta| (rad) over the output times reached, for models with bending
    #: angles; None otherwise.
    max_bending: float | None = None
    #: Whether ``max_bending`` stayed within ``rodval.core.validity.SMALL_BENDING_RAD``, the
    #: small-bending assumption both paper models rest on (None when not measured).
    small_bending: bool | None = None
    #: The model's verdict on its own assumptions (``rodval.core.validity``): whether every
    #: check held (None: nothing could be checked), independent of ``status``: a run can reach
    #: t_end and be invalid.
    valid: bool | None = None
    #: Every check made: assumption, figure, bound, unit, holds, reason.
    validity: list[dict[str, Any]] = field(default_factory=list)
    #: Where "auto"'s compiled DOP853 found its steps limited by stability and went on with
    #: Radau IIA (``rodval.solvers.dop853.SWITCHING_STEPPER``): {"to", "t" (s), "h_lambda",
    #: "h" (s), "reason"}; None when it did not switch.
    switch: dict[str, Any] | None = None
    #: What the model did not take from the scene, one sentence each with the reason (e.g. the
    #: reduced model's quasi-static bending has no bending rates for the rods' bending
    #: damping to act on): ``rodval.core.contract.Model.scene_notes``.
    notes: list[str] = field(default_factory=list)

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "status":
            value = Status(value)
        object.__setattr__(self, name, value)

    @property
    def success(self) -> bool:
        return self.status == STATUS_SUCCESS

    def as_dict(self) -> dict:
        return {
            "status": int(self.status),
            "success": self.success,
            "message": self.message,
            "t_reached": self.t_reached,
            "nfev": self.nfev,
            "njev": self.njev,
            "nlu": self.nlu,
            "nsteps": self.nsteps,
            "wall_s": self.wall_s,
            "energy_residual": self.energy_residual,
            "momentum_residual": self.momentum_residual,
            "max_bending": self.max_bending,
            "small_bending": self.small_bending,
            "valid": self.valid,
            "validity": [dict(c) for c in self.validity],
            "switch": None if self.switch is None else dict(self.switch),
            "notes": list(self.notes),
        }


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
    settings: dict = field(default_factory=dict)
    #: The model's options (e.g. coefficients, kernel; exudyn's discretization).
    options: dict = field(default_factory=dict)
    #: State events in time order (e.g. latches locking), each a plain dict with "t" (s),
    #: "label" and the model's own measures.
    events: list = field(default_factory=list)
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
        settings: dict | None = None,
        options: dict | None = None,
    ) -> Trajectory:
        """The trajectory of a run that produced no output time (a set-up error, a timeout, a
        crashed worker): no times, no values; ``stats`` says how it ended. The one
        constructor of a failed run, for every model and the study runner."""
        return cls(
            model=model,
            scene_name=scene_name,
            times=np.zeros(0),
            values={},
            k_index={},
            stats=stats,
            settings=dict(settings or {}),
            options=dict(options or {}),
        )

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

    def to_dict(self) -> dict:
        """Plain JSON-ready form (lists and numbers); inverse of ``from_dict``."""
        return {
            "model": self.model,
            "scene_name": self.scene_name,
            "times": self.times.tolist(),
            "values": {q: v.tolist() for q, v in self.values.items()},
            "k_index": {q: k.tolist() for q, k in self.k_index.items()},
            "stats": self.stats.as_dict(),
            "settings": self.settings,
            "options": self.options,
            "events": self.events,
        }

    @classmethod
    def from_dict(cls, d: dict) -> Trajectory:
        times = np.asarray(d["times"], dtype=float)
        stats = {k: v for k, v in d["stats"].items() if k != "success"}
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
            stats=SolverStats(**stats),
            settings=dict(d.get("settings", {})),
            options=dict(d.get("options", {})),
            events=list(d.get("events", [])),
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
