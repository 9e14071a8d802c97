"""The mechanisms as an independent multibody engine sees them: bodies with their initial
placement, ideal revolute and prismatic joints, clearance joints with their own contact
parameters, drives and the recorded slider (:class:`Mechanism`), the builders of the built-in
mechanisms and of any declared linkage (each model names its own:
:attr:`workbench.models.Model.verification`), and which scenes can be rebuilt at all.

Only the initial placement and velocities come from the workbench's kinematics; the engine then
holds the bodies to its own constraints. The nine-bar's placement is its public
:func:`workbench.models.ninebar.placement`; a declared linkage's is its ideal-joint kinematics at
t = 0 (its model's ``ideal_motion``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from workbench.models import available_models, get_model, joint_stiffness
from workbench.scene import Scene, SceneError

__all__ = [
    "Body",
    "ClearanceJoint",
    "Guide",
    "Mechanism",
    "Point",
    "Prismatic",
    "build_mechanism",
    "check_scene",
    "declared_mechanism",
    "verifiable_models",
]

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
class Prismatic:
    """An ideal prismatic joint: ``body1`` slides along ``body0`` (None: the ground) on the line
    through ``point`` (m, at t = 0) along ``axis`` (a direction in the ground frame at t = 0),
    and keeps its angle relative to ``body0``."""

    body0: int | None
    body1: int
    point: Point
    axis: Point


@dataclass
class ClearanceJoint:
    """A revolute joint that may have a radial clearance: the bearing's and the journal's bodies
    (None: the ground), the joint's place at t = 0 (m, the journal centred), its clearance (m),
    contact stiffness (N m^-n) and the contact and friction parameters that the engine's contact
    uses, by the built-ins' names (``bearing_radius`` m, ``contact_exponent``, ``restitution``,
    ``impact_velocity_floor`` m s-1, ``friction_coefficient``, ``coulomb_v1`` m s-1)."""

    bearing: int | None
    journal: int | None
    point: Point
    clearance: float
    stiffness: float
    bearing_radius: float
    contact_exponent: float
    restitution: float
    impact_velocity_floor: float
    friction_coefficient: float
    coulomb_v1: float


@dataclass
class Guide:
    """The recorded slider: its body, and its position ``offset + (x - origin) . axis`` (m) from
    its centroid x (m); its velocity and acceleration are the centroid's along ``axis`` (a unit
    vector in the ground frame)."""

    body: int
    origin: Point
    axis: Point
    offset: float

    def position(self, x: np.ndarray) -> np.ndarray:
        """The slider's position (m) from its centroid's positions (arrays (n, 2), m)."""
        return self.offset + self.along(x - np.asarray(self.origin))

    def along(self, v: np.ndarray) -> np.ndarray:
        """The component along the guide of vectors (n, 2)."""
        return v[:, 0] * self.axis[0] + v[:, 1] * self.axis[1]


@dataclass
class Mechanism:
    """A mechanism as exudyn sees it. Bodies are indices into ``bodies``; None is the ground.

    ``revolutes``: ideal pins (body0, body1, point); ``prismatics``: ideal sliding joints;
    ``clearances``: joint name -> :class:`ClearanceJoint`, ideal pins when the scene has no
    clearance there; ``drives``: (body, angular rate rad s-1) per driven crank, in the order of
    the model's ``crank`` coordinate; ``slider``: the slider the model records (None: it records
    none).
    """

    bodies: list[Body]
    revolutes: list[tuple[int | None, int, Point]]
    prismatics: list[Prismatic]
    clearances: dict[str, ClearanceJoint]
    drives: list[tuple[int, float]]
    slider: Guide | None


def clearance_joint(
    bearing: int | None, journal: int | None, point: Point, c: float, params: Mapping[str, float]
) -> ClearanceJoint:
    """A clearance joint with the clearance ``c`` (m) and the contact and friction parameters
    ``params`` (the built-ins' names)."""
    return ClearanceJoint(
        bearing,
        journal,
        point,
        c,
        joint_stiffness(params, c),
        params["bearing_radius"],
        params["contact_exponent"],
        params["restitution"],
        params["impact_velocity_floor"],
        params["friction_coefficient"],
        params["coulomb_v1"],
    )


def ninebar_mechanism(scene: Scene) -> Mechanism:
    """The nine-bar mechanism at t = 0 (placement from the workbench's position analysis)."""
    from workbench.models.ninebar import BODY_INDEX, placement

    params = scene.resolved_parameters
    model = get_model("ninebar")
    at = placement(params)
    omega = params["omega"]
    bodies = [
        Body(
            name,
            params[f"mass_{name}"],
            params.get(f"inertia_{name}", 0.0) or 1e-6,  # the slider's rotation is locked
            tuple(at.position[b]),
            tuple(at.velocity[b]),
        )
        for b, name in enumerate(at.names)
    ]
    A, B, P, C, D, E = (at.points[k] for k in "ABPCDE")
    o6 = at.ground["O6"]
    c = model.clearances(params)
    b = BODY_INDEX
    slider = bodies[b["slider9"]].placement
    return Mechanism(
        bodies=bodies,
        revolutes=[
            (None, b["crank1"], at.ground["O1"]),
            (None, b["crank4"], at.ground["O5"]),
            (b["link2"], b["link3"], P),
            (b["link2"], b["panel7"], P),
            (None, b["rocker6"], o6),
            (b["rocker6"], b["panel7"], C),
            (b["panel7"], b["link8"], D),
            (b["link8"], b["slider9"], E),
        ],
        prismatics=[Prismatic(None, b["slider9"], slider[:2], (1.0, 0.0))],
        clearances={
            "A": clearance_joint(b["crank1"], b["link2"], A, c["A"], params),
            "B": clearance_joint(b["crank4"], b["link3"], B, c["B"], params),
        },
        drives=[(b["crank1"], -omega), (b["crank4"], omega)],
        # S9 = S0 - (x_E - x_O6)
        slider=Guide(b["slider9"], (o6[0], o6[1]), (-1.0, 0.0), at.slider_offset),
    )


def slider_crank_mechanism(scene: Scene) -> Mechanism:
    """The slider-crank at t = 0: crank at theta10, rod on the +x branch, journal centred."""
    params = scene.resolved_parameters
    c = get_model("slider_crank").clearances(params)["B"]
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
        prismatics=[Prismatic(None, 2, b, (1.0, 0.0))],
        clearances={"B": clearance_joint(2, 1, b, c, params)},
        drives=[(0, w1)],
        slider=Guide(2, (0.0, 0.0), (1.0, 0.0), 0.0),
    )


