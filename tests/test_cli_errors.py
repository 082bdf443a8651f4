"""The command line refuses bad options: one line naming the option and what is allowed,
exit status 2, no traceback.

Every case runs in-process through ``rodval.cli.main`` (fast); a few also run as
``python -m rodval`` in a subprocess, the way users meet them.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest
from checks import assert_refused, run_main

ROOT = Path(__file__).resolve().parents[1]


def run_cli(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-m", "rodval", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )


@pytest.fixture(scope="module")
def bad_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("scenes")
    (d / "malformed.toml").write_text("n = [\n")
    (d / "zero_rods.toml").write_text("n = 0\n")
    (d / "unknown_key.toml").write_text("rods = 3\n")
    (d / "negative_ei.toml").write_text('based_on = "paper"\n[chain]\nEI = -1.0\n')
    return d


CASES = [
    (["--rtol", "-1e-3"], ["--rtol", "(0, 1)"]),
    (["--rtol", "0"], ["--rtol", "(0, 1)"]),
    (["--atol", "0"], ["--atol", "> 0"]),
    (["--atol", "nan"], ["--atol", "> 0"]),
    (["--max-step", "-2"], ["--max-step", "> 0"]),
    (["--model", "fancy"], ["--model", "full", "reduced"]),
    (["--method", "Euler"], ["--method", "DOP853", "Radau"]),
    (["--times", "1,0.5"], ["--times", "increasing"]),
    (["--times", "-1,2"], ["--times", ">= 0"]),
    (["--times", "0.5,9"], ["times", "[0, 2.0]"]),
    (["--t-end", "-1"], ["--t-end", "> 0"]),
    (["--t-end", "0"], ["--t-end", "> 0"]),
    (["--set", "foo=1"], ["option", "foo"]),
]


@pytest.mark.parametrize("options, words", CASES, ids=[" ".join(c[0]) for c in CASES])
def test_bad_option_is_refused(options, words, tmp_path, capsys):
    assert_refused(run_main(capsys, "simulate", "paper", "--out", str(tmp_path), *options), words)
    assert not (tmp_path / "trajectory.csv").exists()


@pytest.mark.parametrize(
    "options, words", [CASES[0], CASES[8], CASES[12]], ids=["rtol", "times", "set"]
)
def test_python_m_rodval_refuses_without_traceback(options, words, tmp_path):
    assert_refused(run_cli("simulate", "paper", "--out", str(tmp_path), *options), words)


@pytest.mark.parametrize(
    "name, words",
    [
        ("missing.toml", ["SCENE", "existing TOML file"]),
        ("malformed.toml", ["malformed.toml", "malformed TOML"]),
        ("zero_rods.toml", ["'n'", ">= 1"]),
        ("unknown_key.toml", ["'rods'", "allowed"]),
        ("negative_ei.toml", ["EI", "> 0"]),
    ],
)
def test_bad_scene_file_is_refused(bad_files, name, words, tmp_path, capsys):
    assert_refused(
        run_main(capsys, "simulate", str(bad_files / name), "--out", str(tmp_path)), words
    )


def test_python_m_rodval_refuses_a_malformed_scene_file(bad_files, tmp_path):
    assert_refused(
        run_cli("simulate", str(bad_files / "malformed.toml"), "--out", str(tmp_path)),
        ["malformed TOML"],
    )
