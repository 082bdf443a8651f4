"""What subnormal (denormal) floating-point numbers cost the runs of the paper chain.

On a long chain the pulse at the last node moves only the rods near the tip within 0..2 s;
towards the root the state and the O(n) solves' intermediate values decay geometrically
through the subnormal range (|v| < 2.2e-308), and on x86 every operation on (or giving) a
subnormal takes a microcode assist of ~100 cycles. In the reduced model's tip-to-root sweep
(rodval/models/bending/reduced_banded.py) one coefficient of the tail relation (F[0, 1], the P_y ->
S_x coupling) even stays stuck at a few ulps of the smallest subnormal from where the motion
dies out down to the root, so every rod of the sweep pays the assist.

This script times the same runs and right-hand sides with the CPU's default floating-point
mode and with flush-to-zero + denormals-are-zero (MXCSR FTZ|DAZ, set through LLVM's
ldmxcsr intrinsic, for this thread only), side by side, and reports how far the results
differ (they may differ only through values below 2.2e-308). x86-64 only.

Run: OMP_NUM_THREADS=1 PYTHONPATH=. python benchmarks/subnormal_cost.py [--reduced-only] [n ...]
"""

from __future__ import annotations

import sys
import time
from contextlib import contextmanager

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from rodval import bench
from rodval.core.settings import IntegratorSettings
from rodval.models import get_model
from rodval.solvers.driver import integrate

FTZ_DAZ = 0x8040
_PTR = ir.IntType(8).as_pointer()


@intrinsic
def _stmxcsr(typingctx):
    def codegen(context, builder, sig, args):
        slot = builder.alloca(ir.IntType(32))
        fn = builder.module.declare_intrinsic(
            "llvm.x86.sse.stmxcsr", fnty=ir.FunctionType(ir.VoidType(), [_PTR])
        )
        builder.call(fn, [builder.bitcast(slot, _PTR)])
        return builder.zext(builder.load(slot), ir.IntType(64))

    return types.int64(), codegen


@intrinsic
def _ldmxcsr(typingctx, value):
    def codegen(context, builder, sig, args):
        slot = builder.alloca(ir.IntType(32))
        builder.store(builder.trunc(args[0], ir.IntType(32)), slot)
        fn = builder.module.declare_intrinsic(
            "llvm.x86.sse.ldmxcsr", fnty=ir.FunctionType(ir.VoidType(), [_PTR])
        )
        builder.call(fn, [builder.bitcast(slot, _PTR)])
        return context.get_dummy_value()

    return types.void(types.int64), codegen


@njit
def get_mxcsr():
    return _stmxcsr()


@njit
def set_mxcsr(value):
    _ldmxcsr(value)


@contextmanager
def flush_to_zero():
    """FTZ and DAZ on for this thread inside the block."""
    old = get_mxcsr()
    set_mxcsr(old | FTZ_DAZ)
    try:
        yield
    finally:
        set_mxcsr(old)


def timed_pair(f, repeats: int) -> tuple[float, float, object, object]:
    """min wall of f() with the default mode and with FTZ/DAZ, alternating; last results."""
    best = [np.inf, np.inf]
    out = [None, None]
    for _ in range(repeats):
        for i in (0, 1):
            if i:
                with flush_to_zero():
                    start = time.perf_counter()
                    out[i] = f()
                    dt = time.perf_counter() - start
            else:
                start = time.perf_counter()
                out[i] = f()
                dt = time.perf_counter() - start
            best[i] = min(best[i], dt)
    return best[0], best[1], out[0], out[1]


def main() -> None:
    args = sys.argv[1:]
    models = ("reduced",) if "--reduced-only" in args else ("reduced", "full")
    sizes = [int(a) for a in args if a != "--reduced-only"] or [64, 1024, 8192, 65536]
    settings = IntegratorSettings("DOP853-numba", rtol=1e-6, atol=1e-8)
    print(
        f"{'model':8s} {'n':>6s} {'run s':>9s} {'run FTZ s':>10s} {'ratio':>6s} {'nfev':>12s} "
        f"{'phi diff':>9s} {'RHS@0.5 us':>11s} {'FTZ us':>9s} {'ratio':>6s} {'subn. y':>7s}"
    )
    for n in sizes:
        for model in models:
            if model == "full" and n > 8192:
                continue
            scene = bench.scale_scene(n)
            system = get_model(model).system(scene)
            repeats = 3 if n <= 8192 else 1
            w0, w1, t0, t1 = timed_pair(
                lambda s=system, sc=scene, m=model: integrate(s, sc, settings, model=m), repeats
            )
            diff = np.max(np.abs(t0["phi"] - t1["phi"])) / np.max(np.abs(t0["phi"]))
            states = bench.compiled_states(system, scene, settings)
            y = states[5]  # t = 0.5 s
            form = system.compiled()
            r0 = bench.compiled_rhs_cost(form, 0.5, y, 0.05)
            with flush_to_zero():
                r1 = bench.compiled_rhs_cost(form, 0.5, y, 0.05)
            print(
                f"{model:8s} {n:6d} {w0:9.4f} {w1:10.4f} {w0 / w1:6.2f} "
                f"{t0.stats.nfev:>6d}/{t1.stats.nfev:<6d}{diff:9.1e} {r0 * 1e6:11.1f} "
                f"{r1 * 1e6:9.1f} {r0 / r1:6.2f} {bench.subnormal_count(y):7d}",
                flush=True,
            )


if __name__ == "__main__":
    main()
