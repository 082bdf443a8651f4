"""One result, finished in one place (issue 48): one precedence rule for how a run ended
(``rodval.core.status.update_result`` / ``update_status``), one run-result type that reads the
same in memory, in a study's case record and in run.json, one ``finish`` that every model and
every failure path ends with, and no other site that writes a status."""

from __future__ import annotations

import ast
import itertools
import json
from pathlib import Path

import numpy as np
import pytest
from scenes import two_rod_latch

from rodval.core.run_result import SolverStats
from rodval.core.status import PRECEDENCE, Status, update_result, update_status
from rodval.core.trajectory import RESULT_KEYS, Trajectory, finish
from rodval.report.run_files import read_run, write_run
from rodval.study.records import CaseRecord, RunRecord, read_case

ROOT = Path(__file__).resolve().parents[1]

#: The order written out by hand, least to most severe; endings on one line rank alike (the
#: first of them stays).
ORDER = [
    [Status.SUCCESS],
    [Status.WALL, Status.BUDGET, Status.TIMEOUT],
    [Status.FAILED],
    [Status.STALLED],
    [Status.BLOWUP],
    [Status.DIVERGED],
    [Status.ERROR, Status.CRASHED],
]
LEVEL = {s: i for i, group in enumerate(ORDER) for s in group}


def test_every_status_has_a_rank_and_the_order_is_the_documented_one():
    assert set(LEVEL) == set(Status) == set(PRECEDENCE)
    for a, b in itertools.product(Status, Status):
        assert (PRECEDENCE[a] < PRECEDENCE[b]) == (LEVEL[a] < LEVEL[b]), (a, b)


@pytest.mark.parametrize("old, new", list(itertools.product(Status, Status)))
def test_precedence_table_every_pair(old, new):
    """A worse ending replaces a better one, never the reverse; among equals the first stays."""
    expected = new if LEVEL[new] > LEVEL[old] else old
    assert update_result(old, new) is expected
    stats = SolverStats(status=old, message="first", t_reached=1.0)
    won = update_status(stats, new, "second", 0.5)
    assert won == (expected is new and new is not old)
    assert stats.status is expected
    assert (stats.message, stats.t_reached) == (("second", 0.5) if won else ("first", 1.0))


def test_update_status_keeps_t_reached_without_t_and_refuses_no_status():
    stats = SolverStats(t_reached=2.0)
    assert update_status(stats, Status.FAILED, "gave up")
    assert (stats.status, stats.message, stats.t_reached) == (Status.FAILED, "gave up", 2.0)
    with pytest.raises(ValueError):
        update_status(stats, 7, "no such status")


def _stats() -> SolverStats:
    """A result with every field away from its default."""
    return SolverStats(
        status=Status.WALL,
        message="wall-clock budget exhausted at t = 0.1 s",
        t_reached=0.1,
        nfev=120,
        njev=3,
        nlu=4,
        nsteps=17,
        wall_s=0.25,
        energy_residual=1e-7,
        momentum_residual=2e-9,
        max_bending=0.01,
        small_bending=True,
        valid=False,
        validity=[{"assumption": "energy balance", "figure": 1e-7, "holds": True}],
        switch={"to": "Radau", "t": 0.05, "h_lambda": 3.3, "h": 1e-4, "reason": "stiff"},
        notes=["bending damping left out"],
    )


def _trajectory(scene) -> Trajectory:
    times = np.array([0.0, 0.05, 0.1])
    phi = np.array([[0.0, 3.09], [0.05, 3.1], [0.1, 3.11]])
    return finish(
        _stats(),
        model="full",
        scene_name=scene.name,
        times=times,
        observed={"phi": (phi, np.array([1, 2]))},
        settings={"method": "DOP853", "rtol": 1e-8},
        options={"kernel": "numba"},
        events=[{"t": 0.07, "label": "latch 1 locks", "impulse": 0.5}],
    )


def _plain(value):
    return json.loads(json.dumps(value))


