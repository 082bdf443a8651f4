"""The result of one run, the same in memory, in a study's case record and in run.json:
how it ended (``status``, ``message``, ``t_reached``), what it cost and what the model said
of its own validity. Its status changes only through ``rodval.core.status.update_status``
(the precedence rule); a run is finished by ``rodval.core.trajectory.finish``."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from rodval.core.status import STATUS_SUCCESS, Status


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
    #: The largest |value| of each ``rodval.core.quantities.PEAK_QUANTITIES`` the scene
    #: outputs, read between the output times, so that it is the run's and not its output
    #: grid's: ``{"read_on": how, "values": {quantity: [{"k", "peak", "t" (s)}, ...]}}`` (a
    #: hinge whose moment is impulsive at its lock: ``peak`` None, ``impulse`` N m s, ``t``
    #: the lock's time; ``rodval.core.quantities.impulsive_locks``); None: none recorded.
    peaks: dict[str, Any] | None = None

    def __setattr__(self, name: str, value: Any) -> None:
        if name == "status":
            value = Status(value)
        object.__setattr__(self, name, value)

    @property
    def success(self) -> bool:
        return self.status == STATUS_SUCCESS

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready form, the same in a study's case record and in run.json (with
        ``success``, derived from ``status``); inverse of ``from_dict``."""
        record = asdict(self)  # the lists and dicts copied: the record's own
        del record["status"]
        return {"status": int(self.status), "success": self.success, **record}

    #: The name callers used before ``to_dict``.
    as_dict = to_dict

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> SolverStats:
        """The result ``to_dict`` wrote (``success`` is derived, not read); TypeError naming
        a key that is no field, ValueError for a status that is no ``Status``."""
        return cls(**{k: v for k, v in d.items() if k != "success"})
