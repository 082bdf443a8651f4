"""The bending damping of the deployed structure (``[chain] bending_damping = { ratio = z,
of = "deployed" }``, ``rodval.core.damping``): the Kelvin-Voigt c of every rod that gives the
deployed structure's first flexible mode the damping ratio z, resolved once where a scene
enters a model (``resolve_damping``), so that every model (full, reduced, rigid, exudyn)
runs the same c and run.json records it.

The deployed structure (``deployed_scene``): the scene with every latch held at its angle
(``Latch.held``), the hinges without a latch at their springs' rest angles, the rods straight,
at rest; loads and stops left out (the structure's free vibration, as a test states its
damping). On a free base the body stays (its three rigid modes are not flexible); a
prescribed base is held fixed (pinned: its motion is a law of time, not a stiffness). A scene
without latches is deployed as it is given: its own first flexible mode.

Its first flexible mode and damping ratio are the **full model's** (``linear_modes.modes_about``
about that configuration, or ``free_modes`` on a free base; the paper's rung: one cubic
per rod, first-order kinematics, printed coefficients), the one model whose bending has
dynamics, and hence damping, on every base: the reduced model's bending is quasi-static and
the rigid model's rods do not bend (Kelvin-Voigt damping does nothing in either), and exudyn
is the reference it is checked against. The mode is the lowest of positive omega (after the
three rigid modes of a free base); its ratio is the quadratic eigenproblem's,
zeta = -Re(s) / |s| (``rodval.mechanics.modal.damping_ratios``), hinge dampers included.

c_r = beta EI_r on every rod: one retardation time beta (s), the same material loss in every
panel (each rod's own bending modes then have zeta = beta omega / 2). beta is the root of
zeta_1(beta) = z by the secant method from beta = 0 (the hinge dampers' ratio alone) and
beta = 2 z / omega_1 (the ratio of a mode that is all bending); zeta_1 is nearly linear in
beta for light damping, so it stops within a few steps at |zeta_1 - z| <= ``RTOL`` z. A
ratio the hinge dampers alone exceed, or one Kelvin-Voigt damping cannot give the mode (its
ratio stops growing with beta: a mode that bends the rods too little, e.g. the whole wing
turning on a soft root spring), is refused with the ratio reached. Cost: one dense modal
analysis per step, O((3n)^3).

A ratio of each panel's own first mode (``of = "panel"``, the default) damps the deployed
structure's slower first mode far less (zeta scales with omega: 0.01 of a panel can be 6e-5
of the wing); ``panel_note`` states that figure in the run's notes (one modal analysis,
cached), so that a designer sees what the panel ratio gives the structure.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from rodval.core.base import PINNED
from rodval.core.bounds import MAX_MAGNITUDE
from rodval.core.damping import DEPLOYED, PANEL, DampingRequest
from rodval.core.scene import InitialState, Scene

#: Relative tolerance of the deployed first mode's ratio: |zeta_1 - z| <= RTOL z.
RTOL = 1e-6
#: Most secant steps before the request is refused as not reached.
MAX_ITERATIONS = 30
#: The model (and rung) whose linearization converts the request, as run.json records it.
MODEL = "full (shapes = 1, first-order kinematics, printed coefficients)"
#: Converted requests kept in this process (``resolve_damping`` is asked again for the same
#: scene at each boundary: the models' run, a study's plan, the run folder's record).
CACHE_SIZE = 64
_CACHE: dict[tuple[Any, ...], tuple[np.ndarray, dict[str, Any]]] = {}
#: The panel-ratio notes kept in this process (``panel_note``), by the same key and the c.
_NOTES: dict[tuple[Any, ...], list[str]] = {}


def deployed_scene(scene: Scene, c: Any = None) -> Scene:
    """The deployed structure of ``scene`` (module docstring): every latch held at its angle,
    the other hinges at their rest angles, straight rods at rest, no loads, stops, motors or
    rate dampers (the structure's own modes), a prescribed base pinned; its rods' bending
    damping ``c`` (N m^2 s; None: the scene's, with its damping request, so that a deployed
    request is converted for this structure)."""
    latches = tuple(dataclasses.replace(latch, held=True) for latch in scene.latches)
    D = np.array(scene.chain.rest_angle, float)  # rad: the springs' rest angles,
    for latch in latches:  # each latch's angle on its hinge (``equilibrium_angles``)
        D[latch.hinge] = float(latch.angle)
    base = scene.base
    if base.free:
        base = dataclasses.replace(base, velocity=(0.0, 0.0), rate=0.0)
    elif base.prescribed:
        base = PINNED
    attitude = base.attitude if base.free else 0.0
    phi = attitude + np.cumsum(D)
    chain = scene.chain if c is None else scene.chain.with_(bending_damping=c)
    return Scene(
        chain=chain,
        t_end=scene.t_end,
        outputs=("phi",),
        initial=InitialState(phi=phi),
        name=f"{scene.name} (deployed)",
        latches=latches,
        base=base,
        damping=scene.damping if c is None else None,
    )


def first_mode(deployed: Scene) -> tuple[float, float]:
    """(omega (rad/s), zeta) of the deployed structure's first flexible mode, by the full
    model's linearization about its configuration (module docstring)."""
    from rodval.models.observation.free_modes import free_modes
    from rodval.models.observation.linear_modes import modes_about

    if deployed.base.free:
        modes = free_modes(deployed, about="initial", count=1).flexible()
    else:
        modes = modes_about(deployed, "full", about="initial", count=None)
        modes = modes.rows(np.flatnonzero(modes.omega > 0)[:1])
    if modes.count == 0:
        raise ValueError("the deployed structure has no flexible mode")
    return float(modes.omega[0]), float(modes.damping[0])


def check_deployable(scene: Scene) -> None:
    """ValueError (before any work) when the deployed structure is a mechanism: a hinge with
    neither a latch nor a spring (kappa = 0) turns freely, so it has zero-frequency modes
    and no first flexible mode for the ratio to be of. Names the hinges and the fixes."""
    latched = {latch.hinge for latch in scene.latches}
    loose = [
        int(k) for k in np.flatnonzero(np.asarray(scene.chain.kappa) == 0.0) if k not in latched
    ]
    if loose:
        raise ValueError(
            f'bending_damping of = "deployed": hinge(s) {loose} have neither a latch nor a '
            "spring (chain.kappa = 0), so the deployed structure is a mechanism without a "
            "first flexible mode; give them a latch or a spring, or state the ratio of each "
            'panel (of = "panel") or c in N m^2 s'
        )


def deployed_damping(scene: Scene, ratio: float) -> tuple[np.ndarray, dict[str, Any]]:
    """(c per rod (N m^2 s), the record): c_r = beta EI_r with beta (s) the secant root of
    zeta_1(beta) = ``ratio`` (module docstring), and what run.json records of it: c, beta,
    the mode's omega (rad/s) and the ratio it reached, the secant steps (modal analyses after
    the one at beta = 0), the model. ValueError, naming the ratio reached, when the hinge
    dampers alone exceed ``ratio`` or Kelvin-Voigt damping cannot reach it."""
    check_deployable(scene)
    EI = scene.chain.EI

    def zeta_at(beta: float) -> tuple[float, float]:
        return first_mode(deployed_scene(scene, beta * EI))

    omega0, zeta0 = zeta_at(0.0)
    tol = RTOL * ratio
    b0, z0, omega, zeta, beta, steps = 0.0, zeta0, omega0, zeta0, 0.0, 0
    if zeta0 > ratio + tol:
        raise ValueError(
            f'bending_damping = {{ ratio = {ratio:g}, of = "deployed" }}: the hinge dampers '
            f"(chain.nu) alone give the deployed structure's first mode ({omega0:.6g} rad/s) "
            f"the ratio {zeta0:.6g}, more than asked; lower nu or the ratio"
        )
    if abs(zeta0 - ratio) > tol:
        beta = 2.0 * (ratio - zeta0) / omega0  # a mode that is all bending: zeta = beta omega/2
        while True:
            steps += 1
            omega, zeta = zeta_at(beta)
            if abs(zeta - ratio) <= tol:
                break
            slope = (zeta - z0) / (beta - b0)
            if not (slope > 0 and np.isfinite(zeta)) or steps >= MAX_ITERATIONS:
                raise _unreached(ratio, omega, zeta, beta, steps)
            b0, z0, beta = beta, zeta, beta + (ratio - zeta) / slope
            if not 0 < beta * float(np.max(EI)) <= MAX_MAGNITUDE:  # beyond: c out of bounds
                raise _unreached(ratio, omega, zeta, b0, steps)
    c = beta * EI
    record = {
        "c_N_m2_s": c.tolist(),
        "beta_s": beta,
        "mode_omega_rad_s": omega,
        "zeta": zeta,
        "iterations": steps,
        "model": MODEL,
        "held_hinges": sorted(latch.hinge for latch in scene.latches),
    }
    return c, record


def _unreached(ratio: float, omega: float, zeta: float, beta: float, steps: int) -> ValueError:
    return ValueError(
        f'bending_damping = {{ ratio = {ratio:g}, of = "deployed" }}: Kelvin-Voigt damping of '
        f"the rods does not give the deployed structure's first mode ({omega:.6g} rad/s) that "
        f"ratio (it reached {zeta:.6g} at c = {beta:.6g} s x EI, {steps} secant steps): "
        "the mode bends the rods too little (a hinge without a latch turning on its spring); "
        'latch that hinge, add a hinge damper (chain.nu), or state the ratio of each panel (of = "panel")'
    )


def _key(scene: Scene, ratio: float | tuple[float, ...]) -> tuple[Any, ...]:
    """What the conversion depends on: the deployed structure's chain (but its placeholder
    c), latches and base, and the ratio (a scene and its deployed structure share it)."""
    deployed = deployed_scene(scene, 0.0)
    chain = tuple(
        getattr(deployed.chain, f).tobytes()
        for f in deployed.chain.FIELDS
        if f != "bending_damping"
    )
    return (ratio, chain, deployed.latches, repr(deployed.base))


def resolve_damping(scene: Scene) -> Scene:
    """``scene`` with its deployed damping request (``Scene.damping``, ``of = "deployed"``)
    converted: the chain's c (N m^2 s) per rod and the request's record (``resolved``). Any
    other scene is returned as it is (c given in N m^2 s or as a panel ratio, or converted
    already). Called where a scene enters a model; converted once per process for a scene
    (``CACHE_SIZE``)."""
    request = scene.damping
    if request is None or not request.pending:
        return scene
    assert request.of == DEPLOYED and isinstance(request.ratio, float)
    ratio = request.ratio
    c, record = _cached(_CACHE, _key(scene, ratio), lambda: deployed_damping(scene, ratio))
    return scene.with_(
        chain=scene.chain.with_(bending_damping=c),
        damping=DampingRequest(request.ratio, request.of, dict(record)),
    )


def _cached(cache: dict[tuple[Any, ...], Any], key: tuple[Any, ...], compute: Any) -> Any:
    """``cache[key]``, computed by ``compute()`` when missing; the oldest entry dropped beyond
    ``CACHE_SIZE``."""
    if key not in cache:
        if len(cache) >= CACHE_SIZE:
            cache.pop(next(iter(cache)))
        cache[key] = compute()
    return cache[key]


def panel_note(scene: Scene) -> list[str]:
    """The note of a run of ``scene`` whose damping is a ratio of each panel's first mode
    (``of = "panel"``, the default) and that has latches: the ratio that c gives the deployed
    structure's first flexible mode (its frequency in Hz), and that ``of = "deployed"`` would
    state it instead. None for a scene without a panel ratio or without latches, nor when the
    deployed structure has no first flexible mode (``check_deployable``: a mechanism). One
    modal analysis per scene and c, cached."""
    request = scene.damping
    if request is None or request.of != PANEL or not scene.latches:
        return []
    c = np.asarray(scene.chain.bending_damping, float)
    key = (*_key(scene, request.ratio), c.tobytes())
    notes: list[str] = _cached(_NOTES, key, lambda: _panel_note(scene, c))
    return list(notes)


def _panel_note(scene: Scene, c: np.ndarray) -> list[str]:
    """``panel_note``'s sentence, computed: the first mode of the deployed structure with c."""
    try:
        check_deployable(scene)
        omega, zeta = first_mode(deployed_scene(scene, c))
    except ValueError:
        return []
    ratio = scene.damping.ratio if scene.damping is not None else 0.0
    stated = f"{ratio:g}" if isinstance(ratio, float) else f"{list(ratio)}"
    return [
        f"bending_damping ratio {stated} of each panel's first mode gives the deployed "
        f"structure's first flexible mode ({omega / (2.0 * np.pi):.3g} Hz, every latch held) "
        f'a ratio of {zeta:.2g}; of = "deployed" states that ratio instead'
    ]
