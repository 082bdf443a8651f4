"""Scene validation: every bad input names the parameter and the allowed range."""

import math

import numpy as np
import pytest

from rodval import Chain, InitialState, NodalForce, constant, paper_scene, pulse
from rodval.core.scene_file import load_scene, scene_from_dict


@pytest.mark.parametrize(
    "field,value,match",
    [
        ("l", 0.0, r"l \(rod length\) must be > 0"),
        ("m", -1.0, r"m \(mass per length\) must be > 0"),
        ("EI", 0.0, r"EI \(bending stiffness\) must be > 0"),
        ("mu", -0.1, r"mu \(node mass\) must be >= 0"),
        ("kappa", -1.0, r"kappa \(hinge stiffness\) must be >= 0"),
        ("nu", -1e-3, r"nu \(hinge damping\) must be >= 0"),
        ("l", math.nan, r"l \(rod length\) must be finite"),
        ("EI", math.inf, r"EI .* must be finite"),
        ("kappa", [1.0, 2.0], r"kappa .* length n = 3"),
    ],
)
def test_chain_rejects_bad_values(field, value, match):
    with pytest.raises(ValueError, match=match):
        Chain.uniform(3, **{field: value})


@pytest.mark.parametrize("n", [0, -2, 1.5, True])
def test_chain_rejects_bad_n(n):
    with pytest.raises(ValueError, match=r"n \(number of rods\)"):
        Chain.uniform(n)


@pytest.mark.parametrize(
    "changes,match",
    [
        ({"t_end": 0.0}, r"t_end \(horizon\) must be finite and > 0"),
        ({"t_end": -1.0}, r"t_end \(horizon\)"),
        ({"t_end": math.nan}, r"t_end \(horizon\)"),
        ({"times": []}, r"times .* non-empty"),
        ({"times": [1.0, 0.5]}, r"times .* strictly increasing"),
        ({"times": [0.5, 0.5]}, r"strictly increasing"),
        ({"times": [-0.1, 1.0]}, r"times .* \[0, t_end\]"),
        ({"times": [1.0, 3.0]}, r"times .* \[0, t_end\]"),
        ({"outputs": ("phi", "psi")}, r"outputs must be"),
        ({"outputs": ()}, r"outputs must be"),
        ({"loads": (pulse(9),)}, r"load node must be in 1..n"),
        ({"initial": InitialState(phi=[0.0, 1.0])}, r"initial phi .* length n = 8"),
    ],
)
def test_scene_rejects_bad_values(changes, match):
    with pytest.raises(ValueError, match=match):
        paper_scene().with_(**changes)


def test_load_validation():
    with pytest.raises(ValueError, match="load node must be >= 1"):
        pulse(0)
    with pytest.raises(ValueError, match="pulse T must be"):
        pulse(1, T=0.0)
    with pytest.raises(ValueError, match="load support"):
        NodalForce(1, support=(2.0, 1.0))
    with pytest.raises(ValueError, match="fx must be callable"):
        NodalForce(1, fx=3.0)


def test_pulse_matches_the_paper_and_declares_its_kinks():
    f = pulse(8)
    assert f.breakpoints == (0.5, 1.0)
    assert f.fx(0.25) == pytest.approx(-150.0) and f.fx(0.5) == pytest.approx(0.0, abs=1e-12)
    assert f.fy(0.5) == pytest.approx(1200.0) and f.fy(1.2) == 0.0
    assert not f.active(1.01)
    assert list(paper_scene().breakpoints) == [0.5, 1.0]


def test_constant_load_switches():
    f = constant(2, X=5.0, t_on=0.2, t_off=0.7)
    assert f.breakpoints == (0.2, 0.7) and f.active(0.5) and not f.active(0.1)


def test_chain_broadcasts_and_is_immutable():
    c = Chain.uniform(4, EI=[1.0, 2.0, 3.0, 4.0])
    assert c.n == 4 and c.l.tolist() == [2.0] * 4
    with pytest.raises(ValueError):
        c.l[0] = 3.0


def test_scene_file_round_trip(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(
        'based_on = "paper"\nn = 3\nt_end = 0.5\ntimes = {num = 11}\noutputs = ["phi", "x"]\n'
        '[chain]\nEI = [1e4, 2e4, 3e4]\n[[loads]]\ntype = "pulse"\nnode = 3\nYbar = 10.0\n'
    )
    s = load_scene(path)
    assert s.n == 3 and s.t_end == 0.5 and s.times.size == 11 and s.outputs == ("phi", "x")
    assert s.chain.EI.tolist() == [1e4, 2e4, 3e4] and s.loads[0].params["Ybar"] == 10.0


@pytest.mark.parametrize(
    "d,match",
    [
        ({"n": 3, "colour": 1}, r"unknown key 'colour'"),
        ({"based_on": "paper", "chain": {"E": 1}}, r"\[chain\]: unknown key 'E'"),
        ({"n": 0}, r"key 'n'"),
        (
            {"based_on": "paper", "loads": [{"type": "gust", "node": 1}]},
            r"load type must be one of",
        ),
        (
            {"based_on": "paper", "loads": [{"type": "pulse", "node": 1, "Zbar": 1}]},
            r"unexpected keyword",
        ),
        ({"based_on": "paper", "times": {"num": 0}}, r"num must be >= 1"),
        ({"based_on": "paper", "chain": {"l": -1.0}}, r"l \(rod length\)"),
        ({"base": "lab"}, r"key 'base'"),
        ({"based_on": "paper", "t_end": "long"}, r"key 't_end'"),
    ],
)
def test_scene_file_errors_name_file_and_key(d, match):
    with pytest.raises(ValueError, match=match) as info:
        scene_from_dict(d, where="f.toml")
    assert str(info.value).startswith("f.toml")


def test_malformed_scene_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("n = [\n")
    with pytest.raises(ValueError, match="malformed TOML"):
        load_scene(bad)
    with pytest.raises(ValueError, match="SCENE must be 'paper' or an existing TOML file"):
        load_scene(tmp_path / "missing.toml")


def test_default_scene_is_the_paper_example():
    s = paper_scene()
    assert s.n == 8 and s.t_end == 2.0 and np.allclose(s.chain.kappa, 100.0)
    assert s.loads[0].node == 8 and s.loads[0].params == {"Xbar": -150.0, "Ybar": 1200.0, "T": 1.0}
