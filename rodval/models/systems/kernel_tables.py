"""The compiled kernels of every chain system, one table per rung x base kind (``KERNEL_TABLES``):
the kernels stay in their modules (``kinematics.ladder_kernels``, ``kinematics.rigid_kernels``,
``base.chain_base``, ``base.rigid_base``, ``base.free_base``); a system looks its table up
(``chain_system.ChainSystem``). The paper's rung on a pinned base is the full model
(``presets.full.FullSystem``), whose kernels are its own."""

from __future__ import annotations

from typing import Any, NamedTuple

from rodval.models.base import chain_base as cb
from rodval.models.base import free_base as fb
from rodval.models.base import rigid_base as rb
from rodval.models.hinge_items.deployment import full_hinge_events
from rodval.models.kinematics import ladder_kernels as lk
from rodval.models.kinematics import rigid_kernels as rk


class KernelTable(NamedTuple):
    """A rung's kernels on one base kind. ``accel(V, y, loads, damped, out)``: q'' (None on a
    prescribed base, whose constrained solve always runs; ``loads`` = (has_load, SX, SY, Tq),
    ``kernels.Loads``: the load suffix sums and the hinge moments Tq (N m) of the motors and
    rate dampers, length n, or length 0 for none); ``locked(V, y, loads, damped, locks, out,
    lam)``: q'' and the multipliers with ``locks`` held (a prescribed base's: ``locked(V, y,
    mo, loads, damped, locks, (out, lam))``, ``mo`` its motion at t); ``unit(V, q, locks, U)``: U[j] = M^-1
    a_{locks[j]}; ``rhs``, ``mechanics``, ``rhs_locked``: RHS_TYPE, ``events``: EVENTS_TYPE;
    ``momentum(V, y)``: a moving base's total P; ``kinetic``: the RHS_TYPE function whose
    out[0] is T (a prescribed base's: the massless body's, the drive's power left out);
    ``drive(V, y, mo, S, L, t)``: (F_dx, F_dy, m_1), the base's force and moment on the
    chain; ``damper_mechanics``: the dampers' power is ``mechanics``' out[2] (else
    ``paper_matrices.damper_power``)."""

    accel: Any
    locked: Any
    unit: Any
    rhs: Any
    mechanics: Any
    rhs_locked: Any
    events: Any
    momentum: Any = None
    kinetic: Any = None
    drive: Any = None
    damper_mechanics: bool = True


#: The kernels every pinned or free table names alike (a module's ``prefix`` + name).
NAMES = ("accel", "accel_locked", "unit_responses", "rhs", "mechanics", "rhs_locked")


def _table(
    k: Any, prefix: str, events: Any, momentum: Any = None, damper_mechanics: bool = True
) -> KernelTable:
    """A pinned or free base's table from a kernel module's kernels ``prefix`` + ``NAMES``."""
    accel, locked, unit, rhs, mech, rhs_locked = (getattr(k, prefix + name) for name in NAMES)
    return KernelTable(
        accel, locked, unit, rhs, mech, rhs_locked, events, momentum, mech, None, damper_mechanics
    )


def _prescribed(k: Any) -> KernelTable:
    """A prescribed base's table from a kernel module (its rhs reads the held hinges from S)."""
    return KernelTable(
        None,
        k.prescribed_accel_locked,
        k.prescribed_unit_responses,
        k.prescribed_rhs,
        k.prescribed_mechanics,
        k.prescribed_rhs,
        k.free_hinge_events,
        k.free_momentum,
        k.free_mechanics,
        k.drive,
    )


#: (rung, base kind) -> its kernels; rungs: "paper" (free base only), "ladder", "rigid".
KERNEL_TABLES: dict[tuple[str, str], KernelTable] = {
    ("paper", "free"): _table(fb, "base_", fb.base_hinge_events, fb.momentum, False),
    # D from [phi; alpha; beta]
    ("ladder", "pinned"): _table(lk, "ladder_", full_hinge_events),
    ("ladder", "free"): _table(cb, "free_", cb.free_hinge_events, cb.free_momentum),
    ("ladder", "prescribed"): _prescribed(cb),
    ("rigid", "pinned"): _table(rk, "rigid_", rk.rigid_hinge_events, damper_mechanics=False),
    ("rigid", "free"): _table(rb, "free_", rb.free_hinge_events, rb.free_momentum),
    ("rigid", "prescribed"): _prescribed(rb),
}
