"""Sampling of uncertain parameters in a study (the ``[sample]`` table): a design of points in
the unit cube (Sobol, Latin hypercube or plain random, ``scipy.stats.qmc``), seeded, mapped
through each key's distribution. Every sample is one case; the same seed gives the same
values, hence identical tables.

    [sample]
    design = "sobol"        # "sobol" (count a power of 2), "lhs", "random" or "saltelli"
    count = 256
    seed = 1
    [sample.keys]
    "scene.chain.kappa.rest" = { dist = "uniform", low = 30.0, high = 70.0 }
    "scene.latches.*.angle" = { dist = "normal", mean = 0.0, std = 0.01, low = -0.03, high = 0.03 }
    "scene.chain.nu.rest" = { dist = "lognormal", median = 0.05, sigma = 0.3 }

``design = "saltelli"`` is SALib's scheme for Sobol indices (``rodval.report.sensitivity``):
count = N (D + 2) cases, N a power of 2 >= 8 base samples, D the number of keys, in blocks of D
+ 2 consecutive cases.

Keys are paths into the study document like grid keys; ``*`` sets every element of a list
(every latch), an integer one element. Distributions (values in the key's own unit):

* ``uniform``: ``low``, ``high`` (low < high);
* ``normal``: ``mean``, ``std`` > 0, optional ``low`` / ``high``: truncated there (the design's
  points mapped through the truncated distribution's quantile function, so none is rejected);
* ``lognormal``: ``median`` > 0 and ``sigma`` > 0 (of the logarithm), optional ``low`` /
  ``high`` > 0 (truncated likewise).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from typing import Any

import numpy as np

from rodval.core.checks import check_keys
from rodval.report.sensitivity import SALTELLI, saltelli_count_error, saltelli_unit_design
from rodval.study.document import flatten

DESIGNS = ("sobol", "lhs", "random", SALTELLI)
SAMPLE_KEYS = {"design", "count", "seed", "keys"}
#: Most samples a study may draw (each is a case).
MAX_SAMPLES = 100_000
#: Parameters of each distribution: required, optional.
DISTRIBUTIONS = {
    "uniform": (("low", "high"), ()),
    "normal": (("mean", "std"), ("low", "high")),
    "lognormal": (("median", "sigma"), ("low", "high")),
}


def _real(where: str, key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ValueError(f"{where}: {key} must be a finite number, got {value!r}")
    return float(value)


def check_distribution(where: str, spec: Any) -> dict[str, Any]:
    """The distribution table ``spec`` checked (ValueError naming ``where`` and the key)."""
    if (
        not isinstance(spec, dict)
        or not isinstance(spec.get("dist"), str)
        or spec["dist"] not in DISTRIBUTIONS
    ):
        raise ValueError(
            f"{where}: must be a table with dist = one of {', '.join(DISTRIBUTIONS)}, "
            f"got {spec!r:.80}"
        )
    required, optional = DISTRIBUTIONS[spec["dist"]]
    unknown = sorted(set(spec) - {"dist", *required, *optional})
    if unknown:
        raise ValueError(
            f"{where}: unknown key {unknown[0]!r} for dist = {spec['dist']!r} "
            f"(allowed: {', '.join((*required, *optional))})"
        )
    missing = [k for k in required if k not in spec]
    if missing:
        raise ValueError(f"{where}: dist = {spec['dist']!r} needs {', '.join(missing)}")
    p = {k: _real(where, k, spec[k]) for k in (*required, *optional) if k in spec}
    lo, hi = p.get("low", -math.inf), p.get("high", math.inf)
    if not lo < hi:
        raise ValueError(f"{where}: low must be < high, got {lo:g} and {hi:g}")
    if spec["dist"] == "normal" and not p["std"] > 0:
        raise ValueError(f"{where}: std must be > 0, got {p['std']:g}")
    if spec["dist"] == "lognormal":
        for k in ("median", "sigma"):
            if not p[k] > 0:
                raise ValueError(f"{where}: {k} must be > 0, got {p[k]:g}")
        if "low" in p and not p["low"] > 0:
            raise ValueError(f"{where}: low must be > 0 for a lognormal, got {p['low']:g}")
    return {"dist": spec["dist"], **p}


def quantiles(spec: dict[str, Any], u: np.ndarray) -> np.ndarray:
    """The values of the (checked) distribution ``spec`` at the unit-cube coordinates ``u``
    (inverse transform; truncation by mapping u into the bounds' probability interval)."""
    from scipy.stats import norm

    if spec["dist"] == "uniform":
        uniform: np.ndarray = spec["low"] + u * (spec["high"] - spec["low"])
        return uniform
    to_z: Callable[[float], float]  # the bound's standard-normal coordinate
    if spec["dist"] == "normal":
        mean, scale = spec["mean"], spec["std"]
        to_z = lambda x: (x - mean) / scale  # noqa: E731 - a one-line change of variable
    else:
        mean, scale = math.log(spec["median"]), spec["sigma"]
        to_z = lambda x: (math.log(x) - mean) / scale if x > 0 else -math.inf  # noqa: E731
    a = norm.cdf(to_z(spec["low"])) if "low" in spec else 0.0
    b = norm.cdf(to_z(spec["high"])) if "high" in spec else 1.0
    z: np.ndarray = mean + scale * norm.ppf(a + u * (b - a))
    return z if spec["dist"] == "normal" else np.exp(z)


def unit_design(design: str, count: int, dims: int, seed: int) -> np.ndarray:
    """(count, dims) points in [0, 1)^dims of the named design, reproducible from ``seed``
    (a Saltelli design's in its blocks of dims + 2 rows)."""
    from scipy.stats import qmc

    points: np.ndarray
    if design == "sobol":
        points = qmc.Sobol(dims, scramble=True, seed=seed).random(count)
    elif design == "lhs":
        points = qmc.LatinHypercube(dims, seed=seed).random(count)
    elif design == SALTELLI:
        points = saltelli_unit_design(count, dims, seed)
    else:
        points = np.random.default_rng(seed).random((count, dims))
    return points


def sample_columns(table: Any, where: str) -> dict[str, list[float]]:
    """The ``[sample]`` table checked and drawn: key path -> its ``count`` values, in sample
    order. ValueError naming ``sample.<key>`` for anything wrong, before any case exists."""
    if not isinstance(table, dict):
        raise ValueError(f"{where} key 'sample': must be a table")
    check_keys(table, SAMPLE_KEYS, where, path="sample")
    design = table.get("design", "sobol")
    if design not in DESIGNS:
        raise ValueError(f"{where} key 'sample.design': must be one of {DESIGNS}, got {design!r}")
    count = table.get("count")
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_SAMPLES:
        raise ValueError(
            f"{where} key 'sample.count': must be an integer in 1..{MAX_SAMPLES}, got {count!r}"
        )
    if design == "sobol" and count & (count - 1):
        raise ValueError(
            f"{where} key 'sample.count': a Sobol design needs a power of 2 (its balance "
            f"properties hold only then), got {count}; use {1 << (count.bit_length() - 1)} or "
            f"{1 << count.bit_length()}, or design = 'lhs'"
        )
    seed = table.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(
            f"{where} key 'sample.seed': must be an integer >= 0 (the same seed gives the same "
            f"samples), got {seed!r}"
        )
    keys = table.get("keys")
    if not isinstance(keys, dict) or not keys:
        raise ValueError(
            f"{where} key 'sample.keys': must be a table of paths -> distributions, e.g. "
            '"scene.chain.EI" = {dist = "uniform", low = 1e4, high = 2e4}'
        )
    specs = {
        path: check_distribution(f"{where} key 'sample.keys.{path}'", spec)
        for path, spec in flatten(keys, leaf="dist").items()
    }
    if design == SALTELLI and (why := saltelli_count_error(count, len(specs))):
        raise ValueError(f"{where} key 'sample.count': {why}")
    u = unit_design(design, count, len(specs), seed)
    return {path: quantiles(spec, u[:, j]).tolist() for j, (path, spec) in enumerate(specs.items())}