def declared_mechanism(scene: Scene) -> Mechanism:
    """A declared linkage at t = 0 (:mod:`workbench.models._declared_model`): its links and
    sliders placed by its ideal-joint kinematics at the scene's crank speed, a pin wherever two
    bodies (or a body and the ground) carry one point, a clearance joint where the declaration
    has one (the journal's body at the bearing's place, which the other bodies carrying the
    point share), a prismatic joint along each slider's guide and each RPR group's line, a drive
    per crank and the first slider as the recorded one."""
    model = get_model(scene.model)
    params = scene.resolved_parameters
    linkage = model.linkage
    for c in linkage.cranks:
        if c.torque_driven:
            raise SceneError(
                f"{c.key}.drive",
                "got 'torque'; the exudyn model drives its cranks at constant speeds: verify "
                'the linkage with drive = "speed"',
            )
    motion = model.ideal_motion(params, 0.0)
    parts = linkage.bodies()  # links, then sliders, by name
    names = list(parts)
    index: dict[str, int] = {n: i for i, n in enumerate(names)}  # the ground: None
    links = {link.name for link in linkage.links}
    bodies = []
    for n in names:
        centre, angle = motion.centres[n], motion.angles[n]
        bodies.append(
            Body(
                n,
                params[f"mass_{n}"],
                params[f"inertia_{n}"] if n in links else 1e-6,  # a slider does not turn
                (*centre.position[0], angle.position[0]),
                (*centre.velocity[0], angle.velocity[0]),
            )
        )

    def at(point: str) -> Point:
        x, y = motion.points[point].position[0]
        return (float(x), float(y))

    journals = {c.joint: c.journal for c in linkage.clearances}
    revolutes: list[tuple[int | None, int, Point]] = []
    for point in motion.points:
        carriers = [n for n in names if point in parts[n].points]
        pinned = ([None] if point in linkage.ground else []) + [
            index[n] for n in carriers if n != journals.get(point)
        ]
        revolutes += [(pinned[0], b, at(point)) for b in pinned[1:]]
    joints = {
        c.joint: clearance_joint(
            index.get(c.bearing),
            index.get(c.journal),
            at(c.joint),
            params[f"clearance_{c.joint}"],
            model.joint_parameters(params, c.joint),
        )
        for c in linkage.clearances
    }
    prismatics = []
    for g in linkage.groups:
        if g.kind == "RRP":
            s = parts[g.slider]
            u = (math.cos(s.angle), math.sin(s.angle))
            prismatics.append(Prismatic(None, index[s.name], at(s.pin), u))
        elif g.kind == "RPR":
            a, b = at(g.line[0]), at(g.line[1])
            u = (b[0] - a[0], b[1] - a[1])
            prismatics.append(Prismatic(index[g.guide], index[g.block], at(g.pin), u))
    slider = None
    if linkage.sliders:
        s = linkage.sliders[0]
        g = linkage.ground[s.guide]
        u = (math.cos(s.angle), math.sin(s.angle))
        com = s.centre_of_mass
        origin = (g[0] + u[0] * com[0] - u[1] * com[1], g[1] + u[1] * com[0] + u[0] * com[1])
        slider = Guide(index[s.name], origin, u, s.offset)
    drives = [(index[c.link], float(motion.angles[c.link].velocity[0])) for c in linkage.cranks]
    return Mechanism(
        bodies=bodies,
        revolutes=revolutes,
        prismatics=prismatics,
        clearances=joints,
        drives=drives,
        slider=slider,
    )


