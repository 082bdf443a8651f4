"""The energy audit read between the output times (issue 47): a run's scalar energy residual
(``SolverStats.energy_residual``, the validity check's figure) is read on the fixed audit
grid (``rodval.solvers.audit.audit_times``, recorded beside the output times by
``rodval.solvers.outputs.Outputs`` from the integrator's dense output), so it is the run's and
not its output grid's. Read at the output times, the first-order latched wing gave 0.0486
with 11 output times and 0.0510 with 201 (pinned), 0.0490 and 0.0511 (on the 800 kg body).
"""

import sys
from pathlib import Path

import numpy as np
import pytest

from rodval import Chain, InitialState, Scene, constant, paper_scene, simulate
from rodval.core.validity import ENERGY_RESIDUAL_BOUND
from rodval.solvers.audit import AUDIT_INTERVALS, audit_times
from rodval.solvers.outputs import AuditGrid, Outputs

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from exudyn_speed import latch3_scene  # noqa: E402
from momentum_audit import BODY  # noqa: E402

#: The output grids compared: the same run, the same steps (output times never change a step).
GRIDS = (11, 201)
#: Equality of the two runs' residuals: the same states at the same grid times through the same
#: arithmetic (measured bit for bit); 1e-12 leaves room for round-off in the sums only. Read
#: at the output times the two differed by 4.7 % (pinned) and 4.3 % (body).
SAME = 1e-12


def with_grid(scene: Scene, num: int) -> Scene:
    return scene.with_(times=np.linspace(0.0, scene.t_end, num))


def latched_wing(base: str) -> Scene:
    """3 rods, hinge 0 free, hinges 1 and 2 latched at 0 (``latch3_scene``: nu = 0, no
    bending damping, no loads), pinned or on the 800 kg free body."""
    wing = latch3_scene()
    if base == "pinned":
        return wing.with_(outputs=("phi", "energy"))
    return wing.with_(base=BODY, outputs=("phi", "base", "energy"))


def test_the_audit_grid_is_recorded_beside_the_output_times():
    """Outputs records the scene's output times and the grid's (a time in both once) and
    tells them apart; the lock windows' probes are not recorded."""
    scene_times = np.array([0.0, 0.2501, 0.5])
    out = Outputs(scene_times, 1, audit=AuditGrid(0.5))
    assert out.times.size == AUDIT_INTERVALS + 2  # 0 and 0.5 are on both
    pending = out.remaining()
    out.write(pending[:, None])
    np.testing.assert_array_equal(out.times[out.scene_rows()], scene_times)
    np.testing.assert_array_equal(out.times[out.audit_rows()], audit_times(0.5))
    np.testing.assert_array_equal(out.Y[:, 0], out.times)


@pytest.mark.parametrize("base", ["pinned", "body"])
def test_a_latched_runs_energy_residual_is_the_same_on_any_output_grid(base):
    """The first-order full model leaves a residual beyond the bound on the latched wing (its
    kinematics': docs/stability.md); read on the audit grid it is the same with 11 and 201
    output times (``SAME``), so is the verdict. The locks' kinetic energy losses are booked
    as dissipation: with no damper, D(t_end) is their sum (to round-off: a sum of the same
    numbers)."""
    runs = [
        simulate(with_grid(latched_wing(base), num), "full", kinematics="first-order")
        for num in GRIDS
    ]
    coarse, fine = (tr.stats for tr in runs)
    assert coarse.nsteps == fine.nsteps and coarse.nfev == fine.nfev
    assert coarse.energy_residual > ENERGY_RESIDUAL_BOUND  # the first-order residual
    assert coarse.energy_residual == pytest.approx(fine.energy_residual, rel=SAME)
    assert coarse.valid is False and fine.valid is False
    for tr in runs:
        locks = [ev["instant_energy_loss"] for ev in tr.events]
        assert len(locks) >= 2 and sum(locks) > 0.0
        assert tr["dissipated"][-1, 0] == pytest.approx(sum(locks), rel=1e-12)


@pytest.mark.parametrize("loaded", [False, True], ids=["free", "constant load"])
def test_an_undamped_chain_conserves_its_energy_on_any_output_grid(loaded):
    """An undamped, unlatched chain on the exact kinematics (a Lagrangian system): E - W_ext
    is conserved, so the residual on the audit grid is the integration's, below its rtol
    (measured 1.8e-13 free, 2.4e-12 loaded), the same on either output grid. The loaded case
    pairs each grid state's E with its own W (off by one grid row: ~1e-3)."""
    rtol = 1e-7
    loads = (constant(3, X=40.0, Y=-25.0),) if loaded else ()
    scene = Scene(
        Chain.uniform(3, nu=0.0),
        t_end=0.5,
        outputs=("energy",),
        initial=InitialState(dphi=[1.0, -0.5, 0.8]),
        loads=loads,
    )
    runs = [
        simulate(with_grid(scene, num), "full", kinematics="exact", rtol=rtol, atol=rtol * 1e-2)
        for num in GRIDS
    ]
    if loaded:
        assert abs(runs[0]["work"][-1, 0]) > 10.0  # the load does work (J)
    first, second = (tr.stats.energy_residual for tr in runs)
    assert first < rtol
    assert first == pytest.approx(second, rel=SAME)


def test_the_scipy_path_reads_the_same_grid():
    """The scipy loop records the grid as the compiled one does: the reduced model on the
    paper's damped, loaded chain, the same residual on either output grid (read at the
    output times: 4.4e-5 with 11, 4.7e-4 with 201; on the grid 5.2e-4)."""
    scene = paper_scene(8, outputs=("phi", "energy"))
    stats = [simulate(with_grid(scene, num), "reduced", method="DOP853").stats for num in GRIDS]
    assert stats[0].energy_residual > 1e-4
    assert stats[0].energy_residual == pytest.approx(stats[1].energy_residual, rel=SAME)


@pytest.mark.exudyn
def test_exudyn_reads_its_residual_on_every_recorded_step():
    """exudyn audits its energy on every step it recorded (``exudyn_audit.account``), from
    E(0) at t = 0: the same residual with 11 and 201 output times on the latched wing
    (read at the output times: 0.06228 and 0.06234), and with output times that do not
    start at 0 (read there, E(0) was the first output time's: 0.017 against 3.2e-6)."""
    pytest.importorskip("exudyn")
    options = {"elements": 2, "step": 2e-4}
    wing = latch3_scene().with_(outputs=("phi", "energy"))
    coarse, fine = (
        simulate(with_grid(wing, num), "exudyn", **options).stats.energy_residual for num in GRIDS
    )
    assert coarse == pytest.approx(fine, rel=SAME)
    short = paper_scene(3, t_end=0.2, outputs=("energy",))
    late, whole = (
        simulate(short.with_(times=times), "exudyn").stats.energy_residual
        for times in ([0.1, 0.2], [0.0, 0.1, 0.2])
    )
    assert late == pytest.approx(whole, rel=SAME)
