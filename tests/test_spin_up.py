"""Kane, Ryan and Banerjee's spin-up benchmark on a prescribed hub (``benchmarks/spin_up.py``,
docs/base.md): the tip's transverse deflection in the hub frame against exudyn's geometrically
exact ANCF beam (EA 2.8e7 N, 2 elements per rod, 1e-3 s; 4 elements at 5e-4 s moves its
extreme by less than 1e-4 m). Measured (t_end 20 s, n = 8): min v = -0.4007 m native exact,
-0.4001 m exudyn at omega_s = 4 rad/s (0.15 %); -0.8628 m and -0.8580 m at 10 rad/s (0.56 %).
The bound is the issue's 1 %; the gap falls with n as the rods' own bending does (n = 4: 2.3 %
at 10 rad/s)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from spin_up import EA, spin_up_scene, tip_deflection  # noqa: E402

from rodval import simulate  # noqa: E402

#: The deflection's extreme is at 6.5-7 s: 8 s holds it.
T_END = 8.0


def extreme(tr) -> float:
    return float(tip_deflection(tr).min())


@pytest.mark.parametrize("omega", [4.0, 10.0])
def test_both_kinematics_converge_with_the_rods(omega):
    """From n = 4 to 8 rods the extreme moves by under 2 % (the rods' own bending shrinks as
    1/n^2), and the two kinematics agree to 0.1 %: the chords carry the spin's stiffening."""
    v = {
        (n, k): extreme(simulate(spin_up_scene(n, omega, T_END, 161), "full", kinematics=k))
        for n in (4, 8)
        for k in ("first-order", "exact")
    }
    for k in ("first-order", "exact"):
        assert abs(v[4, k] - v[8, k]) < 0.02 * abs(v[8, k])
    assert abs(v[8, "first-order"] - v[8, "exact"]) < 1e-3 * abs(v[8, "exact"])


@pytest.mark.exudyn
@pytest.mark.parametrize("omega", [4.0, 10.0])
def test_the_exact_kinematics_is_within_one_percent_of_exudyn(omega):
    pytest.importorskip("exudyn")
    scene = spin_up_scene(8, omega, T_END, 161)
    native = extreme(simulate(scene, "full", kinematics="exact"))
    reference = simulate(scene, "exudyn", elements=2, step=1e-3, EA=EA)
    assert reference.success
    assert abs(native - extreme(reference)) < 0.01 * abs(extreme(reference))
    assert np.isfinite(native)
