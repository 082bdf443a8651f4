"""The model ladder's figures quoted in docs/model.md and docs/modes.md ("The model ladder"),
from the same scenes and checks as tests/test_ladder.py (which asserts their bounds).

Run:  PYTHONPATH=.:tests python benchmarks/ladder_checks.py   (about a minute)

Prints: the independent-Lagrangian residual and forward error per p; energy and angular
momentum drift of the free paper chain and of the latched flexible pair, per rung; the one-rod
frequency errors against Euler-Bernoulli per p; the paper chain's modes against exudyn (16
elements per rod) per p.
"""

from __future__ import annotations

import numpy as np
from ladder_lagrangian import Chain as IndependentChain
from ladder_lagrangian import equations
from test_ladder import (
    BL_CLAMPED,
    BL_PINNED,
    free_paper_chain,
    latch_scene,
    random_chain,
)

import rodval
from reference_models.exudyn_modes import exudyn_modes
from rodval import simulate
from rodval.core.scene import Chain, Scene
from rodval.models.kinematics.ladder import ladder_constants
from rodval.models.kinematics.ladder_kernels import ladder_accel
from rodval.models.observation.linear_modes import modes


def lagrangian() -> None:
    print("independent Lagrangian (3 random chains and states per p, n = 3):")
    for p in (1, 2, 3, 4):
        rng = np.random.default_rng(100 + p)  # the draws of the test
        worst_res = worst_fwd = 0.0
        for _ in range(3):
            data = random_chain(rng, 3)
            ref = IndependentChain(
                p,
                *(data[k] for k in ("l", "m", "mu", "EI", "kappa", "nu")),
                data["rest_angle"],
                data["bending_damping"],
            )
            V = ladder_constants(Chain(**data), p, exact=True)
            N = 3 * (p + 2)
            q, v = rng.uniform(-1.0, 1.0, N), rng.uniform(-2.0, 2.0, N)
            X, Y = rng.uniform(-5.0, 5.0, 3), rng.uniform(-5.0, 5.0, 3)
            acc = np.empty(N)
            loads = (True, np.cumsum(X[::-1])[::-1], np.cumsum(Y[::-1])[::-1], np.empty(0))
            ladder_accel(V, np.concatenate([q, v]), loads, True, acc)
            M, f = equations(ref, q, v, X, Y)
            scale = np.max(np.abs(f)) + np.max(np.abs(M)) * np.max(np.abs(acc))
            worst_res = max(worst_res, np.max(np.abs(M @ acc - f)) / scale)
            fwd = np.max(np.abs(acc - np.linalg.solve(M, f))) / np.max(np.abs(acc))
            worst_fwd = max(worst_fwd, fwd)
        print(f"  p = {p}: residual {worst_res:.1e}, forward error {worst_fwd:.1e}")


def drift(tr, rows) -> str:
    out = []
    for q in ("energy", "angular_momentum"):
        if q in tr.quantities:
            x = tr[q][rows, 0]
            out.append(f"{q} {np.ptp(x) / np.max(np.abs(x)):.1e}")
    return ", ".join(out)


def conservation() -> None:
    scene = free_paper_chain()
    after = scene.times >= 1.0
    print("free undamped paper chain, kappa_0 = 0, after the pulse, rtol 1e-10 (relative drift):")
    for kin, p in (("first-order", 1), ("exact", 1), ("exact", 3)):
        tr = simulate(scene, "full", shapes=p, kinematics=kin, rtol=1e-10, atol=1e-12)
        print(f"  {kin}, p = {p}: {drift(tr, after)}")
    scene = latch_scene()
    print("flexible pair through a latch, 0..0.6 s, rtol 1e-10:")
    for kin, p in (("first-order", 1), ("exact", 3)):
        tr = simulate(scene, "full", shapes=p, kinematics=kin, rtol=1e-10, atol=1e-12)
        print(f"  {kin}, p = {p}: {drift(tr, slice(None))}")


def one_rod() -> None:
    EI, m, l = 1e5, 3.0, 2.0
    print("one rod, relative error of the first three bending frequencies:")
    for name, kappa0, bl in (("clamped", 1e12, BL_CLAMPED), ("pinned", 0.0, BL_PINNED)):
        chain = Chain.uniform(1, l=l, m=m, mu=0.0, EI=EI, kappa=kappa0, nu=0.0)
        exact = bl**2 * np.sqrt(EI / (m * l**4))
        for p in range(1, 8):
            w = modes(Scene(chain=chain, t_end=1.0), "full", shapes=p).omega
            w = w[(w > 1e-3 * exact[0]) & (w < 1e3 * exact[-1])][:3]
            errs = " / ".join(f"{e:.1e}" for e in w / exact[: len(w)] - 1)
            print(f"  {name}, p = {p}: {errs}")


def paper_modes() -> None:
    scene = rodval.paper_scene()
    ex = exudyn_modes(scene, elements=16).omega[:10]
    print(f"paper chain, exudyn 16 elements: modes 9, 10 = {ex[8]:.3f}, {ex[9]:.3f} rad/s")
    p1 = modes(scene, "full", count=10).omega
    for p in (1, 2, 3, 4):
        w = modes(scene, "full", shapes=p, count=10).omega
        gap = w / ex - 1
        print(
            f"  p = {p}: modes 9, 10 = {w[8]:.3f}, {w[9]:.3f} (gaps {gap[8]:.1e}, {gap[9]:.1e});"
            f" hinge modes 2-8 largest gap {np.max(np.abs(gap[1:8])):.1e},"
            f" hinge modes 1-8 largest change from p = 1 {np.max(np.abs(w[:8] / p1[:8] - 1)):.1e}"
        )


if __name__ == "__main__":
    lagrangian()
    conservation()
    one_rod()
    paper_modes()
