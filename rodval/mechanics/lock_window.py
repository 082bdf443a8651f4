"""The lock window: the declared stretch of time after a latch locks over which every model
measures the lock's impulse (docs/deployment.md, "The lock impulse") and at whose end it
accounts for the lock's energy (``window_energies``; "Where the lock energy goes").

A latch joins two elastic rods; at the lock the relative rate of the rods' end tangents drops
to zero, but the rods' chords keep turning against each other and the latch's reaction rings
at the locked structure's bending frequencies. The cumulative impulse of the reaction,
S(tau) = mu + int_0^tau lambda ds (mu: the instantaneous part, lambda: the constraint moment
on the outboard rod, N m), therefore oscillates: for one mode of frequency omega without
damping, S(tau) = S_pl (1 - cos omega tau) with S_pl the plastic (rigid-panel) impulse, so
the plain integral over one period is 0 and over half a period 2 S_pl. Its mean over the
window has the limit: the reported lock impulse is

    S_w = (1/w) int_0^w S(tau) dtau = mu + int_0^w lambda(s) (1 - s/w) ds,

the integral of the reaction over the window with the weight falling linearly from 1 at the
lock to 0 at its end. Over one period of the first bending mode it removes that mode's ring
exactly (undamped) or to O(zeta^2) (damped), and it equals S_pl for rigid rods up to the
smooth reaction's lambda w / 2.

The window w (s) is the latch's ``window`` when the scene sets one; by default the period of
the first bending mode of the **locked segment** the lock completes: the rods joined to the
hinge's two rods through held hinges (the new one and those locked before it), clamped
together into one Euler-Bernoulli beam with their node masses, pinned at its inboard node
(clamped at the root when hinge 0 is held and the segment reaches it); the hinge springs are
left out (soft against the panels' bending, the deployable's regime) and so are the rods
beyond the segment. The segment's first bending mode is the lowest ring the lock excites in
it, so one period of it is the smallest window over which the ring averages out: the locked
pair alone rings 3.8x higher than a four-panel segment, and a pair window left most of that
segment's ring in S_w (docs/deployment.md). Cubic Hermite elements, ``ELEMENTS_PER_ROD`` per
rod of a pair and at least ``MIN_ELEMENTS`` in all, give the period to 3e-6 relative (the
element's error falls as h^4; from above in frequency), far below what the window needs.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg

from rodval.core.scene import Chain, Latch

#: Cubic Hermite Euler-Bernoulli elements per rod of a locked pair's beam; a longer segment
#: gets ceil(MIN_ELEMENTS / rods) per rod (at least 1).
ELEMENTS_PER_ROD = 8
MIN_ELEMENTS = 2 * ELEMENTS_PER_ROD
#: A longer locked segment is cut into this many uniform sections (``_sections``).
MAX_SECTIONS = 128
#: The fewest steps of a fixed-step model (exudyn) that a lock window must hold (its record's
#: ``window_steps`` = impulse_window / step) for the window mean to be resolved: the impulse
#: is the trapezoid rule of S(tau) on the steps (1.8-2.6 % off the rigid-panel limit with 23
#: steps, docs/deployment.md). The native models integrate the window on their dense output
#: under error control and record no ``window_steps``. Used by the lock comparison
#: (``rodval.analysis.events``) and by exudyn's ``step = "auto"`` (``exudyn_step``).
MIN_WINDOW_STEPS = 20
#: The window's quadrature: Gauss-Legendre on equal panels (degree 2 * NODES - 1 per panel).
WINDOW_PANELS = 64
WINDOW_NODES = 4
_GL_X, _GL_W = np.polynomial.legendre.leggauss(WINDOW_NODES)


def _element(EI: float, rho: float, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass of one Hermite element of length h (m), EI (N m^2), mass
    per length rho (kg/m); dofs (w_a, theta_a, w_b, theta_b) (m, rad)."""
    k = (EI / h**3) * np.array(
        [
            [12, 6 * h, -12, 6 * h],
            [6 * h, 4 * h * h, -6 * h, 2 * h * h],
            [-12, -6 * h, 12, -6 * h],
            [6 * h, 2 * h * h, -6 * h, 4 * h * h],
        ]
    )
    m = (rho * h / 420.0) * np.array(
        [
            [156, 22 * h, 54, -13 * h],
            [22 * h, 4 * h * h, 13 * h, -3 * h * h],
            [54, 13 * h, 156, -22 * h],
            [-13 * h, -3 * h * h, -22 * h, 4 * h * h],
        ]
    )
    return k, m


def locked_segment(n: int, hinge: int, held: tuple[int, ...] | list[int]) -> tuple[range, bool]:
    """The locked segment a lock at ``hinge`` completes among n rods: the 0-based indices of its
    rods (rod r + 1 is index r; hinge k joins indices k - 1 and k) and whether its inboard end
    is clamped (it reaches the root and hinge 0 is held). ``held``: the hinges held after the
    lock (``hinge`` is added if missing). O(n)."""
    if not 0 <= hinge < n:
        raise ValueError(f"hinge must be 0..{n - 1}, got {hinge!r}")
    locked = set(int(h) for h in held) | {hinge}
    first = max(hinge - 1, 0)
    while first > 0 and first in locked:
        first -= 1
    last = hinge
    while last + 1 < n and last + 1 in locked:
        last += 1
    return range(first, last + 1), first == 0 and 0 in locked