def test_the_result_reads_the_same_in_memory_in_a_case_record_and_in_run_json(tmp_path):
    scene = two_rod_latch(1e3)
    traj = _trajectory(scene)
    memory = _plain(traj.result_dict())
    assert tuple(memory) == RESULT_KEYS
    assert SolverStats.from_dict(traj.stats.to_dict()) == traj.stats
    assert Trajectory.from_dict(_plain(traj.to_dict())).result_dict() == memory

    case = CaseRecord(
        case="c0",
        fingerprint="f",
        params={},
        scene={"chain": {"l": [1.5, 1.5]}, "t_end": 0.42},
        reference="full",
        runs=[RunRecord(label="full", setup_s=0.1, trajectory=traj)],
        discrepancies=[],
    )
    path = tmp_path / "c0.json"
    path.write_text(case.to_json())
    on_disk = json.loads(path.read_text())["runs"][0]["trajectory"]
    assert {k: on_disk[k] for k in RESULT_KEYS} == memory
    assert read_case(path).runs[0].trajectory.result_dict() == memory

    write_run(traj, scene, tmp_path / "run")
    run_json = json.loads((tmp_path / "run" / "run.json").read_text())
    assert {k: run_json[k] for k in RESULT_KEYS} == memory
    back = read_run(tmp_path / "run")
    assert back.result_dict() == memory
    assert back.stats == traj.stats


def test_finish_says_a_success_reached_t_end_and_leaves_a_failure_as_it_was():
    done = finish(SolverStats(t_reached=1.0), model="m", scene_name="s")
    assert (done.stats.message, done.times.size, done.values) == ("reached t_end", 0, {})
    failed = Trajectory.failed(
        "m", "s", SolverStats(status=Status.TIMEOUT, message="timeout after 5 s")
    )
    assert (failed.stats.status, failed.stats.message) == (Status.TIMEOUT, "timeout after 5 s")


def _sources():
    for folder in ("rodval", "reference_models"):
        yield from sorted((ROOT / folder).rglob("*.py"))


def _status_writes(tree: ast.AST) -> list[int]:
    """Lines assigning an attribute named ``status`` (plain, augmented, annotated or in a
    tuple of targets)."""
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, (ast.AugAssign, ast.AnnAssign)):
            targets = [node.target]
        else:
            continue
        for target in targets:
            for sub in ast.walk(target):
                if isinstance(sub, ast.Attribute) and sub.attr == "status":
                    lines.append(node.lineno)
    return lines


def test_status_is_written_at_no_more_than_three_sites():
    sites = [
        f"{path.relative_to(ROOT)}:{line}"
        for path in _sources()
        for line in _status_writes(ast.parse(path.read_text()))
    ]
    assert 1 <= len(sites) <= 3, sites
    assert all(s.startswith("rodval/core/") for s in sites), sites


def test_the_writes_counter_sees_a_tuple_assignment():
    """The counter above can fail: a status written in a tuple of targets is a site."""
    tree = ast.parse("stats.status, stats.message = 1, 'x'\nx = stats.status\n")
    assert _status_writes(tree) == [1]


def _calls_finish(path: Path, function: str) -> bool:
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and node.name == function:
            return any(
                isinstance(c, ast.Call) and getattr(c.func, "id", None) == "finish"
                for c in ast.walk(node)
            )
    raise AssertionError(f"{path}: no function {function!r}")


def test_one_finish_function_every_model_and_failure_path_ends_with():
    defined = [  # module-level functions (a lock window's ``finish`` method is not one)
        f"{path.relative_to(ROOT)}"
        for path in _sources()
        for node in ast.parse(path.read_text()).body
        if isinstance(node, ast.FunctionDef) and node.name == "finish"
    ]
    assert defined == ["rodval/core/trajectory.py"]
    assert _calls_finish(ROOT / "rodval/solvers/driver.py", "integrate")
    assert _calls_finish(ROOT / "reference_models/exudyn_chain.py", "_trajectory")
    assert _calls_finish(ROOT / "rodval/core/trajectory.py", "failed")
