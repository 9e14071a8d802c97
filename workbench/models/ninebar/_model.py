"""The ``ninebar`` model: declarations, validation, problem building and derived outputs."""

from __future__ import annotations

import math

import numpy as np

from workbench.models import register
from workbench.models._base import Effect, Model, Parameter, Problem
from workbench.models._clearance import (
    ENERGY_STATES,
    FRICTION_CODES,
    FRICTION_EFFECT,
    check_records,
    clearance_states,
    contact_parameters,
    failure_messages,
    friction_block,
    mechanism_outputs,
    state_scales,
    validate_joint,
)
from workbench.models._clearance import stiffness as joint_stiffness
from workbench.models._reduced import N_FP
from workbench.models.ninebar import _dynamics as dyn
from workbench.models.ninebar._geometry import (
    BODY_NAMES,
    DEFAULT_GEOMETRY,
    GEOMETRY_FIELDS,
    INERTIAS,
    MASSES,
)

JOINTS = ("A", "B")

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
_GEOMETRY_BY_FIELD = {f: name for name, f, _, _ in _GEOMETRY_PARAMETERS}


def _parameters() -> tuple[Parameter, ...]:
    pos = {"lower": 0.0, "lower_open": True}
    out = []
    for name, fieldname, long_name, units in _GEOMETRY_PARAMETERS:
        bounds = {} if fieldname in ("O6x", "O6y", "S0", "beta") else pos
        out.append(Parameter(name, DEFAULT_GEOMETRY[fieldname], units, long_name, **bounds))
    for b, body in enumerate(BODY_NAMES):
        out.append(Parameter(f"mass_{body}", MASSES[b], "kg", f"mass of {body}", **pos))
    for b, body in enumerate(BODY_NAMES):
        if INERTIAS[b] > 0:
            out.append(
                Parameter(
                    f"inertia_{body}",
                    INERTIAS[b],
                    "kg m2",
                    f"centroidal moment of inertia of {body}",
                    **pos,
                )
            )
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
class NineBar(Model):
    """Two-DOF nine-bar mechanism with revolute clearance joints A and B (Chen et al. 2019)."""

    name = "ninebar"
    description = (
        "2-DOF nine-bar planar mechanism, cranks driven at -omega and +omega, revolute "
        "clearance joints A (crank 1 / link 2) and B (crank 4 / link 3)"
    )
    reference = (
        "Chen, Jiang, Wang & Deng (2019), Multibody Syst. Dyn. 47:317; parameters: "
        "shared/spec/ninebar-parameters.md"
    )
    parameters = _parameters()
    effects = (
        Effect("clearance", ("A", "B"), "subset", "joints with a radial clearance", JOINTS),
        FRICTION_EFFECT,
        Effect("gravity", True, "bool", "apply gravity"),
    )

    # -- declarations -------------------------------------------------------------------------
    def states(self, effects):
        return tuple(clearance_states(effects["clearance"], effects["friction"]))

    def outputs(self, effects):
        return mechanism_outputs(effects, "slider displacement S9")

    def variables(self, effects):
        return {q.name: q for q in self.outputs(effects)}

    def coords(self, effects):
        return {
            "joint": (list(effects["clearance"]), {"long_name": "clearance joint", "units": "1"}),
            "crank": (["1", "4"], {"long_name": "driven crank", "units": "1"}),
        }

    def forcing_period(self, params):
        return 2.0 * math.pi / params["omega"]

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
    def problem(self, params, effects, initial, requested):
        joints = effects["clearance"]
        lugre = effects["friction"] == "lugre"
        energy = "driver_work" in requested or "dissipated_energy" in requested
        states = list(self.states(effects))
        y0 = [float(initial.get(q.name, 0.0)) for q in states]
        if energy:
            states += ENERGY_STATES
            y0 += [0.0, 0.0]
        p = np.zeros(dyn.N_P)
        for i, f in enumerate(GEOMETRY_FIELDS):
            p[i] = params[_GEOMETRY_BY_FIELD[f]] if f in _GEOMETRY_BY_FIELD else DEFAULT_GEOMETRY[f]
        for b, body in enumerate(BODY_NAMES):
            p[dyn.P_MASS + b] = params[f"mass_{body}"]
            p[dyn.P_INERTIA + b] = params.get(f"inertia_{body}", 0.0)
        g = params["gravity"] if effects["gravity"] else 0.0
        p[dyn.P_GX] = g * math.cos(params["gravity_angle"])
        p[dyn.P_GY] = g * math.sin(params["gravity_angle"])
        p[dyn.P_OMEGA] = params["omega"]
        p[dyn.P_TH10] = params["theta10"]
        p[dyn.P_TH40] = params["theta40"]
        stiffness = {}
        for j, (name, c) in enumerate(self.clearances(params).items()):
            base = dyn.P_JOINT + j * dyn.N_PJ
            r1 = params["bearing_radius"]
            k = joint_stiffness(params, c)
            stiffness[name] = k
            p[base + dyn.PJ_R1] = r1
            p[base + dyn.PJ_R2] = r1 - c
            p[base + dyn.PJ_C] = c
            p[base + dyn.PJ_K] = k
            p[base + dyn.PJ_N] = params["contact_exponent"]
            p[base + dyn.PJ_CE] = params["restitution"]
            p[base + dyn.PJ_DMAX] = params["max_penetration"]
        p[dyn.P_CF : dyn.P_CF + N_FP] = friction_block(params)
        p[dyn.P_VFLOOR] = params["impact_velocity_floor"]

        nf = 2 * len(joints)
        ip = np.full(dyn.N_IP, -1, np.int64)
        ip[dyn.IP_HAS] = int("A" in joints)
        ip[dyn.IP_HAS + 1] = int("B" in joints)
        ip[dyn.IP_FRICTION] = FRICTION_CODES[effects["friction"]]
        ip[dyn.IP_ENERGY] = int(energy)
        ip[dyn.IP_NF] = nf
        for i, j in enumerate(joints):
            ix = 2 + 2 * JOINTS.index(j)
            ip[dyn.IP_FREE + 2 * i] = ix
            ip[dyn.IP_FREE + 2 * i + 1] = ix + 1
            if lugre:
                ip[dyn.IP_Z + JOINTS.index(j)] = 2 * nf + i
        if energy:
            ip[dyn.IP_W] = 2 * nf + (len(joints) if lugre else 0)
        c_min = min(self.clearances(params)[j] for j in joints) if joints else 1.0
        bristles = joints if lugre else ()  # the LuGre bristle states are stiff (ARK548)
        codes = failure_messages(
            "the mechanism cannot be assembled at this configuration (a loop does not close)"
        )
        return Problem(
            hooks="workbench.models.ninebar._dynamics",
            states=tuple(states),
            y0=np.array(y0, dtype=float),
            p=p,
            ip=ip,
            aux0=np.zeros(2),
            event_direction=np.array([1, -1] * len(joints), dtype=np.int64),
            atol_scale=state_scales(states, c_min, params["omega"]),
            t0=0.0,
            work_size=dyn.WORK_SIZE,
            failure=lambda code: codes.get(code, f"model failure code {code}"),
            data={"stiffness": stiffness, "joints": joints},
            stiff_states=[ip[dyn.IP_Z + JOINTS.index(j)] for j in bristles],
            stiff_slots=[dyn.W_JOINT + JOINTS.index(j) * dyn.N_WJ + dyn.WJ_DECAY for j in bristles],
            implicit_slot=dyn.O_HG,
        )

    def derive(self, problem, t, Y, AUX, requested):
        ws = _workspaces(problem, t, Y, AUX)
        joints = problem.data["joints"]
        jcols = [JOINTS.index(j) for j in joints]

        def per_joint(slot):
            return np.stack([ws[:, dyn.W_JOINT + j * dyn.N_WJ + slot] for j in jcols], axis=1)

        out = {}
        if joints:
            out.update(
                clearance_x=per_joint(dyn.WJ_X),
                clearance_y=per_joint(dyn.WJ_Y),
                clearance_vx=per_joint(dyn.WJ_VX),
                clearance_vy=per_joint(dyn.WJ_VY),
                eccentricity=per_joint(dyn.WJ_E),
                penetration=np.maximum(per_joint(dyn.WJ_DELTA), 0.0),
                contact_force=per_joint(dyn.WJ_FN),
                friction_force=per_joint(dyn.WJ_FT),
            )
            iz = problem.ip[dyn.IP_Z : dyn.IP_Z + 2]
            if iz.max() >= 0:
                out["lugre_z"] = np.stack([Y[:, iz[j]] for j in jcols], axis=1)
            iw = problem.ip[dyn.IP_W]
            if iw >= 0:
                out["driver_work"] = Y[:, iw] - Y[0, iw]
                out["dissipated_energy"] = Y[:, iw + 1] - Y[0, iw + 1]
        out["torque"] = ws[:, dyn.W_TAU : dyn.W_TAU + 2]
        out["slider_position"] = ws[:, dyn.W_SLIDER]
        out["slider_velocity"] = ws[:, dyn.W_SLIDER + 1]
        out["slider_acceleration"] = ws[:, dyn.W_SLIDER + 2]
        out["kinetic_energy"] = ws[:, dyn.W_KE]
        out["potential_energy"] = ws[:, dyn.W_PE]
        return {k: v for k, v in out.items() if k in requested}


def _workspaces(problem: Problem, t, Y, AUX) -> np.ndarray:
    """The model's workspace (dyn.W_* layout) at every record."""
    ws = np.empty((t.size, dyn.N_W))
    check_records(problem, t, Y, dyn.evaluate_many(t, Y, problem.p, problem.ip, AUX, ws))
    return ws
