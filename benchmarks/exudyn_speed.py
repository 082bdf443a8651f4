"""The exudyn reference model at its engine's speed (issue 39): wall time and Python share.

Prints, side by side in one run, for the paper example (n = 8, 0..2 s) and a 6-panel folded
wing with latches on every hinge (0..2 s):

* rodval's exudyn model (``simulate(scene, "exudyn")``): wall time of the run and of its solve,
  and the Python share of the solve (cProfile: the time not spent inside exudyn's
  ``SolveSystem`` C++ call itself, i.e. the pre-step function, user functions and guard),
* a plain exudyn script of the same beams (the same ObjectANCFCable2D elements, revolute
  joints, torsional spring-dampers, point masses and loads built with exudyn's own API, no
  pre-step function, no guard, no latches' switching): the engine's limit,
* the native full and reduced models.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/exudyn_speed.py [--repeat 1] [--only paper|wing]
"""

from __future__ import annotations

import math
import time

import numpy as np

from rodval.core.hinges import Latch
from rodval.core.scene import Chain, InitialState, Scene, paper_scene


def wing_scene(t_end: float = 2.0) -> Scene:
    """6 panels, l = 1.2 m, 8 kg each (m = 8/1.2 kg/m), EI = 2e4 N m^2, folded zig-zag
    phi = [0, pi-0.05, 0, pi-0.05, 0, pi-0.05] at rest, hinge springs kappa = [1e5, 50 x 5]
    N m/rad relaxed at 0, nu = [10, 0.05 x 5] N m s/rad, mu = 0.5 kg, latches at 0 on hinges
    1..5; outputs phi."""
    n = 6
    fold = math.pi - 0.05
    chain = Chain.uniform(
        n,
        l=1.2,
        m=8.0 / 1.2,
        EI=2e4,
        mu=0.5,
        kappa=[1e5] + [50.0] * (n - 1),
        nu=[10.0] + [0.05] * (n - 1),
        rest_angle=0.0,
    )
    return Scene(
        chain=chain,
        t_end=t_end,
        times=np.linspace(0.0, t_end, 201),
        outputs=("phi",),
        initial=InitialState(phi=[0.0, fold, 0.0, fold, 0.0, fold]),
        latches=tuple(Latch(k, 0.0) for k in range(1, n)),
        name="wing6",
    )


def latch3_scene() -> Scene:
    """3 rods (l = 1.5 m, m = 3 kg/m, EI = 1e5, mu = 0.5 kg), hinge 0 free, hinges 1, 2 stowed
    at +-(pi - 0.05) unfolding on 50 N m/rad springs, latches at 0 on hinges 1 and 2."""
    fold = math.pi - 0.05
    chain = Chain.uniform(3, l=1.5, m=3.0, EI=1e5, mu=0.5, kappa=[0.0, 50.0, 50.0], nu=0.0)
    return Scene(
        chain=chain,
        t_end=0.8,
        times=np.linspace(0.0, 0.8, 81),
        outputs=("phi",),
        initial=InitialState(phi=[0.0, fold, 0.0]),
        latches=(Latch(1, 0.0), Latch(2, 0.0)),
        name="latch3",
    )


def paper() -> Scene:
    return paper_scene(8)


SCENES = {"paper": paper, "wing": wing_scene}


