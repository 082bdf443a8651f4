"""The study runner: resume after a kill, failure isolation, the dask backend."""

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest
from study_helpers import write_study

from rodval.study import load_study, run_study

TIMING = ["wall_s", "setup_s"]


def _tables(out: Path) -> dict[str, pd.DataFrame]:
    return {t: pd.read_csv(out / f"{t}.csv") for t in ("trajectories", "discrepancies", "runtime")}


def _assert_same_results(a: Path, b: Path) -> None:
    ta, tb = _tables(a), _tables(b)
    pd.testing.assert_frame_equal(ta["trajectories"], tb["trajectories"])
    pd.testing.assert_frame_equal(ta["discrepancies"], tb["discrepancies"])
    pd.testing.assert_frame_equal(
        ta["runtime"].drop(columns=TIMING), tb["runtime"].drop(columns=TIMING)
    )


def _study_cmd(path: Path, out: Path, *extra: str) -> list[str]:
    return [
        sys.executable,
        "-m",
        "rodval",
        "study",
        str(path),
        "--out",
        str(out),
        "--no-progress",
        *extra,
    ]


def test_killed_study_resumes_without_redoing_finished_cases(tmp_path):
    path = write_study(tmp_path, grid="scene.t_end = [0.1, 0.2, 0.3, 0.4]")  # 8 cases
    n_cases = len(load_study(path).cases)
    out = tmp_path / "killed"
    proc = subprocess.Popen(
        _study_cmd(path, out, "--workers", "1"), stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    deadline = time.monotonic() + 120
    while len(list((out / "cases").glob("*.json"))) < 2 and time.monotonic() < deadline:
        assert proc.poll() is None, "the study ended before it could be killed"
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    # a second link to each finished record keeps its file: a rewrite (os.replace) would put
    # another file under the name (no dependence on modification times)
    kept = tmp_path / "kept"
    kept.mkdir()
    finished = {p: kept / p.name for p in (out / "cases").glob("*.json")}
    for p, link in finished.items():
        os.link(p, link)
    assert 2 <= len(finished) < n_cases
    assert not (out / "discrepancies.csv").exists()
    res = subprocess.run(_study_cmd(path, out, "--workers", "2"), capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert f"{n_cases - len(finished)} cases run, {len(finished)} reused" in res.stdout
    assert all(p.samefile(link) for p, link in finished.items())  # not recomputed
    assert len(list((out / "cases").glob("*.json"))) == n_cases
    assert not list((out / "cases").glob(".*.tmp"))
    fresh = tmp_path / "fresh"
    run_study(load_study(path), fresh, workers=2, progress=False, report=False)
    _assert_same_results(out, fresh)


def test_failing_case_is_recorded_and_the_others_finish(tmp_path):
    # The full model with max_step 1e-8 s needs 5e6 Radau steps (minutes): stopped by the
    # case timeout; the same cases with max_step = inf take about a second.
    models = '[models.reduced]\n[models.full]\nmethod = "Radau"\nrtol = 1e-5\natol = 1e-7\n'
    grid = "scene.t_end = [0.05]\nmodels.full.max_step = [inf, 1e-8]"
    path = write_study(tmp_path, models=models, grid=grid)
    out = tmp_path / "out"
    res = subprocess.run(
        _study_cmd(path, out, "--case-timeout", "20"), capture_output=True, text=True
    )
    assert res.returncode == 0, res.stderr
    rt = pd.read_csv(out / "runtime.csv")
    assert len(rt) == 4 * 2
    bad = rt[rt["status"] != "success"]
    assert list(bad["model"]) == ["full", "full"] and set(bad["max_step"]) == {1e-8}
    assert set(bad["status"]) == {"timeout"}
    assert bad["message"].str.contains("time limit of 20 s").all()
    # the reference run of a timed-out case is kept; nothing else failed
    axis = "models.full.max_step"
    assert (rt[rt[axis] == 1e-8].query("model == 'reduced'")["status"] == "success").all()
    disc = pd.read_csv(out / "discrepancies.csv")
    ok = disc[disc[axis] == math.inf]
    assert (ok["status"] == "ok").all() and not ok[
        ["max_abs", "rms", "final_abs", "max_rel"]
    ].isna().any().any()
    failed = disc[disc[axis] == 1e-8]
    assert (failed["status"] == "model failed (timeout)").all() and failed["max_abs"].isna().all()
    assert set(disc["case"]) == set(rt["case"])


def test_dask_backend_on_a_local_cluster_gives_the_same_tables(tmp_path):
    distributed = pytest.importorskip("distributed")
    spec = load_study(write_study(tmp_path, grid="scene.t_end = [0.1]"))
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster:
        res = run_study(
            spec,
            tmp_path / "dask",
            backend="dask",
            scheduler=cluster.scheduler_address,
            progress=False,
            report=False,
        )
    assert sorted(res.ran) == sorted(c.id for c in spec.cases)
    run_study(spec, tmp_path / "procs", workers=2, progress=False, report=False)
    _assert_same_results(tmp_path / "dask", tmp_path / "procs")


def test_bad_runner_arguments(tmp_path):
    spec = load_study(write_study(tmp_path))
    for kwargs, word in (
        ({"workers": 0}, "workers"),
        ({"case_timeout": -1.0}, "case_timeout"),
        ({"backend": "mpi"}, "backend"),
        ({"backend": "dask"}, "scheduler"),
    ):
        with pytest.raises(ValueError, match=word):
            run_study(spec, tmp_path / "x", **kwargs)
    assert not (tmp_path / "x").exists()
