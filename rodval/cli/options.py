"""Option parsers shared by subcommands: each rejects bad values with a message naming them."""
from __future__ import annotations

import argparse
import math

from ..settings import METHODS


def positive_float(name: str, *, finite: bool = True, below: float = math.inf):
    """Parser of a number > 0 (and < ``below``) for option ``name``; finite unless
    ``finite=False``."""
    allowed = "a finite number > 0" if finite else "a number > 0 (inf allowed)"
    if below < math.inf:
        allowed = f"a number in (0, {below:g})"

    def parse(text: str) -> float:
        try:
            v = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be {allowed}, got {text!r}") from None
        if not (0 < v < below) or (finite and math.isinf(v)):
            raise argparse.ArgumentTypeError(f"{name} must be {allowed}, got {text!r}")
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
        raise argparse.ArgumentTypeError(f"--times must be finite and >= 0 s, got {text!r}")
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
    p.add_argument("--method", default="DOP853", choices=METHODS,
                   help="scipy solve_ivp method, or DOP853-numba (compiled loop), for native "
                        "models (default DOP853)")
    p.add_argument("--rtol", type=positive_float("--rtol", below=1.0), default=1e-10,
                   help="relative tolerance in (0, 1) (default 1e-10)")
    p.add_argument("--atol", type=positive_float("--atol"), default=1e-12,
                   help="absolute tolerance > 0 (default 1e-12)")
    p.add_argument("--max-step", type=positive_float("--max-step", finite=False), default=math.inf,
                   help="largest step, s (default unbounded)")
