"""The contract between an ODE model and rodval's driver.

A model that is integrated by the driver builds one ``OdeSystem`` per scene: a first-order ODE
y' = f(t, y) with its initial state, its observation map, and optional capabilities, each a
method with the same (t, y) signature:

* ``jacobian(t, y)``: analytic df/dy, used by implicit scipy methods (``has_jacobian``);
* ``kinetic_energy``, ``energy``, ``energy_budget``, ``power``, ``energy_history``
  (``has_energy``): used by the divergence guard (``rodval.solvers.guard``) and the energy
  audit (``rodval.solvers.audit``); ``momentum_audit_rows`` (``has_momentum``): the
  angular-momentum audit;
* ``event_functions`` / ``apply_event``: state events (a hybrid system whose state jumps and
  whose equations switch at a crossing, e.g. a hinge latching), handled by the driver's event
  loop (``rodval.solvers.events``);
* ``compiled()``: a ``CompiledForm`` that rodval's compiled integrators run without returning
  to Python (``rodval.solvers.compiled``).

The solvers layer imports no model: models implement this contract.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

#: quantity -> (values (len(times), n_k), k labels (n_k,))
Observed = dict[str, tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True, eq=False)
class CompiledForm:
    """A system's compiled right-hand side and the arrays it reads.

    ``rhs`` is a numba function of the first-class type ``rodval.solvers.signature.RHS_TYPE``:
    ``rhs(t, y, P, S, M, L, out)`` writes y' (same length as y) into ``out``. What the arrays
    hold is the model's business: ``P`` (rows of per-rod constants, float64 2-D), ``S``
    (scalars, float64 1-D), ``M`` (dense matrices or work space the rhs reuses, float64 3-D,
    may be empty), ``L`` (the load
    table, ``rodval.core.load_table.load_table``). The integrator passes them through untouched.

    ``mechanics`` (optional, same type): writes (T, P_ext, P_diss) — kinetic energy (J), power
    of the loads (W) and power taken out by the dampers (W, ``OdeSystem.power``) — into a
    length-3 ``out``, for the divergence guard and the energy audit inside the loop; None
    disables both (the energy blow-up check, and "auto" then runs an audit on scipy).

    ``events`` (optional, ``rodval.solvers.signature.EVENTS_TYPE``): ``events(t, y, P, S, M,
    L, E, out)`` writes the value g_i(t, y) of each state event of the current mode into
    ``out``, one per row of the model's event table ``E`` (float64 2-D, what a row holds is
    the model's business), in the order of ``OdeSystem.event_functions()`` (so the index the
    loop reports is the one ``apply_event`` takes); ``directions`` (float64, one per row)
    are their ``EventSpec.direction``. None: a system with events has no compiled event
    form (its runs with events go to scipy). A form describes one mode: after an event the
    integrator asks the system for its form again.
    """

    rhs: Any
    P: np.ndarray
    S: np.ndarray
    M: np.ndarray
    L: np.ndarray
    mechanics: Any = None
    name: str = ""
    events: Any = None
    E: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    directions: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        for label, arr, ndim in (
            ("P", self.P, 2),
            ("S", self.S, 1),
            ("M", self.M, 3),
            ("L", self.L, 2),
            ("E", self.E, 2),
            ("directions", self.directions, 1),
        ):
            if not (
                isinstance(arr, np.ndarray)
                and arr.dtype == np.float64
                and arr.ndim == ndim
                and arr.flags.c_contiguous
            ):
                raise TypeError(
                    f"CompiledForm.{label} must be a C-contiguous float64 array "
                    f"with {ndim} dimensions"
                )
        if self.events is None and self.E.shape[0]:
            raise ValueError("CompiledForm.E has event rows but no event function")
        if self.directions.shape[0] != self.E.shape[0]:
            raise ValueError(
                f"CompiledForm.directions has {self.directions.shape[0]} entries for "
                f"{self.E.shape[0]} event rows"
            )


@dataclass(frozen=True)
class EventSpec:
    """One state event: ``g(t, y)`` crosses zero in ``direction`` (+1 rising, -1 falling,
    0 both). ``label`` names it in reports (e.g. "latch hinge 1")."""

    g: Callable[[float, np.ndarray], float]
    direction: int = 0
    label: str = ""


@dataclass
class EventRecord:
    """What happened at one event: its time (s), label and the model's own measures (e.g.
    impulses, energies before and after)."""

    t: float
    label: str
    data: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return {"t": self.t, "label": self.label, **self.data}


class OdeSystem(ABC):
    """A first-order ODE y' = f(t, y) built for one scene, plus its observation map."""

    #: Initial state (N,).
    y0: np.ndarray
    #: True when ``jacobian`` is implemented.
    has_jacobian: bool = False
    #: True when ``kinetic_energy``, ``energy``, ``energy_budget`` and ``power`` are.
    has_energy: bool = False
    #: True when ``momentum_audit_rows`` is (the driver's angular-momentum audit).
    has_momentum: bool = False

    @abstractmethod
    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """Time derivative of the state."""

    @abstractmethod
    def observe(self, times: np.ndarray, Y: np.ndarray) -> Observed:
        """The scene's requested quantities from states Y (len(times), N)."""

    def jacobian(self, t: float, y: np.ndarray) -> np.ndarray:
        """df/dy (N, N)."""
        raise NotImplementedError

    def kinetic_energy(self, t: float, y: np.ndarray) -> float:
        """Kinetic energy T (J); cheap (called after every step by the divergence guard)."""
        raise NotImplementedError

    def energy(self, t: float, y: np.ndarray) -> float:
        """Mechanical energy E = T + Pi (J), the same the observation reports."""
        raise NotImplementedError

    def energy_budget(self, t: float, y: np.ndarray) -> float:
        """E = T + Pi (J) without expensive recovery: the divergence guard's initial budget."""
        raise NotImplementedError

    def power(self, t: float, y: np.ndarray) -> tuple[float, float]:
        """(P_ext, P_diss) (W): power of the applied loads and power taken out by dampers."""
        raise NotImplementedError

    def energy_history(self, times: np.ndarray, Y: np.ndarray) -> np.ndarray:
        """E (J) per state of a history Y (nt, N) at ``times`` (s), each in the mode in effect
        at its time, as ``observe`` reports it: the energy audit's E on its grid; state by
        state (``energy``) unless the system evaluates whole histories."""
        return np.array([self.energy(float(t), y) for t, y in zip(times, Y)])

    def momentum_audit_rows(self, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(H, G) (N m s, (nt,) each) per state of Y: the angular momentum about the point the
        scene conserves it about, and the gross one (``rodval.core.validity.momentum_balance``)."""
        raise NotImplementedError

    def max_bending(self, times: np.ndarray, Y: np.ndarray) -> float | None:
        """Largest |bending angle| (rad) over states Y, or None for a model without bending
        coordinates (the driver's small-bending check)."""
        return None

    def bending_mask(self) -> np.ndarray | None:
        """Which state components are bending coordinates or their rates (bool, (N,)), the
        block that per-block error control (``IntegratorSettings.bending_atol``) judges on a
        scale of its own; None (default): the system has no bending coordinates."""
        return None

    def event_functions(self) -> tuple[EventSpec, ...]:
        """The system's state events in its current mode (none by default)."""
        return ()

    def apply_event(self, index: int, t: float, y: np.ndarray) -> tuple[np.ndarray, EventRecord]:
        """At the located crossing of event ``index`` in state y: the state after the jump
        and the record; the system switches its mode (its ``rhs`` and ``event_functions``
        may change)."""
        raise NotImplementedError

    def window_terms(self, t: float, y: np.ndarray, hinge: int) -> tuple[float, ...]:
        """(lambda (N m), H_out (N m s), M_fin (N m), P_ext, P_diss (W)) of the held ``hinge``
        at one state: the integrands of a lock window (``rodval.solvers.outputs.LockWindows``);
        a system whose lock records declare an ``impulse_window`` implements it."""
        raise NotImplementedError

    def window_rows(self, times: np.ndarray, Y: np.ndarray, hinge: int) -> np.ndarray:
        """``window_terms`` at the states Y (nt, N) at ``times`` (s), all in the current mode,
        as rows (nt, 5); state by state unless the system evaluates them on whole arrays."""
        rows = [self.window_terms(float(t), y, hinge) for t, y in zip(times, Y)]
        return np.array(rows, dtype=float).reshape(-1, 5)

    def energy_parts(self, t: float, y: np.ndarray) -> tuple[float, float, float]:
        """(kinetic, hinge, bending) energy (J) at one state, summing to ``energy``: a lock
        window's accounts at its end (``rodval.mechanics.lock_window.window_energies``)."""
        raise NotImplementedError

    def reset(self) -> None:
        """Return to the initial mode before a run (a system whose events switch its
        equations forgets them here); the driver calls it first. Nothing by default."""
        return None

    def compiled(self) -> CompiledForm | None:
        """The compiled form, or None when the system has none."""
        return None
