"""Declarations shared by every mechanism with revolute clearance joints (Python side).

The parameters of the contact law (Lankarani & Nikravesh 1990, stiffness from Hertz, Eq. 4 of
Chen et al. 2019) and of the friction laws (modified Coulomb, Ambrosio 2003; LuGre, Canudas de
Wit et al. 1995), the friction effect, the per-joint output variables, the cross-field checks and
the packing of the compiled parameter blocks of :mod:`workbench.models._reduced` (layouts JOINT,
FRICTION), and what every such mechanism does alike on the Python side: the problem it hands to
the solver (:func:`mechanism_problem`) and the outputs it derives from the record-time
evaluation (:func:`mechanism_derive`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from workbench._errors import SceneError, SolverError
from workbench.models._base import Effect, Parameter, Problem, Quantity
from workbench.models._layout import Layout
from workbench.models._reduced import (
    CODE_ASSEMBLY,
    CODE_NONFINITE,
    CODE_PENETRATION,
    CODE_SINGULAR,
    FRICTION,
    JOINT,
    JOINT_RECORD,
)
from workbench.models.contact import hertz_internal_stiffness

_POS = {"lower": 0.0, "lower_open": True}

FRICTION_CODES = {"none": 0, "coulomb": 1, "lugre": 2}

FRICTION_EFFECT = Effect(
    "friction", "coulomb", "choice", "friction law in the clearance joints", tuple(FRICTION_CODES)
)


def contact_parameters(clearance: float, friction_coefficient: float) -> tuple[Parameter, ...]:
    """Parameters of the contact and friction laws, with the model's default clearance (m) and
    Coulomb coefficient."""
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
        Parameter("lugre_sigma1", 316.2, "s m-1", "LuGre bristle damping (normalised)", lower=0.0),
        Parameter("lugre_sigma2", 0.4, "s m-1", "LuGre viscous friction (normalised)", lower=0.0),
        Parameter("lugre_stribeck_velocity", 1e-3, "m s-1", "LuGre Stribeck velocity v_s", **_POS),
        Parameter("lugre_stribeck_exponent", 2.0, "1", "LuGre Stribeck exponent", **_POS),
    )


def failure_messages(assembly: str) -> dict[int, str]:
    """Message per failure code of a mechanism's right-hand side (CODE_* of ``_reduced``);
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
        Quantity("clearance_x", "m", "journal centre relative to bearing centre, x", jd),
        Quantity("clearance_y", "m", "journal centre relative to bearing centre, y", jd),
        Quantity("clearance_vx", "m s-1", "rate of the clearance vector, x", jd),
        Quantity("clearance_vy", "m s-1", "rate of the clearance vector, y", jd),
        Quantity("eccentricity", "m", "eccentricity of the journal", jd),
        Quantity("penetration", "m", "penetration depth max(e - c, 0)", jd),
        Quantity("contact_force", "N", "normal contact force", jd),
        Quantity("friction_force", "N", "friction force on the journal along t", jd),
    ]
    if effects["friction"] == "lugre":
        out.append(Quantity("lugre_z", "m", "LuGre bristle deflection", jd))
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
    """The friction parameters in the FRICTION layout of :mod:`workbench.models._reduced`."""
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
        }
    )


def joint_block(params: Mapping[str, float], clearance: float) -> np.ndarray:
    """One joint's parameters (clearance in m) in the JOINT layout of
    :mod:`workbench.models._reduced`."""
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


def mechanism_outputs(effects: Mapping[str, Any], slider: str) -> tuple[Quantity, ...]:
    """Output variables of a crank-driven mechanism with a slider (``slider``: the long name
    of its position) and clearance joints."""
    joints = bool(effects["clearance"])
    out = joint_outputs(effects) if joints else []
    out += [
        Quantity("torque", "N m", "driving torque", ("crank",)),
        Quantity("slider_position", "m", slider),
        Quantity("slider_velocity", "m s-1", "slider velocity"),
        Quantity("slider_acceleration", "m s-2", "slider acceleration"),
        Quantity("kinetic_energy", "J", "kinetic energy of the mechanism"),
        Quantity("potential_energy", "J", "gravity and contact elastic potential energy"),
    ]
    if joints:
        out += energy_outputs()
    return tuple(out)


