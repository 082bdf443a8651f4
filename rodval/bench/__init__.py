"""Performance measurements: work-precision, cost per evaluation against n, the cost of what a
scene may skip, reduced-vs-full speed-up at equal accuracy, the fast path (events, energy)
and stiff chains on the default method.

Conventions
-----------
* Wall time is the integration's own ``stats.wall_s`` (no model set-up, no compilation), the
  minimum over ``repeats`` runs after one warm-up run. Runs that are compared are measured in
  the same process, one after the other, so that their ratio is meaningful on a shared machine.
* Errors are against a reference computed with a *different* method: LSODA at rtol 1e-12 for
  the DOP853 family, the compiled DOP853 at rtol 1e-13 for every other method (their mutual
  difference is reported as the reference uncertainty). Per quantity q (phi, dphi, alpha,
  beta), with d = q - q_ref over all output times and rods and s = max |q_ref|:
  ``final_q`` = max_k |d(t_end)| / s, ``rms_q`` = RMS(d) / s, ``max_q`` = max |d| / s;
  ``scd`` = -log10 of the largest ``max_q``.
"""

from rodval.analysis.metrics import pareto_front
from rodval.bench.cost import fitted_exponent, per_eval_cost, skip_rows, speedup_vs_n
from rodval.bench.fast_path import (
    eight_rod_wing,
    fast_path_rows,
    feature_costs,
    four_panel_wing,
)
from rodval.bench.precision import (
    baseline_ratios,
    cheapest,
    errors,
    kernel_options,
    numpy_models,
    work_precision,
)
from rodval.bench.scale import (
    SCALE_N,
    SCALE_REFERENCE_RTOL,
    compiled_rhs_cost,
    compiled_states,
    scale_fits,
    scale_rows,
    scale_scene,
    speedup_scale,
    subnormal_count,
)
from rodval.bench.stiffness import growth, rigid_latch, stiff_paper, stiffness_rows

__all__ = [
    "eight_rod_wing",
    "fast_path_rows",
    "feature_costs",
    "four_panel_wing",
    "growth",
    "kernel_options",
    "numpy_models",
    "rigid_latch",
    "stiff_paper",
    "stiffness_rows",
    "SCALE_N",
    "SCALE_REFERENCE_RTOL",
    "baseline_ratios",
    "cheapest",
    "compiled_rhs_cost",
    "compiled_states",
    "errors",
    "fitted_exponent",
    "pareto_front",
    "per_eval_cost",
    "scale_fits",
    "scale_rows",
    "scale_scene",
    "skip_rows",
    "speedup_scale",
    "speedup_vs_n",
    "subnormal_count",
    "work_precision",
]
