"""The rungs of the full model's ladder (docs/model.md, "The model ladder"): the bending shapes
per rod and the kinematics a rung takes, and the checks of those options. Kept apart from the
ladder's system and kernels (``rodval.models.kinematics.ladder``) so that a model made on the paper's rung
imports none of them."""

from __future__ import annotations

from rodval.core.checks import check_choice, check_number
from rodval.models.kinematics.shapes import MAX_SHAPES

#: ``kinematics`` of the full model; the first is the paper's (the default).
KINEMATICS = ("first-order", "exact")
#: The paper's rung: one cubic shape per rod, first-order kinematics.
PAPER_RUNG = (1, KINEMATICS[0])


def check_shapes(shapes) -> int:
    """``shapes`` (p, the bending shapes per rod beyond the rigid rotation: p + 1 shape
    coordinates) as an int in 1..MAX_SHAPES, else a ValueError naming the range."""
    allowed = f"an integer in 1..{MAX_SHAPES}"
    return int(
        check_number("shapes", shapes, low=1, high=MAX_SHAPES, integer=True, allowed=allowed)
    )


def check_kinematics(kinematics) -> str:
    return check_choice("kinematics", kinematics, KINEMATICS)


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