def state_scales(states, clearance: float, omega: float) -> np.ndarray:
    """Characteristic size of each state for the solver's atol: the clearance c (m) for
    lengths, c omega (m s-1) for rates, 1 J for the energy quadratures."""
    size = {"m": clearance, "m s-1": clearance * omega}
    return np.array([size.get(q.units, 1.0) for q in states])


def check_records(problem, t: np.ndarray, Y: np.ndarray, codes: np.ndarray) -> None:
    """Raise SolverError at the first record whose model evaluation failed (``codes`` != 0):
    the integrator accepted (or interpolated) a state the mechanism cannot take."""
    if not codes.any():
        return
    bad = int(np.flatnonzero(codes)[0])
    raise SolverError(
        f"the record at t = {float(t[bad]):.9g} s is outside the model's domain: "
        f"{problem.failure(int(codes[bad]))}; the solver's tolerance is too loose for this "
        "scene (tighten solver.rtol/atol)",
        time=float(t[bad]),
        state={q.name: float(v) for q, v in zip(problem.states, Y[bad], strict=True)},
        cause=f"model_{int(codes[bad])}",
    )


def mechanism_parameters(
    params: Mapping[str, float], effects: Mapping[str, Any], bodies: tuple[str, ...]
) -> dict[str, Any]:
    """The fields that every crank-driven mechanism's parameter layout has, by name: the
    bodies' masses (kg) and centroidal inertias (kg m2; 0 for a body that only translates),
    the gravity vector (m s-2; 0 when the effect is off), the crank speed (rad s-1) and the
    friction block."""
    g = params["gravity"] if effects["gravity"] else 0.0
    return {
        "mass": [params[f"mass_{body}"] for body in bodies],
        "inertia": [params.get(f"inertia_{body}", 0.0) for body in bodies],
        "gx": g * math.cos(params["gravity_angle"]),
        "gy": g * math.sin(params["gravity_angle"]),
        "omega": params["omega"],
        "friction": friction_block(params),
    }


def mechanism_problem(
    *,
    hooks: str,
    effects: Mapping[str, Any],
    initial: Mapping[str, float],
    requested: tuple[str, ...],
    joints: tuple[str, ...],
    clearances: Mapping[str, float],
    omega: float,
    p: np.ndarray,
    IP: Layout,
    work: Layout,
    n_driven: int,
    assembly: str,
) -> Problem:
    """The solver's problem for a crank-driven mechanism with clearance joints.

    Parameters
    ----------
    hooks : str
        Module of the compiled hooks.
    effects, initial, requested
        As :meth:`workbench.models.Model.problem` receives them; ``effects["clearance"]``
        names the joints with a clearance, ``effects["friction"]`` the friction law.
    joints : tuple of str
        Every joint of the mechanism that can have a clearance, in the order of its blocks.
    clearances : mapping of str to float
        Clearance of each joint, m.
    omega : float
        Crank speed, rad s-1 (for the states' characteristic sizes).
    p : ndarray
        The packed float parameters.
    IP, work : Layout
        The model's integer-parameter layout (fields of
        :func:`workbench.models._reduced.index_fields`) and workspace layout (the fields of
        :func:`workbench.models._reduced.record_fields` and ``work_fields``): the hooks write
        joint j's LuGre decay rate into its record's ``decay`` and find h gamma in ``hg``.
    n_driven : int
        Number of driven coordinates, first in q; joint j's clearance vector follows at
        q[n_driven + 2 j].
    assembly : str
        Why this mechanism cannot be assembled (for the failure messages).

    Returns
    -------
    Problem
        State: the clearance vectors, their rates, the LuGre bristles (see
        :func:`clearance_states`) and the energy quadratures when ``driver_work`` or
        ``dissipated_energy`` is requested.
    """
    present = [j for j in joints if j in effects["clearance"]]
    lugre = effects["friction"] == "lugre"
    energy = bool(present) and ("driver_work" in requested or "dissipated_energy" in requested)
    states = list(clearance_states(present, effects["friction"]))
    y0 = [float(initial.get(q.name, 0.0)) for q in states]
    if energy:
        states += ENERGY_STATES
        y0 += [0.0, 0.0]
    nf = 2 * len(present)
    n = len(joints)
    has, slot, z = [0] * n, [-1] * n, [-1] * n
    free = [-1] * (2 * n)
    for i, name in enumerate(present):
        j = joints.index(name)
        has[j] = 1
        slot[j] = 2 * i
        free[2 * i : 2 * i + 2] = [n_driven + 2 * j, n_driven + 2 * j + 1]
        if lugre:
            z[j] = 2 * nf + i
    ip = IP.pack(
        {
            "has": has,
            "slot": slot,
            "z": z,
            "friction": FRICTION_CODES[effects["friction"]],
            "energy": int(energy),
            "w": 2 * nf + (len(present) if lugre else 0) if energy else -1,
            "nf": nf,
            "free": free,
        },
        fill=-1,
        dtype=np.int64,
    )
    stiff = [joints.index(name) for name in present] if lugre else []
    c_min = min(clearances[j] for j in present) if present else 1.0
    codes = failure_messages(assembly)
    return Problem(
        hooks=hooks,
        states=tuple(states),
        y0=np.array(y0, dtype=float),
        p=p,
        ip=ip,
        aux0=np.zeros(n),
        event_direction=np.array([1, -1] * len(present), dtype=np.int64),
        atol_scale=state_scales(states, c_min, omega),
        work_size=work.size,
        failure=lambda code: codes.get(code, f"model failure code {code}"),
        data={"joints": tuple(present), "all_joints": joints, "IP": IP},
        stiff_states=[z[j] for j in stiff],
        stiff_slots=[work.joint + j * JOINT_RECORD.size + JOINT_RECORD.decay for j in stiff],
        implicit_slot=work.hg,
    )


