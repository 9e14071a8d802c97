"""The mechanisms as an independent multibody engine sees them: bodies with their initial
placement, ideal joints, clearance joints, drives and the slider (:class:`Mechanism`), the
builders of the built-in mechanisms (each model names its own:
:attr:`workbench.models.Model.verification`), and which scenes can be rebuilt at all.

Only the initial placement and velocities come from the workbench's kinematics; the engine then
holds the bodies to its own constraints. The nine-bar's placement is its public
:func:`workbench.models.ninebar.placement`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from workbench.models import available_models, get_model, joint_stiffness
from workbench.scene import Scene, SceneError

__all__ = [
    "Body",
    "Mechanism",
    "Point",
    "build_mechanism",
    "check_scene",
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
class Mechanism:
    """A mechanism as exudyn sees it. Bodies are indices into ``bodies``; None is the ground.

    ``revolutes``: ideal pins (body0, body1, point); ``clearances``: joint name -> (bearing
    body, journal body, point, clearance m, contact stiffness N m^-n), ideal pins when the scene
    has no clearance there; ``drives``: (body, angular rate rad s-1) per driven crank, in the
    order of the model's ``crank`` coordinate; ``slider``: the body on the guide (the x axis of
    its initial placement), ``slider_position``: the map x_body -> slider position (m) and
    ``slider_sign``: the sign of the slider's velocity against x_body.
    """

    bodies: list[Body]
    revolutes: list[tuple[int | None, int, Point]]
    clearances: dict[str, tuple[int, int, Point, float, float]]
    drives: list[tuple[int, float]]
    slider: int
    slider_position: Callable[[np.ndarray], np.ndarray]
    slider_sign: float


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
    s0 = at.slider_offset
    b = BODY_INDEX
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
        clearances={
            "A": (b["crank1"], b["link2"], A, c["A"], joint_stiffness(params, c["A"])),
            "B": (b["crank4"], b["link3"], B, c["B"], joint_stiffness(params, c["B"])),
        },
        drives=[(b["crank1"], -omega), (b["crank4"], omega)],
        slider=b["slider9"],
        slider_position=lambda x: s0 - (x - o6[0]),  # S9 = S0 - (x_E - x_O6)
        slider_sign=-1.0,
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
        clearances={"B": (2, 1, b, c, joint_stiffness(params, c))},
        drives=[(0, w1)],
        slider=2,
        slider_position=lambda x: x,
        slider_sign=1.0,
    )


def verifiable_models() -> tuple[str, ...]:
    """The models that exudyn can rebuild: those that declare their ``verification`` builder
    (:attr:`workbench.models.Model.verification`)."""
    return tuple(m for m in available_models() if get_model(m).verification is not None)


def build_mechanism(scene: Scene) -> Mechanism:
    """The scene's mechanism at t = 0 as exudyn sees it, from the builder its model declares
    (:attr:`workbench.models.Model.verification`); call :func:`check_scene` first."""
    return get_model(scene.model).plugin("verification")(scene)


def check_scene(scene: Scene) -> None:
    """Raise SceneError (naming the key) unless exudyn can rebuild this scene (model and
    friction law)."""
    if get_model(scene.model).verification is None:
        raise SceneError(
            "model.name",
            f"exudyn verification knows the models {sorted(verifiable_models())}; got "
            f"{scene.model!r}",
        )
    if scene.effects["friction"] == "lugre":
        raise SceneError(
            "effects.friction",
            "'lugre' has no counterpart in exudyn's contact; verify a scene with friction "
            "'none' or 'coulomb'",
        )
