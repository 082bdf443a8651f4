"""Every integration method on every base and output, or refused before any work (issue 46).

The matrix: every method ``simulate`` accepts (``METHODS``: "auto", scipy's and the compiled
ones) x every base (pinned, free, prescribed) x every output that base has (``drive`` on the
prescribed base) x the model (the full model's paper rung, its exact p = 2 rung, the reduced
model) on a small scene with a latch that locks and two stops on hinge 0. Each combination
runs to t_end with the answer of "auto" to what the tolerance carries (rtol 1e-6: 1e-3 of each
quantity's scale; measured at most 2.4e-4, RK23 on the free base's hinge moment), or is
refused before any work (the reduced model on a moving base) with one line naming the base.
A prescribed base's ``drive`` and energy audit on a scipy method failed with numba's
TypingError ("reshape() supports contiguous array only"): scipy hands strided states to the
model (the audit's columns of a dense output, the finite-difference Jacobian's columns).
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest

from rodval import Base, simulate
from rodval.core.base import Motion
from rodval.core.hinges import Latch, Stop
from rodval.core.loads import NodalForce
from rodval.core.scene import QUANTITIES, UNITS, Chain, InitialState, Scene
from rodval.core.settings import COMPILED_METHODS, METHODS, SCIPY_METHODS
from rodval.study.spec import StudySpec

BASES = {
    "pinned": Base(),
    "free": Base(kind="free", mass=5.0, inertia=2.0, hinge_offset=(0.3, 0.0)),
    "prescribed": Base(
        kind="prescribed",
        hinge_offset=(0.3, 0.0),
        motion={
            "attitude": Motion("spin_up", (2.0, 0.2)),
            "x": Motion("harmonic", (0.05, 10.0, 0.0)),
        },
    ),
}
#: the outputs every base has: every quantity (``QUANTITIES``, the one list) but the moving
#: bases' own, so a quantity added to rodval joins the matrix by itself
MOVING_OUTPUTS = ("base", "drive")
PINNED_OUTPUTS = tuple(q for q in QUANTITIES if q not in MOVING_OUTPUTS)
#: every output each base has
OUTPUTS = {
    "pinned": PINNED_OUTPUTS,
    "free": PINNED_OUTPUTS + ("base",),
    "prescribed": PINNED_OUTPUTS + ("base", "drive"),
}
#: the models: registry name and options
MODELS = {
    "full": ("full", {"kinematics": "first-order"}),
    "full-exact-p2": ("full", {"kinematics": "exact", "shapes": 2}),
    "reduced": ("reduced", {}),
}
TOLERANCES = {"rtol": 1e-6, "atol": 1e-8}
#: agreement with "auto", relative to each quantity's scale: 1000 rtol
AGREE = 1e-3
#: the methods whose runs of the full model take seconds each (scipy's Python loop on an
#: implicit method or a low order): run with -m slow
HEAVY = ("RK23", "Radau", "BDF", "LSODA")


def scene(base: str) -> Scene:
    """2 rods (EI 2e3), hinge 1 unfolding on a spring onto its latch at 0.3 rad (it locks at
    0.02-0.03 s), hinge 0 between two stops at +-0.01 rad; 0.12 s."""
    chain = Chain.uniform(2, l=1.0, m=1.0, EI=2e3, mu=0.1, kappa=[0.0, 20.0], nu=[0.0, 0.1])
    return Scene(
        chain=chain,
        t_end=0.12,
        times=np.linspace(0.0, 0.12, 4),
        outputs=OUTPUTS[base],
        initial=InitialState(phi=[0.0, 0.6]),
        latches=(Latch(1, 0.3),),
        stops=(
            Stop(0, 0.01, side="upper", stiffness=2e3),
            Stop(0, -0.01, side="lower", stiffness=2e3),
        ),
        base=BASES[base],
        name="matrix",
    )


@cache
def reference(model: str, base: str):
    name, options = MODELS[model]
    return simulate(scene(base), name, **options, **TOLERANCES)


def scales(tr, sc: Scene) -> dict[str, float]:
    """Each quantity's scale: the largest magnitude among the quantities of its unit (the
    energy audit's residual against the energies), and for a momentum at least the chain's
    gross momentum (M L max|phi'|; a free chain at rest keeps P = 0 to round-off)."""
    mass = float(np.sum(sc.chain.m * sc.chain.l) + np.sum(sc.chain.mu))
    length = float(np.sum(sc.chain.l))
    rate = float(np.abs(tr["dphi"]).max())
    gross = {"N s": mass * length * rate, "N m s": mass * length**2 * rate}
    by_unit: dict[str, float] = {}
    for q in tr.values:
        by_unit[UNITS[q]] = max(by_unit.get(UNITS[q], 0.0), float(np.abs(tr[q]).max()))
    return {q: max(by_unit[UNITS[q]], gross.get(UNITS[q], 0.0)) for q in tr.values}


def cases():
    for model in MODELS:
        for base in BASES:
            for method in METHODS:
                heavy = model != "reduced" and method in HEAVY
                marks = [pytest.mark.slow] if heavy else []
                yield pytest.param(model, base, method, marks=marks, id=f"{model}-{base}-{method}")


def refused_before_work(model: str, base: str) -> bool:
    return model == "reduced" and base != "pinned"


@pytest.mark.parametrize(("model", "base", "method"), list(cases()))
def test_every_method_runs_every_base_and_output_or_refuses_before_work(
    model, base, method, monkeypatch
):
    name, options = MODELS[model]
    sc = scene(base)
    if refused_before_work(model, base):
        from rodval.models.presets.reduced import ReducedModel

        def no_work(*_):
            raise AssertionError("the reduced model built a system it refuses")

        monkeypatch.setattr(ReducedModel, "system", no_work)
        with pytest.raises(ValueError, match=f"model 'reduced' has no {base} base") as err:
            simulate(sc, name, method=method, **options, **TOLERANCES)
        assert "\n" not in str(err.value)
        return
    ref = reference(model, base)
    assert ref.success, ref.stats.message
    tr = simulate(sc, name, method=method, **options, **TOLERANCES)
    assert tr.success, tr.stats.message
    assert tr.settings["method"] == (ref.settings["method"] if method == "auto" else method)
    assert tr.times[-1] == sc.t_end
    assert sorted(tr.values) == sorted(ref.values)
    assert [e["label"] for e in tr.events] == [e["label"] for e in ref.events]
    assert ref.events  # the latch locks
    for mine, theirs in zip(tr.events, ref.events):
        assert abs(mine["t"] - theirs["t"]) < AGREE * sc.t_end
    scale = scales(ref, sc)
    for q in ref.values:
        gap = float(np.abs(tr[q] - ref[q]).max())
        assert gap <= AGREE * scale[q], (q, gap, scale[q])


def test_the_matrix_lists_every_method_simulate_accepts():
    assert set(METHODS) == {"auto", *SCIPY_METHODS, *COMPILED_METHODS}
    assert {c.values[2] for c in cases()} == set(METHODS)


@pytest.mark.parametrize("method", ["RK45", "DOP853", "LSODA"])
def test_a_prescribed_base_drive_and_audit_on_a_scipy_method(method):
    """The issue's failure: the drive and the energy audit of a prescribed base on scipy's
    methods (a TypingError in the model's kernel, 60 lines in the run's message)."""
    sc = scene("prescribed").with_(outputs=("phi", "drive", "energy"))
    tr = simulate(sc, "full", method=method, **MODELS["full"][1], **TOLERANCES)
    assert tr.success, tr.stats.message
    ref = reference("full", "prescribed")
    force = scales(ref, scene("prescribed"))["drive_force"]
    assert np.abs(tr["drive_force"] - ref["drive_force"]).max() <= AGREE * force
    assert tr.stats.energy_residual is not None and tr.stats.energy_residual < 1e-4


@pytest.mark.parametrize("method", ["RK45", "auto"])
def test_a_model_error_is_one_line_in_the_runs_message(method):
    """A model's error (numba's TypingError ran to 60 lines) is one line in the run's
    message, run.json and the status line: its type, first line and the count left out."""

    def law(t):
        raise RuntimeError("first line\nsecond line\n\nthird line")

    sc = scene("pinned").with_(loads=(NodalForce(1, fx=law),))
    tr = simulate(sc, "full", method=method)
    assert not tr.success
    assert "\n" not in tr.stats.message
    assert "RuntimeError: first line [2 more lines not shown]" in tr.stats.message


# -- a study refuses, when it is read, a case a model refuses --------------------------------


def study(models: dict, outputs: list[str] | None = None) -> dict:
    scene_table = {
        "n": 2,
        "chain": {"l": 1.0, "m": 1.0, "EI": 1e3},
        "t_end": 0.1,
        "base": {
            "kind": "prescribed",
            "motion": {"attitude": {"law": "spin_up", "rate": 1.0, "time": 0.5}},
        },
    }
    if outputs:
        scene_table["outputs"] = outputs
    return {
        "study": {"name": "hub"},
        "scene": scene_table,
        "grid": {"scene.chain.EI": [1e3, 2e3]},
        "models": models,
    }


def test_a_study_refuses_the_reduced_model_on_a_prescribed_base_when_it_is_read(monkeypatch):
    """It ran, and reported "1 failed model runs"; now it is refused when the study is read,
    naming the file, the case, the model and the reason, before any case runs."""
    from rodval.models.presets.reduced import ReducedModel

    def no_work(*_):
        raise AssertionError("a refused case was run")

    monkeypatch.setattr(ReducedModel, "run", no_work)
    with pytest.raises(ValueError) as err:
        StudySpec.from_dict(study({"full": {}, "quasi": {"model": "reduced"}}), name="hub")
    message = str(err.value)
    assert "\n" not in message
    for part in ("hub", "case 'EI=1000'", "'quasi' (reduced)", "no prescribed base"):
        assert part in message


def test_a_study_refusal_of_a_scene_from_a_file_names_the_file(tmp_path):
    """A fuzz find: the refusal of the reduced model on a prescribed base read from
    [scene] file = "driven.toml" named the study and the case, not the file the base is in."""
    from rodval.study.spec import load_study
    from rodval.study.toml_text import toml_text

    table = study({"full": {}})["scene"]
    (tmp_path / "driven.toml").write_text(toml_text(table))
    doc = {"study": {"name": "hub"}, "scene": {"file": "driven.toml"}, "models": {"full": {},
           "reduced": {}}}  # fmt: skip
    (tmp_path / "s.toml").write_text(toml_text(doc))
    with pytest.raises(ValueError) as err:
        load_study(tmp_path / "s.toml")
    message = str(err.value)
    assert "\n" not in message and "driven.toml" in message and "no prescribed base" in message


def test_a_study_refuses_the_drive_on_exudyn_when_it_is_read():
    pytest.importorskip("exudyn")
    doc = study({"full": {}, "ex": {"model": "exudyn"}}, outputs=["phi", "drive"])
    with pytest.raises(ValueError, match=r"case 'EI=1000': model 'ex' \(exudyn\).*'drive'"):
        StudySpec.from_dict(doc, name="hub")


def test_a_study_the_models_take_is_read():
    spec = StudySpec.from_dict(study({"full": {}}, outputs=["phi", "drive"]), name="hub")
    assert [c.id for c in spec.cases] == ["EI=1000", "EI=2000"]


def test_simulate_and_the_study_ask_the_one_check():
    """``simulate`` refuses what the study refuses, with the same reason, before any work."""
    from rodval.core.settings import IntegratorSettings
    from rodval.models.registry import check_scene, get_model

    sc = scene("prescribed")
    with pytest.raises(ValueError, match="model 'reduced' has no prescribed base"):
        check_scene(get_model("reduced"), sc, IntegratorSettings())
    with pytest.raises(ValueError, match="first_step must be at most the horizon"):
        check_scene(get_model("full"), sc, IntegratorSettings(first_step=1.0))