def mechanism_derive(
    problem: Problem,
    t: np.ndarray,
    Y: np.ndarray,
    AUX: np.ndarray,
    requested: tuple[str, ...],
    evaluate_many: Callable,
    record: Layout,
) -> dict[str, np.ndarray]:
    """The outputs of a mechanism at the records, from its record-time evaluation.

    ``evaluate_many(t, Y, p, ip, AUX, ws)`` fills ``ws[i]`` (layout ``record``, fields of
    :func:`workbench.models._reduced.record_fields`) at every record and returns the failure
    codes; the energy quadratures and the LuGre bristles come from the state.
    """
    ws = np.empty((t.size, record.size))
    check_records(problem, t, Y, evaluate_many(t, Y, problem.p, problem.ip, AUX, ws))
    IP = problem.data["IP"]
    cols = [problem.data["all_joints"].index(j) for j in problem.data["joints"]]
    out: dict[str, np.ndarray] = {}

    def per_joint(field: str) -> np.ndarray:
        offset = getattr(JOINT_RECORD, field)
        return np.stack(
            [ws[:, record.joint + j * JOINT_RECORD.size + offset] for j in cols], axis=1
        )

    if cols:
        for name, field in _JOINT_OUTPUTS.items():
            out[name] = per_joint(field)
        out["penetration"] = np.maximum(per_joint("delta"), 0.0)
        iz = problem.ip[IP.block("z")]
        if iz.max() >= 0:
            out["lugre_z"] = np.stack([Y[:, iz[j]] for j in cols], axis=1)
        iw = problem.ip[IP.w]
        if iw >= 0:
            out["driver_work"] = Y[:, iw] - Y[0, iw]
            out["dissipated_energy"] = Y[:, iw + 1] - Y[0, iw + 1]
    out["torque"] = ws[:, record.block("tau")]
    out["slider_position"] = ws[:, record.slider]
    out["slider_velocity"] = ws[:, record.slider + 1]
    out["slider_acceleration"] = ws[:, record.slider + 2]
    out["kinetic_energy"] = ws[:, record.ke]
    out["potential_energy"] = ws[:, record.pe]
    return {k: v for k, v in out.items() if k in requested}


# output variable -> JOINT_RECORD field (besides the penetration, max(delta, 0))
_JOINT_OUTPUTS = {
    "clearance_x": "x",
    "clearance_y": "y",
    "clearance_vx": "vx",
    "clearance_vy": "vy",
    "eccentricity": "e",
    "contact_force": "fn",
    "friction_force": "ft",
}
