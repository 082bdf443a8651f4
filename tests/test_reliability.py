"""Bad input and failures, item by item: each ends with a status, or a one-line error naming
what is wrong, before any work where it can be; never a traceback, a hang or a silent loss.

(The study-folder items, which start processes, are in tests/test_reliability_study.py.)
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from checks import TimeLimit, one_line

from rodval import (
    Chain,
    InitialState,
    IntegratorSettings,
    NodalForce,
    Scene,
    paper_scene,
    pulse,
    simulate,
)
from rodval.cli import main
from rodval.core.resources import ENV_LIMIT, check_run_memory, estimate_run_bytes
from rodval.core.scene_file import scene_from_dict
from rodval.core.status import (
    STATUS_BUDGET,
    STATUS_DIVERGED,
    STATUS_ERROR,
    STATUS_STALLED,
    STATUS_WALL,
)

SMALL = paper_scene(4, t_end=0.5, times=np.linspace(0, 0.5, 6))


# --------------------------------------------------------------- huge initial values: no hang

HUGE = [("dphi", 1e160), ("alpha", 1e305)]
METHODS = ["DOP853", "RK45", "RK23", "DOP853-numba", "auto"]


@pytest.mark.parametrize("model", ["full", "reduced"])
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("key, value", HUGE, ids=["dphi=1e160", "alpha=1e305"])
def test_huge_initial_state_ends_with_a_status(model, method, key, value):
    """Issue: [initial] dphi = 1e160 (or alpha = 1e305) with DOP853/RK45/RK23 hung forever.
    Now every method, scipy and compiled, full and reduced, ends at once with a status (the
    reduced model has no alpha: it runs normally)."""
    scene = SMALL.with_(initial=InitialState(**{key: value}))
    with TimeLimit(20):
        tr = simulate(scene, model, method=method)
    if model == "reduced" and key == "alpha":
        assert tr.success
        return
    assert not tr.success
    assert "diverged" in tr.stats.message or "non-finite" in tr.stats.message
    assert tr.stats.t_reached == 0.0
    assert np.all(np.isfinite(tr.values["phi"]))


@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_huge_initial_rate_is_reported_as_divergence_not_model_error(method):
    tr = simulate(SMALL.with_(initial=InitialState(dphi=1e160)), "full", method=method)
    assert tr.stats.status == STATUS_DIVERGED, tr.stats.message


def test_huge_initial_rate_on_the_cli(tmp_path, capsys):
    """`rodval simulate F.toml --model full --method DOP853` with dphi = 1e160: exit 1 and a
    status line, within a time limit."""
    path = tmp_path / "F.toml"
    path.write_text('based_on = "paper"\nn = 4\nt_end = 0.5\n[initial]\ndphi = 1e160\n')
    for method in ("DOP853", "RK45", "RK23"):
        with TimeLimit(20):
            code = main(
                [
                    "simulate",
                    str(path),
                    "--model",
                    "full",
                    "--method",
                    method,
                    "--out",
                    str(tmp_path / method),
                ]  # fmt: skip
            )
        out = capsys.readouterr()
        assert code == 1, out
        assert "diverged" in out.out and "Traceback" not in out.err


# ------------------------------------------------------------- the last output time is kept


@pytest.mark.parametrize("model", ["full", "reduced"])
@pytest.mark.parametrize("method", ["DOP853", "RK45", "DOP853-numba"])
def test_last_output_time_within_round_off_is_returned(model, method):
    """Issue: Scene(t_end=0.3, times=np.arange(0, 0.35, 0.1)) returned 3 of 4 times with
    status 0 (the last, 0.30000000000000004, lies beyond t_end by round-off)."""
    times = np.arange(0, 0.35, 0.1)
    assert times[-1] > 0.3
    scene = Scene(chain=Chain.uniform(3), loads=(pulse(3),), t_end=0.3, times=times)
    tr = simulate(scene, model, method=method)
    assert tr.success
    assert tr.times.size == 4 and tr.times[-1] == times[-1]
    for v in tr.values.values():
        assert v.shape[0] == 4 and np.all(np.isfinite(v))


# ------------------------------------------------------------------------------ size limits


def test_memory_estimate_is_refused_before_any_work():
    """Issue: n = 20000 grew to 24 GB; n = 100000 and times = {num = 1e9} ended in
    tracebacks after long waits. A scene whose outputs would exceed the limit is refused
    when it is built, with the estimate in the message: before any of it is allocated (the
    peak of Python's allocations measured, not the time taken)."""
    import tracemalloc

    tracemalloc.start()
    try:
        with pytest.raises(ValueError, match=r"would need about 16 GB.*limit of 4 GB.*RODVAL_MAX"):
            paper_scene(20000, times=np.linspace(0, 2, 10000))
        with pytest.raises(ValueError, match=r"would need about .* GB"):
            paper_scene(100000, times=np.linspace(0, 2, 5000))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 100e6, peak  # the outputs would be 16 GB and more
    with pytest.raises(
        ValueError, match=r"key .times.num.: must be an integer \(\[1, 1e6\]\), got float"
    ):
        scene_from_dict({"based_on": "paper", "times": {"num": 1e9}})
    with pytest.raises(ValueError, match=r"num must be >= 1 and <= 1000000, got 1000000000"):
        scene_from_dict({"based_on": "paper", "times": {"num": 10**9}})


def test_memory_limit_is_a_setting(monkeypatch):
    """RODVAL_MAX_MEMORY_GB sets the limit (default 4 GB); a bad value is named."""
    monkeypatch.setenv(ENV_LIMIT, "0.001")
    with pytest.raises(ValueError, match="limit of 0.001 GB"):
        paper_scene(200, times=np.linspace(0, 2, 201))
    monkeypatch.setenv(ENV_LIMIT, "inf")
    check_run_memory(10**6, 10**6, ("phi",))  # no limit
    monkeypatch.setenv(ENV_LIMIT, "lots")
    with pytest.raises(ValueError, match=f"{ENV_LIMIT} must be a number of GB > 0"):
        paper_scene(2)


def test_memory_estimate_counts_outputs_and_dense_matrices():
    """outputs: nt x (state + quantities x (n + 1)) doubles; dense: 4 (6 n)^2 doubles."""
    est = estimate_run_bytes(10, 5, ("phi", "dphi"), model="full")
    assert est["outputs"] == 8 * 5 * (60 + 2 * 11) and est["dense"] == 0
    est = estimate_run_bytes(10, 5, ("phi",), model="reduced", dense=True)
    assert est["dense"] == 8 * 4 * 20 * 20


def test_scene_file_too_large_on_the_cli(tmp_path, capsys):
    path = tmp_path / "big.toml"
    path.write_text('based_on = "paper"\nn = 50000\ntimes = {num = 100000}\n')
    assert main(["simulate", str(path), "--out", str(tmp_path / "o")]) == 2
    line = one_line(capsys)
    assert "big.toml" in line and "GB of memory" in line


# -------------------------------------------------------- set-up failures and absurd values


@pytest.mark.parametrize(
    "law, words",
    [
        (lambda t: 1 / 0, "ZeroDivisionError"),
        (lambda t: "x", "X = 'x'"),
        (lambda t: None, "X = None"),
        (lambda t: 1 + 2j, "X = (1+2j)"),
    ],
    ids=["raises", "string", "None", "complex"],
)
@pytest.mark.parametrize("model", ["full", "reduced"])
def test_bad_callable_load_is_a_model_error(law, words, model):
    """Issue: a callable load that raises or returns a string or None escaped simulate();
    a complex load lost its imaginary part. Now: status 'model error' naming the load."""
    scene = SMALL.with_(loads=(NodalForce(4, law),))
    tr = simulate(scene, model)
    assert tr.stats.status == STATUS_ERROR
    assert "model set-up failed" in tr.stats.message and "node 4" in tr.stats.message
    assert words in tr.stats.message


@pytest.mark.parametrize(
    "field, value",
    [("m", 1e-300), ("kappa", 1e300), ("EI", 1e-15), ("kappa", 1e25), ("l", 1e13)],
)
def test_absurd_magnitudes_are_refused_with_the_allowed_range(field, value):
    """Issue: m = 1e-300 raised ZeroDivisionError from the full model's set-up; the reduced
    model with kappa = 1e300 ended with a LinAlgError naming no parameter. Chain data are
    bounded to [1e-12, 1e12] (SI, see rodval.core.bounds.MAX_MAGNITUDE)."""
    with pytest.raises(ValueError, match=rf"^{field} \(.*must lie in \[.*1e\+12\].*got"):
        SMALL.chain.with_(**{field: value})
    with pytest.raises(ValueError, match=rf"\[chain\].*{field}|{field} \("):
        scene_from_dict({"based_on": "paper", "chain": {field: value}}, where="F.toml [chain]")


def test_huge_initial_rate_of_the_reduced_model_is_a_divergence():
    """Issue: the reduced model with dphi = 1e200 ended with 'Array must not contain infs or
    NaNs.' naming no parameter; now a divergence status at t = 0."""
    tr = simulate(SMALL.with_(initial=InitialState(dphi=1e200)), "reduced")
    assert tr.stats.status == STATUS_DIVERGED
    assert "non-finite" in tr.stats.message and tr.stats.t_reached == 0


def test_bounds_keep_the_extremes_in_use():
    """The bounds admit the values the test suite and studies use (rigid limits 1e12)."""
    Chain.uniform(2, EI=1e12, kappa=1e12, mu=0.0, nu=0.0, m=1e-12, l=1e-12)


# ----------------------------------------------------------------------------- type errors


@pytest.mark.parametrize(
    "build, words",
    [
        (
            lambda: scene_from_dict({"based_on": "paper", "initial": {"phi": "a"}}),
            "key 'initial.phi': must be a number, a list of n numbers",
        ),
        (
            lambda: scene_from_dict({"based_on": "paper", "times": {"num": "x"}}),
            "key 'times.num': must be an integer",
        ),
        (lambda: scene_from_dict({"based_on": "paper", "times": {"num": 2.7}}), "got float 2.7"),
        (lambda: scene_from_dict({"based_on": "paper", "times": {"start": "0"}}), "times.start"),
        (lambda: SMALL.with_(times={"num": 3}), "times (output times) must be a 1-D"),
        (lambda: SMALL.with_(loads=None), "loads must be a sequence of NodalForce"),
        (lambda: SMALL.with_(loads=[1]), "loads must be NodalForce objects"),
        (lambda: pulse(4, Xbar="a"), "pulse Xbar must be a finite real number"),
        (lambda: pulse(4, Xbar=1 + 2j), "pulse Xbar must be a finite real number"),
        (lambda: simulate(SMALL, settings={}), "settings must be a rodval.IntegratorSettings"),
        (lambda: SMALL.with_(t_end="2"), "t_end (horizon) must be a real number"),
        (lambda: SMALL.with_(t_end=2 + 0j), "t_end (horizon) must be a real number"),
        (lambda: InitialState(phi=1j).resolve(3), "initial phi must be a real number"),
        (lambda: Chain.uniform(3, m="3"), "m (mass per length) must be a real number"),
        (lambda: IntegratorSettings(rtol="1e-6"), "rtol must be a real number"),
        (lambda: IntegratorSettings(max_evaluations=2.5), "max_evaluations must be an integer"),
        (lambda: SMALL.with_(outputs=("phi", "z")), "outputs must be a non-empty subset"),
    ],
)
def test_type_errors_name_the_parameter(build, words):
    """Issue: type errors that named no parameter, and values coerced silently (num = 2.7
    became 2, Scene(t_end="2") was accepted, a complex load lost its imaginary part)."""
    with pytest.raises(ValueError) as info:
        build()
    assert words in str(info.value)


def test_settings_and_keywords_together_are_refused():
    """Issue: keyword options were silently overridden by settings=."""
    with pytest.raises(ValueError, match="not both .*rtol"):
        simulate(SMALL, settings=IntegratorSettings(), rtol=1e-6)


# ------------------------------------------------------------------------- stiff: budgets


@pytest.mark.parametrize("method", ["DOP853-numba", "DOP853"])
def test_stiff_chain_ends_at_its_evaluation_budget(method):
    """Issue: m = 1e-6 on 4 rods ran 80 s (2.2e6 evaluations) with the default explicit
    method. The evaluation budget ends an explicit method with its status."""
    scene = SMALL.with_(chain=SMALL.chain.with_(m=1e-6), t_end=2.0, times=[1.0, 2.0])
    with TimeLimit(20):
        tr = simulate(scene, "full", method=method, max_evaluations=20_000)
    assert tr.stats.status == STATUS_BUDGET
    assert "max_evaluations = 20000" in tr.stats.message
    assert tr.stats.nfev <= 20_000 + 20


@pytest.mark.parametrize("model, m", [("full", 1e-6), ("full", 1e-10), ("reduced", 1e-10)])
def test_stiff_chain_ends_at_its_wall_budget(model, m):
    """m = 1e-10 ran past 90 s; the wall-clock budget ends it (the reduced model has no
    bending modes and is not stiff: it finishes)."""
    scene = SMALL.with_(chain=SMALL.chain.with_(m=m), t_end=2.0, times=[1.0, 2.0])
    with TimeLimit(15):
        tr = simulate(scene, model, method="DOP853", max_wall_s=1.0)
    if model == "reduced":
        assert tr.success
    elif tr.stats.status == STATUS_WALL:
        assert "max_wall_s = 1 s" in tr.stats.message
    else:  # at m = 1e-10 the steps may collapse (below 1e-9 t_end) before the wall budget
        assert tr.stats.status == STATUS_STALLED and m == 1e-10, tr.stats.message


def test_the_default_method_finishes_the_stiff_chain():
    """The same chain on "auto": the bending block (spectral radius 4e6 1/s) sets DOP853's
    steps, so it goes on with Radau IIA and reaches t_end in ~14,000 evaluations (DOP853
    alone: 2e6 by t = 0.07 s), with Radau IIA's result to its tolerance (rtol 1e-8)."""
    scene = SMALL.with_(chain=SMALL.chain.with_(m=1e-6), t_end=2.0, times=[1.0, 2.0])
    with TimeLimit(20):
        auto = simulate(scene, "full", max_evaluations=50_000)
        radau = simulate(scene, "full", method="Radau-numba", max_evaluations=50_000)
    assert auto.success and auto.stats.switch["ended_on"] == "Radau-numba"
    np.testing.assert_allclose(auto["phi"], radau["phi"], rtol=1e-7)


def test_budgets_on_the_cli(tmp_path, capsys):
    path = tmp_path / "stiff.toml"
    path.write_text('based_on = "paper"\nn = 4\n[chain]\nm = 1e-6\n')
    out = str(tmp_path / "o")
    with TimeLimit(20):
        code = main(
            ["simulate", str(path), "--method", "DOP853-numba", "--max-evaluations", "50000"]
            + ["--out", out]
        )
    assert code == 1
    assert "evaluation budget exhausted" in capsys.readouterr().out


# ------------------------------------------------------------------- the CLI never traces


def test_unexpected_exception_is_one_line_naming_its_type(monkeypatch, tmp_path, capsys):
    """Anything unexpected is one line, exit 2, with the exception's type and message."""
    import rodval.cli.simulate as sim

    def boom(args):
        raise RuntimeError("boom\nsecond line")

    monkeypatch.setattr(sim, "run", boom)
    assert main(["simulate", "paper", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "internal error: RuntimeError: boom | second line" in err


def test_numerical_warnings_are_not_printed(tmp_path, capsys):
    path = tmp_path / "F.toml"
    path.write_text('based_on = "paper"\nn = 4\nt_end = 0.5\n[initial]\ndphi = 1e160\n')
    main(["simulate", str(path), "--method", "RK45", "--out", str(tmp_path / "o")])
    assert "Warning" not in capsys.readouterr().err


def test_finite_or_reported_at_magnitude_bounds():
    """Runs at the bounds end with a status or finite values (never an exception)."""
    for change in ({"m": 1e-12}, {"l": 1e-12}, {"kappa": 1e12}, {"nu": 1e12}, {"EI": 1e-12}):
        for model in ("full", "reduced"):
            scene = SMALL.with_(chain=SMALL.chain.with_(**change))
            tr = simulate(scene, model, max_wall_s=2.0, max_evaluations=200_000)
            for v in tr.values.values():
                assert np.all(np.isfinite(v)), (change, model)
            assert tr.success or tr.stats.message
    assert math.isfinite(SMALL.t_end)
