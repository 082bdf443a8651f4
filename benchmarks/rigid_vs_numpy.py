"""The rigid model against what an engineer writes instead (issue 49): a ~40-line numpy rigid
chain on scipy's DOP853, derived here independently (Lagrange's equations of rigid rods with
far-node masses, hinge springs and dampers), on the 6-panel wing without latches over 10 s
(``exudyn_speed.wing_scene``: EI plays no part). Both at rtol 1e-8, atol 1e-10; prints the
largest |phi| difference at the 1001 output times (rad) and the integrations' wall times (the
best of REPEATS; the rigid model's is its integration, ``stats.wall_s``).

    .venv/bin/python benchmarks/rigid_vs_numpy.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from exudyn_speed import wing_scene  # noqa: E402

from rodval import simulate  # noqa: E402

RTOL, ATOL, T_END, REPEATS = 1e-8, 1e-10, 10.0, 5


def numpy_chain(l, m, mu, kappa, nu, rest):
    """y' = f(t, y) of the rigid chain, y = [phi; phi'] (the engineer's version)."""
    n = l.size
    # point masses: rod centres (m l, at half of their own rod) and far nodes (mu); a[p, j]:
    # the share of rod j's chord in point p's position (1 before it, 1/2 for its own centre)
    a = np.vstack([np.tril(np.ones((n, n)), -1) + 0.5 * np.eye(n), np.tril(np.ones((n, n)))])
    mass = np.concatenate([m * l, mu])
    G = (a.T * mass) @ a * np.outer(l, l)  # T = 1/2 sum G_ij cos(phi_i - phi_j) phi_i' phi_j'
    J = m * l**3 / 12.0  # the rods' own rotary inertia about their centres
    A = np.eye(n) - np.eye(n, k=-1)  # D = A phi (hinge 0 from the ground)

    def f(t, y):
        phi, w = y[:n], y[n:]
        d = phi[:, None] - phi[None, :]
        M = G * np.cos(d) + np.diag(J)
        Q = -A.T @ (kappa * (A @ phi - rest) + nu * (A @ w)) - (G * np.sin(d)) @ (w * w)
        return np.concatenate([w, np.linalg.solve(M, Q)])

    return f


def main() -> None:
    scene = wing_scene(T_END).with_(latches=(), times=np.linspace(0.0, T_END, 1001))
    ch = scene.chain
    f = numpy_chain(ch.l, ch.m, ch.mu, ch.kappa, ch.nu, ch.rest_angle)
    y0 = np.concatenate([scene.initial.resolve(ch.n)["phi"], np.zeros(ch.n)])

    def engineer(rtol: float, atol: float) -> np.ndarray:
        sol = solve_ivp(f, (0.0, T_END), y0, "DOP853", scene.times, rtol=rtol, atol=atol)
        return sol.y[: ch.n].T

    walls, rigid = [], []
    for _ in range(REPEATS):
        start = time.perf_counter()
        phi_np = engineer(RTOL, ATOL)
        walls.append(time.perf_counter() - start)
        tr = simulate(scene, "rigid", rtol=RTOL, atol=ATOL)
        rigid.append(tr.stats.wall_s)
    gap = np.abs(tr["phi"] - phi_np).max(axis=1)
    apart = scene.times[np.argmax(gap > 1e-5)] if np.any(gap > 1e-5) else T_END
    # the same at rtol 1e-12, and each rtol 1e-8 run against the numpy chain at rtol 1e-12:
    # the wing's motion without latches amplifies any error (chaotic), so what two correct
    # integrations at rtol 1e-8 share over 10 s is bounded by that growth, not by the models
    ref = engineer(1e-12, 1e-14)
    tight = simulate(scene, "rigid", rtol=1e-12, atol=1e-14)["phi"]
    print(f"6-panel wing, no latches, {T_END:g} s, rtol {RTOL:g}, atol {ATOL:g}:")
    print(f"  numpy chain on scipy DOP853: {min(walls):.4f} s")
    print(
        f"  rigid model ({tr.settings['method']}): {min(rigid):.4f} s ({tr.stats.nfev} evaluations)"
    )
    print(f"  speed ratio {min(walls) / min(rigid):.1f}x")
    print(f"  max |phi difference| {gap.max():.2e} rad; within 1e-5 rad up to t = {apart:g} s")
    for t in (2.0, 5.0, 10.0):
        i = int(np.searchsorted(scene.times, t))
        print(
            f"  t = {t:g} s: rigid - numpy {gap[i]:.1e} rad; against numpy at rtol 1e-12: "
            f"rigid {np.abs(tr['phi'][i] - ref[i]).max():.1e}, numpy "
            f"{np.abs(phi_np[i] - ref[i]).max():.1e}"
        )
    print(
        f"  at rtol 1e-12: max |rigid - numpy| {np.abs(tight - ref).max():.2e} rad over {T_END:g} s"
    )


if __name__ == "__main__":
    main()
