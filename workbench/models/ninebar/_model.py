"""The ``ninebar`` model: declarations, validation, problem building and derived outputs."""

from __future__ import annotations

import math

import numpy as np

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
from workbench.models.ninebar import _dynamics as dyn
from workbench.models.ninebar._geometry import (
    BODY_NAMES,
    DEFAULT_GEOMETRY,
    INERTIAS,
    MASSES,
    geometry_array,
)

JOINTS = ("A", "B")


def geometry_of(params) -> np.ndarray:
    """The geometry block (m, rad) of the kinematics for the model's resolved parameters."""
    return geometry_array({f: params[name] for name, f, _, _ in _GEOMETRY_PARAMETERS})


# scene name, geometry field, long name, units
_GEOMETRY_PARAMETERS = (
    ("crank1_length", "L1", "length O1A of crank 1", "m"),
    ("link2_length", "L2", "length AP of link 2", "m"),
    ("link3_length", "L3", "length BP of link 3", "m"),
    ("crank4_length", "L4", "length O4B of crank 4", "m"),
    ("frame_length", "L5", "distance O1O4 of the crank pivots", "m"),
    ("rocker6_length", "L6", "length O6C of rocker 6", "m"),
    ("panel7_cp", "L71", "side CP of triangular panel 7", "m"),
    ("panel7_cd", "L72", "side CD of triangular panel 7", "m"),
    ("panel7_angle", "beta", "angle PCD of triangular panel 7", "rad"),
    ("link8_length", "L8", "length DE of link 8", "m"),
    ("rocker_pivot_x", "O6x", "x of the rocker pivot O6", "m"),
    ("rocker_pivot_y", "O6y", "y of the rocker pivot O6 (and of the slider guide)", "m"),
    ("slider_offset", "S0", "slider offset S0 in S9 = S0 - (x_E - x_O6)", "m"),
    ("crank1_centroid", "Ls1", "distance of the crank 1 centroid from O1", "m"),
    ("link2_centroid", "Ls2", "distance of the link 2 centroid from A", "m"),
    ("link3_centroid", "Ls3", "distance of the link 3 centroid from B", "m"),
    ("crank4_centroid", "Ls4", "distance of the crank 4 centroid from O4", "m"),
    ("rocker6_centroid", "Ls6", "distance of the rocker 6 centroid from O6", "m"),
    ("link8_centroid", "Ls8", "distance of the link 8 centroid from D", "m"),
)


def _parameters() -> tuple[Parameter, ...]:
    pos = {"lower": 0.0, "lower_open": True}
    out = []
    for name, fieldname, long_name, units in _GEOMETRY_PARAMETERS:
        bounds = {} if fieldname in ("O6x", "O6y", "S0", "beta") else pos
        out.append(Parameter(name, DEFAULT_GEOMETRY[fieldname], units, long_name, **bounds))
    out += body_parameters(BODY_NAMES, MASSES, INERTIAS)
    out += [
        Parameter(
            "omega",
            2.5 * math.pi,
            "rad s-1",
            "crank speed (crank 4 at +omega, crank 1 at -omega)",
            **pos,
        ),
        Parameter("theta10", 0.0, "rad", "initial angle of crank 1"),
        Parameter("theta40", 0.0, "rad", "initial angle of crank 4"),
        Parameter("gravity", 9.81, "m s-2", "gravitational acceleration", lower=0.0),
        Parameter(
            "gravity_angle",
            math.pi,
            "rad",
            "direction of gravity, counter-clockwise from +X (pi: along -X, Eq. 17)",
        ),
        Parameter("clearance_A", 0.0, "m", "clearance of joint A (0: use clearance)", lower=0.0),
        Parameter("clearance_B", 0.0, "m", "clearance of joint B (0: use clearance)", lower=0.0),
        *contact_parameters(clearance=0.5e-3, friction_coefficient=0.05),
    ]
    return tuple(out)


@register
class NineBar(Mechanism):
    """Two-DOF nine-bar mechanism with revolute clearance joints A and B (Chen et al. 2019)."""

    name = "ninebar"
    description = (
        "2-DOF nine-bar planar mechanism, cranks driven at -omega and +omega, revolute "
        "clearance joints A (crank 1 / link 2) and B (crank 4 / link 3)"
    )
    reference = (
        "Chen, Jiang, Wang & Deng (2019), Multibody Syst. Dyn. 47:317; parameters: "
        "docs/ninebar-parameters.md"
    )
    parameters = _parameters()
    effects = (
        Effect("clearance", ("A", "B"), "subset", "joints with a radial clearance", JOINTS),
        FRICTION_EFFECT,
        CONTACT_EFFECT,
        Effect("gravity", True, "bool", "apply gravity"),
    )

    joints = JOINTS
    cranks = ("1", "4")
    slider = "slider displacement S9"
    assembly = "the mechanism cannot be assembled at this configuration (a loop does not close)"
    dynamics = dyn
    overview_figure = "workbench.plot._ninebar:ninebar_overview"
    verification = "workbench.verification._mechanisms:ninebar_mechanism"

    # -- declarations -------------------------------------------------------------------------
    def variables(self, effects):
        return {q.name: q for q in self.outputs(effects)}

    def clearances(self, params) -> dict[str, float]:
        """Clearance of each joint, m."""
        return {j: params[f"clearance_{j}"] or params["clearance"] for j in JOINTS}

    def validate(self, params, effects):
        for j, c in self.clearances(params).items():
            key = (
                f"parameters.clearance_{j}" if params[f"clearance_{j}"] else "parameters.clearance"
            )
            validate_joint(params, c, key)

    # -- building ------------------------------------------------------------------------------
    def pack(self, params, effects):
        clearances = self.clearances(params)
        return dyn.P.pack(
            {
                "geometry": geometry_of(params),
                **mechanism_parameters(params, effects, BODY_NAMES),
                "theta10": params["theta10"],
                "theta40": params["theta40"],
                "joint": np.concatenate(
                    [joint_block(params, clearances[j], contact_law(effects)) for j in JOINTS]
                ),
            }
        )
