"""The rungs of the full model's ladder (docs/model.md, "The model ladder"): the bending shapes
per rod and the kinematics a rung takes, and the checks of those options. Kept apart from the
ladder's system (``rodval.models.systems.chain_system``), constants and kernels so that a model
made on the paper's rung imports none of them."""

from __future__ import annotations

from typing import Any

from rodval.core.checks import check_choice, check_number
from rodval.core.scene import Scene
from rodval.core.validity import setting
from rodval.models.kinematics.shapes import MAX_SHAPES

#: The kinematics of the full model's rungs; the first is the paper's.
KINEMATICS = ("first-order", "exact")
#: The paper's rung: one cubic shape per rod, first-order kinematics.
PAPER_RUNG = (1, KINEMATICS[0])
#: The full model's default ``kinematics``: one of KINEMATICS chosen for the scene
#: (``auto_kinematics``).
AUTO = "auto"
#: The values the ``kinematics`` option takes.
KINEMATICS_OPTIONS = (*KINEMATICS, AUTO)


def check_shapes(shapes: Any) -> int:
    """``shapes`` (p, the bending shapes per rod beyond the rigid rotation: p + 1 shape
    coordinates) as an int in 1..MAX_SHAPES, else a ValueError naming the range."""
    allowed = f"an integer in 1..{MAX_SHAPES}"
    return int(
        check_number("shapes", shapes, low=1, high=MAX_SHAPES, integer=True, allowed=allowed)
    )


def check_kinematics(kinematics: Any, auto: bool = False) -> str:
    """``kinematics`` among KINEMATICS (a rung's), or among KINEMATICS_OPTIONS ("auto"
    included: the option of the full model and its modes) with ``auto``; else a ValueError
    naming the allowed values."""
    return check_choice("kinematics", kinematics, KINEMATICS_OPTIONS if auto else KINEMATICS)


#: Why "auto" takes the exact kinematics on such a scene (docs/model.md, "Which kinematics
#: runs").
BREAKS = (
    "(the first-order kinematics breaks its energy and momentum balance there: a lock or a "
    "stop sets the rods ringing with bending rates that do not shrink with EI, docs/model.md)"
)


def _why_exact(scene: Scene) -> list[str]:
    """What in ``scene`` breaks the first-order kinematics' energy balance: its latches (held
    ones included), its stops, its moving base."""
    return [
        what
        for what, present in (
            ("latches", bool(scene.latches)),
            ("stops", bool(scene.stops)),
            ("compliant latches", bool(scene.compliant_latches)),
            (f"a {scene.base.kind} base", scene.base.moving),
        )
        if present
    ]


def auto_kinematics(
    scene: Scene, coefficients: str = "printed", kernel: str = "numba"
) -> tuple[str, str]:
    """The kinematics ``kinematics = "auto"`` (the full model's default) runs ``scene`` with,
    and the note that says so and why (``SolverStats.notes``): the one definition of the
    rule. "exact" where the scene has latches (held ones included), stops or a moving base
    (free or prescribed): there the first-order kinematics breaks its energy and momentum
    balance at a lock whatever EI (docs/model.md); the paper's "first-order" otherwise, and
    also where the user gave an option only the paper's rung takes (``coefficients =
    "published"``, ``kernel = "numpy"``: the user's explicit option wins)."""
    why = _why_exact(scene)
    paper = f"{setting('kinematics', KINEMATICS[0])} for the paper's model"
    if not why:
        return KINEMATICS[0], (
            f'kinematics "{KINEMATICS[0]}" (the paper\'s) chosen by kinematics = "auto": the '
            "scene has no latches, stops or moving base"
        )
    has = f"the scene has {' and '.join(why)}"
    given = [
        setting(key, value)
        for key, value, paper_only in (
            ("coefficients", coefficients, "published"),
            ("kernel", kernel, "numpy"),
        )
        if value == paper_only
    ]
    if given:
        return KINEMATICS[0], (
            f'kinematics "{KINEMATICS[0]}" kept by kinematics = "auto" although {has} '
            f"{BREAKS}: "
            f"{' and '.join(given)} runs on the paper's rung only, and the option given "
            f"wins; {setting('kinematics', KINEMATICS[1])} with the printed coefficients and "
            "the numba kernel keeps it"
        )
    return KINEMATICS[1], (
        f'kinematics "{KINEMATICS[1]}" chosen by kinematics = "auto": {has} {BREAKS}; {paper}'
    )


def resolve_kinematics(
    kinematics: str, scene: Scene, coefficients: str = "printed", kernel: str = "numba"
) -> str:
    """``kinematics`` (checked) as it runs on ``scene``: "auto" by ``auto_kinematics``, the
    others as given."""
    kinematics = check_kinematics(kinematics, auto=True)
    if kinematics == AUTO:
        return auto_kinematics(scene, coefficients, kernel)[0]
    return kinematics


def check_rung_options(coefficients: str, kernel: str) -> None:
    """ValueError unless a rung other than the paper's has the options it runs with: the
    printed coefficients and the compiled kernel (checked when the model is made, before
    any work)."""
    if coefficients != "printed":
        raise ValueError(
            "coefficients must be 'printed' with shapes > 1 or exact kinematics (the "
            f"published erratum belongs to the paper's model), got {coefficients!r}"
        )
    if kernel != "numba":
        raise ValueError(
            "kernel must be 'numba' with shapes > 1 or exact kinematics (the numpy "
            f"kernel is the paper model's dense reference), got {kernel!r}"
        )
