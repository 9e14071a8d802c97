"""The ``slider_crank`` model: the community benchmark of a revolute clearance joint.

Slider-crank mechanism with a clearance in the joint between the connecting rod and the slider
(Flores, Ambrosio, Claro & Lankarani 2006, Mech. Mach. Theory 41:247; the same case in Flores et
al. 2008, *Kinematics and Dynamics of Multibody Systems with Imperfect Joints*): crank O-A of
length L1 driven at constant speed, rod A-B' of length L2 ideal-pinned to the crank at A, its
end B' a journal in a bearing of the slider, whose pin B = (s, 0) runs on the x axis through O.

Reduced coordinates q = (theta1, x, y) [rad, m, m]: the driven crank angle theta1 = theta10 +
omega t and the clearance vector (x, y) = B' - B. Closed-form kinematics (branch: B to the +x
side of A): sin(theta2) = (y - L1 sin(theta1)) / L2, s = L1 cos(theta1) + L2 cos(theta2) - x.
Bodies (rows of pos, J, gam): crank (centroid at L1/2), rod (centroid at L2/2 from A), slider.
The equations of motion, contact (Lankarani-Nikravesh) and friction (modified Coulomb, LuGre)
are those of every mechanism, :mod:`workbench.models._reduced`; ``x, y`` are the free
coordinates, the crank torque is the motor's reaction. Units SI.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numba import njit

from workbench._errors import SceneError
from workbench.models import register
from workbench.models._base import EVENT_INSIDE_STEP, Effect, Model, Parameter, Problem
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
from workbench.models._reduced import (
    CODE_ASSEMBLY,
    CODE_NONFINITE,
    CODE_PENETRATION,
    CODE_SINGULAR,
    FRICTION_LUGRE,
    N_FP,
    all_finite,
    assemble,
    clearance_joint,
)
from workbench.models.contact import onset_velocity

# -- float parameters p ------------------------------------------------------------------------
P_L1, P_L2, P_LC1, P_LC2 = 0, 1, 2, 3  # crank, rod lengths; their centroid distances, m
P_MASS = 4  # 3 masses, kg
P_INERTIA = 7  # 3 centroidal inertias, kg m2
P_GX, P_GY = 10, 11  # gravity, m s-2
P_OMEGA, P_TH10 = 12, 13  # crank speed (rad s-1), initial crank angle (rad)
P_R1, P_R2, P_C, P_K, P_N, P_CE, P_DMAX, P_VFLOOR = range(14, 22)  # the clearance joint
P_FRICTION = 22  # N_FP friction parameters (layout of _reduced.FP_*)
N_P = P_FRICTION + N_FP
# -- integer parameters ip: has clearance, friction law, energy quadratures on ----------------
IP_HAS, IP_FRICTION, IP_ENERGY = 0, 1, 2
N_IP = 3
# -- workspace of `evaluate` ---------------------------------------------------------------------
W_X, W_Y, W_VX, W_VY, W_E, W_DELTA, W_FN, W_FT = range(8)
W_TAU, W_S, W_SV, W_SA, W_KE, W_PE, W_PDRIVE, W_PDISS, W_XDD, W_YDD, W_ZDOT = range(8, 19)
W_DECAY = 19  # decay rate of the LuGre bristle deflection in contact (s-1; 0 otherwise)
N_W = 20
_O_POS = N_W  # scratch: pos (3x3), J (3x3x3), gam (3x3), M (3x3), h, Q, qd
_O_J = _O_POS + 9
_O_GAM = _O_J + 27
_O_M = _O_GAM + 9
_O_H = _O_M + 9
_O_Q = _O_H + 3
_O_QD = _O_Q + 3
O_HG = _O_QD + 3  # h gamma of an implicit ARK548 stage (s; 0 otherwise), set by the solver
WORK_SIZE = O_HG + 1

_POS = {"lower": 0.0, "lower_open": True}


@njit(cache=True)
def kinematics(th1, w1, x, y, vx, vy, p, pos, J, gam):
    """Bodies' positions, Jacobians (wrt theta1, x, y) and bias accelerations; returns s, or
    NaN where the rod cannot reach the guide."""
    l1, l2, lc1, lc2 = p[P_L1], p[P_L2], p[P_LC1], p[P_LC2]
    c1, s1 = math.cos(th1), math.sin(th1)
    u = (y - l1 * s1) / l2
    if not -1.0 < u < 1.0:
        return math.nan
    s2 = u
    c2 = math.sqrt(1.0 - u * u)
    d2 = (-l1 * c1 / (l2 * c2), 0.0, 1.0 / (l2 * c2))  # d theta2 / d q
    w2 = d2[0] * w1 + d2[2] * vy
    s = l1 * c1 + l2 * c2 - x
    # crank
    pos[0, 0], pos[0, 1], pos[0, 2] = lc1 * c1, lc1 * s1, th1
    # rod
    pos[1, 0], pos[1, 1], pos[1, 2] = l1 * c1 + lc2 * c2, l1 * s1 + lc2 * s2, math.atan2(s2, c2)
    # slider
    pos[2, 0], pos[2, 1], pos[2, 2] = s, 0.0, 0.0
    for b in range(3):
        for r in range(3):
            for k in range(3):
                J[b, r, k] = 0.0
    J[0, 0, 0], J[0, 1, 0], J[0, 2, 0] = -lc1 * s1, lc1 * c1, 1.0
    for k in range(3):
        ja_x = -l1 * s1 if k == 0 else 0.0
        ja_y = l1 * c1 if k == 0 else 0.0
        J[1, 0, k] = ja_x - lc2 * s2 * d2[k]
        J[1, 1, k] = ja_y + lc2 * c2 * d2[k]
        J[1, 2, k] = d2[k]
        J[2, 0, k] = ja_x - l2 * s2 * d2[k] - (1.0 if k == 1 else 0.0)
    # bias accelerations (qdd = 0)
    a2 = (l1 * s1 * w1 * w1 + l2 * s2 * w2 * w2) / (l2 * c2)
    gam[0, 0], gam[0, 1], gam[0, 2] = -lc1 * c1 * w1 * w1, -lc1 * s1 * w1 * w1, 0.0
    ax = -l1 * c1 * w1 * w1
    ay = -l1 * s1 * w1 * w1
    gam[1, 0] = ax - lc2 * (s2 * a2 + c2 * w2 * w2)
    gam[1, 1] = ay + lc2 * (c2 * a2 - s2 * w2 * w2)
    gam[1, 2] = a2
    gam[2, 0] = ax - l2 * (s2 * a2 + c2 * w2 * w2)
    gam[2, 1] = 0.0
    gam[2, 2] = 0.0
    return s


@njit(cache=True)
def evaluate(t, y, p, ip, aux, work):
    """Accelerations, torque, forces and energies at (t, y) into work[:N_W]; 0 or a CODE_*."""
    ws = work
    for i in range(N_W):
        ws[i] = 0.0
    has = ip[IP_HAS] == 1
    x, yy, vx, vy = (y[0], y[1], y[2], y[3]) if has else (0.0, 0.0, 0.0, 0.0)
    w1 = p[P_OMEGA]
    pos = work[_O_POS : _O_POS + 9].reshape((3, 3))
    J = work[_O_J : _O_J + 27].reshape((3, 3, 3))
    gam = work[_O_GAM : _O_GAM + 9].reshape((3, 3))
    s = kinematics(p[P_TH10] + w1 * t, w1, x, yy, vx, vy, p, pos, J, gam)
    if math.isnan(s):
        return CODE_ASSEMBLY
    M = work[_O_M : _O_M + 9].reshape((3, 3))
    h = work[_O_H : _O_H + 3]
    Q = work[_O_Q : _O_Q + 3]
    qd = work[_O_QD : _O_QD + 3]
    qd[0], qd[1], qd[2] = w1, vx, vy
    ke, pe = assemble(
        J, gam, pos, qd, p[P_MASS : P_MASS + 3], p[P_INERTIA : P_INERTIA + 3], p[P_GX], p[P_GY],
        M, h, Q,
    )  # fmt: skip
    xdd = 0.0
    ydd = 0.0
    if has:
        friction = ip[IP_FRICTION]
        z = y[4] if friction == FRICTION_LUGRE else 0.0
        e, delta, ddot, fn, ft, vt, z, zdot, decay, pd, eel = clearance_joint(
            Q, J, pos, qd, 1, 2, s, 0.0, x, yy, vx, vy, aux[0], p[P_R1], p[P_R2], p[P_C],
            p[P_K], p[P_N], p[P_CE], p[P_VFLOOR], friction, p[P_FRICTION : P_FRICTION + N_FP], z,
            work[O_HG],
        )  # fmt: skip
        if friction == FRICTION_LUGRE:
            y[4] = z  # solved in an implicit stage (unchanged otherwise)
        if delta > p[P_DMAX]:
            return CODE_PENETRATION
        ws[W_X], ws[W_Y], ws[W_VX], ws[W_VY] = x, yy, vx, vy
        ws[W_E], ws[W_DELTA], ws[W_FN], ws[W_FT] = e, delta, fn, ft
        ws[W_PDISS] = pd
        pe += eel
        ws[W_ZDOT] = zdot
        ws[W_DECAY] = decay
        # free accelerations: 2 x 2 solve of M_ff qdd_f = Q_f - h_f
        r0 = Q[1] - h[1]
        r1 = Q[2] - h[2]
        det = M[1, 1] * M[2, 2] - M[1, 2] * M[2, 1]
        if not det > 0.0:
            return CODE_SINGULAR
        xdd = (r0 * M[2, 2] - r1 * M[1, 2]) / det
        ydd = (M[1, 1] * r1 - M[2, 1] * r0) / det
    # driving torque (reaction): tau = M_0f qdd_f + h_0 - Q_0
    ws[W_TAU] = M[0, 1] * xdd + M[0, 2] * ydd + h[0] - Q[0]
    ws[W_S] = s
    ws[W_SV] = J[2, 0, 0] * w1 + J[2, 0, 1] * vx + J[2, 0, 2] * vy
    ws[W_SA] = gam[2, 0] + J[2, 0, 1] * xdd + J[2, 0, 2] * ydd
    ws[W_KE] = ke
    ws[W_PE] = pe
    ws[W_PDRIVE] = ws[W_TAU] * w1
    ws[W_XDD] = xdd
    ws[W_YDD] = ydd
    if not all_finite(ws, N_W):
        return CODE_NONFINITE
    return 0


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):
    code = evaluate(t, y, p, ip, aux, work)
    if code != 0:
        return code
    if ip[IP_HAS] == 0:
        return 0
    dydt[0] = y[2]
    dydt[1] = y[3]
    dydt[2] = work[W_XDD]
    dydt[3] = work[W_YDD]
    k = 4
    if ip[IP_FRICTION] == FRICTION_LUGRE:
        # bristles exist only in contact: frozen out of contact (reset at each onset)
        dydt[4] = work[W_ZDOT]
        k = 5
    if ip[IP_ENERGY] == 1:
        dydt[k] = work[W_PDRIVE]
        dydt[k + 1] = work[W_PDISS]
    if aux[0] == 0.0 and work[W_DELTA] > 0.0:
        return EVENT_INSIDE_STEP  # in contact, but its onset has not been located
    return 0


@njit(cache=True)
def event_values(t, y, p, ip, aux, work, g):
    """Penetration e - c (m) of the clearance joint: rising zero = onset, falling = end."""
    if ip[IP_HAS] == 1:
        d = math.sqrt(y[0] * y[0] + y[1] * y[1]) - p[P_C]
        g[0] = d
        g[1] = d


@njit(cache=True)
def apply_event(k, t, y, p, ip, aux, work):
    """Contact onset: hold the normal velocity (and reset the LuGre bristles); end: clear it."""
    if k == 0:
        aux[0] = onset_velocity(y[0], y[1], y[2], y[3])
        if ip[IP_FRICTION] == FRICTION_LUGRE:
            y[4] = 0.0
    else:
        aux[0] = 0.0
    return 0


@njit(cache=True)
def evaluate_many(t, Y, p, ip, AUX, ws):
    """`evaluate` at every record into ws[i, :N_W]; the failure code per record."""
    codes = np.zeros(t.size, np.int64)
    work = np.zeros(WORK_SIZE)
    for i in range(t.size):
        codes[i] = evaluate(t[i], Y[i], p, ip, AUX[i], work)
        ws[i, :] = work[:N_W]
    return codes


JOINTS = ("B",)
_FAILURES = failure_messages("the rod cannot reach the slider guide (|y - L1 sin theta1| >= L2)")


@register
class SliderCrank(Model):
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
    parameters = (
        Parameter("crank_length", 0.05, "m", "length OA of the crank", **_POS),
        Parameter("rod_length", 0.12, "m", "length AB of the connecting rod", **_POS),
        Parameter("crank_centroid", 0.025, "m", "distance of the crank centroid from O", **_POS),
        Parameter("rod_centroid", 0.06, "m", "distance of the rod centroid from A", **_POS),
        Parameter("mass_crank", 0.30, "kg", "mass of the crank", **_POS),
        Parameter("mass_rod", 0.21, "kg", "mass of the connecting rod", **_POS),
        Parameter("mass_slider", 0.14, "kg", "mass of the slider", **_POS),
        Parameter("inertia_crank", 1.0e-4, "kg m2", "centroidal inertia of the crank", **_POS),
        Parameter("inertia_rod", 2.5e-4, "kg m2", "centroidal inertia of the rod", **_POS),
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
    )
    effects = (
        Effect("clearance", ("B",), "subset", "joints with a radial clearance", JOINTS),
        dataclasses.replace(FRICTION_EFFECT, default="none"),
        Effect("gravity", True, "bool", "apply gravity"),
    )

    def states(self, effects):
        return tuple(clearance_states(effects["clearance"], effects["friction"]))

    def outputs(self, effects):
        return mechanism_outputs(effects, "slider position s (pin B on the x axis)")

    def coords(self, effects):
        return {
            "joint": (list(effects["clearance"]), {"long_name": "clearance joint", "units": "1"}),
            "crank": (["1"], {"long_name": "driven crank", "units": "1"}),
        }

    def forcing_period(self, params):
        return 2.0 * math.pi / params["omega"]

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

    def problem(self, params, effects, initial, requested):
        has = bool(effects["clearance"])
        energy = has and ("driver_work" in requested or "dissipated_energy" in requested)
        states = list(self.states(effects))
        y0 = [float(initial.get(q.name, 0.0)) for q in states]
        if energy:
            states += ENERGY_STATES
            y0 += [0.0, 0.0]
        c = params["clearance"]
        g = params["gravity"] if effects["gravity"] else 0.0
        p = np.zeros(N_P)
        p[P_L1], p[P_L2] = params["crank_length"], params["rod_length"]
        p[P_LC1], p[P_LC2] = params["crank_centroid"], params["rod_centroid"]
        p[P_MASS : P_MASS + 3] = [params["mass_crank"], params["mass_rod"], params["mass_slider"]]
        p[P_INERTIA : P_INERTIA + 3] = [params["inertia_crank"], params["inertia_rod"], 0.0]
        p[P_GX] = g * math.cos(params["gravity_angle"])
        p[P_GY] = g * math.sin(params["gravity_angle"])
        p[P_OMEGA], p[P_TH10] = params["omega"], params["theta10"]
        k = joint_stiffness(params, c)
        p[P_R1], p[P_R2], p[P_C] = params["bearing_radius"], params["bearing_radius"] - c, c
        p[P_K], p[P_N], p[P_CE] = k, params["contact_exponent"], params["restitution"]
        p[P_DMAX], p[P_VFLOOR] = params["max_penetration"], params["impact_velocity_floor"]
        p[P_FRICTION : P_FRICTION + N_FP] = friction_block(params)
        ip = np.array([int(has), FRICTION_CODES[effects["friction"]], int(energy)], dtype=np.int64)
        return Problem(
            hooks=__name__,
            states=tuple(states),
            y0=np.array(y0, dtype=float),
            p=p,
            ip=ip,
            aux0=np.zeros(1),
            event_direction=np.array([1, -1] if has else [], dtype=np.int64),
            atol_scale=state_scales(states, c, params["omega"]),
            work_size=WORK_SIZE,
            failure=lambda code: _FAILURES.get(code, f"model failure code {code}"),
            data={"stiffness": {"B": k}, "joints": tuple(effects["clearance"])},
            stiff_states=[4] if has and ip[IP_FRICTION] == FRICTION_LUGRE else [],
            stiff_slots=[W_DECAY] if has and ip[IP_FRICTION] == FRICTION_LUGRE else [],
            implicit_slot=O_HG,
        )

    def derive(self, problem, t, Y, AUX, requested):
        ws = np.empty((t.size, N_W))
        check_records(problem, t, Y, evaluate_many(t, Y, problem.p, problem.ip, AUX, ws))
        out = {
            "torque": ws[:, W_TAU : W_TAU + 1],
            "slider_position": ws[:, W_S],
            "slider_velocity": ws[:, W_SV],
            "slider_acceleration": ws[:, W_SA],
            "kinetic_energy": ws[:, W_KE],
            "potential_energy": ws[:, W_PE],
        }
        if problem.ip[IP_HAS]:
            col = {
                "clearance_x": W_X,
                "clearance_y": W_Y,
                "clearance_vx": W_VX,
                "clearance_vy": W_VY,
                "eccentricity": W_E,
                "contact_force": W_FN,
                "friction_force": W_FT,
            }
            out.update({name: ws[:, i : i + 1] for name, i in col.items()})
            out["penetration"] = np.maximum(ws[:, W_DELTA : W_DELTA + 1], 0.0)
            if problem.ip[IP_FRICTION] == FRICTION_LUGRE:
                out["lugre_z"] = Y[:, 4:5]
            if problem.ip[IP_ENERGY]:
                iw = len(Y[0]) - 2
                out["driver_work"] = Y[:, iw] - Y[0, iw]
                out["dissipated_energy"] = Y[:, iw + 1] - Y[0, iw + 1]
        return {k: v for k, v in out.items() if k in requested}
