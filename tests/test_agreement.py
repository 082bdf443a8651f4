"""The answer a study report opens with (rodval.analysis.agreement): the agreement horizon,
the first lock where a model parts and the measured cause, on synthetic data; the study's
[agreement] table and its twin run."""

import copy
import math

import numpy as np
import pandas as pd
import pytest

from rodval.analysis.agreement import (
    AgreementSettings,
    agreement_horizon,
    agreement_table,
    cause,
    deployed_gap,
    gap_series,
    lock_order,
    locks_within,
    parting_lock,
    twin_parts_as_much,
)
from rodval.study import StudySpec

T = np.linspace(0.0, 2.0, 201)


def _phi(shift: float = 0.0) -> np.ndarray:
    """Two chord angles, the second with a delay ``shift`` s after t = 1 s."""
    a = np.sin(T)
    b = np.where(T < 1.0, 2.0 * T, 2.0 + 3.0 * (T - 1.0 - shift).clip(min=0.0))
    return np.column_stack([a, b])


def test_gap_is_the_largest_column_gap_over_the_quantity_scale():
    ref = np.array([[1.0, -4.0], [2.0, 0.0]])
    got = gap_series(ref + np.array([[0.4, 0.0], [0.0, -0.8]]), ref)
    assert got == pytest.approx([0.1, 0.2])
    assert np.isnan(gap_series(np.ones((3, 2)), np.zeros((3, 2)))).all()


def test_horizon_is_the_first_output_time_beyond_the_tolerance():
    ref, model = _phi(), _phi(shift=0.05)
    scale = np.abs(ref).max()
    gap = np.abs(model - ref).max(axis=1) / scale
    expected = T[np.argmax(gap > 0.02)]
    t_h, q = agreement_horizon(T, {"phi": model}, {"phi": ref}, 0.02)
    assert (t_h, q) == (pytest.approx(expected), "phi")
    assert 1.0 < t_h < 1.2
    # the reference's own error bar widens the band: a later horizon
    assert agreement_horizon(T, {"phi": model}, {"phi": ref}, 0.02, 0.005)[0] > t_h
    assert agreement_horizon(T, {"phi": ref}, {"phi": ref}, 0.02) == (None, None)


REF = [("latch hinge 3", 0.4), ("latch hinge 2", 0.6), ("latch hinge 1", 1.7)]


def test_parting_lock_late_early_missing_out_of_order_extra():
    assert parting_lock(REF, REF, 1e-3) is None
    late = [REF[0], ("latch hinge 2", 0.6005), ("latch hinge 1", 2.0)]
    part = parting_lock(late, REF, 1e-3)
    assert part["label"] == "latch hinge 1" and part["why"] == "late"
    assert part["dt"] == pytest.approx(0.3)
    assert parting_lock(late, REF, 0.5) is None
    early = parting_lock([REF[0], ("latch hinge 2", 0.59), REF[2]], REF, 1e-3)
    assert (early["label"], early["why"]) == ("latch hinge 2", "early")
    missing = parting_lock(REF[:2], REF, 1e-3)
    assert missing["label"] == "latch hinge 1" and math.isnan(missing["dt"])
    swapped = parting_lock([REF[1], REF[0], REF[2]], REF, 1.0)
    assert swapped["label"] == "latch hinge 3" and swapped["why"].startswith("out of order")
    extra = parting_lock([*REF, ("latch hinge 4", 2.0)], REF, 1e-3)
    assert extra["label"] == "latch hinge 4"


def test_cause_is_measured_not_guessed():
    part = {"label": "latch hinge 1", "dt": 0.3, "why": "late"}
    quiet = {"parts_as_much": False, "dt": 1e-8, "horizon": None}
    loud = {"parts_as_much": True, "dt": 0.2, "horizon": 1.0}
    assert cause("", None, None, quiet) == ""
    assert cause("", part, 1.5, quiet).startswith("model difference; predictable")
    assert cause("small bending", part, 1.5, quiet).startswith("out of domain (small bending)")
    assert "model difference" not in cause("small bending", part, 1.5, quiet)
    assert cause("", part, 1.5, loud).startswith("unpredictable (the twin moves it by +200 ms)")
    assert "not measured" in cause("", part, 1.5, None)
    # no parting lock: the predictability horizon against the agreement horizon
    assert cause("", None, 1.5, {**loud, "horizon": 1.2}).startswith("unpredictable")
    assert cause("", None, 1.5, {**loud, "horizon": 1.8}).startswith("model difference")


