"""Rod bending damping stated as engineers state it: a modal damping ratio.

A rod's Kelvin-Voigt damping c (N m^2 s; bending moment EI kappa_b + c dkappa_b/dt,
docs/model.md) is proportional to its stiffness, so every bending mode of a uniform rod has
the damping ratio zeta_k = c omega_k / (2 EI): one number fixes c once the mode it refers to is
named. Here it is the rod's **first free-free Euler-Bernoulli bending mode**, of the rod alone
(its own l, mass per length m and EI; node masses, hinges and neighbours left out, so that c is
a property of the panel and the same in every model and every chain it sits in):

    omega_1 = (beta_1 l)^2 / l^2 sqrt(EI / m),  beta_1 l = 4.730040744862704,
    c = 2 zeta EI / omega_1.

Higher modes of the rod are damped more (zeta_k = zeta omega_k / omega_1), as with any
stiffness-proportional damping. A scene file writes ``[chain] bending_damping = { ratio =
0.01 }`` (1 % of critical; a number or one per rod), or ``{ ratio = 0.01, of = "panel" }``
(the same: ``of`` names the mode the ratio is of, ``DAMPING_OF``); the scene holds the
converted c in N m^2 s, which is what run.json records and every model uses.

``{ ratio = z, of = "deployed" }`` states the ratio of the **deployed structure's first
flexible mode** instead (every latch held at its angle; docs/model.md, "Damping of the
deployed structure"): c_r = beta EI_r on every rod, one retardation time beta (s), solved so
that that mode has the ratio z. That needs the full model's linearization, which lives in the
models layer: the scene file records the request (``DampingRequest``, the scene's
``damping``) with c = 0 until ``rodval.models.observation.deployed_damping.resolve_damping``
converts it where a scene enters a model (``rodval.models.registry.simulate`` and
``check_scene``, ``rodval.analysis.modes.model_modes``, the run folder's record);
``Model.simulate`` and ``Model.modes`` refuse a request not yet converted
(``check_resolved``), so that no model runs it undamped by omission.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from typing import Any

import numpy as np

#: beta_1 l of a free-free Euler-Bernoulli beam's first bending mode (cos x cosh x = 1).
FREE_FREE_BETA_L = 4.730040744862704
#: The allowed ratios: a fraction of critical damping, 0 <= zeta < 1 (0.01 is 1 %).
MAX_RATIO = 1.0
#: What the ratio of ``bending_damping = { ratio, of }`` is of: each rod's own first free-free
#: mode (``"panel"``, the default and the meaning without ``of``) or the deployed structure's
#: first flexible mode (``"deployed"``).
PANEL, DEPLOYED = "panel", "deployed"
DAMPING_OF = (PANEL, DEPLOYED)
#: The keys of the ratio form of ``bending_damping``.
RATIO_KEYS = ("ratio", "of")


@dataclass(frozen=True)
class DampingRequest:
    """``[chain] bending_damping = { ratio = z, of = ... }`` as the scene file states it (a
    scene's ``damping``): ``ratio`` a fraction of critical damping (``"panel"``: one number or
    one per rod; ``"deployed"``: one number), ``of`` one of ``DAMPING_OF``. ``resolved``: the
    record of a deployed request's conversion (c per rod in N m^2 s, beta in s, the mode's
    omega in rad/s and the ratio it reached, the iterations:
    ``deployed_damping.resolve_damping``), None until then; a panel request is converted when
    its scene is built and needs none."""

    ratio: float | tuple[float, ...]
    of: str = PANEL
    resolved: dict[str, Any] | None = field(default=None, compare=False)

    @property
    def pending(self) -> bool:
        """Whether the request waits for its conversion (a deployed one, not resolved): the
        scene's c is then a placeholder 0 that no model may run."""
        return self.of == DEPLOYED and self.resolved is None

    def as_dict(self) -> dict[str, Any]:
        """The scene file's form ``{ ratio = ..., of = ... }``."""
        ratio = list(self.ratio) if isinstance(self.ratio, tuple) else self.ratio
        return {"ratio": ratio, "of": self.of}

    def record(self) -> dict[str, Any]:
        """What run.json records under ``bending_damping``: the request and, once converted,
        its conversion (``resolved``)."""
        return {**self.as_dict(), **(self.resolved or {})}


