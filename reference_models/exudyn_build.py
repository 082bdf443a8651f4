"""Building the exudyn beam model of a scene: nodes, ANCF cable elements, a free or prescribed
base's rigid body, hinges (joints, spring-dampers, stops, torque items, latch joints), point
masses, loads and sensors
(``build``), and a run's records read back from the sensors (``read_records``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from reference_models.exudyn_beam import (
    BODY,
    Array,
    Nodes,
    engaged_law,
    initial_node_states,
    load_function,
    revolutions,
    stop_law,
    torque_law,
)
from rodval.core.scene import Scene
from rodval.core.validity import momentum_point


@dataclass
class BuiltSystem:
    """An assembled exudyn system and the sensor ids needed for the scene's outputs."""

    SC: Any
    mbs: Any
    #: (rod, local node) -> sensors (q, v, a); a free base's body node under ``BODY``
    node_sensors: dict[tuple[int, int], tuple[int, ...]]
    load_errors: list[Exception]
    nodes: list[list[int]]  # beam node numbers per rod
    initial: tuple[Array, ...]  # initial_node_states: ref, offsets, velocities
    latch_joints: dict[int, int]  # hinge -> exudyn object number of its locking joint
    body: int | None = None  # a moving base's NodeRigidBody2D (None: pinned to the ground)
    #: a prescribed base's CoordinateConstraints (x, y, theta), () otherwise
    drives: tuple[int, ...] = ()
    #: hinge -> the switch [engaged] of its compliant latch's laws (``engaged_law``)
    latch_switches: dict[int, list[bool]] = field(default_factory=dict)


def _items() -> Any:
    """exudyn's item classes (exudyn is optional: imported on first use)."""
    from exudyn import itemInterface

    return itemInterface


def build(scene: Scene, E: int, EA: float) -> BuiltSystem:
    """The exudyn beam model of ``scene``, each rod meshed into E ANCF cable elements of axial
    stiffness EA (N), assembled: O(n E) items. Hinges are a position joint plus a torsional
    spring-damper on the end tangents (relaxed at the rest angle: exudyn's ``offset``); limit
    stops a second spring-damper with a one-sided user law; latches a rotation-locking
    ObjectJointGeneric, inactive until the pre-step function (``Latches``) switches it on;
    a compliant latch its two stops' spring-dampers (``CompliantLatch.engaged_stops``), whose
    laws are zero until ``Latches`` sets the latch's switch (``engaged_law``);
    a torque item (motor, rate damper) a zero spring-damper whose user law is its moment.
    A free base is a NodeRigidBody2D (reference coordinates [x_c, y_c, theta] at the initial
    position and attitude) with an ObjectRigidBody2D of the body's mass and inertia; hinge 0
    joins it, at the hinge offset, to rod 1 (instead of the ground). A prescribed base is the
    same node (referenced at its laws' values at t = 0, moving at their rates) with a nominal
    ``PRESCRIBED_MASS``, ``PRESCRIBED_INERTIA`` body whose three coordinates are imposed by
    CoordinateConstraints (``_add_drives``). A held latch's joint is active from the start."""
    import exudyn as exu

    chain = scene.chain
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(_items().ObjectGround())
    ref, q0, v0 = initial_node_states(scene, E)
    nodes, elems = _add_rods(mbs, scene, E, EA, (ref, q0, v0))
    body_node, root_body = _add_body(mbs, scene, ground)
    drives = _add_drives(mbs, scene, body_node)
    load_errors: list[Exception] = []
    switches = {latch.hinge: [False] for latch in scene.compliant_latches}
    springs = _hinge_springs(scene, (load_errors, switches))
    latch_joints = _add_hinges(mbs, scene, E, root_body, (nodes, elems), springs)
    it = _items()
    for k in range(chain.n):
        if chain.mu[k] > 0:
            mbs.AddObject(it.ObjectMassPoint2D(nodeNumber=nodes[k][-1], mass=float(chain.mu[k])))
    for f in scene.loads:
        marker = mbs.AddMarker(it.MarkerNodePosition(nodeNumber=nodes[f.node - 1][-1]))
        mbs.AddLoad(
            it.LoadForceVector(
                markerNumber=marker,
                loadVector=[0, 0, 0],
                loadVectorUserFunction=load_function(f, load_errors),
            )
        )
    node_sensors = _add_sensors(mbs, scene, E, nodes, body_node)
    mbs.Assemble()
    return BuiltSystem(
        SC,
        mbs,
        node_sensors,
        load_errors,
        nodes,
        (ref, q0, v0),
        latch_joints,
        body_node,
        drives,
        switches,
    )


