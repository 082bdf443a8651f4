"""Validity of a run: the assumptions a model rests on, checked against what the run did.

A run can reach t_end and still be invalid: its results are then not those of the model's
premise (a paper model bent far beyond small angles, an energy balance that does not close).
Success (how the integration ended, ``SolverStats.status``) and validity (``SolverStats.valid``,
``SolverStats.validity``) are separate. Each model states its checks
(``rodval.core.contract.Model.validity_checks``); each check carries its figure and bound, so a
verdict always says why.

Checks defined here (the one place their bounds live):

* ``small_bending``: the paper models keep only first-order terms in the bending angles alpha,
  beta (sin a ~ a, products with rates dropped): at 0.2 rad the first neglected terms are about
  2 % (1 - cos) of the kept ones. Figure: the largest |alpha|, |beta| over the output times (rad).
* ``energy_balance``: where the scene asks for "energy", the audit residual
  max |E - E(0) - W_ext + D| / max(max E, max |W_ext|) (``rodval.solvers.audit``). The paper
  models' own residual is 5e-5 .. 2e-3 on the paper's chain (first-order kinematics,
  docs/stability.md); a run beyond 1e-2 has left the regime the model describes (the 10x load:
  2.4e-2 .. 6.6e-2; EI = 1e3: 2.2e-2 .. 3.9e-2) or its integration went wrong.
* ``step_resolution`` (exudyn): the largest rotation of a rod per time step (rad) against the
  model's ``max_rotation_per_step``.
* ``momentum_balance``: where angular momentum is conserved (``momentum_point``: a free base,
  or a pinned chain whose hinge 0 is free, with no loads), the residual
  max |H(t) - H(0)| / max G(t), H the angular momentum about the conserved point and G the
  gross angular momentum, the sum of the magnitudes of its parts' (each rod with its far node,
  and the body) about the same point: the share of the motion's angular momentum the run
  created or lost. Exact kinematics keeps it to round-off (1e-14 on a pinned chain); a run
  beyond ``MOMENTUM_RESIDUAL_BOUND`` has an attitude that drifts for no physical reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rodval.core.hinges import HINGE_ITEMS

#: Largest bending angle (rad) within the paper models' small-bending assumption.
SMALL_BENDING_RAD = 0.2
#: Largest relative energy-audit residual of a valid run (see the module docstring).
ENERGY_RESIDUAL_BOUND = 1e-2
#: Largest relative angular-momentum residual of a valid run (see the module docstring).
MOMENTUM_RESIDUAL_BOUND = 1e-2
#: The points about which a scene's angular momentum is conserved (``momentum_point``).
MOMENTUM_POINTS = ("centre of mass", "root")


#: Where a setting a fix names lives: a model option (a study's ``[models.LABEL]``, the command
#: line's ``--set KEY=VALUE``), an integrator setting (``[integrator]``, ``--KEY VALUE``) or a
#: scene value (the scene file's table, ``--set PATH=VALUE``).
SETTING_PLACES = ("model", "integrator", "scene")


def _toml(value: Any) -> str:
    """``value`` as TOML text: a string quoted, a number in its shortest form."""
    if isinstance(value, str):
        return f'"{value}"'
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def setting(key: str, value: Any, place: str = "model") -> str:
    """A setting a fix names, in both spellings (the one definition of how a fix is
    written): the file's and the command line's, e.g. 'kinematics = "exact" (command line:
    --set kinematics=exact)'; an integrator setting 'rtol = 1e-10 in [integrator] (command
    line: --rtol 1e-10)'; a scene value by its dotted path ``chain.bending_damping``:
    '[chain] bending_damping = { ratio = 0.01 } (command line: --set
    chain.bending_damping={ratio=0.01})'. ``value`` may be text already in TOML form (an
    inline table)."""
    if place not in SETTING_PLACES:
        raise ValueError(f"place must be one of {SETTING_PLACES}, got {place!r}")
    if place == "scene":
        text = value if isinstance(value, str) else _toml(value)
        table, _, leaf = key.rpartition(".")
        file = f"[{table}] {leaf} = {text}" if table else f"{key} = {text}"
        return f"{file} (command line: --set {key}={text.replace(' ', '')})"
    text = _toml(value)
    plain = value if isinstance(value, str) else text
    if place == "integrator":
        return f"{key} = {text} in [integrator] (command line: --{key.replace('_', '-')} {plain})"
    return f"{key} = {text} (command line: --set {key}={plain})"


#: The fix that damps the rods' bending, in both spellings (``setting``).
DAMPING_FIX = setting("chain.bending_damping", "{ ratio = ... }", "scene")


@dataclass(frozen=True)
class Check:
    """One assumption checked on one run: ``figure`` (in ``unit``) must not exceed ``bound``.
    A non-finite figure breaks the assumption."""

    assumption: str
    figure: float
    bound: float
    unit: str
    what: str
    #: The setting that would address a broken check ("" when none is known).
    fix: str = ""

    @property
    def holds(self) -> bool:
        return math.isfinite(self.figure) and self.figure <= self.bound

    def reason(self) -> str:
        """One phrase: '<what> <figure> <unit> > <bound> <unit> (<assumption>)', and for a
        broken check the setting that would address it: '; fix: <fix>'."""
        unit = f" {self.unit}" if self.unit else ""
        sign = "<=" if self.holds else ">"
        fix = f"; fix: {self.fix}" if self.fix and not self.holds else ""
        return (
            f"{self.what} {self.figure:.3g}{unit} {sign} {self.bound:g}{unit} "
            f"({self.assumption}){fix}"
        )

    def as_dict(self) -> dict[str, Any]:
        return {
            "assumption": self.assumption,
            "figure": self.figure if math.isfinite(self.figure) else None,
            "bound": self.bound,
            "unit": self.unit,
            "holds": self.holds,
            "reason": self.reason(),
            "fix": self.fix,
        }


def small_bending(max_bending: float | None) -> list[Check]:
    """The small-bending check of a run whose largest |alpha|, |beta| is ``max_bending`` (rad);
    none when it was not measured."""
    if max_bending is None:
        return []
    return [
        Check(
            "small bending",
            float(max_bending),
            SMALL_BENDING_RAD,
            "rad",
            "largest bending angle",
            "stiffer rods (EI), or the exudyn beam model, which has no small-bending premise",
        )
    ]


def energy_balance(
    residual: float | None, bound: float = ENERGY_RESIDUAL_BOUND, fix: str = ""
) -> list[Check]:
    """The energy-balance check of an audited run (relative residual); none when not
    audited. ``fix``: the model's setting that would close the balance."""
    if residual is None:
        return []
    return [Check("energy balance", float(residual), bound, "", "energy-audit residual", fix)]


