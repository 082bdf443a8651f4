"""Cost of the rigid-panel lock (``rodval.mechanics.rigid.rigid_lock``) against n: one call on a
chain of n rods in a random configuration with every second hinge held (so the KKT system has
its largest number of constraint rows). The time should grow linearly with n (one sparse LU
of a banded system). Run: ``python benchmarks/rigid_lock_scale.py``."""

import time

import numpy as np

from rodval.core.scene import Chain
from rodval.mechanics.rigid import rigid_lock


def main() -> None:
    print("n, held hinges, seconds (best of 3), seconds per rod")
    for n in (100, 1_000, 10_000, 100_000):
        rng = np.random.default_rng(0)
        chain = Chain.uniform(n)
        phi, dphi = rng.uniform(-3.0, 3.0, n), rng.normal(size=n)
        held = list(range(1, n, 2))
        best = np.inf
        for _ in range(3):
            start = time.perf_counter()
            rigid_lock(chain, phi, dphi, held, 1)
            best = min(best, time.perf_counter() - start)
        print(f"{n}, {len(held)}, {best:.4f}, {best / n:.2e}")


if __name__ == "__main__":
    main()
