"""What a simulation returns: requested quantities at requested times, and how the run ended."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

#: Status codes. 0 and -1 follow scipy's OdeResult; the others are rodval's.
STATUS_SUCCESS = 0
STATUS_FAILED = -1          # the integrator gave up (step size too small, singular matrix, ...)
STATUS_ERROR = -2           # the model raised an exception
STATUS_DIVERGED = -3        # NaN/inf in the state
# -4, -5: timeout and worker crash of the study runner (branch study)
STATUS_BLOWUP = -6          # energy grew beyond settings.blowup_factor x its physical budget
STATUS_STALLED = -7         # step size collapsed below settings.min_step_fraction x t_end
STATUS_MESSAGES = {0: "success", -1: "integration failed", -2: "model error",
                   -3: "diverged (non-finite state)", -6: "diverged (energy blow-up)",
                   -7: "stalled (step size collapse)"}


@dataclass
class SolverStats:
    """Cost and outcome of one run. ``wall_s`` is the integration's own wall time (s), without
    imports, model set-up or one-time compilation."""

    status: int = STATUS_SUCCESS
    message: str = ""
    t_reached: float = 0.0
    nfev: int = 0
    njev: int = 0
    nlu: int = 0
    nsteps: int = 0
    wall_s: float = 0.0
    #: max |E - E(0) - W_ext + D| / max(max E, max |W_ext|) over the output times, when the
    #: scene asks for "energy" (see rodval.energy); None otherwise.
    energy_residual: float | None = None

    @property
    def success(self) -> bool:
        return self.status == STATUS_SUCCESS

    def as_dict(self) -> dict:
        return {"status": self.status, "success": self.success, "message": self.message,
                "t_reached": self.t_reached, "nfev": self.nfev, "njev": self.njev,
                "nlu": self.nlu, "nsteps": self.nsteps, "wall_s": self.wall_s,
                "energy_residual": self.energy_residual}


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
    settings: dict = field(default_factory=dict)

    @property
    def success(self) -> bool:
        return self.stats.success

    def __getitem__(self, quantity: str) -> np.ndarray:
        return self.values[quantity]

    @property
    def quantities(self) -> tuple[str, ...]:
        return tuple(self.values)

    def at(self, quantity: str, t: float, k: int) -> float:
        """Value of ``quantity`` for index k at output time t (exact match of t)."""
        i = int(np.flatnonzero(np.isclose(self.times, t, rtol=0, atol=1e-12))[0])
        j = int(np.flatnonzero(self.k_index[quantity] == k)[0])
        return float(self.values[quantity][i, j])

    def to_frame(self) -> pd.DataFrame:
        """Tidy table with columns t, quantity, k, value."""
        parts = []
        for q, arr in self.values.items():
            nt, nk = arr.shape
            parts.append(pd.DataFrame({
                "t": np.repeat(self.times, nk), "quantity": q,
                "k": np.tile(self.k_index[q], nt), "value": arr.ravel()}))
        if not parts:
            return pd.DataFrame(columns=["t", "quantity", "k", "value"])
        return pd.concat(parts, ignore_index=True)
