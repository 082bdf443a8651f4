"""Energy audit: the balance E(t) - E(0) - W_ext(t) + D(t) along a trajectory.

E = T + Pi is the mechanical energy the model reports (quantities "kinetic", "potential",
"energy"); W_ext(t) = int_0^t P_ext dt is the work of the nodal forces, P_ext = Q . phi' (J);
D(t) = int_0^t P_diss dt >= 0 is the energy taken out by the hinge dampers,
P_diss = q'^T C q' (W), plus each event's instantaneous loss (a lock's kinetic energy). Both
powers come from the model's ``OdeSystem.power``.

The powers are integrated per accepted step of the integrator by Gauss-Legendre quadrature on
the step's dense output (here for scipy's steps; the compiled DOP853 loop does the same inside
its loop, ``rodval.solvers.dop853._audit_step``) (``GAUSS_NODES`` nodes, exact for polynomials of degree
2 GAUSS_NODES - 1 >= the order of every scipy dense output). The trajectory itself is
not changed by the audit: the integrator's step selection sees the same state as without it.

The running W_ext, D are recorded at the output times (the quantities "work", "dissipated",
"energy_residual") and at the audit grid's (``audit_times``, recorded beside them by
``rodval.solvers.outputs.Outputs``). The run's scalar residual (``energy_residual``,
``SolverStats.energy_residual``, the validity check's figure) is read on the audit grid only,
so it is the run's, not its output grid's: the same states at the same times whatever the
output times (read at the output times, one first-order latched run gave 0.0486 with 11 and
0.0510 with 201). An exact balance gives R(t) = 0; what each model leaves in R is in
docs/stability.md.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

#: Gauss-Legendre nodes per integrator step.
GAUSS_NODES = 4
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(GAUSS_NODES)

Power = Callable[[float, np.ndarray], tuple[float, float]]
Dense = Callable[[np.ndarray], np.ndarray]


def step_integral(power: Power, dense: Dense, t0: float, t1: float) -> np.ndarray:
    """[int P_ext dt, int P_diss dt] (J) over [t0, t1] inside one step with dense output
    ``dense`` (t array -> states (N, len(t)))."""
    h = t1 - t0
    if h <= 0:
        return np.zeros(2)
    ts = t0 + 0.5 * h * (_NODES + 1.0)
    states = dense(ts)
    P = np.array([power(t, states[:, i]) for i, t in enumerate(ts)])
    integral: np.ndarray = 0.5 * h * (_WEIGHTS @ P)
    return integral


class PowerLedger:
    """Running W_ext and D along the accepted steps, recorded at the recorded times (the
    output times and the audit grid's, ``rodval.solvers.outputs.Outputs``)."""

    def __init__(self, power: Power):
        self.power = power
        self.total = np.zeros(2)
        self._records: list[np.ndarray] = []

    def record(self) -> None:
        """Record the running totals at the current time (a recorded time at a step end)."""
        self._records.append(self.total.copy())

    def step(self, dense: Dense, t0: float, t1: float, out_times: np.ndarray) -> None:
        """Advance over the accepted step [t0, t1], recording at ``out_times`` in (t0, t1]."""
        for t in out_times:
            self._records.append(self.total + step_integral(self.power, dense, t0, t))
        self.total = self.total + step_integral(self.power, dense, t0, t1)

    def replace(self, rows: np.ndarray) -> None:
        """Take the running [W_ext, D] (J) at the recorded times from an integrator that
        audits inside its own loop (the compiled DOP853): ``rows`` (recorded times reached,
        2)."""
        self._records = [np.array(r, float) for r in rows]
        self.total = np.array(rows[-1], float) if len(rows) else np.zeros(2)

    def series(self) -> tuple[np.ndarray, np.ndarray]:
        """W_ext, D (J) at the recorded times."""
        rec = np.array(self._records).reshape(-1, 2)
        return rec[:, 0], rec[:, 1]


def balance(E: np.ndarray, E0: float, W: np.ndarray, D: np.ndarray) -> tuple[np.ndarray, float]:
    """Residual R(t) = E(t) - E0 - W(t) + D(t) (J) and its scalar max|R| / max(max E, max|W|)
    (0 when nothing moves). E0 is the energy at t = 0."""
    R = E - E0 - W + D
    if R.size == 0:
        return R, 0.0
    scale = max(float(np.max(np.abs(E))), abs(E0), float(np.max(np.abs(W))))
    return R, float(np.max(np.abs(R)) / scale) if scale > 0 else 0.0


def audit_quantities(
    E: np.ndarray, E0: float, W: np.ndarray, D: np.ndarray
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The audit's trajectory quantities at the output times (name -> (values (nt, 1), k
    labels [0])): "work" W, "dissipated" D and "energy_residual" R, from the observed energy
    E (J) there and the ledger's W, D (J) at the same times."""
    R = balance(E, E0, W, D)[0]
    k = np.zeros(1, dtype=int)
    return {
        "work": (W[:, None], k),
        "dissipated": (D[:, None], k),
        "energy_residual": (R[:, None], k),
    }


def energy_residual(E: np.ndarray, E0: float, W: np.ndarray, D: np.ndarray) -> float:
    """The run's scalar energy residual max |R| / max(max E, |E0|, max |W|) (``balance``) on
    the audit grid's states (``audit_times``): E (J) there, W, D (J) the ledger's there;
    the figure of ``rodval.core.validity.energy_balance``. Rows from the first non-finite
    one on are left out (a run that diverged: its finite prefix is audited)."""
    bad = ~(np.isfinite(E) & np.isfinite(W) & np.isfinite(D))
    cut = int(np.argmax(bad)) if bad.any() else E.size
    return balance(E[:cut], E0, W[:cut], D[:cut])[1]


#: Intervals of the audit grid: the momentum and energy residuals are read at
#: AUDIT_INTERVALS + 1 evenly spaced times of [0, t_end] (``audit_times``), whatever the
#: scene's output times.
AUDIT_INTERVALS = 500


def audit_times(t_end: float) -> np.ndarray:
    """The audit grid (s): AUDIT_INTERVALS + 1 evenly spaced times of [0, t_end], on which
    every model reads its momentum residual (the native models by dense output,
    ``rodval.solvers.outputs.AuditGrid``; exudyn from its recorded steps) and the native
    models their energy residual (``energy_residual``; exudyn reads its own on every
    recorded step, ``reference_models.exudyn_audit``)."""
    return np.linspace(0.0, float(t_end), AUDIT_INTERVALS + 1)


def momentum_residual(H: np.ndarray, G: np.ndarray) -> float:
    """max |H(t) - H(0)| / max G(t) (0 when nothing moves): the angular momentum H (N m s)
    about a conserved point and the gross G (N m s), the sum of its parts' magnitudes
    (``rodval.core.validity``, ``momentum_balance``), on the audit grid's states
    (``rodval.solvers.outputs.AuditGrid``), not the output times."""
    if H.size == 0:
        return 0.0
    scale = float(np.max(G))
    return float(np.max(np.abs(H - H[0])) / scale) if scale > 0 else 0.0
