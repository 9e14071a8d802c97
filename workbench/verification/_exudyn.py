"""A workbench mechanism rebuilt in exudyn (Gerstmayr 2023), an independent multibody engine.

Exudyn formulates the mechanism its own way: planar rigid bodies in absolute coordinates
(x, y, phi of each centroid), ideal revolute and prismatic joints as algebraic constraints, the
cranks driven by rheonomic coordinate constraints whose Lagrange multipliers are the driving
torques, and the clearance joints as its C++ journal-in-hole contact
(``ObjectContactSphereSphere`` with ``isHollowSphere1``: a sphere in a hollow sphere, which in the
plane z = 0 is the journal in the bearing). It integrates the index-3 DAE with the implicit
generalised-alpha method at a fixed step. Nothing of the workbench's reduced formulation (closed-
form kinematics, Jacobians, reduced mass matrix, compiled right-hand side) is used, except the
*initial* placement and velocities of the bodies, which exudyn then holds to its own constraints.

Contact law. Exudyn's Hunt-Crossley model (``impactModel = 1``) is
``F = K delta^n (1 + 3 (1 - e) / 2 * delta_dot / delta_dot_minus)``; with ``e = (1 + c_e^2) / 2``
its damping equals Lankarani-Nikravesh's ``3 (1 - c_e^2) / 4`` (Lankarani & Nikravesh 1990), so
both sides integrate the same force law. ``minimumImpactVelocity`` is the workbench's
``impact_velocity_floor``.

Friction. Exudyn's contact friction is a Coulomb law regularised linearly below
``frictionProportionalZone`` (m/s); the workbench's modified Coulomb law (Ambrosio 2002) has no
friction below v0 and a linear ramp up to v1. With ``friction = "coulomb"`` the comparison sets the
regularisation zone to v1: the two laws agree outside (0, v1) only, which matters in stick-slip
but hardly at impacts. LuGre has no exudyn counterpart and is refused.

Each model describes itself as a :class:`Mechanism` (bodies with their initial placement,
joints, drives, clearance joints, the slider); :func:`run_exudyn` builds and runs any of them.
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from workbench.models import get_model
from workbench.models._clearance import stiffness as joint_stiffness
from workbench.scene import Scene

Point = tuple[float, float]


@dataclass
class Body:
    """A planar rigid body: mass (kg), centroidal inertia (kg m2), initial centroid placement
    (x, y, phi) (m, m, rad) and its rates (m s-1, m s-1, rad s-1)."""

    name: str
    mass: float
    inertia: float
    placement: tuple[float, float, float]
    rates: tuple[float, float, float]


@dataclass
class Mechanism:
    """A mechanism as exudyn sees it. Bodies are indices into ``bodies``; None is the ground.

    ``revolutes``: ideal pins (body0, body1, point); ``clearances``: joint name -> (bearing
    body, journal body, point, clearance m), ideal pins when the scene has no clearance there;
    ``drives``: (body, angular rate rad s-1) per driven crank, in the order of the ``crank``
    coordinate; ``slider``: the body on the guide (the x axis of its initial placement) and the
    map x_body -> slider position (m).
    """

    bodies: list[Body]
    revolutes: list[tuple[int | None, int, Point]]
    clearances: dict[str, tuple[int, int, Point, float]]
    drives: list[tuple[int, float]]
    slider: int
    slider_position: Callable[[np.ndarray], np.ndarray]
    slider_sign: float
    cranks: list[str] = field(default_factory=lambda: ["1"])


def _import_exudyn():
    try:
        import exudyn
        import exudyn.itemInterface as items
    except ImportError as err:  # pragma: no cover - depends on the environment
        raise ImportError(
            "workbench.verify needs exudyn: install the extra with "
            "`pip install -e '.[verify]'` (exudyn 1.13.6 on PyPI)"
        ) from err
    return exudyn, items


def _rotate(phi: float, x: float, y: float) -> tuple[float, float]:
    c, s = math.cos(phi), math.sin(phi)
    return c * x - s * y, s * x + c * y


def ninebar_mechanism(scene: Scene) -> Mechanism:
    """The nine-bar mechanism at t = 0 (placement from the workbench's position analysis)."""
    from workbench.models.ninebar._dynamics import N_GEO
    from workbench.models.ninebar._geometry import BODY_NAMES
    from workbench.models.ninebar._kinematics import (
        CRANK1,
        CRANK4,
        G_L5,
        G_O6X,
        G_O6Y,
        G_S0,
        LINK2,
        LINK3,
        LINK8,
        N_POINTS,
        PANEL7,
        PT_A,
        PT_B,
        PT_C,
        PT_D,
        PT_E,
        PT_P,
        ROCKER6,
        SLIDER9,
        jacobian,
        positions,
    )

    params = scene.resolved_parameters
    model = get_model("ninebar")
    geo = model.problem(params, scene.effects, {}, ("torque",)).p[:N_GEO]
    omega = params["omega"]
    q = np.array([params["theta10"], params["theta40"], 0.0, 0.0, 0.0, 0.0])
    qd = np.array([-omega, omega, 0.0, 0.0, 0.0, 0.0])
    pos = np.empty((8, 3))
    pts = np.empty((N_POINTS, 2))
    J = np.empty((8, 3, 6))
    Jp = np.empty((N_POINTS, 2, 6))
    if positions(q, geo, pos, pts) or jacobian(q, geo, J, Jp):
        raise ValueError("the nine-bar mechanism does not assemble at its initial angles")
    vel = J @ qd
    bodies = [
        Body(
            name,
            params[f"mass_{name}"],
            params.get(f"inertia_{name}", 0.0) or 1e-6,  # the slider's rotation is locked
            tuple(pos[b]),
            tuple(vel[b]),
        )
        for b, name in enumerate(BODY_NAMES)
    ]
    A, B, P, C, D, E = (tuple(pts[i]) for i in (PT_A, PT_B, PT_P, PT_C, PT_D, PT_E))
    o6 = (float(geo[G_O6X]), float(geo[G_O6Y]))
    clearances = model.clearances(params)
    s0 = float(geo[G_S0])
    return Mechanism(
        bodies=bodies,
        revolutes=[
            (None, CRANK1, (0.0, 0.0)),
            (None, CRANK4, (float(geo[G_L5]), 0.0)),
            (LINK2, LINK3, P),
            (LINK2, PANEL7, P),
            (None, ROCKER6, o6),
            (ROCKER6, PANEL7, C),
            (PANEL7, LINK8, D),
            (LINK8, SLIDER9, E),
        ],
        clearances={
            "A": (CRANK1, LINK2, A, clearances["A"]),
            "B": (CRANK4, LINK3, B, clearances["B"]),
        },
        drives=[(CRANK1, -omega), (CRANK4, omega)],
        slider=SLIDER9,
        slider_position=lambda x: s0 - (x - o6[0]),  # S9 = S0 - (x_E - x_O6)
        slider_sign=-1.0,
        cranks=["1", "4"],
    )


def slider_crank_mechanism(scene: Scene) -> Mechanism:
    """The slider-crank at t = 0: crank at theta10, rod on the +x branch, journal centred."""
    params = scene.resolved_parameters
    l1, l2 = params["crank_length"], params["rod_length"]
    lc1, lc2 = params["crank_centroid"], params["rod_centroid"]
    th1, w1 = params["theta10"], params["omega"]
    c1, s1 = math.cos(th1), math.sin(th1)
    s2 = -l1 * s1 / l2
    c2 = math.sqrt(1.0 - s2 * s2)
    w2 = -l1 * c1 * w1 / (l2 * c2)
    a = (l1 * c1, l1 * s1)
    va = (-l1 * s1 * w1, l1 * c1 * w1)
    b = (a[0] + l2 * c2, 0.0)
    vb = va[0] - l2 * s2 * w2
    bodies = [
        Body("crank", params["mass_crank"], params["inertia_crank"], (lc1 * c1, lc1 * s1, th1),
             (-lc1 * s1 * w1, lc1 * c1 * w1, w1)),
        Body("rod", params["mass_rod"], params["inertia_rod"],
             (a[0] + lc2 * c2, a[1] + lc2 * s2, math.atan2(s2, c2)),
             (va[0] - lc2 * s2 * w2, va[1] + lc2 * c2 * w2, w2)),
        Body("slider", params["mass_slider"], 1e-6, (b[0], 0.0, 0.0), (vb, 0.0, 0.0)),
    ]  # fmt: skip
    return Mechanism(
        bodies=bodies,
        revolutes=[(None, 0, (0.0, 0.0)), (0, 1, a)],
        clearances={"B": (2, 1, b, params["clearance"])},
        drives=[(0, w1)],
        slider=2,
        slider_position=lambda x: x,
        slider_sign=1.0,
    )


MECHANISMS: dict[str, Callable[[Scene], Mechanism]] = {
    "ninebar": ninebar_mechanism,
    "slider_crank": slider_crank_mechanism,
}


def check_scene(scene: Scene) -> None:
    """Raise ValueError unless exudyn can rebuild this scene (model and friction law)."""
    if scene.model not in MECHANISMS:
        raise ValueError(
            f"exudyn verification knows the models {sorted(MECHANISMS)}; got {scene.model!r}"
        )
    if scene.effects["friction"] == "lugre":
        raise ValueError(
            "effects.friction = 'lugre' has no counterpart in exudyn's contact; verify a scene "
            "with friction 'none' or 'coulomb'"
        )


def run_exudyn(
    scene: Scene,
    *,
    t_end: float,
    step: float,
    record_dt: float,
    spectral_radius: float = 0.6,
    newton: dict | None = None,
) -> xr.Dataset:
    """Simulate a scene of a mechanism model in exudyn from t = 0 to ``t_end``.

    Parameters
    ----------
    scene : Scene
        A scene of a model in :data:`MECHANISMS` (``ninebar``, ``slider_crank``): its
        parameters, clearance joints, gravity and friction ("none" or "coulomb") are rebuilt in
        exudyn; the run and record tables are not used.
    t_end : float
        End time, s.
    step : float
        Fixed time step of the generalised-alpha integrator, s.
    record_dt : float
        Output interval, s (a whole multiple of ``step``).
    spectral_radius : float
        Numerical damping of generalised-alpha (1 = none, unstable for these index-3 systems;
        smaller values damp the start-up transient of the multipliers faster).
    newton : dict, optional
        Overrides of exudyn's ``timeIntegration.newton`` settings.

    Returns
    -------
    xarray.Dataset
        Dim ``time`` (s) and, as the workbench names them, ``torque`` (N m, dims time, crank),
        ``slider_position``, ``slider_velocity``, ``slider_acceleration``, and with clearances
        ``clearance_x``, ``clearance_y`` (m), ``contact_force``, ``friction_force`` (N) (dims
        time, joint). Attributes: ``engine``, ``step``, ``wall_time``, ``drive_angle_error``.

    Raises
    ------
    ValueError
        For a model without a :class:`Mechanism` description or with LuGre friction.
    RuntimeError
        Where exudyn's Newton iteration fails at this step.
    """
    check_scene(scene)
    friction = scene.effects["friction"]
    exu, it = _import_exudyn()
    params = scene.resolved_parameters
    mech = MECHANISMS[scene.model](scene)
    joints = tuple(scene.effects["clearance"])

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(it.ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
    g = params["gravity"] if scene.effects["gravity"] else 0.0
    gvec = [g * math.cos(params["gravity_angle"]), g * math.sin(params["gravity_angle"]), 0.0]

    nodes, bodies = [], []
    for body in mech.bodies:
        n = mbs.AddNode(
            it.NodeRigidBody2D(
                referenceCoordinates=list(body.placement), initialVelocities=list(body.rates)
            )
        )
        nodes.append(n)
        bodies.append(
            mbs.AddObject(it.ObjectRigidBody2D(mass=body.mass, inertia=body.inertia, nodeNumber=n))
        )
        if g:
            mass_marker = mbs.AddMarker(it.MarkerBodyMass(bodyNumber=bodies[-1]))
            mbs.AddLoad(it.LoadMassProportional(markerNumber=mass_marker, loadVector=gvec))

    def local(b: int, point: Point) -> list[float]:
        x, y, phi = mech.bodies[b].placement
        lx, ly = _rotate(-phi, point[0] - x, point[1] - y)
        return [lx, ly, 0.0]

    def marker(b: int | None, point: Point, rigid: bool = False) -> int:
        cls = it.MarkerBodyRigid if rigid else it.MarkerBodyPosition
        if b is None:
            return mbs.AddMarker(cls(bodyNumber=ground, localPosition=[point[0], point[1], 0.0]))
        return mbs.AddMarker(cls(bodyNumber=bodies[b], localPosition=local(b, point)))

    def revolute(b0: int | None, b1: int, point: Point) -> None:
        mbs.AddObject(
            it.ObjectJointRevolute2D(markerNumbers=[marker(b0, point), marker(b1, point)])
        )

    for b0, b1, point in mech.revolutes:
        revolute(b0, b1, point)
    slider_point = mech.bodies[mech.slider].placement[:2]
    mbs.AddObject(
        it.ObjectJointPrismatic2D(
            markerNumbers=[
                marker(None, slider_point, rigid=True),
                marker(mech.slider, slider_point, rigid=True),
            ],
            axisMarker0=[1.0, 0.0, 0.0],
            normalMarker1=[0.0, 1.0, 0.0],
            constrainRotation=True,
        )
    )

    # clearance joints: journal in the bearing; ideal pins where the scene has no clearance
    contacts = {}
    for j, (bearing, journal, point, c) in mech.clearances.items():
        if j not in joints:
            revolute(bearing, journal, point)
            continue
        r1 = params["bearing_radius"]
        data = mbs.AddNode(
            it.NodeGenericData(numberOfDataCoordinates=4, initialCoordinates=[0.0] * 4)
        )
        rigid = friction == "coulomb"
        m_journal = marker(journal, point, rigid)
        m_bearing = marker(bearing, point, rigid)
        contacts[j] = (
            mbs.AddObject(
                it.ObjectContactSphereSphere(
                    markerNumbers=[m_journal, m_bearing],
                    nodeNumber=data,
                    spheresRadii=[r1 - c, r1],
                    isHollowSphere1=True,
                    contactStiffness=joint_stiffness(params, c),
                    contactStiffnessExponent=params["contact_exponent"],
                    restitutionCoefficient=(1.0 + params["restitution"] ** 2) / 2.0,
                    impactModel=1,
                    minimumImpactVelocity=params["impact_velocity_floor"],
                    dynamicFriction=params["friction_coefficient"] if rigid else 0.0,
                    frictionProportionalZone=params["coulomb_v1"],
                )
            ),
            journal,
            bearing,
            local(journal, point),
            local(bearing, point),
        )

    # the drives: crank angles imposed by rheonomic coordinate constraints
    ground_node = mbs.AddNode(it.NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    m_ground = mbs.AddMarker(it.MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0))
    drives = []
    for b, rate in mech.drives:
        m_angle = mbs.AddMarker(it.MarkerNodeCoordinate(nodeNumber=nodes[b], coordinate=2))

        def offset(mbs_, t, item, l_offset, rate=rate):
            return rate * t

        drives.append(
            mbs.AddObject(
                it.ObjectConnectorCoordinate(
                    markerNumbers=[m_ground, m_angle], offsetUserFunction=offset
                )
            )
        )

    # sensors, recorded every record_dt
    out = exu.OutputVariableType
    sensors: dict[str, Any] = {
        "drive": [
            mbs.AddSensor(
                it.SensorObject(objectNumber=d, outputVariableType=out.Force, storeInternal=True)
            )
            for d in drives
        ],
        "angle": [
            mbs.AddSensor(
                it.SensorNode(
                    nodeNumber=nodes[b], outputVariableType=out.Coordinates, storeInternal=True
                )
            )
            for b, _ in mech.drives
        ],
        "slider_x": mbs.AddSensor(
            it.SensorNode(
                nodeNumber=nodes[mech.slider], outputVariableType=out.Position, storeInternal=True
            )
        ),
        "slider_v": mbs.AddSensor(
            it.SensorNode(
                nodeNumber=nodes[mech.slider], outputVariableType=out.Velocity, storeInternal=True
            )
        ),
        "slider_a": mbs.AddSensor(
            it.SensorNode(
                nodeNumber=nodes[mech.slider],
                outputVariableType=out.Acceleration,
                storeInternal=True,
            )
        ),
    }
    for j, (obj, journal, bearing, lj, lb) in contacts.items():
        sensors[f"force_{j}"] = mbs.AddSensor(
            it.SensorObject(objectNumber=obj, outputVariableType=out.Force, storeInternal=True)
        )
        sensors[f"journal_{j}"] = mbs.AddSensor(
            it.SensorBody(
                bodyNumber=bodies[journal],
                localPosition=lj,
                outputVariableType=out.Position,
                storeInternal=True,
            )
        )
        sensors[f"bearing_{j}"] = mbs.AddSensor(
            it.SensorBody(
                bodyNumber=bodies[bearing],
                localPosition=lb,
                outputVariableType=out.Position,
                storeInternal=True,
            )
        )
    mbs.Assemble()

    settings = exu.SimulationSettings()
    n_steps = int(round(t_end / step))
    settings.timeIntegration.numberOfSteps = n_steps
    settings.timeIntegration.endTime = n_steps * step
    settings.timeIntegration.verboseMode = 0
    settings.timeIntegration.generalizedAlpha.spectralRadius = spectral_radius
    # exudyn would otherwise abort at the first impact asking for a smaller step
    settings.timeIntegration.discontinuous.useRecommendedStepSize = False
    settings.timeIntegration.newton.useModifiedNewton = False
    # a truly fixed step: exudyn would otherwise cut the step where Newton struggles, which
    # moves its records off the comparison grid and mixes steps in a step-refinement study
    settings.timeIntegration.adaptiveStep = False
    # Newton: exudyn's default relative tolerance 1e-8 stalls in some friction contacts at
    # 25 iterations; 1e-6 converges in a few and moves the peak forces by < 1e-6 (relative)
    settings.timeIntegration.newton.relativeTolerance = 1e-6
    settings.timeIntegration.newton.maxIterations = 50
    for key, value in (newton or {}).items():
        setattr(settings.timeIntegration.newton, key, value)
    settings.solutionSettings.sensorsWritePeriod = record_dt
    settings.solutionSettings.writeSolutionToFile = False
    settings.displayComputationTime = False
    settings.displayStatistics = False
    start = _time.perf_counter()
    try:
        exu.SolveDynamic(mbs, settings)
    except exu.SolverError as err:
        raise RuntimeError(
            f"exudyn's generalised-alpha did not converge at the fixed step {step!r} s ({err}); "
            "use a smaller step"
        ) from err
    wall = _time.perf_counter() - start

    # exudyn writes a record when its time passes a multiple of the write period; keep the
    # records that fall on the grid k * record_dt (to round-off) and put them exactly there
    t_raw = mbs.GetSensorStoredData(sensors["drive"][0])[:, 0]
    k = np.round(t_raw / record_dt)
    keep = np.flatnonzero(np.abs(t_raw - k * record_dt) < 1e-3 * step)
    keep = keep[np.unique(k[keep], return_index=True)[1]]
    if keep.size != int(k[keep][-1]) + 1:
        raise RuntimeError(
            f"exudyn's records miss some of the times k * {record_dt!r} s; record_dt must be a "
            f"whole multiple of the step {step!r} s"
        )
    t = k[keep] * record_dt

    def data(key):
        """A sensor's records on the grid."""
        return mbs.GetSensorStoredData(key)[keep]

    rates = [rate for _, rate in mech.drives]
    # the drive multiplier acts on the crank's angle coordinate; the torque the motor applies
    # to the crank (counter-clockwise positive) is its negative (the workbench's torques, which
    # pass their energy-balance tests, agree with it record by record)
    torque = np.stack([-data(s)[:, 1] for s in sensors["drive"]], axis=1)
    angle_error = max(
        float(np.max(np.abs(data(s)[:, 3] - r * t)))
        for s, r in zip(sensors["angle"], rates, strict=True)
    )
    x_e = data(sensors["slider_x"])[:, 1]
    variables: dict[str, Any] = {
        "torque": (("time", "crank"), torque, {"units": "N m", "long_name": "driving torque"}),
        "slider_position": (
            ("time",),
            mech.slider_position(x_e),
            {"units": "m", "long_name": "slider position"},
        ),
        "slider_velocity": (
            ("time",),
            mech.slider_sign * data(sensors["slider_v"])[:, 1],
            {"units": "m s-1", "long_name": "slider velocity"},
        ),
        "slider_acceleration": (
            ("time",),
            mech.slider_sign * data(sensors["slider_a"])[:, 1],
            {"units": "m s-2", "long_name": "slider acceleration"},
        ),
    }
    coords: dict[str, Any] = {
        "time": ("time", t, {"units": "s", "long_name": "time"}),
        "crank": ("crank", mech.cranks, {"units": "1", "long_name": "driven crank"}),
    }
    if contacts:
        cx, cy, fn, ft = [], [], [], []
        for j in contacts:
            rel = data(sensors[f"journal_{j}"])[:, 1:3] - data(sensors[f"bearing_{j}"])[:, 1:3]
            e = np.hypot(rel[:, 0], rel[:, 1])
            n = rel / np.where(e > 0, e, 1.0)[:, None]
            f = data(sensors[f"force_{j}"])[:, 1:3]  # force on the journal's sphere (marker 0)
            cx.append(rel[:, 0])
            cy.append(rel[:, 1])
            fn.append(np.abs(f[:, 0] * n[:, 0] + f[:, 1] * n[:, 1]))
            ft.append(-f[:, 0] * n[:, 1] + f[:, 1] * n[:, 0])
        jd = ("time", "joint")
        coords["joint"] = ("joint", list(contacts), {"units": "1", "long_name": "clearance joint"})
        variables.update(
            clearance_x=(jd, np.stack(cx, 1), {"units": "m", "long_name": "clearance vector x"}),
            clearance_y=(jd, np.stack(cy, 1), {"units": "m", "long_name": "clearance vector y"}),
            contact_force=(
                jd,
                np.stack(fn, 1),
                {"units": "N", "long_name": "normal contact force"},
            ),
            friction_force=(
                jd,
                np.stack(ft, 1),
                {"units": "N", "long_name": "tangential contact force"},
            ),
        )
    return xr.Dataset(
        variables,
        coords=coords,
        attrs={
            "engine": f"exudyn {exu.__version__}",
            "integrator": "generalised-alpha (index 3), fixed step",
            "step": step,
            "spectral_radius": spectral_radius,
            "wall_time": wall,
            "drive_angle_error": angle_error,
        },
    )
