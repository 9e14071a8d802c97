"""The layouts every mechanism with revolute clearance joints shares
(:mod:`workbench.models._layout`): the friction laws' parameter block, a clearance joint's
parameter block and record, the fields of a mechanism's integer parameters, record and
workspace; and the failure codes of its hooks. Units: SI (m, rad, kg, N, J)."""

from __future__ import annotations

from workbench.models._layout import layout

FRICTION_NONE = 0
FRICTION_COULOMB = 1
FRICTION_LUGRE = 2

# failure codes a mechanism's right-hand side returns (messages: _clearance.failure_messages)
CODE_ASSEMBLY = 1  # the mechanism cannot be assembled (a loop does not close)
CODE_PENETRATION = 2  # penetration beyond parameters.max_penetration
CODE_SINGULAR = 3  # reduced mass matrix not positive definite
CODE_NONFINITE = 4  # non-finite force or acceleration

# the friction laws' parameters (one block per mechanism)
FRICTION = layout(
    "Friction",
    [
        ("cf", 1),  # Coulomb coefficient c_f
        ("v0", 1),  # Coulomb thresholds v0, v1, m s-1
        ("v1", 1),
        ("mu_k", 1),  # LuGre mu_k, mu_s
        ("mu_s", 1),
        ("sigma0", 1),  # LuGre sigma0 (m-1), sigma1, sigma2 (s m-1)
        ("sigma1", 1),
        ("sigma2", 1),
        ("v_s", 1),  # Stribeck velocity, m s-1
        ("gamma", 1),  # Stribeck exponent
        ("v_d", 1),  # velocity of the bristle damping's decay, m s-1 (0: constant sigma1)
    ],
)

# one clearance joint's parameters (one block per joint)
JOINT = layout(
    "Joint",
    [
        ("r1", 1),  # bearing radius, m
        ("r2", 1),  # journal radius, m
        ("c", 1),  # clearance, m
        ("k", 1),  # contact stiffness, N m^-n
        ("n", 1),  # contact exponent
        ("ce", 1),  # restitution
        ("dmax", 1),  # largest allowed penetration, m
        ("vfloor", 1),  # impact-velocity floor of the LN damping, m s-1
        ("law", 1),  # contact law: CONTACT_LAWS code of workbench.models.contact (0 LN, 1 HC)
        ("alpha", 1),  # material damping constant of the Hunt-Crossley law, s m-1
    ],
)

# what the record-time evaluation stores per clearance joint
JOINT_RECORD = layout(
    "JointRecord",
    [
        ("x", 1),  # clearance vector, m
        ("y", 1),
        ("vx", 1),  # its rate, m s-1
        ("vy", 1),
        ("e", 1),  # eccentricity, m
        ("delta", 1),  # e - c, m
        ("ddot", 1),  # penetration rate, m s-1
        ("fn", 1),  # normal force, N
        ("ft", 1),  # friction force on the journal along t, N
        ("mu", 1),  # friction coefficient of the law, -ft / fn (0 out of contact)
        ("above", 1),  # 1 where |mu| > mu_s (LuGre), else 0
        ("beyond", 1),  # 1 where |mu| > the law's envelope 2 mu_s + sigma2 |vt| (LuGre), else 0
        ("vt", 1),  # sliding velocity, m s-1
        ("zdot", 1),  # bristle rate, m s-1
        ("pdiss", 1),  # dissipated power, W
        ("eel", 1),  # elastic contact energy, J
        ("decay", 1),  # decay rate of the LuGre bristle deflection in contact, s-1 (0 otherwise)
    ],
)


def index_fields(n_joints: int) -> list[tuple[str, int]]:
    """Fields of a mechanism's integer array ``ip`` that every mechanism has.

    ``has + j``: 1 if joint j has a clearance; ``slot + j``: index in y of joint j's clearance
    x (its y follows, the rates nf later), -1 if none; ``z + j``: index in y of joint j's
    bristle deflection, -1 if none; ``mu + j``: index in y of joint j's quadrature of the time
    its LuGre friction coefficient exceeds mu_s (the time beyond the law's envelope follows),
    -1 if none; ``friction``: FRICTION_*; ``energy``: 1 if the energy quadratures are
    integrated; ``w``: index in y of the driver-work quadrature (the dissipated energy
    follows), -1 if none; ``nf``: number of free coordinates; ``free + i``: index in q of free
    coordinate i (-1 beyond nf). The free coordinates of joint j are the q[nd + 2 j],
    q[nd + 2 j + 1] after the nd driven ones.
    """
    return [
        ("has", n_joints),
        ("slot", n_joints),
        ("z", n_joints),
        ("mu", n_joints),
        ("friction", 1),
        ("energy", 1),
        ("w", 1),
        ("nf", 1),
        ("free", 2 * n_joints),
    ]


def record_fields(n_q: int, n_cranks: int, n_joints: int) -> list[tuple[str, int]]:
    """Fields of what a mechanism's record-time evaluation stores (its workspace's head):
    full qdd (driven entries 0), driving torques (N m), the per-joint records
    (JOINT_RECORD), slider position, velocity, acceleration (m, m s-1, m s-2), kinetic and
    potential energy (J), driver and dissipated power (W)."""
    return [
        ("qdd", n_q),
        ("tau", n_cranks),
        ("joint", n_joints * JOINT_RECORD.size),
        ("slider", 3),
        ("ke", 1),
        ("pe", 1),
        ("pdrive", 1),
        ("pdiss", 1),
    ]


def work_fields(n_q: int, n_bodies: int, n_points: int) -> list[tuple[str, int]]:
    """Fields of the scratch that follows the record in a mechanism's workspace (the hooks' work
    array): q, qd, the kinematics arrays of the record-time evaluation (see
    :func:`kinematic_arrays`), M, h, Q, and ``hg``, where the solver puts h gamma (s) of an
    implicit ARK548 stage (0 otherwise)."""
    return [
        ("q", n_q),
        ("qd", n_q),
        ("pos", 3 * n_bodies),
        ("pts", 2 * n_points),
        ("J", 3 * n_bodies * n_q),
        ("Jp", 2 * n_points * n_q),
        ("gam", 3 * n_bodies),
        ("gamp", 2 * n_points),
        ("vel", 3 * n_bodies),
        ("velp", 2 * n_points),
        ("M", n_q * n_q),
        ("h", n_q),
        ("Q", n_q),
        ("hg", 1),
    ]
