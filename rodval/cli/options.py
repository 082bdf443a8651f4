"""Option parsers shared by subcommands: each rejects bad values with a message naming them."""
from __future__ import annotations

import argparse
import math

from ..settings import SCIPY_METHODS


def positive_float(name: str):
    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number > 0, got {text!r}") from None
        if not (v > 0) or math.isnan(v):
            raise argparse.ArgumentTypeError(f"{name} must be a number > 0, got {text!r}")
        return v
    return parse


def positive_int(name: str):
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be an integer >= 1, got {text!r}") from None
        if v < 1:
            raise argparse.ArgumentTypeError(f"{name} must be an integer >= 1, got {text!r}")
        return v
    return parse


def time_list(text: str) -> list[float]:
    try:
        values = [float(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--times must be comma-separated seconds like 0.5,1,2, got {text!r}") from None
    if not values:
        raise argparse.ArgumentTypeError("--times must list at least one time")
    if any(v < 0 or not math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"--times must be finite and >= 0, got {text!r}")
    if any(b <= a for a, b in zip(values, values[1:])):
        raise argparse.ArgumentTypeError(f"--times must be strictly increasing, got {text!r}")
    return values


def key_value(text: str) -> tuple[str, object]:
    """KEY=VALUE for model options; VALUE parsed as int, float or kept as text."""
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"--set expects KEY=VALUE, got {text!r}")
    key, raw = text.split("=", 1)
    value: object = raw
    for cast in (int, float):
        try:
            value = cast(raw)
            break
        except ValueError:
            continue
    return key.strip(), value


def add_integrator_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--method", default="DOP853", choices=SCIPY_METHODS,
                   help="scipy solve_ivp method for native models (default DOP853)")
    p.add_argument("--rtol", type=positive_float("--rtol"), default=1e-10,
                   help="relative tolerance > 0 (default 1e-10)")
    p.add_argument("--atol", type=positive_float("--atol"), default=1e-12,
                   help="absolute tolerance > 0 (default 1e-12)")
    p.add_argument("--max-step", type=positive_float("--max-step"), default=math.inf,
                   help="largest step, s (default unbounded)")