def test_the_twin_parts_as_much_at_or_before_the_lock_or_by_half_its_gap():
    part = {"label": "latch hinge 1", "dt": 0.3, "why": "late"}
    assert not twin_parts_as_much(part, REF, REF, 1e-3)
    half = [REF[0], REF[1], ("latch hinge 1", 1.7 + 0.16)]
    assert twin_parts_as_much(part, half, REF, 1.0)  # 0.16 s >= 0.5 x 0.3 s
    sooner = [REF[0], ("latch hinge 2", 0.65), REF[2]]
    assert twin_parts_as_much(part, sooner, REF, 1e-3)


def _tables(twin_shift: float, model_valid: bool = True):
    """Tidy trajectories, events and runtime of one case: reference, its twin (locks moved
    by ``twin_shift`` s) and a model 0.3 s late at hinge 1."""
    rows, events, runtime = [], [], []
    runs = {"ref": (_phi(), 0.0, 0.0), "ref twin": (_phi(twin_shift), twin_shift, 0.0)}
    runs["m"] = (_phi(0.3), 0.0, 0.3)
    for model, (phi, shift, late) in runs.items():
        for j in range(phi.shape[1]):
            rows += [
                {"case": "c", "model": model, "t": t, "quantity": "phi", "k": j + 1, "value": v}
                for t, v in zip(T, phi[:, j])
            ]
        for label, t in REF:
            dt = late + shift if label == "latch hinge 1" else 0.0
            events.append(
                {"case": "c", "model": model, "label": label, "t": t + dt, "impulse": 1.0}
            )
        runtime.append(
            {
                "case": "c",
                "model": model,
                "status": "success",
                "valid": model_valid or model != "m",
                "invalid_because": ""
                if model_valid or model != "m"
                else "largest bending angle 0.3 rad > 0.2 rad (small bending); fix: stiffer rods",
                "wall_s": 1.0,
            }
        )
    return pd.DataFrame(rows), pd.DataFrame(events), pd.DataFrame(runtime)


def test_agreement_table_names_a_model_difference_when_the_twin_stays():
    traj, events, runtime = _tables(twin_shift=1e-7)
    table = agreement_table(traj, events, runtime, "ref", AgreementSettings()).set_index("model")
    assert list(table["role"]) == ["reference", "twin", "model"]
    m = table.loc["m"]
    assert 1.0 < m["horizon"] < 1.2 and m["horizon_quantity"] == "phi"
    assert (m["part_lock"], m["part_why"]) == ("latch hinge 1", "late")
    assert m["part_dt"] == pytest.approx(0.3)
    assert m["cause"].startswith("model difference; predictable (the twin moves it by")
    assert m["worst_dt"] == pytest.approx(0.3) and m["worst_dt_lock"] == "latch hinge 1"
    assert math.isnan(table.loc["ref twin", "horizon"])  # agrees to the end


def test_agreement_table_names_unpredictable_motion_and_the_domain():
    traj, events, runtime = _tables(twin_shift=0.25, model_valid=False)
    table = agreement_table(traj, events, runtime, "ref", AgreementSettings()).set_index("model")
    got = table.loc["m", "cause"]
    assert got.startswith("out of domain (small bending); unpredictable (the twin moves it by +250")
    assert (
        table.loc["m", "out_of_domain"] == "largest bending angle 0.3 rad > 0.2 rad (small bending)"
    )
    assert table.loc["ref twin", "horizon"] < 1.2  # the predictability horizon


