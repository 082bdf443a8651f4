"""The evidence behind the stiffness switch's design (docs/performance.md, "Stiff chains").

1. Hairer's stiffness test of dop853.f, h |f(y1) - f(s12)| / |y1 - s12|, on the paper chain
   at EI = 1e9 (full model, scipy's DOP853 at rtol 1e-6, first 20,000 steps): its
   percentiles, against the spectral radius times the step, which sits at the stability
   boundary.
2. The rigid two-rod latch scene (``rodval.bench.rigid_latch``, free motion before the lock):
   the bending vibration the unbent start excites (0..2e-4 s), and the steps the compiled
   Radau IIA takes over 0..0.01 s at rtol 1e-6.
3. The switch records of "auto" on the paper chain at EI = 1e5 (tried, came back) and on the
   reduced rigid latch (the constraint mode after the lock).

    OMP_NUM_THREADS=1 python benchmarks/stiffness_evidence.py
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.integrate import DOP853
from scipy.integrate._ivp import dop853_coefficients as dc

from rodval import simulate
from rodval.bench.stiffness import rigid_latch, stiff_paper
from rodval.core.settings import IntegratorSettings
from rodval.models import get_model
from rodval.solvers import stiffness
from rodval.solvers.compiled import Controls, integrate_compiled, packed
from rodval.solvers.dop853 import RADAU_STEPPER
from rodval.solvers.guard import GuardSpec


def hairer_test(EI: float = 1e9, steps: int = 20_000) -> None:
    system = get_model("full").system(stiff_paper(EI))
    solver = DOP853(system.rhs, 0.0, system.y0, 0.3, rtol=1e-6, atol=1e-8)
    ratios, sizes = [], []
    while solver.status == "running" and len(ratios) < steps:
        y0 = solver.y.copy()
        solver.step()
        h = solver.t - solver.t_old
        stage = y0 + h * (solver.K[: dc.N_STAGES].T @ dc.A[dc.N_STAGES - 1, : dc.N_STAGES])
        num = np.sum((solver.K[dc.N_STAGES] - solver.K[dc.N_STAGES - 1]) ** 2)
        den = np.sum((solver.y - stage) ** 2)
        ratios.append(h * np.sqrt(num / den) if den > 0 else 0.0)
        sizes.append(h)
    form = system.compiled()
    y = np.array(system.y0, float)
    f = np.empty(y.size)
    form.rhs(0.0, y, form.P, form.S, form.M, form.L, f)
    rho = stiffness.spectral_radius(packed(form), 0.0, y, f, *(np.empty(y.size) for _ in range(3)))
    pct = np.percentile(ratios, [10, 50, 90])
    print(f"paper chain, EI = {EI:.0e}: Hairer's h|lambda| 10/50/90 % = {pct.round(2)}")
    print(f"  median step {np.median(sizes):.3g} s, spectral radius {rho:.4g} 1/s,")
    print(
        f"  median h rho = {np.median(sizes) * rho:.3g} (DOP853's boundary {stiffness.STABILITY_IMAG:.3g})"
    )


def rigid_latch_vibration() -> None:
    free = dataclasses.replace(rigid_latch(), latches=())
    short = dataclasses.replace(
        free, t_end=2e-4, times=np.linspace(0.0, 2e-4, 401), outputs=("phi", "alpha", "beta")
    )
    tr = simulate(short, "full", settings=IntegratorSettings("DOP853-numba"))
    a = tr["alpha"][200:]
    amplitude = float(np.max((a.max(axis=0) - a.min(axis=0)) / 2))
    print(f"rigid latch, full model: bending vibration amplitude {amplitude:.3g} rad about a")
    static, largest = np.abs(a.mean(axis=0)).max(), np.abs(tr["alpha"]).max()
    print(f"  quasi-static {static:.3g} rad, max |alpha| {largest:.3g} rad")
    system = get_model("full").system(free)
    Y = np.empty((2, system.y0.size))
    ends = np.array([0.0, 0.01])
    controls = Controls(1e-6, 1e-8, np.inf, None, 10**7, stepper=RADAU_STEPPER)
    run = integrate_compiled(system.compiled(), system.y0, ends, ends, Y, controls, GuardSpec())
    print(f"  Radau IIA, rtol 1e-6, 0..0.01 s: {run.nsteps} steps (mean {0.01 / run.nsteps:.3g} s)")


def switch_records() -> None:
    """What "auto" recorded (``stats.switch``) where it tried Radau IIA and came back (paper
    chain, EI = 1e5, full model) and where the stiffness arrives with a lock (the rigid latch,
    reduced model)."""
    for label, scene, model in (
        ("paper chain, EI = 1e5, full", stiff_paper(1e5), "full"),
        ("rigid latch, reduced", rigid_latch(), "reduced"),
    ):
        print(f"{label}: {simulate(scene, model).stats.switch['reason']}")


if __name__ == "__main__":
    hairer_test()
    rigid_latch_vibration()
    switch_records()
