"""A crank-driven mechanism with revolute clearance joints, on the Python side: the base class
of such models (:class:`Mechanism`) with what they do alike (their state, outputs, coordinates,
forcing period, the problem they hand to the solver and the outputs they derive from the
record-time evaluation) and the parameters of their bodies. The joints' own declarations are in
:mod:`workbench.models._clearance`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from types import ModuleType
from typing import Any, ClassVar

import numpy as np

from workbench._attributes import variable
from workbench.models._base import Model, Parameter, Problem, Quantity
from workbench.models._clearance import (
    ENERGY_STATES,
    FRICTION_CODES,
    clearance_states,
    contact_law,
    energy_outputs,
    failure_messages,
    friction_block,
    joint_outputs,
)
from workbench.models._friction_report import (
    DIAGNOSTICS,
    TIME_SCALE,
    diagnostic_outputs,
    diagnostic_states,
    friction_summary,
    friction_warnings,
)
from workbench.models._layout import Layout
from workbench.models._mechanism_layouts import JOINT_RECORD
from workbench.solver import SolverError

__all__ = [
    "Mechanism",
    "body_parameters",
    "mechanism_derive",
    "mechanism_outputs",
    "mechanism_parameters",
    "mechanism_problem",
]

_POS = {"lower": 0.0, "lower_open": True}


class Mechanism(Model):
    """Base class of a mechanism whose cranks are driven at a constant speed ``omega`` and whose
    joints may have a radial clearance. A subclass declares its joints, cranks, slider and
    compiled hooks, packs its float parameters (:meth:`pack`) and says each joint's clearance
    (:meth:`clearances`)."""

    #: every joint that can have a clearance, in the order of its parameter blocks
    joints: ClassVar[tuple[str, ...]]
    #: labels of the driven cranks (coordinate ``crank``), first in q
    cranks: ClassVar[tuple[str, ...]]
    #: long name of the slider's position
    slider: ClassVar[str]
    #: why the mechanism cannot be assembled (for the failure messages)
    assembly: ClassVar[str]
    #: module of the compiled hooks, with the layouts P, IP, W, RECORD and ``evaluate_many``
    dynamics: ClassVar[ModuleType]
    #: event functions: each clearance joint's penetration (onset, end); discrete state (under
    #: the Lankarani-Nikravesh law; none under Hunt-Crossley's): each joint's normal velocity
    #: held from its contact onset (0 out of contact)
    event_units = "m"
    discrete_state_units = "m s-1"
    #: a mechanism not yet measured compiles about as long as the smaller measured mechanism
    compile_stand_in = "slider_crank"

    def states(self, effects):
        return tuple(clearance_states(effects["clearance"], effects["friction"]))

    def outputs(self, effects):
        return mechanism_outputs(effects, self.slider)

    def coords(self, effects):
        return {
            "joint": (list(effects["clearance"]), variable("clearance joint")),
            "crank": (list(self.cranks), variable("driven crank")),
        }

    def forcing_period(self, params):
        return 2.0 * math.pi / params["omega"]

    def recorded_always(self, effects):
        lugre = effects["friction"] == "lugre" and bool(effects["clearance"])
        return DIAGNOSTICS if lugre else ()

    def diagnose(self, ds, params):
        return friction_warnings(ds, params)

    def summary(self, ds, params):
        return friction_summary(ds, params)

    def clearances(self, params) -> dict[str, float]:
        """Clearance of each joint, m."""
        raise NotImplementedError

    def pack(self, params, effects) -> np.ndarray:
        """The float parameters in the layout ``dynamics.P``."""
        raise NotImplementedError

    def motors(self, params) -> tuple[tuple[str, int, float, float], ...]:
        """The motor-driven cranks (see :func:`mechanism_problem`'s ``motors``): none; every
        crank turns at its constant speed."""
        return ()

    def problem(self, params, effects, initial, requested):
        return mechanism_problem(
            hooks=self.dynamics.__name__,
            effects=effects,
            initial=initial,
            requested=requested,
            joints=self.joints,
            clearances=self.clearances(params),
            omega=params["omega"],
            p=self.pack(params, effects),
            IP=self.dynamics.IP,
            work=self.dynamics.W,
            n_driven=len(self.cranks),
            assembly=self.assembly,
            motors=self.motors(params),
        )

    def derive(self, problem, t, Y, AUX, requested):
        return mechanism_derive(
            problem, t, Y, AUX, requested, self.dynamics.evaluate_many, self.dynamics.RECORD
        )


def body_parameters(
    bodies: tuple[str, ...],
    masses,
    inertias,
    mass_name: str = "mass of {}",
    inertia_name: str = "centroidal moment of inertia of {}",
) -> list[Parameter]:
    """``mass_<body>`` (kg) of every body and ``inertia_<body>`` (kg m2) of every body that
    turns (inertia > 0), with their defaults; ``mass_name`` and ``inertia_name`` format the
    long names with the body's name."""
    out = [
        Parameter(f"mass_{body}", masses[b], "kg", mass_name.format(body), **_POS)
        for b, body in enumerate(bodies)
    ]
    out += [
        Parameter(f"inertia_{body}", inertias[b], "kg m2", inertia_name.format(body), **_POS)
        for b, body in enumerate(bodies)
        if inertias[b] > 0
    ]
    return out


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
    lengths, c omega (m s-1) for rates, 1 J for the energy quadratures, TIME_SCALE (s) for
    the friction-law quadratures (:mod:`workbench.models._friction_report`), 1 rad for a
    motor-driven crank's angle and omega (rad s-1) for its speed."""
    size = {"m": clearance, "m s-1": clearance * omega, "s": TIME_SCALE, "rad s-1": omega}
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


def motor_states(states, present, motors) -> list[Quantity]:
    """The clearance joints' ``states`` (:func:`clearance_states` of the joints ``present``)
    with the angle (rad) of every motor-driven crank of ``motors`` (label first) after the
    clearance vectors and its speed (rad s-1) after their rates."""
    n = 2 * len(present)
    angles = [Quantity(f"crank_angle_{m[0]}", "rad", f"angle of crank {m[0]}") for m in motors]
    speeds = [Quantity(f"crank_speed_{m[0]}", "rad s-1", f"speed of crank {m[0]}") for m in motors]
    states = list(states)
    return [*states[:n], *angles, *states[n : 2 * n], *speeds, *states[2 * n :]]


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
    motors: tuple[tuple[str, int, float, float], ...] = (),
) -> Problem:
    """The solver's problem for a crank-driven mechanism with clearance joints.

    Parameters
    ----------
    hooks : str
        Module of the compiled hooks.
    effects, initial, requested
        As :meth:`workbench.models.Model.problem` receives them; ``effects["clearance"]``
        names the joints with a clearance, ``effects["friction"]`` the friction law,
        ``effects["contact"]`` the contact law (the Lankarani-Nikravesh law holds each
        joint's onset velocity in the discrete state; the Hunt-Crossley law has none).
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
        :func:`workbench.models._mechanism_layouts.index_fields`) and workspace layout (the
        fields of :func:`workbench.models._mechanism_layouts.record_fields` and
        ``work_fields``): the hooks write joint j's LuGre decay rate into its record's
        ``decay`` and find h gamma in ``hg``.
    n_driven : int
        Number of driven coordinates, first in q; joint j's clearance vector follows at
        q[n_driven + 2 j].
    assembly : str
        Why this mechanism cannot be assembled (for the failure messages).
    motors : tuple of (str, int, float, float), optional
        The cranks that a motor drives: (label, index in q, initial angle (rad), initial speed
        (rad s-1)). Their angles follow the clearance vectors in the state and in the free
        coordinates (``ip[IP.motor + m]`` gives the m-th one's index in y), their speeds the
        clearance rates (:func:`motor_states`).

    Returns
    -------
    Problem
        State: the clearance vectors, their rates, the LuGre bristles (see
        :func:`clearance_states`), the friction-law quadratures of
        :mod:`workbench.models._friction_report` when LuGre's ``time_above_static_friction``
        or ``time_beyond_friction_law`` is requested, and the energy quadratures when
        ``driver_work`` or ``dissipated_energy`` is. Discrete state: one held onset velocity
        per joint under the Lankarani-Nikravesh law, none under the Hunt-Crossley law.
    """
    present = [j for j in joints if j in effects["clearance"]]
    lugre = effects["friction"] == "lugre"
    moving = bool(present) or bool(motors)
    energy = moving and ("driver_work" in requested or "dissipated_energy" in requested)
    timed = lugre and any(q.name in requested for q in diagnostic_outputs())
    states = motor_states(clearance_states(present, effects["friction"]), present, motors)
    start = {
        q.name: v for m in motors for q, v in zip(motor_states([], [], (m,)), m[2:], strict=True)
    }
    y0 = [float(initial.get(q.name, start.get(q.name, 0.0))) for q in states]
    if timed:
        states += diagnostic_states(present)
        y0 += [0.0, 0.0] * len(present)
    if energy:
        states += ENERGY_STATES
        y0 += [0.0, 0.0]
    nf = 2 * len(present) + len(motors)
    n = len(joints)
    has, slot, z, mu = [0] * n, [-1] * n, [-1] * n, [-1] * n
    free = [-1] * (2 * n + len(motors))
    for m, (_, k, _, _) in enumerate(motors):
        free[2 * len(present) + m] = k
    n_z = len(present) if lugre else 0
    for i, name in enumerate(present):
        j = joints.index(name)
        has[j] = 1
        slot[j] = 2 * i
        free[2 * i : 2 * i + 2] = [n_driven + 2 * j, n_driven + 2 * j + 1]
        if lugre:
            z[j] = 2 * nf + i
        if timed:
            mu[j] = 2 * nf + n_z + 2 * i
    ip = IP.pack(
        {
            "has": has,
            "slot": slot,
            "z": z,
            "mu": mu,
            "friction": FRICTION_CODES[effects["friction"]],
            "energy": int(energy),
            "w": 2 * nf + n_z + (2 * len(present) if timed else 0) if energy else -1,
            "nf": nf,
            "free": free,
            **({"motor": [2 * len(present) + m for m in range(len(motors))]} if motors else {}),
        },
        fill=-1,
        dtype=np.int64,
    )
    stiff = [joints.index(name) for name in present] if lugre else []
    c_min = min(clearances[j] for j in present) if present else 1.0
    codes = failure_messages(assembly)
    held = n if contact_law(effects) == "lankarani_nikravesh" else 0  # held onset velocities
    return Problem(
        hooks=hooks,
        states=tuple(states),
        y0=np.array(y0, dtype=float),
        p=p,
        ip=ip,
        aux0=np.zeros(held),
        event_direction=np.array([1, -1] * len(present), dtype=np.int64),
        atol_scale=state_scales(states, c_min, omega),
        aux_scale=np.full(held, c_min * omega),  # held onset velocities, m s-1
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
    :func:`workbench.models._mechanism_layouts.record_fields`) at every record and returns the
    failure codes; the energy quadratures and the LuGre bristles come from the state.
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
        out["friction_ratio"] = np.abs(per_joint("mu"))
        iz = problem.ip[IP.block("z")]
        if iz.max() >= 0:
            out["lugre_z"] = np.stack([Y[:, iz[j]] for j in cols], axis=1)
        im = problem.ip[IP.block("mu")]
        if im.max() >= 0:
            for k, q in enumerate(diagnostic_outputs()):
                out[q.name] = np.stack([Y[:, im[j] + k] - Y[0, im[j] + k] for j in cols], axis=1)
    iw = problem.ip[IP.w]
    if iw >= 0:  # with a clearance joint or a motor
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