STUDY = {
    "study": {"name": "latched", "reference": "full"},
    "scene": {
        "n": 4,
        "t_end": 0.5,
        "times": {"num": 51},
        "outputs": ["phi", "dphi"],
        "chain": {
            "l": 1.5,
            "m": 3.0,
            "EI": 5e4,
            "mu": 0.5,
            "kappa": [1e5, 50.0, 50.0, 50.0],
            "nu": [10.0, 0.05, 0.05, 0.05],
            "rest_angle": 0.0,
        },
        "initial": {"phi": [0.0, 3.0915926535897933, 0.0, 3.0915926535897933]},
        "latches": [{"hinge": 3, "angle": 0.0}],
    },
    "models": {"full": {}, "reduced": {}},
    "agreement": {"twin": {"rod": 2, "angle": 1e-6}},
}


def test_the_twin_payload_moves_one_initial_angle_and_is_labelled():
    spec = StudySpec.from_dict(STUDY)
    case = spec.cases[0]
    assert case.labels == ["full", "reduced", "full twin"]
    main, twin = case.payloads()
    assert [m["label"] for m in twin["models"]] == ["full twin"]
    assert twin["models"][0]["model"] == "full" and twin["part"] == "twin"
    phi = twin["scene"]["initial"]["phi"]
    assert phi[1] - 3.0915926535897933 == pytest.approx(1e-6, rel=1e-6)
    assert phi[0] == phi[2] == 0.0
    plain = copy.deepcopy(STUDY)
    del plain["agreement"]
    off = StudySpec.from_dict(plain).cases[0]
    assert off.payloads() == [off.payload()] and off.fingerprint != case.fingerprint
    assert spec.agreement["tol"] == 0.02 and spec.agreement["twin"] == {"rod": 2, "angle": 1e-6}


@pytest.mark.parametrize(
    ("agreement", "message"),
    [
        ({"tol": 2}, "key 'agreement.tol': must be"),
        ({"tol": "x"}, "key 'agreement.tol': must be"),
        ({"lock_dt": 0}, "key 'agreement.lock_dt': must be"),
        ({"quantities": []}, "key 'agreement.quantities': must be a non-empty list"),
        ({"quantities": ["x"]}, "key 'agreement.quantities': 'x' is not an output"),
        ({"twin": {"rod": 5, "angle": 1e-6}}, "key 'agreement.twin.rod': must be in 1..4"),
        ({"twin": {"rod": 2, "angle": 0.0}}, "key 'agreement.twin.angle': must be a nonzero"),
        ({"twin": {"rod": 2, "angle": 0.01}}, "key 'agreement.twin.angle': must be"),
        ({"twin": {"rod": 2}}, "key 'agreement.twin.angle': is missing"),
        ({"reference_error": {"lock_dt": -1}}, "agreement.reference_error.lock_dt"),
        ({"horizon": 1}, "horizon"),
    ],
)
def test_bad_agreement_tables_are_refused_in_one_line(agreement, message):
    doc = {**copy.deepcopy(STUDY), "agreement": agreement}
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(".", r"\.")) as err:
        StudySpec.from_dict(doc)
    assert "\n" not in str(err.value)


def test_a_study_with_a_twin_runs_it_and_its_report_opens_with_the_answer(tmp_path):
    from rodval.study import run_study

    run_study(StudySpec.from_dict(STUDY), tmp_path / "out", workers=1, progress=False)
    report = (tmp_path / "out" / "report.md").read_text()
    lines = report.splitlines()
    assert lines[2] == "## Answer"
    assert "| full twin " in report and "predictability horizon" in report
    runtime = pd.read_csv(tmp_path / "out" / "runtime.csv")
    assert list(runtime["model"]) == ["full", "reduced", "full twin"]
    answer = report.split("## Study")[0]
    assert "`reduced`" in answer and "agrees with `full` until" in answer


