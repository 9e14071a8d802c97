"""The grouped arguments of the record-time evaluation (:mod:`workbench.models._record`).

As the solver's loop (:mod:`workbench.solver._loop_types`), the evaluation takes its inputs
besides the model's flat arrays (state ``y``, parameters ``p``, integer parameters ``ip``,
discrete state ``aux``, workspace ``work``) in named tuples instead of twenty positional
arguments:

- :class:`MechanismLayout`: what a mechanism model is to the evaluation (the layouts of its
  arrays; per clearance joint, the bodies and the point it joins), a module global of the
  model that numba freezes to constants;
- :class:`Kinematics`: the kinematics arrays at (q, qd), views into the workspace
  (:func:`workbench.models._record.kinematic_arrays`) that the model's kinematics fills;
- :class:`Slider`: where the slider's record is read;
- :class:`JointState`: one clearance joint at a record (its bodies, bearing centre, clearance
  vector, contact state).

Numba compiles named tuples as plain structs (no boxing) and caches the functions that take
them. Units: SI (m, rad, s; rates per s).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from workbench.models._layout import Layout


class MechanismLayout(NamedTuple):
    """The layouts of a mechanism model's arrays and the bodies and points its clearance joints
    join (constant: a module global of the model)."""

    P: Layout  # parameters p: the fields mass, inertia, gx, gy, joint, friction
    IP: Layout  # integer parameters ip (workbench.models._mechanism_layouts.index_fields)
    W: Layout  # workspace: the record fields, then q, qd, ..., M, h, Q, hg (work_fields)
    RECORD: Layout  # the record, at the head of the workspace
    journal: tuple[int, ...]  # per joint: the journal's body (row of Kinematics.pos)
    bearing: tuple[int, ...]  # per joint: the bearing's body (row of Kinematics.pos)
    bearing_point: tuple[int, ...]  # per joint: the bearing centre (row of Kinematics.pts)


class Kinematics(NamedTuple):
    """The kinematics at (q, qd), as filled by a model's kinematics passes: views into the
    workspace (fields of :func:`workbench.models._mechanism_layouts.work_fields`)."""

    q: np.ndarray  # [n_q] generalised coordinates (rad, m), the driven ones first
    qd: np.ndarray  # [n_q] their rates (rad s-1, m s-1)
    pos: np.ndarray  # [n_bodies, 3] per body: centroid x, y (m), angle (rad)
    pts: np.ndarray  # [n_points, 2] per point: x, y (m)
    J: np.ndarray  # [n_bodies, 3, n_q] d pos / d q_k: m or rad per unit of q_k (rad or m)
    Jp: np.ndarray  # [n_points, 2, n_q] d pts / d q
    gam: np.ndarray  # [n_bodies, 3] bias accelerations (at qdd = 0): m s-2, rad s-2
    gamp: np.ndarray  # [n_points, 2] of the points: m s-2
    vel: np.ndarray  # [n_bodies, 3] velocities: m s-1, rad s-1
    velp: np.ndarray  # [n_points, 2] of the points: m s-1


class Slider(NamedTuple):
    """The slider's record: ``offset + sign * x`` of body ``body``'s centroid (m), and the
    same sign times its velocity (m s-1) and acceleration (m s-2)."""

    body: int  # row of Kinematics.pos
    sign: float  # +1.0 or -1.0
    offset: float  # m


class JointState(NamedTuple):
    """One clearance joint at a record: the bodies it joins, its bearing centre, its clearance
    vector (journal centre - bearing centre) with its rates, and its contact state."""

    journal: int  # the journal's body (row of Kinematics.pos)
    bearing: int  # the bearing's body
    bcx: float  # bearing centre x, m
    bcy: float  # bearing centre y, m
    x: float  # clearance vector x, m
    y: float  # clearance vector y, m
    vx: float  # its rate, m s-1
    vy: float  # m s-1
    onset: float  # normal velocity held from the contact's onset, m s-1 (0: not in contact)
    z: float  # LuGre bristle deflection, m (0 without a bristle state)