#: A prescribed base's body in exudyn: a small positive mass (kg) and inertia (kg m^2) that
#: keep its node's mass matrix regular; its motion is imposed, so they do not act on the chain
#: (the constraints' forces carry them). The outputs treat the body as massless, as the native
#: models do (``rodval.models.systems.body.Body``).
PRESCRIBED_MASS = 1.0
PRESCRIBED_INERTIA = 1.0


def body_start(scene: Scene) -> tuple[list[float], list[float], float, float]:
    """A moving base's body at t = 0: [x_c, y_c, theta] (m, m, rad), their rates, and the
    body's mass (kg) and inertia (kg m^2) in the exudyn model (a prescribed base's nominal
    ``PRESCRIBED_MASS``, ``PRESCRIBED_INERTIA``)."""
    b = scene.base
    if b.prescribed:
        r, v, th, w = b.state_at(0.0)
        return (
            [float(r[0]), float(r[1]), th],
            [float(v[0]), float(v[1]), w],
            PRESCRIBED_MASS,
            PRESCRIBED_INERTIA,
        )
    return (
        [b.position[0], b.position[1], b.attitude],
        [b.velocity[0], b.velocity[1], b.rate],
        *b.inertial(),
    )


def _add_body(mbs: Any, scene: Scene, ground: int) -> tuple[int | None, int]:
    """A moving base's rigid body: (its NodeRigidBody2D, its ObjectRigidBody2D), the node's
    coordinates [x_c, y_c, theta] (m, m, rad) referenced at the initial position and attitude
    and moving with the initial velocity and rate (``body_start``); (None, ground) on a pinned
    base."""
    if not scene.base.moving:
        return None, ground
    it = _items()
    ref, vel, mass, inertia = body_start(scene)
    node = mbs.AddNode(it.NodeRigidBody2D(referenceCoordinates=ref, initialVelocities=vel))
    body = mbs.AddObject(it.ObjectRigidBody2D(mass=mass, inertia=inertia, nodeNumber=node))
    return node, body