def test_beyond_the_horizon_lock_order_locks_within_and_the_deployed_state():
    """Past its horizon a model is still judged lock by lock and on its deployed state: the
    model of ``_tables`` keeps the reference's lock order, misses hinge 1's bound by 0.3 s and
    ends 0.9 rad off on rod 2 (b = 2 + 3 (t - 1 - shift) after t = 1 s: 3 x 0.3 rad at every
    time after the later last lock); the twin (1e-7 s) is within 3e-7 rad."""
    ref = [("latch hinge 2", 0.4), ("latch hinge 1", 1.0)]
    assert lock_order(ref, ref) == "same"
    assert (
        lock_order(ref[::-1], ref) == "lock 1: latch hinge 1 where the reference has latch hinge 2"
    )
    assert lock_order(ref[:1], ref) == "1 locks, the reference 2"
    assert locks_within([("latch hinge 2", 0.4005), ("latch hinge 1", 1.3)], ref, 1e-3) == "1/2"
    assert locks_within(ref[::-1], ref, 1.0) == "0/2"
    traj, events, runtime = _tables(twin_shift=1e-7)
    settings = AgreementSettings(reference_rel=0.01)
    table = agreement_table(traj, events, runtime, "ref", settings).set_index("model")
    m, twin = table.loc["m"], table.loc["ref twin"]
    assert (m["lock_order"], m["locks_within"]) == ("same", f"{len(REF) - 1}/{len(REF)}")
    assert m["deployed_gap"] == pytest.approx(0.9, rel=1e-9)
    assert twin["deployed_gap"] == pytest.approx(3e-7, rel=1e-6)
    scale = np.max(np.abs(_phi()))
    assert m["deployed_band"] == pytest.approx(0.01 * scale)
    assert math.isnan(m["attitude_gap"])  # no free base


def test_deployed_gap_needs_output_after_the_last_lock():
    t = np.linspace(0.0, 1.0, 11)
    v = np.zeros((11, 1))
    assert math.isnan(deployed_gap((t, t), (v, v + 1.0), since=2.0))
    assert deployed_gap((t, t), (v, v + 1.0), since=0.5) == pytest.approx(1.0)


def test_the_reference_error_bar_takes_a_free_bases_attitude():
    from rodval.study.case import agreement_spec

    spec = agreement_spec({"reference_error": {"attitude": 2e-3, "lock_dt": 1e-3}}, "s.toml")
    assert AgreementSettings.from_dict(spec).reference_attitude == 2e-3


def test_a_free_bases_deployed_attitude_is_compared_against_its_band():
    """The body's attitude (quantity base_attitude, k = 0) of the model 0.01 rad off the
    reference's after the later last lock: attitude_gap 0.01 rad, judged against the
    reference's attitude bar."""
    traj, events, runtime = _tables(twin_shift=1e-7)
    extra = [
        {"case": "c", "model": m, "t": t, "quantity": "base_attitude", "k": 0, "value": v}
        for m, off in (("ref", 0.0), ("ref twin", 0.0), ("m", 0.01))
        for t, v in zip(T, 0.1 * np.sin(T) + off)
    ]
    traj = pd.concat([traj, pd.DataFrame(extra)], ignore_index=True)
    settings = AgreementSettings(reference_attitude=2e-3)
    table = agreement_table(traj, events, runtime, "ref", settings).set_index("model")
    assert table.loc["m", "attitude_gap"] == pytest.approx(0.01, rel=1e-9)
    assert table.loc["m", "attitude_band"] == 2e-3
    assert table.loc["ref twin", "attitude_gap"] == pytest.approx(0.0, abs=1e-15)


def test_the_answer_states_the_references_error_bar_or_that_it_is_not_given():
    """The reference's sentence carries the error bar the study gives (measured by refining
    the reference, `rodval reference`), each figure in its unit; without one, it says so."""
    from rodval.report.study_answer import _sentences

    traj, events, runtime = _tables(twin_shift=1e-7)
    bar = {"lock_dt": 0.00787, "impulse_rel": 0.00842, "rel": 0.00648, "attitude": 4.5e-4}
    settings = AgreementSettings.from_dict({"reference_error": bar})
    table = agreement_table(traj, events, runtime, "ref", settings)
    first = _sentences(table, "ref", settings)[0]
    assert first.startswith("The reference `ref` is valid, its error bar measured by refining")
    for text in ("locks to 7.87 ms", "impulses to 0.84%", "angles to 0.65% of their scale"):
        assert text in first
    assert "deployed attitude to 0.00045 rad" in first
    plain = _sentences(table, "ref", AgreementSettings())[0]
    assert "its error bar not given ([agreement] reference_error)" in plain
