"""The nine-bar mechanism rebuilt in exudyn (Gerstmayr 2023), an independent multibody engine.

Exudyn formulates the mechanism its own way: eight planar rigid bodies in absolute coordinates
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
friction below v0 and a cubic ramp up to v1. With ``friction = "coulomb"`` the comparison sets the
regularisation zone to v1: the two laws agree outside (0, v1) only, which matters in stick-slip
but hardly at impacts. LuGre has no exudyn counterpart and is refused.
"""

from __future__ import annotations

import math
import time as _time
from typing import Any

import numpy as np
import xarray as xr

from workbench._scene import Scene
from workbench.models.contact import hertz_internal_stiffness
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
from workbench.models.ninebar._model import JOINTS, NineBar


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


def run_ninebar_exudyn(
    scene: Scene,
    *,
    t_end: float,
    step: float,
    record_dt: float,
    spectral_radius: float = 0.6,
    newton: dict | None = None,
) -> xr.Dataset:
    """Simulate a nine-bar scene in exudyn from t = 0 to ``t_end``.

    Parameters
    ----------
    scene : Scene
        A ``ninebar`` scene: its parameters, clearance joints, gravity and friction ("none" or
        "coulomb") are rebuilt in exudyn; the run and record tables are not used.
    t_end : float
        End time, s.
    step : float
        Fixed time step of the generalised-alpha integrator, s.
    record_dt : float
        Output interval, s (a multiple of ``step``).
    spectral_radius : float
        Numerical damping of generalised-alpha (1 = none, unstable for this index-3 system;
        smaller values damp the start-up transient of the multipliers faster).
    newton : dict, optional
        Overrides of exudyn's ``timeIntegration.newton`` settings.

    Returns
    -------
    xarray.Dataset
        Dim ``time`` (s) and, as the workbench names them, ``torque`` (N m, dims time, crank),
        ``slider_position``, ``slider_velocity``, ``slider_acceleration``, and with clearances
        ``clearance_x``, ``clearance_y`` (m), ``contact_force``, ``friction_force`` (N) (dims
        time, joint). Attributes: ``engine``, ``step``, ``wall_time``, ``constraint_residual``.

    Raises
    ------
    ValueError
        For a scene of another model or with LuGre friction.
    """
    if scene.model != "ninebar":
        raise ValueError(f"run_ninebar_exudyn needs a 'ninebar' scene; got {scene.model!r}")
    friction = scene.effects["friction"]
    if friction == "lugre":
        raise ValueError(
            "effects.friction = 'lugre' has no counterpart in exudyn's contact; verify a scene "
            "with friction 'none' or 'coulomb'"
        )
    exu, it = _import_exudyn()
    params = scene.resolved_parameters
    model = NineBar()
    problem = model.problem(params, scene.effects, {}, ("torque",))
    geo = problem.p[:N_GEO]  # the geometry heads the parameter array
    joints = tuple(scene.effects["clearance"])
    omega = params["omega"]
    th10, th40 = params["theta10"], params["theta40"]

    # initial placement and body velocities (journals centred, zero relative velocity)
    q = np.array([th10, th40, 0.0, 0.0, 0.0, 0.0])
    qd = np.array([-omega, omega, 0.0, 0.0, 0.0, 0.0])
    pos = np.empty((8, 3))
    pts = np.empty((N_POINTS, 2))
    J = np.empty((8, 3, 6))
    Jp = np.empty((N_POINTS, 2, 6))
    if positions(q, geo, pos, pts) or jacobian(q, geo, J, Jp):
        raise ValueError("the nine-bar mechanism does not assemble at its initial angles")
    vel = J @ qd

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(it.ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
    g = params["gravity"] if scene.effects["gravity"] else 0.0
    gvec = [g * math.cos(params["gravity_angle"]), g * math.sin(params["gravity_angle"]), 0.0]

    nodes, bodies = [], []
    for b, name in enumerate(BODY_NAMES):
        inertia = params.get(f"inertia_{name}", 0.0) or 1e-6  # the slider's rotation is locked
        n = mbs.AddNode(
            it.NodeRigidBody2D(
                referenceCoordinates=[pos[b, 0], pos[b, 1], pos[b, 2]],
                initialVelocities=[vel[b, 0], vel[b, 1], vel[b, 2]],
            )
        )
        body = mbs.AddObject(
            it.ObjectRigidBody2D(mass=params[f"mass_{name}"], inertia=inertia, nodeNumber=n)
        )
        nodes.append(n)
        bodies.append(body)
        if g:
            mass_marker = mbs.AddMarker(it.MarkerBodyMass(bodyNumber=body))
            mbs.AddLoad(it.LoadMassProportional(markerNumber=mass_marker, loadVector=gvec))

    def local(b: int, point: tuple[float, float]) -> list[float]:
        lx, ly = _rotate(-pos[b, 2], point[0] - pos[b, 0], point[1] - pos[b, 1])
        return [lx, ly, 0.0]

    def marker(b: int | None, point, rigid: bool = False) -> int:
        if b is None:
            return mbs.AddMarker(
                it.MarkerBodyRigid(bodyNumber=ground, localPosition=[point[0], point[1], 0.0])
                if rigid
                else it.MarkerBodyPosition(
                    bodyNumber=ground, localPosition=[point[0], point[1], 0.0]
                )
            )
        cls = it.MarkerBodyRigid if rigid else it.MarkerBodyPosition
        return mbs.AddMarker(cls(bodyNumber=bodies[b], localPosition=local(b, point)))

    def revolute(b0: int | None, b1: int, point) -> None:
        mbs.AddObject(
            it.ObjectJointRevolute2D(markerNumbers=[marker(b0, point), marker(b1, point)])
        )

    O1 = (0.0, 0.0)
    O4 = (float(geo[G_L5]), 0.0)
    O6 = (float(geo[G_O6X]), float(geo[G_O6Y]))
    A, B, P, C, D, E = (tuple(pts[i]) for i in (PT_A, PT_B, PT_P, PT_C, PT_D, PT_E))
    revolute(None, CRANK1, O1)
    revolute(None, CRANK4, O4)
    revolute(LINK2, LINK3, P)
    revolute(LINK2, PANEL7, P)
    revolute(None, ROCKER6, O6)
    revolute(ROCKER6, PANEL7, C)
    revolute(PANEL7, LINK8, D)
    revolute(LINK8, SLIDER9, E)
    mbs.AddObject(
        it.ObjectJointPrismatic2D(
            markerNumbers=[marker(None, E, rigid=True), marker(SLIDER9, E, rigid=True)],
            axisMarker0=[1.0, 0.0, 0.0],
            normalMarker1=[0.0, 1.0, 0.0],
            constrainRotation=True,
        )
    )

    # clearance joints: journal (link 2 / link 3) in the bearing (crank 1 / crank 4)
    contacts = {}
    pairs = {"A": (CRANK1, LINK2, A), "B": (CRANK4, LINK3, B)}
    clearances = model.clearances(params)
    for j in JOINTS:
        bearing, journal, point = pairs[j]
        if j not in joints:
            revolute(bearing, journal, point)
            continue
        c = clearances[j]
        r1 = params["bearing_radius"]
        k = params["contact_stiffness"] or hertz_internal_stiffness(
            r1, c, params["youngs_modulus"], params["poisson_ratio"]
        )
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
                    contactStiffness=k,
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
    for b, rate in ((CRANK1, -omega), (CRANK4, omega)):
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
            for b in (CRANK1, CRANK4)
        ],
        "slider_x": mbs.AddSensor(
            it.SensorNode(
                nodeNumber=nodes[SLIDER9], outputVariableType=out.Position, storeInternal=True
            )
        ),
        "slider_v": mbs.AddSensor(
            it.SensorNode(
                nodeNumber=nodes[SLIDER9], outputVariableType=out.Velocity, storeInternal=True
            )
        ),
        "slider_a": mbs.AddSensor(
            it.SensorNode(
                nodeNumber=nodes[SLIDER9], outputVariableType=out.Acceleration, storeInternal=True
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

    def data(key):
        return mbs.GetSensorStoredData(key)

    # exudyn writes a record when its time passes a multiple of the write period; keep the
    # records that fall on the grid k * record_dt (to round-off) and put them exactly there
    t_raw = data(sensors["drive"][0])[:, 0]
    k = np.round(t_raw / record_dt)
    keep = np.flatnonzero(np.abs(t_raw - k * record_dt) < 1e-3 * step)
    keep = keep[np.unique(k[keep], return_index=True)[1]]
    if keep.size != int(k[keep][-1]) + 1:
        raise RuntimeError(
            f"exudyn's records miss some of the times k * {record_dt!r} s; record_dt must be a "
            f"whole multiple of the step {step!r} s"
        )
    t = k[keep] * record_dt

    def data(key):  # noqa: F811 - the records on the grid
        return mbs.GetSensorStoredData(key)[keep]

    rates = (-omega, omega)
    # the drive multiplier acts on the crank's angle coordinate; the torque the motor applies
    # to the crank (counter-clockwise positive) is its negative (the workbench's torques, which
    # pass the energy balance of tests/test_ninebar*.py, agree with it record by record)
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
            geo[G_S0] - (x_e - O6[0]),
            {"units": "m", "long_name": "slider displacement S9"},
        ),
        "slider_velocity": (
            ("time",),
            -data(sensors["slider_v"])[:, 1],
            {"units": "m s-1", "long_name": "slider velocity"},
        ),
        "slider_acceleration": (
            ("time",),
            -data(sensors["slider_a"])[:, 1],
            {"units": "m s-2", "long_name": "slider acceleration"},
        ),
    }
    coords: dict[str, Any] = {
        "time": ("time", t, {"units": "s", "long_name": "time"}),
        "crank": ("crank", ["1", "4"], {"units": "1", "long_name": "driven crank"}),
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