def _add_drives(mbs: Any, scene: Scene, node: int | None) -> tuple[int, ...]:
    """A prescribed base's three CoordinateConstraints (x_c, y_c, theta), () otherwise: each
    between a ground coordinate marker (marker 0) and the body node's coordinate (marker 1),
    which exudyn holds at q_1 - q_0 = offset, q_1 the node's displacement from its reference
    (the laws' values at t = 0): the offset user function returns f(t) - f(0) of the law, its
    ``_t`` twin (index-2 solvers) f'(t)."""
    if node is None or not scene.base.prescribed:
        return ()
    from rodval.core.motion import motion_at

    it = _items()
    table = scene.base.motion_table()
    start = motion_at(table, 0.0)[:, 0].copy()
    ground = mbs.AddNode(it.NodePointGround())
    fixed = mbs.AddMarker(it.MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    drives = []
    for axis in range(3):
        coord = mbs.AddMarker(it.MarkerNodeCoordinate(nodeNumber=node, coordinate=axis))

        def offset(mbs: Any, t: float, itemNumber: int, lOffset: float, axis: int = axis) -> float:
            return float(motion_at(table, t)[axis, 0] - start[axis])

        def offset_t(
            mbs: Any, t: float, itemNumber: int, lOffset: float, axis: int = axis
        ) -> float:
            return float(motion_at(table, t)[axis, 1])

        drives.append(
            mbs.AddObject(
                it.CoordinateConstraint(
                    markerNumbers=[fixed, coord],
                    offset=0.0,
                    offsetUserFunction=offset,
                    offsetUserFunction_t=offset_t,
                )
            )
        )
    return tuple(drives)


def _add_rods(
    mbs: Any, scene: Scene, E: int, EA: float, initial: tuple[Array, ...]
) -> tuple[list[list[int]], list[list[int]]]:
    """Each rod's E + 1 slope nodes at their initial states and its E cable elements."""
    it = _items()
    chain = scene.chain
    ref, q0, v0 = initial
    nodes: list[list[int]] = []
    elems: list[list[int]] = []
    for k in range(chain.n):
        nodes.append(
            [
                mbs.AddNode(
                    it.NodePoint2DSlope1(
                        referenceCoordinates=ref[k, j].tolist(),
                        initialCoordinates=q0[k, j].tolist(),
                        initialVelocities=v0[k, j].tolist(),
                    )
                )
                for j in range(E + 1)
            ]
        )
        le = float(chain.l[k]) / E
        elems.append(
            [
                mbs.AddObject(
                    it.ObjectANCFCable2D(
                        nodeNumbers=[nodes[k][j], nodes[k][j + 1]],
                        length=le,
                        massPerLength=float(chain.m[k]),
                        bendingStiffness=float(chain.EI[k]),
                        bendingDamping=float(chain.bending_damping[k]),
                        axialStiffness=EA,
                    )
                )
                for j in range(E)
            ]
        )
    return nodes, elems


#: A torsional spring-damper: stiffness (N m/rad), damping (N m s/rad), offset (rad), its user
#: law (springTorqueUserFunction) or 0
Spring = tuple[float, float, float, Any]


def _hinge_springs(
    scene: Scene, hooks: tuple[list[Exception], dict[int, list[bool]]]
) -> list[list[Spring]]:
    """Per hinge, its torsional spring-dampers in build order: its spring (kappa, nu, rest
    angle), its stops (one-sided laws, ``stop_law``), its compliant latch's two stops (zero
    until engaged, ``engaged_law``), its torque items (``torque_law``). ``hooks`` = (the list
    a torque law's exceptions go to, hinge -> its compliant latch's switch). O(n + items)."""
    errors, switches = hooks
    chain = scene.chain
    springs: list[list[Spring]] = [
        [(float(chain.kappa[k]), float(chain.nu[k]), float(chain.rest_angle[k]), 0)]
        for k in range(chain.n)
    ]
    for stop in scene.stops:
        springs[stop.hinge].append((stop.stiffness, stop.damping, stop.angle, stop_law(stop.side)))
    for latch in scene.compliant_latches:
        switch = switches[latch.hinge]
        springs[latch.hinge] += [
            (st.stiffness, st.damping, st.angle, engaged_law(stop_law(st.side), switch))
            for st in latch.engaged_stops()
        ]
    for item in scene.torques:
        springs[item.hinge].append((0.0, 0.0, 0.0, torque_law(item, errors)))
    return springs


def _add_hinges(
    mbs: Any,
    scene: Scene,
    E: int,
    root_body: int,
    mesh: tuple[list[list[int]], list[list[int]]],
    springs: list[list[Spring]],
) -> dict[int, int]:
    """Hinge k's joint, spring-dampers (``springs[k]``, ``_hinge_springs``) and latch joint;
    returns hinge -> latch joint. ``mesh`` = (the rods' beam nodes, their elements). Hinge 0
    joins ``root_body`` (the ground, or a free base's body at its hinge offset, the angle
    measured from the body frame; a free or prescribed base) to rod 1: a torque item's moment
    M acts on rod k+1's root, -M on rod k's tip (hinge 0: on the ground or the body). A held
    latch's joint is active from the start."""
    it = _items()
    nodes, elems = mesh
    chain = scene.chain
    ini = scene.initial.resolve(chain.n)
    tangent_left = ini["phi"] + ini["alpha"]
    tangent_right = ini["phi"] + ini["beta"]
    latch_of = {latch.hinge: latch for latch in scene.latches}
    latch_joints: dict[int, int] = {}
    for k in range(chain.n):
        if k == 0 and scene.base.moving:
            offset = [*scene.base.hinge_offset, 0.0]
            pos0 = mbs.AddMarker(it.MarkerBodyPosition(bodyNumber=root_body, localPosition=offset))
            rot0 = mbs.AddMarker(it.MarkerBodyRigid(bodyNumber=root_body, localPosition=offset))
            angle0 = tangent_left[0] - scene.base.initial_attitude()
        elif k == 0:
            pos0 = mbs.AddMarker(it.MarkerBodyPosition(bodyNumber=root_body))
            rot0 = mbs.AddMarker(it.MarkerBodyRigid(bodyNumber=root_body))
            angle0 = tangent_left[0]
        else:
            pos0 = mbs.AddMarker(it.MarkerNodePosition(nodeNumber=nodes[k - 1][-1]))
            rot0 = mbs.AddMarker(
                it.MarkerBodyRigid(
                    bodyNumber=elems[k - 1][-1], localPosition=[chain.l[k - 1] / E, 0, 0]
                )
            )
            angle0 = tangent_left[k] - tangent_right[k - 1]
        pos1 = mbs.AddMarker(it.MarkerNodePosition(nodeNumber=nodes[k][0]))
        mbs.AddObject(it.ObjectJointRevolute2D(markerNumbers=[pos0, pos1]))
        rot1 = mbs.AddMarker(it.MarkerBodyRigid(bodyNumber=elems[k][0], localPosition=[0, 0, 0]))
        _add_springs(mbs, (rot0, rot1), angle0, springs[k])
        if k in latch_of:
            latch = latch_of[k]
            latch_joints[k] = _add_latch_joint(mbs, (rot0, rot1), float(latch.angle), latch.held)
    return latch_joints


def _add_springs(
    mbs: Any,
    markers: tuple[int, int],
    angle0: float,
    springs: list[Spring],
) -> None:
    """Torsional spring-dampers (stiffness N m/rad, damping N m s/rad, offset rad, user law
    or 0) between the two rotation markers, each with its revolution counter from angle0
    (rad); one without stiffness, damping and law is left out."""
    it = _items()
    for stiffness, damping, offset, law in springs:
        if stiffness == 0 and damping == 0 and not law:
            continue
        turns = mbs.AddNode(
            it.NodeGenericData(numberOfDataCoordinates=1, initialCoordinates=[revolutions(angle0)])
        )
        mbs.AddObject(
            it.ObjectConnectorTorsionalSpringDamper(
                markerNumbers=list(markers),
                nodeNumber=turns,
                stiffness=stiffness,
                damping=damping,
                offset=offset,
                springTorqueUserFunction=law,
            )
        )


def _add_latch_joint(mbs: Any, markers: tuple[int, int], angle: float, held: bool = False) -> int:
    """The rotation lock of a latch at ``angle`` (rad), inactive until its event (active from
    the start if ``held``): joint frame 1 = marker 1 turned back by the latch angle, so the
    locked relative rotation is D_k = angle (locally unique)."""
    c, sn = math.cos(-angle), math.sin(-angle)
    joint: int = mbs.AddObject(
        _items().ObjectJointGeneric(
            markerNumbers=list(markers),
            constrainedAxes=[0, 0, 0, 0, 0, 1],
            rotationMarker1=[[c, -sn, 0.0], [sn, c, 0.0], [0.0, 0.0, 1.0]],
            activeConnector=bool(held),
        )
    )
    return joint


#: Sensors per recorded node (coordinates, velocities, accelerations) and the doubles each
#: stores at every step: the time and the node's coordinates (4 for a cable node, 3 for a
#: moving base's body node).
SENSORS_PER_NODE = 3
CABLE_NODE_COORDINATES = 4
BODY_NODE_COORDINATES = 3


def sensor_nodes(scene: Scene, E: int) -> set[tuple[int, int]]:
    """The beam nodes (rod, local node), 0-based, whose states the scene's outputs need (a
    free base's body node is recorded besides them)."""
    n = scene.n
    wanted: set[tuple[int, int]] = set()
    # every output is observed from the rods' end nodes at least (``exudyn_observe``)
    wanted |= {(k, 0) for k in range(n)} | {(k, E) for k in range(n)}
    audit = momentum_point(scene) is not None  # the momentum audit needs every node
    if scene.wants("energy", "angular_momentum", "momentum") or scene.latches or audit:
        wanted |= {(k, j) for k in range(n) for j in range(E + 1)}
    return wanted


def recorded_doubles(scene: Scene, E: int) -> int:
    """Doubles the sensors of a run of ``scene`` (E elements per rod) store at every step."""
    beam = len(sensor_nodes(scene, E)) * (1 + CABLE_NODE_COORDINATES)
    body = (1 + BODY_NODE_COORDINATES) if scene.base.moving else 0
    return SENSORS_PER_NODE * (beam + body)


def _add_sensors(
    mbs: Any, scene: Scene, E: int, nodes: list[list[int]], body_node: int | None = None
) -> dict[tuple[int, int], tuple[int, ...]]:
    """Sensors (coordinates, velocities, accelerations, stored internally) on the beam nodes
    the outputs need (``sensor_nodes``), (rod, node) -> three sensor numbers, and on a moving
    base's body node (``BODY`` -> its three: hinge 0 is measured from it)."""
    import exudyn as exu

    node_of = {key: nodes[key[0]][key[1]] for key in sensor_nodes(scene, E)}
    if body_node is not None:
        node_of[BODY] = body_node
    ovt = exu.OutputVariableType
    return {
        key: tuple(
            mbs.AddSensor(
                _items().SensorNode(
                    nodeNumber=node_of[key],
                    storeInternal=True,
                    writeToFile=False,
                    outputVariableType=v,
                )
            )
            for v in (ovt.CoordinatesTotal, ovt.Coordinates_t, ovt.Coordinates_tt)
        )
        for key in sorted(node_of)
    }


def read_records(built: BuiltSystem) -> tuple[Array, Nodes, bool]:
    """A run's records from the sensors of ``built``: the recorded times (s); per (rod, local
    node) (and ``BODY``) the arrays q, v, a (nt, 4) up to the first non-finite record; whether
    a non-finite record was cut off."""
    mbs = built.mbs
    data = {
        key: tuple(mbs.GetSensorStoredData(s) for s in ids)
        for key, ids in built.node_sensors.items()
    }
    first = next(iter(data.values()))[0]
    if first.ndim != 2 or first.shape[0] == 0:
        return np.empty(0), {}, False
    t = first[:, 0]
    # keep one record per time (the solver may write the last step twice)
    keep = np.concatenate([np.diff(t) > 0, [True]])
    finite = np.ones(keep.sum(), bool)
    out: dict[tuple[int, int], tuple[Array, ...]] = {}
    for key, arrs in data.items():
        q, v, a = (arr[keep, 1:] for arr in arrs)
        finite &= np.isfinite(q).all(1) & np.isfinite(v).all(1) & np.isfinite(a).all(1)
        out[key] = (q, v, a)
    bad = np.flatnonzero(~finite)
    end = bad[0] if bad.size else finite.size
    t = t[keep][:end]
    return t, {key: tuple(x[:end] for x in arrs) for key, arrs in out.items()}, bool(bad.size)