def _sections(chain: Chain, rods: range) -> tuple[np.ndarray, ...]:
    """The segment's beam sections: lengths (m), EI (N m^2), mass per length (kg/m) and the
    node mass at each section's far end (kg). The rods themselves up to MAX_SECTIONS; a
    longer segment is cut into MAX_SECTIONS runs of consecutive rods, each one uniform
    section (compliances l/EI add, masses add, the inner node masses spread along it): the
    first mode's wavelength spans many rods, and the beam's condition number stays
    MAX_SECTIONS^4 (round-off 1e-8) instead of growing as rods^4. O(rods)."""
    l, EI, m, mu = (
        np.asarray(a, dtype=float)[rods.start : rods.stop]
        for a in (chain.l, chain.EI, chain.m, chain.mu)
    )
    if len(l) <= MAX_SECTIONS:
        return l, EI, m, mu
    starts = np.linspace(0, len(l), MAX_SECTIONS + 1).astype(np.int64)[:-1]
    far = mu[np.r_[starts[1:], len(l)] - 1]  # each run's far node mass
    length = np.add.reduceat(l, starts)
    inner = np.add.reduceat(mu, starts) - far
    return (
        length,
        length / np.add.reduceat(l / EI, starts),
        (np.add.reduceat(m * l, starts) + inner) / length,
        far,
    )


def first_bending_period(chain: Chain, hinge: int, held: tuple[int, ...] | list[int] = ()) -> float:
    """Period (s) of the first bending mode of the locked segment a lock at ``hinge``
    completes (``locked_segment``; the module docstring): its rods as one Euler-Bernoulli
    beam, EI and mass per length m of each rod, the node masses mu at the rods' far ends,
    pinned at its inboard node (clamped at a held root). ``held``: the hinges held after the
    lock; () gives the locked pair. O(rods in the segment) to form the sections, then one
    dense generalized eigenproblem of at most 2 * (max(MIN_ELEMENTS, MAX_SECTIONS) + 1)
    dofs (``_sections``)."""
    rods, clamped = locked_segment(chain.n, hinge, held)
    lengths, EI, m, mu = _sections(chain, rods)
    per = max(1, -(-MIN_ELEMENTS // len(lengths)))  # elements per section
    size = 2 * (per * len(lengths) + 1)
    K, M = np.zeros((size, size)), np.zeros((size, size))
    e = 0
    for j in range(len(lengths)):
        k, me = _element(float(EI[j]), float(m[j]), lengths[j] / per)
        for _ in range(per):
            K[2 * e : 2 * e + 4, 2 * e : 2 * e + 4] += k
            M[2 * e : 2 * e + 4, 2 * e : 2 * e + 4] += me
            e += 1
        M[2 * e, 2 * e] += mu[j]  # the section's far node
    free = np.arange(2 if clamped else 1, size)  # clamped: w, theta; pinned: w
    values = scipy.linalg.eigh(
        K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True, subset_by_index=[0, 1]
    )
    # pinned: the rigid rotation about the pin is the zero eigenvalue, the first bending
    # mode the next one; clamped: the first one
    lam = float(values[0] if clamped else values[1])
    period: float = 2.0 * np.pi / np.sqrt(lam)
    return period


def lock_window(chain: Chain, latch: Latch, held: tuple[int, ...] | list[int] = ()) -> float:
    """The latch's window w (s): its ``window``, or ``first_bending_period`` of the segment
    its lock completes with the hinges ``held`` after it."""
    if latch.window is not None:
        return float(latch.window)
    return first_bending_period(chain, latch.hinge, held)


def window_nodes(t_lock: float, w: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Quadrature over the window [t_lock, t_lock + w]: (times (s), weights of
    int f(s) (1 - (s - t_lock)/w) ds, weights of the mean (1/w) int f ds), each
    (WINDOW_PANELS * WINDOW_NODES,). Exact for piecewise polynomials of degree
    2 WINDOW_NODES - 2 on each panel (the taper takes one degree)."""
    edges = np.linspace(0.0, w, WINDOW_PANELS + 1)
    half = 0.5 * np.diff(edges)
    s = (edges[:-1, None] + half[:, None] * (_GL_X + 1.0)).ravel()
    base = (half[:, None] * _GL_W).ravel()
    return t_lock + s, base * (1.0 - s / w), base / w


def window_energies(
    record: dict[str, Any], energies: tuple[float, ...], work: float, lost: float
) -> dict[str, float]:
    """The energy accounts of a lock window the run reached to its end (docs/deployment.md,
    "Where the lock energy goes"), every model's definition: at the window's end the kinetic,
    hinge and bending energy (J) ``energies``, the work of the loads ``work`` and the energy
    dissipated ``lost`` since just before the lock (J; the instantaneous losses included),
    and the balance's residual E(end) - E(before) - work + dissipated (J). A window the run
    did not reach to its end has none (``window_closed`` False)."""
    before = [float(record[f"{name}_before"]) for name in ("kinetic", "hinge", "bending")]
    end = list(energies)
    return {
        "window_end": float(record["t"]) + float(record["impulse_window"]),
        "kinetic_window_end": float(end[0]),
        "hinge_window_end": float(end[1]),
        "bending_window_end": float(end[2]),
        "work_window_end": float(work),
        "dissipated_window_end": float(lost),
        "energy_residual_window_end": float(sum(end) - sum(before) - work + lost),
    }
