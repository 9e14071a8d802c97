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
but hardly at impacts. LuGre has no exudyn counterpart and is refused, as is the workbench's
Hunt-Crossley law (``effects.contact``), whose damping constant exudyn's contact does not have.

Each model is described as a :class:`~workbench.verification._mechanisms.Mechanism` (bodies with
their initial placement, pins, prismatic guides, drives, clearance joints with their own
parameters, the recorded slider if any), the built-ins by hand and a declared mechanism from its
declaration; :func:`run_exudyn`
builds any of them in exudyn, runs it and returns its records under the workbench's names,
units and long names (from the model's declarations).
"""

from __future__ import annotations

import math
import time as _time
from typing import Any

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench.models import get_model
from workbench.run import TIME_ATTRS
from workbench.scene import Scene
from workbench.verification._mechanisms import (
    Mechanism,
    Point,
    Prismatic,
    build_mechanism,
    check_scene,
)

__all__ = ["run_exudyn"]


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


class _Build:
    """One mechanism assembled in an exudyn system: bodies, joints, contacts, drives, sensors."""

    def __init__(self, exu, it, mech: Mechanism, params: dict, gravity: float) -> None:
        self.exu, self.it, self.mech, self.params = exu, it, mech, params
        self.container = exu.SystemContainer()
        self.mbs = self.container.AddSystem()
        self.ground = self.mbs.AddObject(it.ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
        self.nodes: list[int] = []
        self.bodies: list[int] = []
        self.contacts: dict[str, tuple] = {}
        self.drives: list[int] = []
        angle = params["gravity_angle"]
        gvec = [gravity * math.cos(angle), gravity * math.sin(angle), 0.0]
        for body in mech.bodies:
            n = self.mbs.AddNode(
                it.NodeRigidBody2D(
                    referenceCoordinates=list(body.placement), initialVelocities=list(body.rates)
                )
            )
            self.nodes.append(n)
            self.bodies.append(
                self.mbs.AddObject(
                    it.ObjectRigidBody2D(mass=body.mass, inertia=body.inertia, nodeNumber=n)
                )
            )
            if gravity:
                mass_marker = self.mbs.AddMarker(it.MarkerBodyMass(bodyNumber=self.bodies[-1]))
                self.mbs.AddLoad(it.LoadMassProportional(markerNumber=mass_marker, loadVector=gvec))

    def local(self, b: int, point: Point) -> list[float]:
        """A point (ground frame, at t = 0) in body ``b``'s frame."""
        x, y, phi = self.mech.bodies[b].placement
        lx, ly = _rotate(-phi, point[0] - x, point[1] - y)
        return [lx, ly, 0.0]

    def marker(self, b: int | None, point: Point, rigid: bool = False) -> int:
        cls = self.it.MarkerBodyRigid if rigid else self.it.MarkerBodyPosition
        if b is None:
            return self.mbs.AddMarker(
                cls(bodyNumber=self.ground, localPosition=[point[0], point[1], 0.0])
            )
        return self.mbs.AddMarker(
            cls(bodyNumber=self.bodies[b], localPosition=self.local(b, point))
        )

    def revolute(self, b0: int | None, b1: int, point: Point) -> None:
        markers = [self.marker(b0, point), self.marker(b1, point)]
        self.mbs.AddObject(self.it.ObjectJointRevolute2D(markerNumbers=markers))

    def prismatic(self, joint: Prismatic) -> None:
        """An ideal prismatic joint: body1 slides along body0 (or the ground) on the joint's
        axis and keeps its angle relative to it."""
        b0, b1 = joint.body0, joint.body1
        ux, uy = joint.axis
        norm = math.hypot(ux, uy)
        ux, uy = ux / norm, uy / norm
        phi0 = 0.0 if b0 is None else self.mech.bodies[b0].placement[2]
        phi1 = self.mech.bodies[b1].placement[2]
        axis = _rotate(-phi0, ux, uy)  # in body0's frame
        normal = _rotate(-phi1, -uy, ux)  # in body1's frame
        markers = [self.marker(b0, joint.point, True), self.marker(b1, joint.point, True)]
        self.mbs.AddObject(
            self.it.ObjectJointPrismatic2D(
                markerNumbers=markers,
                axisMarker0=[axis[0], axis[1], 0.0],
                normalMarker1=[normal[0], normal[1], 0.0],
                constrainRotation=True,
            )
        )

    def clearance(self, j: str, coulomb: bool) -> None:
        """Joint ``j`` as a journal in a hollow sphere (Hunt-Crossley = Lankarani-Nikravesh),
        with the joint's own clearance and contact parameters."""
        joint = self.mech.clearances[j]
        data = self.mbs.AddNode(
            self.it.NodeGenericData(numberOfDataCoordinates=4, initialCoordinates=[0.0] * 4)
        )
        markers = [
            self.marker(joint.journal, joint.point, coulomb),
            self.marker(joint.bearing, joint.point, coulomb),
        ]
        obj = self.mbs.AddObject(
            self.it.ObjectContactSphereSphere(
                markerNumbers=markers,
                nodeNumber=data,
                spheresRadii=[joint.bearing_radius - joint.clearance, joint.bearing_radius],
                isHollowSphere1=True,
                contactStiffness=joint.stiffness,
                contactStiffnessExponent=joint.contact_exponent,
                restitutionCoefficient=(1.0 + joint.restitution**2) / 2.0,
                impactModel=1,
                minimumImpactVelocity=joint.impact_velocity_floor,
                dynamicFriction=joint.friction_coefficient if coulomb else 0.0,
                frictionProportionalZone=joint.coulomb_v1,
            )
        )
        self.contacts[j] = obj

    def drive(self, b: int, rate: float, m_ground: int) -> None:
        """Crank ``b``'s angle imposed as rate * t by a rheonomic coordinate constraint."""
        m_angle = self.mbs.AddMarker(
            self.it.MarkerNodeCoordinate(nodeNumber=self.nodes[b], coordinate=2)
        )

        def offset(mbs_, t, item, l_offset, rate=rate):
            return rate * t

        self.drives.append(
            self.mbs.AddObject(
                self.it.ObjectConnectorCoordinate(
                    markerNumbers=[m_ground, m_angle], offsetUserFunction=offset
                )
            )
        )

    def sensor(self, kind: str, number: int, output, **where) -> int:
        """A sensor of an object, node or body, stored in memory at every write period."""
        cls = {
            "object": self.it.SensorObject,
            "node": self.it.SensorNode,
            "body": self.it.SensorBody,
        }
        key = {"object": "objectNumber", "node": "nodeNumber", "body": "bodyNumber"}[kind]
        return self.mbs.AddSensor(
            cls[kind](**{key: number}, outputVariableType=output, storeInternal=True, **where)
        )

    def sensors(self) -> dict[str, Any]:
        """The recorded quantities: drive multipliers and angles, slider motion, contacts (a
        joint's side on the ground is its fixed place, not a sensor)."""
        out = self.exu.OutputVariableType
        found: dict[str, Any] = {
            "drive": [self.sensor("object", d, out.Force) for d in self.drives],
            "angle": [
                self.sensor("node", self.nodes[b], out.Coordinates) for b, _ in self.mech.drives
            ],
        }
        if self.mech.slider is not None:
            node = self.nodes[self.mech.slider.body]
            for key, output in (("x", out.Position), ("v", out.Velocity), ("a", out.Acceleration)):
                found[f"slider_{key}"] = self.sensor("node", node, output)
        for j, obj in self.contacts.items():
            joint = self.mech.clearances[j]
            found[f"force_{j}"] = self.sensor("object", obj, out.Force)
            for side, body in (("journal", joint.journal), ("bearing", joint.bearing)):
                found[f"{side}_{j}"] = (
                    joint.point
                    if body is None
                    else self.sensor(
                        "body",
                        self.bodies[body],
                        out.Position,
                        localPosition=self.local(body, joint.point),
                    )
                )
        return found


def _build(exu, it, scene: Scene) -> tuple[_Build, dict[str, Any]]:
    """The scene's mechanism assembled in exudyn, and its sensors."""
    params = scene.resolved_parameters
    mech = build_mechanism(scene)
    b = _Build(exu, it, mech, params, params["gravity"] if scene.effects["gravity"] else 0.0)
    for b0, b1, point in mech.revolutes:
        b.revolute(b0, b1, point)
    for joint in mech.prismatics:
        b.prismatic(joint)
    # clearance joints: journal in the bearing; ideal pins where the scene has no clearance
    for j, joint in mech.clearances.items():
        if j in scene.effects["clearance"]:
            b.clearance(j, coulomb=scene.effects["friction"] == "coulomb")
        else:
            b.revolute(joint.bearing, joint.journal, joint.point)
    ground_node = b.mbs.AddNode(it.NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    m_ground = b.mbs.AddMarker(it.MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0))
    for body, rate in mech.drives:
        b.drive(body, rate, m_ground)
    sensors = b.sensors()
    b.mbs.Assemble()
    return b, sensors


def _settings(exu, t_end: float, step: float, record_dt: float, spectral_radius: float, newton):
    """Generalised-alpha at a truly fixed step, records every ``record_dt``."""
    settings = exu.SimulationSettings()
    n_steps = int(round(t_end / step))
    ti = settings.timeIntegration
    ti.numberOfSteps = n_steps
    ti.endTime = n_steps * step
    ti.verboseMode = 0
    ti.generalizedAlpha.spectralRadius = spectral_radius
    # exudyn would otherwise abort at the first impact asking for a smaller step
    ti.discontinuous.useRecommendedStepSize = False
    ti.newton.useModifiedNewton = False
    # a truly fixed step: exudyn would otherwise cut the step where Newton struggles, which
    # moves its records off the comparison grid and mixes steps in a step-refinement study
    ti.adaptiveStep = False
    # Newton: exudyn's default relative tolerance 1e-8 stalls in some friction contacts at
    # 25 iterations; 1e-6 converges in a few and moves the peak forces by < 1e-6 (relative)
    ti.newton.relativeTolerance = 1e-6
    ti.newton.maxIterations = 50
    for key, value in (newton or {}).items():
        setattr(ti.newton, key, value)
    settings.solution.sensors.writePeriod = record_dt  # exudyn 1.13 names (pinned)
    settings.solution.file.write = False
    settings.show.computationTime = False
    settings.show.statistics = False
    return settings


def _on_grid(t_raw: np.ndarray, record_dt: float, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Exudyn writes a record when its time passes a multiple of the write period: the indices
    of the records that fall on the grid k * record_dt (to round-off), and their exact times."""
    k = np.round(t_raw / record_dt)
    keep = np.flatnonzero(np.abs(t_raw - k * record_dt) < 1e-3 * step)
    keep = keep[np.unique(k[keep], return_index=True)[1]]
    if keep.size != int(k[keep][-1]) + 1:
        raise RuntimeError(
            f"exudyn's records miss some of the times k * {record_dt!r} s; record_dt must be a "
            f"whole multiple of the step {step!r} s"
        )
    return keep, k[keep] * record_dt


def _series(
    b: _Build, sensors: dict, keep: np.ndarray, t: np.ndarray, joints: tuple[str, ...]
) -> tuple[dict, float]:
    """The records under the workbench's names (arrays; the clearance joints' in the order
    ``joints``, the model's ``joint`` coordinate), and the drives' largest angle error."""
    mech = b.mech

    def data(key):
        return b.mbs.GetSensorStoredData(key)[keep]

    def side(key):
        """A joint's side (m, (n, 2)): its sensor's, or its fixed place on the ground."""
        found = sensors[key]
        return (
            np.broadcast_to(found, (t.size, 2)) if isinstance(found, tuple) else data(found)[:, 1:3]
        )

    # the drive multiplier acts on the crank's angle coordinate; the torque the motor applies
    # to the crank (counter-clockwise positive) is its negative (the workbench's torques, which
    # pass their energy-balance tests, agree with it record by record)
    out = {"torque": np.stack([-data(s)[:, 1] for s in sensors["drive"]], axis=1)}
    if mech.slider is not None:
        guide = mech.slider
        out["slider_position"] = guide.position(data(sensors["slider_x"])[:, 1:3])
        out["slider_velocity"] = guide.along(data(sensors["slider_v"])[:, 1:3])
        out["slider_acceleration"] = guide.along(data(sensors["slider_a"])[:, 1:3])
    angle_error = max(
        float(np.max(np.abs(data(s)[:, 3] - rate * t)))
        for s, (_, rate) in zip(sensors["angle"], mech.drives, strict=True)
    )
    per_joint: dict[str, list] = {k: [] for k in ("clearance_x", "clearance_y")}
    per_joint.update(contact_force=[], friction_force=[])
    for j in joints:
        rel = side(f"journal_{j}") - side(f"bearing_{j}")
        e = np.hypot(rel[:, 0], rel[:, 1])
        n = rel / np.where(e > 0, e, 1.0)[:, None]
        f = data(sensors[f"force_{j}"])[:, 1:3]  # force on the journal's sphere (marker 0)
        per_joint["clearance_x"].append(rel[:, 0])
        per_joint["clearance_y"].append(rel[:, 1])
        per_joint["contact_force"].append(np.abs(f[:, 0] * n[:, 0] + f[:, 1] * n[:, 1]))
        per_joint["friction_force"].append(-f[:, 0] * n[:, 1] + f[:, 1] * n[:, 0])
    if b.contacts:
        out.update({k: np.stack(v, axis=1) for k, v in per_joint.items()})
    return out, angle_error


def _dataset(scene: Scene, b: _Build, t: np.ndarray, series: dict, attrs: dict) -> xr.Dataset:
    """The records with the dims, units and long names the model declares for them."""
    model = get_model(scene.model)
    declared = model.variables(scene.effects)
    used = {d for name in series for d in declared[name].dims}
    coords: dict[str, Any] = {"time": ("time", t, dict(TIME_ATTRS))}
    for dim, (values, dim_attrs) in model.coords(scene.effects).items():
        if dim in used:
            coords[dim] = (dim, list(values), dict(dim_attrs))
    variables = {
        name: (
            ("time",) + declared[name].dims,
            values,
            variable(declared[name].long_name, declared[name].units),
        )
        for name, values in series.items()
    }
    return xr.Dataset(variables, coords=coords, attrs=attrs)


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
        A scene of a model that exudyn rebuilds
        (:func:`workbench.verification.verifiable_models`: ``ninebar``, ``slider_crank``) or
        of a declared mechanism (a ``[mechanism]`` table): its parameters, clearance joints,
        gravity and friction ("none" or "coulomb") are rebuilt in exudyn; the run and record
        tables are not used.
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
        Dim ``time`` (s) and, under the workbench's names with the units and long names its
        model declares, ``torque`` (dims time, crank), where the mechanism has a slider
        ``slider_position``, ``slider_velocity``, ``slider_acceleration``, and with clearances
        ``clearance_x``,
        ``clearance_y``, ``contact_force``, ``friction_force`` (dims time, joint). Attributes:
        ``engine``, ``integrator``, ``step``, ``spectral_radius``, ``wall_time`` (s),
        ``drive_angle_error`` (rad).

    Raises
    ------
    SceneError
        For a model without a :class:`Mechanism` description, LuGre friction, the
        Hunt-Crossley contact law or an initial state (the message names the key).
    RuntimeError
        Where exudyn's Newton iteration fails at this step.
    """
    check_scene(scene)
    exu, it = _import_exudyn()
    b, sensors = _build(exu, it, scene)
    settings = _settings(exu, t_end, step, record_dt, spectral_radius, newton)
    start = _time.perf_counter()
    try:
        exu.SolveDynamic(b.mbs, settings)
    except exu.SolverError as err:
        raise RuntimeError(
            f"exudyn's generalised-alpha did not converge at the fixed step {step!r} s ({err}); "
            "use a smaller step"
        ) from err
    wall = _time.perf_counter() - start
    keep, t = _on_grid(b.mbs.GetSensorStoredData(sensors["drive"][0])[:, 0], record_dt, step)
    series, angle_error = _series(b, sensors, keep, t, tuple(scene.effects["clearance"]))
    attrs = {
        "engine": f"exudyn {exu.__version__}",
        "integrator": "generalised-alpha (index 3), fixed step",
        "step": step,
        "spectral_radius": spectral_radius,
        "wall_time": wall,
        "drive_angle_error": angle_error,
    }
    return _dataset(scene, b, t, series, attrs)