# -- a plain exudyn script of the same beams: the engine's limit --------------------------------
def plain_exudyn(scene: Scene, elements: int = 2, step: float = 2e-4, EA: float = 1e10) -> dict:
    """The scene's beams with exudyn's own API only: each rod straight at its initial chord
    angle (the benchmark scenes start straight and at rest), ``elements`` ObjectANCFCable2D per
    rod, ObjectJointRevolute2D and ObjectConnectorTorsionalSpringDamper (with its
    NodeGenericData revolution counter) at every hinge, ObjectMassPoint2D for mu, the loads as
    plain load user functions, the latches as inactive ObjectJointGeneric (a plain script has
    no pre-step function to switch them), sensors on the rods' end nodes; the model's
    generalized-alpha settings (spectral radius 0 with latches, else 0.9), Newton tolerances
    and linear solver. Returns wall times: build (s), solve (s), Newton iterations,
    Jacobians."""
    import exudyn as exu
    from exudyn import itemInterface as it

    from reference_models.exudyn_chain import DEFAULTS, ExudynModel

    t0 = time.perf_counter()
    chain, n = scene.chain, scene.n
    phi0 = scene.initial.resolve(n)["phi"]
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(it.ObjectGround())
    nodes, elems, start = [], [], np.zeros(2)
    for k in range(n):
        le = chain.l[k] / elements
        t = np.array([math.cos(phi0[k]), math.sin(phi0[k])])
        nodes.append(
            [
                mbs.AddNode(it.NodePoint2DSlope1(referenceCoordinates=[*(start + j * le * t), *t]))
                for j in range(elements + 1)
            ]
        )
        elems.append(
            [
                mbs.AddObject(
                    it.ObjectANCFCable2D(
                        nodeNumbers=[nodes[k][j], nodes[k][j + 1]],
                        length=le,
                        massPerLength=float(chain.m[k]),
                        bendingStiffness=float(chain.EI[k]),
                        axialStiffness=EA,
                    )
                )
                for j in range(elements)
            ]
        )
        start = start + chain.l[k] * t
    latched = {latch.hinge: latch.angle for latch in scene.latches}
    for k in range(n):
        if k == 0:
            pos0 = mbs.AddMarker(it.MarkerBodyPosition(bodyNumber=ground))
            rot0 = mbs.AddMarker(it.MarkerBodyRigid(bodyNumber=ground))
            angle0 = phi0[0]
        else:
            pos0 = mbs.AddMarker(it.MarkerNodePosition(nodeNumber=nodes[k - 1][-1]))
            rot0 = mbs.AddMarker(
                it.MarkerBodyRigid(
                    bodyNumber=elems[k - 1][-1], localPosition=[chain.l[k - 1] / elements, 0, 0]
                )
            )
            angle0 = phi0[k] - phi0[k - 1]
        pos1 = mbs.AddMarker(it.MarkerNodePosition(nodeNumber=nodes[k][0]))
        rot1 = mbs.AddMarker(it.MarkerBodyRigid(bodyNumber=elems[k][0]))
        mbs.AddObject(it.ObjectJointRevolute2D(markerNumbers=[pos0, pos1]))
        turns = mbs.AddNode(
            it.NodeGenericData(
                numberOfDataCoordinates=1, initialCoordinates=[float(round(angle0 / (2 * math.pi)))]
            )
        )
        mbs.AddObject(
            it.ObjectConnectorTorsionalSpringDamper(
                markerNumbers=[rot0, rot1],
                nodeNumber=turns,
                stiffness=float(chain.kappa[k]),
                damping=float(chain.nu[k]),
                offset=float(chain.rest_angle[k]),
            )
        )
        if k in latched:
            c, s = math.cos(-latched[k]), math.sin(-latched[k])
            mbs.AddObject(
                it.ObjectJointGeneric(
                    markerNumbers=[rot0, rot1],
                    constrainedAxes=[0, 0, 0, 0, 0, 1],
                    rotationMarker1=[[c, -s, 0], [s, c, 0], [0, 0, 1]],
                    activeConnector=False,
                )
            )
        if chain.mu[k] > 0:
            mbs.AddObject(it.ObjectMassPoint2D(nodeNumber=nodes[k][-1], mass=float(chain.mu[k])))
    for f in scene.loads:
        fx, fy, (a, b) = f.fx, f.fy, f.support

        def law(mbs, t, load, fx=fx, fy=fy, a=a, b=b):
            if not a <= t <= b:
                return [0.0, 0.0, 0.0]
            return [fx(t) if fx else 0.0, fy(t) if fy else 0.0, 0.0]

        marker = mbs.AddMarker(it.MarkerNodePosition(nodeNumber=nodes[f.node - 1][-1]))
        mbs.AddLoad(it.LoadForceVector(markerNumber=marker, loadVectorUserFunction=law))
    for k in range(n):
        for nd in (nodes[k][0], nodes[k][-1]):
            for v in (
                exu.OutputVariableType.CoordinatesTotal,
                exu.OutputVariableType.Coordinates_t,
            ):
                mbs.AddSensor(
                    it.SensorNode(nodeNumber=nd, storeInternal=True, outputVariableType=v)
                )
    mbs.Assemble()
    model = ExudynModel()
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.endTime, ti.numberOfSteps = scene.t_end, int(math.ceil(scene.t_end / step - 1e-9))
    ti.verboseMode = 0
    ti.newton.relativeTolerance = DEFAULTS["newton_rtol"]
    ti.newton.absoluteTolerance = DEFAULTS["newton_atol_per_EA"] * EA
    ti.generalizedAlpha.spectralRadius = model.spectral_radius_for(scene)
    s.solution.file.write = False
    s.solution.sensors.writePeriod = 0.25 * step
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    built = time.perf_counter() - t0
    solver = exu.MainSolverImplicitSecondOrder()
    console, exu.config.printToConsole = exu.config.printToConsole, False
    t1 = time.perf_counter()
    try:
        solver.SolveSystem(mbs, s)
    finally:
        exu.config.printToConsole = console
    return {
        "build_s": built,
        "solve_s": time.perf_counter() - t1,
        "newton": int(solver.it.newtonStepsCount),
        "jacobians": int(solver.it.newtonJacobiCount),
    }


