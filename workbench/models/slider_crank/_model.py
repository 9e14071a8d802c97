"""The ``slider_crank`` model: the community benchmark of a revolute clearance joint.

Slider-crank mechanism with a clearance in the joint between the connecting rod and the slider
(Flores, Ambrosio, Claro & Lankarani 2006, Mech. Mach. Theory 41:247; the same case in Flores et
al. 2008, *Kinematics and Dynamics of Multibody Systems with Imperfect Joints*): crank O-A of
length L1 driven at constant speed, rod A-B' of length L2 ideal-pinned to the crank at A, its
end B' a journal in a bearing of the slider, whose pin B = (s, 0) runs on the x axis through O.
Kinematics :mod:`._kinematics`, dynamics :mod:`._dynamics`; units SI.
"""

from __future__ import annotations

import dataclasses
import math

from workbench._errors import SceneError
from workbench.models import register
from workbench.models._base import Effect, Parameter
from workbench.models._clearance import (
    CONTACT_EFFECT,
    FRICTION_EFFECT,
    contact_law,
    contact_parameters,
    joint_block,
    validate_joint,
)
from workbench.models._mechanism import Mechanism, body_parameters, mechanism_parameters
from workbench.models.slider_crank import _dynamics as dyn
from workbench.models.slider_crank._geometry import (
    BODY_NAMES,
    DEFAULT_GEOMETRY,
    INERTIAS,
    MASSES,
    geometry_array,
)

JOINTS = ("B",)
_POS = {"lower": 0.0, "lower_open": True}
# scene name, geometry field, long name
_GEOMETRY_PARAMETERS = (
    ("crank_length", "L1", "length OA of the crank"),
    ("rod_length", "L2", "length AB of the connecting rod"),
    ("crank_centroid", "Lc1", "distance of the crank centroid from O"),
    ("rod_centroid", "Lc2", "distance of the rod centroid from A"),
)


def _parameters() -> tuple[Parameter, ...]:
    out = [
        Parameter(name, DEFAULT_GEOMETRY[f], "m", long_name, **_POS)
        for name, f, long_name in _GEOMETRY_PARAMETERS
    ]
    out += body_parameters(
        BODY_NAMES, MASSES, INERTIAS, "mass of the {}", "centroidal inertia of the {}"
    )
    out += [
        Parameter("omega", 5000 * 2 * math.pi / 60, "rad s-1", "crank speed (5000 rpm)", **_POS),
        Parameter("theta10", 0.0, "rad", "initial crank angle"),
        Parameter("gravity", 9.81, "m s-2", "gravitational acceleration", lower=0.0),
        Parameter(
            "gravity_angle",
            -math.pi / 2,
            "rad",
            "direction of gravity, counter-clockwise from +X (-pi/2: along -Y)",
        ),
        *contact_parameters(clearance=0.5e-3, friction_coefficient=0.0),
    ]
    return tuple(out)


@register
class SliderCrank(Mechanism):
    """Slider-crank with a revolute clearance joint between rod and slider (Flores et al. 2006)."""

    name = "slider_crank"
    description = (
        "slider-crank mechanism, crank driven at constant omega, revolute clearance joint B "
        "between the connecting rod (journal) and the slider (bearing)"
    )
    reference = (
        "Flores, Ambrosio, Claro & Lankarani (2006), Mech. Mach. Theory 41:247; Flores et al. "
        "(2008), Kinematics and Dynamics of Multibody Systems with Imperfect Joints, Ch. 5"
    )
    parameters = _parameters()
    effects = (
        Effect("clearance", ("B",), "subset", "joints with a radial clearance", JOINTS),
        dataclasses.replace(FRICTION_EFFECT, default="none"),
        CONTACT_EFFECT,
        Effect("gravity", True, "bool", "apply gravity"),
    )

    joints = JOINTS
    cranks = ("1",)
    slider = "slider position s (pin B on the x axis)"
    assembly = "the rod cannot reach the slider guide (|y - L1 sin theta1| >= L2)"
    dynamics = dyn
    overview_figure = "workbench.plot._slider_crank:slider_crank_overview"
    verification = "workbench.verification._mechanisms:slider_crank_mechanism"

    def clearances(self, params) -> dict[str, float]:
        """Clearance of each joint, m."""
        return {"B": params["clearance"]}

    def validate(self, params, effects):
        validate_joint(params, params["clearance"], "parameters.clearance")
        if params["crank_length"] >= params["rod_length"]:
            raise SceneError(
                "parameters.rod_length",
                f"got {params['rod_length']!r} m; the rod must be longer than the crank "
                f"({params['crank_length']!r} m) for the crank to turn fully",
            )

    def pack(self, params, effects):
        return dyn.P.pack(
            {
                "geometry": geometry_array({f: params[n] for n, f, _ in _GEOMETRY_PARAMETERS}),
                **mechanism_parameters(params, effects, BODY_NAMES),
                "theta10": params["theta10"],
                "joint": joint_block(params, params["clearance"], contact_law(effects)),
            }
        )