def verifiable_models() -> tuple[str, ...]:
    """The built-in and registered models that exudyn can rebuild: those that declare their
    ``verification`` builder (:attr:`workbench.models.Model.verification`). Every declared
    mechanism (a scene's ``[mechanism]`` table) can be rebuilt too; its models, made as scenes
    declare them, are not listed."""
    return tuple(
        m
        for m in available_models()
        if get_model(m).verification is not None and getattr(get_model(m), "linkage", None) is None
    )


def build_mechanism(scene: Scene) -> Mechanism:
    """The scene's mechanism at t = 0 as exudyn sees it, from the builder its model declares
    (:attr:`workbench.models.Model.verification`); call :func:`check_scene` first."""
    return get_model(scene.model).plugin("verification")(scene)


def check_scene(scene: Scene) -> None:
    """Raise SceneError (naming the key) unless exudyn can rebuild this scene (model, friction
    and contact laws, journals starting centred)."""
    model = get_model(scene.model)
    if model.verification is None:
        raise SceneError(
            "model.name",
            f"exudyn verification knows the models {sorted(verifiable_models())} and declared "
            f"mechanisms; got {scene.model!r}",
        )
    if scene.effects["friction"] == "lugre":
        raise SceneError(
            "effects.friction",
            "'lugre' has no counterpart in exudyn's contact; verify a scene with friction "
            "'none' or 'coulomb'",
        )
    if scene.effects.get("clearance") and scene.effects.get("contact") == "hunt_crossley":
        raise SceneError(
            "effects.contact",
            "'hunt_crossley' (a constant damping) has no counterpart in exudyn's contact, whose "
            "damping scales with the onset velocity; verify with 'lankarani_nikravesh'",
        )
    moved = {k: v for k, v in scene.initial.items() if v != 0.0}
    if moved:
        key = next(iter(moved))
        raise SceneError(
            f"initial.{key}",
            f"got {moved[key]!r}; exudyn starts every journal centred and at rest in its bearing: "
            "verify a scene without an [initial] state",
        )
