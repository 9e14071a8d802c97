"""Declarations shared by every mechanism with revolute clearance joints (Python side).

The parameters of the contact laws (Lankarani & Nikravesh 1990 or Hunt & Crossley 1975, stiffness
from Hertz, Eq. 4 of Chen et al. 2019) and of the friction laws (modified Coulomb, Ambrosio 2003;
LuGre, Canudas de Wit et al. 1995), the contact and friction effects, the per-joint output
variables, the cross-field checks and the packing of the compiled parameter blocks of
:mod:`workbench.models._mechanism_layouts` (layouts JOINT, FRICTION). What every such mechanism does
alike as a model is :class:`workbench.models._mechanism.Mechanism`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from workbench._errors import SceneError
from workbench.models._base import Effect, Parameter, Quantity
from workbench.models._friction_report import diagnostic_outputs
from workbench.models._mechanism_layouts import (
    CODE_ASSEMBLY,
    CODE_NONFINITE,
    CODE_PENETRATION,
    CODE_SINGULAR,
    FRICTION,
    JOINT,
)
from workbench.models.contact import CONTACT_LAWS, hertz_internal_stiffness

_POS = {"lower": 0.0, "lower_open": True}

FRICTION_CODES = {"none": 0, "coulomb": 1, "lugre": 2}

FRICTION_EFFECT = Effect(
    "friction", "coulomb", "choice", "friction law in the clearance joints", tuple(FRICTION_CODES)
)

CONTACT_EFFECT = Effect(
    "contact",
    "lankarani_nikravesh",
    "choice",
    "normal contact force law in the clearance joints: Lankarani-Nikravesh (damping scaled by "
    "the onset velocity, held through each contact) or Hunt-Crossley (a material damping "
    "constant, no memory)",
    tuple(CONTACT_LAWS),
)


def contact_law(effects: Mapping[str, Any]) -> str:
    """The contact law the effects name (a value of :data:`CONTACT_EFFECT`): the default,
    Lankarani-Nikravesh, for effects that do not name one (a model that does not declare the
    effect)."""
    return effects.get("contact", CONTACT_EFFECT.default)


#: the default Hunt-Crossley damping constant (s m-1): the one whose free impact at
#: HUNT_CROSSLEY_REFERENCE_VELOCITY rebounds with the default restitution 0.9
#: (workbench.models.contact.hunt_crossley_damping(0.9, 1.0) = 0.11099 s m-1)
HUNT_CROSSLEY_DAMPING = 0.111
HUNT_CROSSLEY_REFERENCE_VELOCITY = 1.0  # m s-1


def contact_parameters(clearance: float, friction_coefficient: float) -> tuple[Parameter, ...]:
    """Parameters of the contact and friction laws, with the model's default clearance (m) and
    Coulomb coefficient.

    The LuGre parameters are normalised by the normal force (the paper's Eqs. 8-10; values of
    ``docs/ninebar-parameters.md``): mu_k = 0.05, mu_s = 0.15 (the paper), sigma0 =
    1e5 m-1 (the paper), sigma2 = 0.4 s m-1, v_s = 1e-3 m s-1, exponent 2 (Canudas de Wit et
    al. 1995). The bristle damping is ``lugre_sigma1 * exp(-(v / lugre_damping_velocity)^2)``
    (Olsson et al. 1998, Eur. J. Control 4:176) with ``lugre_sigma1`` = 316.2 s m-1 (the
    paper's sqrt(sigma0), the value of the force-form examples of Canudas de Wit et al. 1995)
    and ``lugre_damping_velocity`` = v_s = 1e-3 m s-1, chosen (issue 29) because the paper's
    constant damping is not passive: Barabanov & Ortega's (2000, IEEE TAC 45:830) condition for
    a constant damping, sigma1 <= sigma2 mu_k / (mu_s - mu_k) = 0.2 s m-1, is broken 1 600-fold,
    and the law then reaches |F_t| / F_n of 25-50 at contact onsets and sliding reversals. The
    fading damping keeps 316.2 s m-1 in pre-sliding, where it belongs (a damping ratio of 1/2
    for a 1-kg block at F_n = 1 N, as in the 1995 example), and is passive because
    sigma1 v_d = 0.316 <= 4 sqrt(2 e) mu_k = 0.466 (derivation in
    :mod:`workbench.models.friction`). ``lugre_damping_velocity = 0`` gives the paper's
    constant damping; ``lugre_sigma1 = 0.2`` with it the largest passive constant one. Every
    LuGre run records how far its friction coefficient went
    (:mod:`workbench.models._friction_report`).

    The Hunt-Crossley damping constant ``hunt_crossley_damping`` (used with the effect
    ``contact = "hunt_crossley"`` only) defaults to HUNT_CROSSLEY_DAMPING = 0.111 s m-1: the
    constant whose free impact at 1 m s-1 rebounds with the restitution 0.9 that the LN law
    takes for steel (the exact relation of :func:`workbench.models.contact.
    hunt_crossley_restitution`; 0.1 s m-1 by the first-order e = 1 - alpha v). A scene that
    compares the laws at another impact velocity v sets ``hunt_crossley_damping(c_e, v)``."""
    return (
        Parameter("clearance", clearance, "m", "radial clearance c of the joints", **_POS),
        Parameter("bearing_radius", 10.0e-3, "m", "bearing radius R1", **_POS),
        Parameter("youngs_modulus", 207e9, "Pa", "Young's modulus of journal and bearing", **_POS),
        Parameter(
            "poisson_ratio",
            0.3,
            "1",
            "Poisson's ratio of journal and bearing",
            lower=0.0,
            upper=0.5,
            upper_open=True,
        ),
        Parameter(
            "contact_stiffness",
            0.0,
            "N m-1.5",
            "contact stiffness K (0: from Eq. 4 for each joint)",
            lower=0.0,
        ),
        Parameter("contact_exponent", 1.5, "1", "exponent n of the contact law", **_POS),
        Parameter(
            "restitution",
            0.9,
            "1",
            "coefficient of restitution c_e",
            lower=0.0,
            upper=1.0,
            lower_open=True,
        ),
        Parameter(
            "impact_velocity_floor",
            1e-4,
            "m s-1",
            "floor of the onset velocity in the LN damping (grazing contact)",
            **_POS,
        ),
        Parameter(
            "hunt_crossley_damping",
            HUNT_CROSSLEY_DAMPING,
            "s m-1",
            "material damping constant alpha of the Hunt-Crossley law, F = K delta^n "
            "(1 + 1.5 alpha delta_dot); its restitution is 1 - alpha v for small alpha v "
            "(effects.contact = 'hunt_crossley' only)",
            lower=0.0,
        ),
        Parameter(
            "max_penetration",
            1e-4,
            "m",
            "penetration beyond which a run fails (Hertz contact is invalid)",
            **_POS,
        ),
        Parameter(
            "friction_coefficient",
            friction_coefficient,
            "1",
            "Coulomb friction coefficient c_f",
            lower=0.0,
        ),
        Parameter("coulomb_v0", 1e-4, "m s-1", "sliding speed below which c_d = 0", lower=0.0),
        Parameter("coulomb_v1", 1e-3, "m s-1", "sliding speed above which c_d = 1", **_POS),
        Parameter("lugre_mu_k", 0.05, "1", "LuGre kinetic friction coefficient", lower=0.0),
        Parameter("lugre_mu_s", 0.15, "1", "LuGre static friction coefficient", lower=0.0),
        Parameter("lugre_sigma0", 1e5, "m-1", "LuGre bristle stiffness (normalised)", **_POS),
        Parameter(
            "lugre_sigma1",
            316.2,
            "s m-1",
            "LuGre bristle damping at zero sliding velocity (normalised)",
            lower=0.0,
        ),
        Parameter(
            "lugre_damping_velocity",
            1e-3,
            "m s-1",
            "LuGre sliding speed v_d over which the bristle damping fades, sigma1 "
            "exp(-(v/v_d)^2) (0: constant sigma1)",
            lower=0.0,
        ),
        Parameter("lugre_sigma2", 0.4, "s m-1", "LuGre viscous friction (normalised)", lower=0.0),
        Parameter("lugre_stribeck_velocity", 1e-3, "m s-1", "LuGre Stribeck velocity v_s", **_POS),
        Parameter("lugre_stribeck_exponent", 2.0, "1", "LuGre Stribeck exponent", **_POS),
    )


def failure_messages(assembly: str) -> dict[int, str]:
    """Message per failure code of a mechanism's right-hand side (CODE_* of ``_mechanism_layouts``);
    ``assembly`` says why this mechanism cannot be assembled."""
    return {
        CODE_ASSEMBLY: f"{assembly}; the clearance vector left its physical range",
        CODE_PENETRATION: "a penetration exceeded parameters.max_penetration; the contact is too "
        "soft for this load or speed (raise contact_stiffness, check units)",
        CODE_SINGULAR: "the reduced mass matrix is singular (a singular position)",
        CODE_NONFINITE: "a force or acceleration became non-finite",
    }


def joint_outputs(effects: Mapping[str, Any]) -> list[Quantity]:
    """The per-joint output variables (dim ``joint``) of a mechanism with clearances."""
    jd = ("joint",)
    out = [
        Quantity(
            "clearance_x", "m", "journal centre relative to bearing centre, x", jd, "clearance_vx"
        ),
        Quantity(
            "clearance_y", "m", "journal centre relative to bearing centre, y", jd, "clearance_vy"
        ),
        Quantity("clearance_vx", "m s-1", "rate of the clearance vector, x", jd),
        Quantity("clearance_vy", "m s-1", "rate of the clearance vector, y", jd),
        Quantity("eccentricity", "m", "eccentricity of the journal", jd),
        Quantity("penetration", "m", "penetration depth max(e - c, 0)", jd),
        Quantity("contact_force", "N", "normal contact force", jd),
        Quantity("friction_force", "N", "friction force on the journal along t", jd),
    ]
    if effects["friction"] != "none":
        out.append(
            Quantity(
                "friction_ratio",
                "1",
                "friction ratio |F_t| / F_n of the law (0 out of contact)",
                jd,
            )
        )
    if effects["friction"] == "lugre":
        out.append(Quantity("lugre_z", "m", "LuGre bristle deflection", jd))
        out += diagnostic_outputs()
    return out


def energy_outputs() -> list[Quantity]:
    """Cumulative driver work and dissipation (J, since the record start)."""
    return [
        Quantity("driver_work", "J", "work of the driving torques since record start"),
        Quantity(
            "dissipated_energy",
            "J",
            "energy dissipated by contact damping and friction since record start",
        ),
    ]


def validate_joint(params: Mapping[str, float], clearance: float, key: str) -> None:
    """Cross-field checks of one joint's clearance (m) and of the friction parameters."""
    if not clearance < params["bearing_radius"]:
        raise SceneError(
            key,
            f"got {clearance!r} m; a clearance must be smaller than the "
            f"bearing radius {params['bearing_radius']!r} m",
        )
    if params["coulomb_v1"] <= params["coulomb_v0"]:
        raise SceneError(
            "parameters.coulomb_v1",
            f"got {params['coulomb_v1']!r}; must "
            f"exceed coulomb_v0 = {params['coulomb_v0']!r} m s-1",
        )


def stiffness(params: Mapping[str, float], clearance: float) -> float:
    """Contact stiffness K of a joint with this clearance (m): the scene's, or Hertz's, N m^-n."""
    return params["contact_stiffness"] or hertz_internal_stiffness(
        params["bearing_radius"], clearance, params["youngs_modulus"], params["poisson_ratio"]
    )


def friction_block(params: Mapping[str, float]) -> np.ndarray:
    """The friction parameters in the FRICTION layout of
    :mod:`workbench.models._mechanism_layouts`."""
    return FRICTION.pack(
        {
            "cf": params["friction_coefficient"],
            "v0": params["coulomb_v0"],
            "v1": params["coulomb_v1"],
            "mu_k": params["lugre_mu_k"],
            "mu_s": params["lugre_mu_s"],
            "sigma0": params["lugre_sigma0"],
            "sigma1": params["lugre_sigma1"],
            "sigma2": params["lugre_sigma2"],
            "v_s": params["lugre_stribeck_velocity"],
            "gamma": params["lugre_stribeck_exponent"],
            "v_d": params["lugre_damping_velocity"],
        }
    )


def joint_block(params: Mapping[str, float], clearance: float, contact: str) -> np.ndarray:
    """One joint's parameters (clearance in m) in the JOINT layout of
    :mod:`workbench.models._mechanism_layouts`, for the contact law ``contact`` (a value of
    the effect ``contact``)."""
    r1 = params["bearing_radius"]
    return JOINT.pack(
        {
            "r1": r1,
            "r2": r1 - clearance,
            "c": clearance,
            "k": stiffness(params, clearance),
            "n": params["contact_exponent"],
            "ce": params["restitution"],
            "dmax": params["max_penetration"],
            "vfloor": params["impact_velocity_floor"],
            "law": CONTACT_LAWS[contact],
            "alpha": params["hunt_crossley_damping"],
        }
    )


def clearance_states(joints, friction: str) -> list[Quantity]:
    """The integrated state of the clearance joints: every clearance vector (m), then every
    rate (m s-1), then the LuGre bristle deflections (m) when friction is "lugre"."""
    out = []
    for j in joints:
        out += [
            Quantity(f"x_{j}", "m", f"clearance vector x at joint {j}"),
            Quantity(f"y_{j}", "m", f"clearance vector y at joint {j}"),
        ]
    for j in joints:
        out += [
            Quantity(f"vx_{j}", "m s-1", f"clearance velocity x at joint {j}"),
            Quantity(f"vy_{j}", "m s-1", f"clearance velocity y at joint {j}"),
        ]
    if friction == "lugre":
        out += [Quantity(f"z_{j}", "m", f"LuGre bristle deflection at joint {j}") for j in joints]
    return out


# internal quadratures appended to the state when driver_work or dissipated_energy is requested
ENERGY_STATES = (
    Quantity("_driver_work", "J", "driver work since t0"),
    Quantity("_dissipated", "J", "dissipated energy since t0"),
)