# -- rodval's exudyn model, profiled -----------------------------------------------------------
def model_run(scene: Scene, **options) -> dict:
    """``simulate(scene, "exudyn")`` under cProfile: wall (s, the whole call), solve (s, the
    model's SolveSystem call), engine (s: SolveSystem's own time, cProfile tottime, i.e. the
    C++ solver less the Python called from it) and the Python share = 1 - engine / wall."""
    import cProfile
    import pstats

    from rodval import simulate

    prof = cProfile.Profile()
    t0 = time.perf_counter()
    prof.enable()
    tr = simulate(scene, "exudyn", **options)
    prof.disable()
    wall = time.perf_counter() - t0
    engine = sum(
        row[2] for fn, row in pstats.Stats(prof).stats.items() if fn[2].endswith("SolveSystem>")
    )
    return {
        "trajectory": tr,
        "wall_s": wall,
        "solve_s": tr.stats.wall_s,
        "engine_s": engine,
        "python_share": 1.0 - engine / wall,
        "newton": tr.stats.nfev,
        "jacobians": tr.stats.njev,
    }


def timed_run(scene: Scene, **options) -> dict:
    """``simulate(scene, "exudyn")`` without a profiler, the Python called from inside the
    solver timed by wrappers (perf_counter, ~0.2 us a call): the pre-step function's parts
    (guard, latches, budget) and the load and stop-law user functions. wall (s, the whole
    call), solve (s, the SolveSystem call), python_in_solve (s), engine = solve - python in
    it, Python share = (wall - engine) / wall."""
    from reference_models import exudyn_budget, exudyn_build, exudyn_guard, exudyn_latches
    from rodval import simulate

    spent = [0.0]

    def timed(fn):
        def wrapper(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                spent[0] += time.perf_counter() - t0

        return wrapper

    def timed_factory(factory):
        return lambda *args, **kwargs: timed(factory(*args, **kwargs))

    patches = [
        (exudyn_guard.Guard, "pre_step", timed),
        (exudyn_latches.Latches, "pre_step", timed),
        (exudyn_budget.RunBudget, "pre_step", timed),
        (exudyn_build, "load_function", timed_factory),
        (exudyn_build, "stop_law", timed_factory),
    ]
    saved = [(owner, name, getattr(owner, name)) for owner, name, _ in patches]
    try:
        for owner, name, wrap in patches:
            setattr(owner, name, wrap(getattr(owner, name)))
        t0 = time.perf_counter()
        tr = simulate(scene, "exudyn", **options)
        wall = time.perf_counter() - t0
    finally:
        for owner, name, fn in saved:
            setattr(owner, name, fn)
    engine = tr.stats.wall_s - spent[0]
    return {
        "trajectory": tr,
        "wall_s": wall,
        "solve_s": tr.stats.wall_s,
        "python_in_solve_s": spent[0],
        "engine_s": engine,
        "python_share": (wall - engine) / wall,
    }


def native_wall(scene: Scene, model: str, repeat: int = 2) -> float:
    """Wall (s) of ``simulate(scene, model)``, the best of ``repeat`` runs (the first may
    compile the model's kernels)."""
    from rodval import simulate

    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        tr = simulate(scene, model)
        best = min(best, time.perf_counter() - t0)
        if tr.stats.status != 0:
            return float("nan")
    return best


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=sorted(SCENES), action="append")
    ap.add_argument("--no-native", action="store_true", help="skip the native models")
    args = ap.parse_args(argv)
    rows = []
    for name in args.only or sorted(SCENES):
        scene = SCENES[name]()
        from rodval import simulate

        simulate(scene, "reduced")  # warm-up: imports, compiled kernels
        m = model_run(scene)
        timed = timed_run(scene)
        wall = timed["wall_s"]
        plain = plain_exudyn(scene)
        row = {
            "scene": name,
            "exudyn wall (s)": wall,
            "engine (s)": timed["engine_s"],
            "Python share (timers)": timed["python_share"],
            "wall, cProfile (s)": m["wall_s"],
            "Python share (cProfile)": m["python_share"],
            "Newton it.": m["newton"],
            "Jacobians": m["jacobians"],
            "plain exudyn (s)": plain["solve_s"] + plain["build_s"],
            "plain Newton it.": plain["newton"],
            "plain Jacobians": plain["jacobians"],
            "exudyn / plain": wall / (plain["solve_s"] + plain["build_s"]),
        }
        if not args.no_native:
            row["native full (s)"] = native_wall(scene, "full")
            row["native reduced (s)"] = native_wall(scene, "reduced")
        rows.append(row)
        print(name, "done", flush=True)
    keys = list(rows[0])
    print("| " + " | ".join(keys) + " |")
    print("|" + "---|" * len(keys))
    for row in rows:
        cells = [f"{v:.3g}" if isinstance(v, float) else str(v) for v in row.values()]
        print("| " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