def damping_request(value: dict[str, Any], where: str) -> DampingRequest:
    """The request of ``bending_damping = { ratio = ..., of = ... }`` (``value``: a table with
    ``ratio``), checked before any work: no key besides ``RATIO_KEYS``; ``of`` one of
    ``DAMPING_OF`` (default ``"panel"``); the ratio a number >= 0 and < 1, or (panel only)
    one per rod. A one-line ValueError naming the key (``where``: the file) otherwise."""
    key = f"{where} [chain] bending_damping"
    if set(value) - set(RATIO_KEYS):
        raise ValueError(
            f"{key}: a table with 'ratio' takes no other key than 'of' (got {sorted(value)}); "
            "give { ratio = 0.01 } for 1 % of critical damping of each panel's first mode, "
            '{ ratio = 0.01, of = "deployed" } for the deployed structure\'s first mode'
        )
    of = value.get("of", PANEL)
    if not isinstance(of, str) or of not in DAMPING_OF:
        raise ValueError(
            f"{key}.of: must be one of {', '.join(map(repr, DAMPING_OF))} (the mode the ratio "
            "is of: each rod's own first free-free mode, or the deployed structure's first "
            f"flexible mode), got {of!r}"
        )
    ratio = value["ratio"]
    check_ratio(ratio, per_rod=of == PANEL)
    if isinstance(ratio, (list, tuple)):
        return DampingRequest(tuple(float(v) for v in ratio), of)
    return DampingRequest(float(ratio), of)


def check_ratio(ratio: Any, per_rod: bool = True) -> None:
    """ValueError naming ``bending_damping.ratio`` unless ``ratio`` is a damping ratio (a
    fraction of critical damping, >= 0 and < ``MAX_RATIO``) or, when ``per_rod``, a list of
    them (their count is checked against n by ``bending_damping_for_ratio``)."""
    many = isinstance(ratio, (list, tuple, np.ndarray))
    values = ratio if many else [ratio]
    if (
        (many and not per_rod)
        or not all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in values)
        or not all(0.0 <= float(v) < MAX_RATIO for v in values)
    ):
        allowed = "or one per rod" if per_rod else 'one number: of = "deployed" is of one mode'
        raise ValueError(
            "bending_damping.ratio must be a damping ratio (a fraction of critical damping, "
            f">= 0 and < {MAX_RATIO:g}; 1 % is 0.01) {allowed}, got {ratio!r}"
        )


def check_resolved(scene: Any, what: str) -> None:
    """ValueError (before any work) when ``scene``'s bending damping is a deployed request not
    yet converted to c (``DampingRequest.pending``), which ``what`` (a model's run or modes)
    would otherwise run with c = 0. Names the fix."""
    request = getattr(scene, "damping", None)
    if request is not None and request.pending:
        raise ValueError(
            f"{what}: bending_damping = {{ ratio = {request.ratio:g}, of = 'deployed' }} is not "
            "converted to the rods' c yet; run the scene through rodval.simulate or "
            "rodval.modes, or convert it first with "
            "rodval.models.observation.deployed_damping.resolve_damping(scene)"
        )


def first_free_free_frequency(l: Any, m: Any, EI: Any) -> np.ndarray:
    """omega_1 (rad/s) of each rod's first free-free bending mode: l (m), m (kg/m), EI (N m^2),
    scalars or arrays (broadcast). O(n)."""
    l, m, EI = (np.asarray(v, dtype=float) for v in (l, m, EI))
    omega: np.ndarray = (FREE_FREE_BETA_L / l) ** 2 * np.sqrt(EI / m)
    return omega


def bending_damping_for_ratio(ratio: Any, l: Any, m: Any, EI: Any) -> np.ndarray:
    """The Kelvin-Voigt damping c (N m^2 s) that gives each rod's first free-free bending mode
    the damping ratio ``ratio`` (a fraction of critical, 0 <= ratio < 1): c = 2 ratio EI /
    omega_1. ValueError naming ``bending_damping.ratio`` and the allowed range otherwise."""
    check_ratio(ratio)
    zeta = np.asarray(ratio if isinstance(ratio, (list, tuple, np.ndarray)) else [ratio], float)
    EI = np.asarray(EI, dtype=float)
    if zeta.size not in (1, np.size(EI)):
        raise ValueError(
            f"bending_damping.ratio must be one number or one per rod ({np.size(EI)}), "
            f"got {zeta.size}"
        )
    zeta = zeta if zeta.size > 1 else zeta[0]
    c: np.ndarray = 2.0 * zeta * EI / first_free_free_frequency(l, m, EI)
    return c