def momentum_point(scene: Any) -> str | None:
    """The point about which the angular momentum of ``scene`` is conserved, or None: "centre
    of mass" on a free base, "root" (node 0) on a pinned chain whose hinge 0 has no spring,
    damper or hinge item (a latch, stop, motor, ... reacts on the ground); None with any load
    (their moments would have to be booked) and on a prescribed base.
    Hinge items elsewhere are internal: the momentum is kept through their events."""
    if scene.loads or scene.base.prescribed:  # a prescribed base drives the chain
        return None
    if scene.base.free:
        return MOMENTUM_POINTS[0]
    items = [item for table in HINGE_ITEMS for item in getattr(scene, table)]
    if scene.chain.kappa[0] == 0 and scene.chain.nu[0] == 0 and all(i.hinge != 0 for i in items):
        return MOMENTUM_POINTS[1]
    return None


def momentum_balance(
    residual: float | None, bound: float = MOMENTUM_RESIDUAL_BOUND, fix: str = ""
) -> list[Check]:
    """The angular-momentum check of a run whose momentum was audited (relative residual,
    see the module docstring); none when not audited. ``fix``: the setting that would keep it."""
    if residual is None:
        return []
    return [Check("momentum balance", float(residual), bound, "", "angular-momentum residual", fix)]


def step_resolution(rotation: float | None, bound: float, step: float | None = None) -> list[Check]:
    """The time-step resolution check of a fixed-step run: the largest rotation of a rod in one
    step (rad) against ``bound``; none when not measured. With the run's ``step`` (s) the fix
    names the step that would resolve the fastest rotation seen."""
    if rotation is None:
        return []
    fix = "a smaller step"
    if step is not None and rotation > 0 and math.isfinite(rotation):
        fix = f"{setting('step', float(f'{step * bound / rotation:.2g}'))} or smaller (s)"
    return [
        Check("step resolution", float(rotation), bound, "rad", "largest rotation per step", fix)
    ]


def verdict(checks: list[Check], finished: bool = True) -> tuple[bool | None, list[dict[str, Any]]]:
    """(valid, validity): valid is None when nothing could be checked, else whether every
    check holds; validity lists every check with its figure, bound and reason. A run that
    did not finish (``finished`` False) is never called valid: its checks cover only the part
    it computed, so where they all hold valid is None (no verdict), and False where one broke."""
    if not checks:
        return None, []
    holds = all(c.holds for c in checks)
    return (None if holds and not finished else holds), [c.as_dict() for c in checks]


def broken(validity: list[dict[str, Any]]) -> list[str]:
    """The reasons of the checks that do not hold."""
    return [c["reason"] for c in validity if not c["holds"]]


def describe(valid: bool | None, validity: list[dict[str, Any]]) -> str:
    """The verdict in a few words, for summary lines: 'valid', 'INVALID: <reason>; ...',
    'validity not checked', or, for a run that stopped early whose checks held up to there,
    'no verdict (the run stopped early; its checks held up to the time reached)'."""
    if valid is None:
        if validity:
            return "no verdict (the run stopped early; its checks held up to the time reached)"
        return "validity not checked"
    return "valid" if valid else "INVALID: " + "; ".join(broken(validity))
