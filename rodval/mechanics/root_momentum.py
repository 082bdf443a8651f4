"""The angular momentum about the root in a lock record, and when it means something.

The chain's angular momentum about node 0 is kept through a lock of hinge k >= 1 (an internal
impulse) while hinge 0 is free: the root joint passes a force, no moment about node 0, and hinge
0's spring, damper and stops are finite moments (no part of an instantaneous jump; exudyn's
window jump subtracts their integral). Once hinge 0 is held (latched now or earlier) the ground,
or a free base's body, passes an impulsive moment onto rod 1 and the jump measures nothing: the
record carries None there, on a pinned chain and on a free base alike (docs/deployment.md).
"""

from __future__ import annotations

from typing import Any

ROOT_KEYS = (
    "angular_momentum_root_before",
    "angular_momentum_root_after",
    "angular_momentum_root_jump",
)


def root_momentum_fields(
    before: float, after: float, root_held: bool, jump: float | None = None
) -> dict[str, Any]:
    """A lock record's ``angular_momentum_root_before``, ``_after`` and ``_jump`` (N m s; the
    jump ``after - before`` unless given, e.g. less the integrated external moment), all None
    when hinge 0 is held (``root_held``)."""
    if root_held:
        return dict.fromkeys(ROOT_KEYS)
    return dict(zip(ROOT_KEYS, (before, after, after - before if jump is None else jump)))
