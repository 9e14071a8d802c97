"""The compiled hooks of a declared linkage, generated as Python text: the module that the solver
imports by name for it, as it imports a built-in mechanism's ``_dynamics``.

The text defines, for one declaration (:mod:`workbench.models._declaration`), what a built-in
mechanism's ``_dynamics`` module defines by hand (:mod:`workbench.models.ninebar._dynamics`):

- the layouts ``P``, ``IP``, ``W``, ``RECORD`` and ``MECHANISM``
  (:mod:`workbench.models._mechanism_layouts`) sized for the linkage;
- ``kinematics(q, qd, pos, pts, J, Jp, gam, gamp, vel, velp)``: the linkage's closed-form
  kinematics as straight-line code, the cranks, then each Assur group in the declared order
  through the dyads of :mod:`workbench.models._assur` (positions once, then the velocity pass
  for a unit rate of every coordinate (the Jacobian's columns) and for qd, then the bias
  accelerations at qdd = 0), the geometry folded in as constants;
- ``evaluate``, the record-time evaluation through the mechanisms' shared
  :func:`workbench.models._record.evaluate_mechanism`, and the hooks every mechanism shares
  (:func:`workbench.models._mechanism_hooks.mechanism_hooks`), with ``rhs`` the right-hand side
  that ``evaluate`` gives.

Coordinates q: the cranks' angles (rad) in their declared order, then the clearance vector
(journal centre minus bearing centre, m) of every declared clearance joint, in order; a joint
whose clearance is off keeps its vector at 0 (an ideal pin). A point of a body sits where the
body that solved it first (its *owner*, or the ground) has it, moved by the clearance vector d
when a clearance joins the two bodies there: + d on the journal's side, - d on the bearing's.
So a group's known point, read as the body that the group solves carries it, and a group's own
joint (an RRR's common point, an RRP's slider pin) with a clearance between its two bodies, are
the dyad's inputs shifted by d (an RRR's second known point by + d when its first link carries
the journal, an RRP's known point by - d when its link does).

Rows of the bodies (``pos``, ``J``, ...): the links, the sliders, then two rows without mass: a
marker whose x is the first slider's position along its guide (what the record reads as the
slider's, :class:`workbench.models._record_types.Slider`) and the ground (a bearing may be the
ground). Rows of the points: each clearance joint's bearing centre. Units: SI (m, rad, s, kg).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from workbench.models._declaration import GROUND, RPR, RRP, RRR, Linkage, Slider

__all__ = ["MARKER", "body_rows", "generated_source"]

#: the massless row whose x is the first slider's position along its guide
MARKER = "_slider_position"


def body_rows(linkage: Linkage) -> tuple[str, ...]:
    """The names of the rows of ``pos`` (and ``J``, ``vel``, ``gam``, masses, inertias): the
    links, the sliders, :data:`MARKER`, the ground."""
    return (*(b.name for b in linkage.links), *(s.name for s in linkage.sliders), MARKER, GROUND)


def _f(x: float) -> str:
    """A float literal that reads back to the same double."""
    return repr(float(x))


class _Emitter:
    """Writes the kinematics of one linkage, phase by phase."""

    def __init__(self, linkage: Linkage) -> None:
        self.linkage = linkage
        self.rows = {name: i for i, name in enumerate(body_rows(linkage))}
        self.nc = len(linkage.cranks)
        self.joints = linkage.clearances
        self.lines: list[str] = []
        self.owner: dict[str, str] = dict.fromkeys(linkage.ground, GROUND)
        for body in self.solving_order():
            for point in linkage.points_of(body):
                self.owner.setdefault(point, body)

    # -- the linkage -----------------------------------------------------------------------------
    def solving_order(self) -> list[str]:
        """The moving bodies in the order the cranks and groups solve them."""
        out = [c.link for c in self.linkage.cranks]
        for g in self.linkage.groups:
            out += list(g.moves())
        return out

    def local(self, body: str, point: str) -> tuple[float, float]:
        return self.linkage.points_of(body)[point]

    def shift(self, body: str, point: str) -> list[tuple[int, int]]:
        """(sign, joint index) of the clearance vectors that move ``point`` as ``body`` carries
        it from where its owner has it."""
        owner = self.owner[point]
        out = []
        for j, c in enumerate(self.joints):
            if c.joint != point:
                continue
            sign = (body == c.journal) - (owner == c.journal)
            if sign:
                out.append((sign, j))
        return out

    def between(self, first: str, second: str, point: str) -> list[tuple[int, int]]:
        """(sign, joint) of the clearance vectors d with ``point`` on ``first`` = on ``second``
        + sign d."""
        out = []
        for j, c in enumerate(self.joints):
            if c.joint == point and {c.journal, c.bearing} == {first, second}:
                out.append((1 if first == c.journal else -1, j))
        return out

    # -- emitting ---------------------------------------------------------------------------------
    def emit(self, line: str, indent: int) -> None:
        self.lines.append("    " * indent + line)

    def point(self, phase: str, body: str, local, name: str, indent: int) -> None:
        """Emit ``{name}x, {name}y``: the position, velocity or bias acceleration (``phase``
        "p", "v", "a") of the point at ``local`` (m) of ``body``."""
        lx, ly = (_f(v) for v in local)
        if body == GROUND:
            x, y = (lx, ly) if phase == "p" else ("0.0", "0.0")
            self.emit(f"{name}x = {x}", indent)
            self.emit(f"{name}y = {y}", indent)
            return
        i = self.rows[body]
        rx = f"(c{i} * {lx} - s{i} * {ly})"
        ry = f"(s{i} * {lx} + c{i} * {ly})"
        if phase == "p":
            self.emit(f"{name}x = ox{i} + {rx}", indent)
            self.emit(f"{name}y = oy{i} + {ry}", indent)
        elif phase == "v":
            self.emit(f"{name}x = vx{i} - w{i} * {ry}", indent)
            self.emit(f"{name}y = vy{i} + w{i} * {rx}", indent)
        else:
            self.emit(f"{name}x = ax{i} - al{i} * {ry} - w{i} * w{i} * {rx}", indent)
            self.emit(f"{name}y = ay{i} + al{i} * {rx} - w{i} * w{i} * {ry}", indent)

    def add_shift(self, phase: str, name: str, shifts, indent: int, sign: int = 1) -> None:
        """Add sign times the clearance vectors ``shifts`` (their rates in the velocity pass;
        nothing in the bias pass, at qdd = 0) to ``{name}x, {name}y``."""
        if phase == "a":
            return
        src = "q" if phase == "p" else "u"
        for s, j in shifts:
            k = self.nc + 2 * j
            op = "+" if s * sign > 0 else "-"
            if phase == "p":
                self.emit(f"{name}x {op}= q[{k}]", indent)
                self.emit(f"{name}y {op}= q[{k + 1}]", indent)
            else:
                self.emit(f"{name}x {op}= {src}{k}", indent)
                self.emit(f"{name}y {op}= {src}{k + 1}", indent)

    def known(self, phase: str, body: str, point: str, name: str, indent: int) -> None:
        """Emit the point ``point`` as ``body`` carries it, from its owner's."""
        owner = self.owner[point]
        self.point(phase, owner, self.local(owner, point), name, indent)
        self.add_shift(phase, name, self.shift(body, point), indent)

    def frame(self, phase: str, body: str, anchor_local, anchor: str, indent: int) -> None:
        """Emit body's origin (or its rates) from its rotation (or w, al) and the point
        ``anchor`` (emitted as ``{anchor}x, {anchor}y``) at its local ``anchor_local``."""
        i = self.rows[body]
        lx, ly = (_f(v) for v in anchor_local)
        rx = f"(c{i} * {lx} - s{i} * {ly})"
        ry = f"(s{i} * {lx} + c{i} * {ly})"
        if phase == "p":
            self.emit(f"ox{i} = {anchor}x - {rx}", indent)
            self.emit(f"oy{i} = {anchor}y - {ry}", indent)
        elif phase == "v":
            self.emit(f"vx{i} = {anchor}x + w{i} * {ry}", indent)
            self.emit(f"vy{i} = {anchor}y - w{i} * {rx}", indent)
        else:
            self.emit(f"ax{i} = {anchor}x + al{i} * {ry} + w{i} * w{i} * {rx}", indent)
            self.emit(f"ay{i} = {anchor}y - al{i} * {rx} + w{i} * w{i} * {ry}", indent)

    def turn(self, body: str, direction, c: str, s: str, indent: int) -> None:
        """Emit body's rotation taking its local ``direction`` to the world unit vector (c, s)."""
        i = self.rows[body]
        dx, dy = direction
        norm = math.hypot(dx, dy)
        dx, dy = _f(dx / norm), _f(dy / norm)
        self.emit(f"c{i} = {c} * {dx} + {s} * {dy}", indent)
        self.emit(f"s{i} = {s} * {dx} - {c} * {dy}", indent)

    # -- one pass ----------------------------------------------------------------------------------
    def crank(self, phase: str, k: int, indent: int) -> None:
        crank = self.linkage.cranks[k]
        i = self.rows[crank.link]
        if phase == "p":
            self.emit(f"c{i} = math.cos(q[{k}])", indent)
            self.emit(f"s{i} = math.sin(q[{k}])", indent)
        elif phase == "v":
            self.emit(f"w{i} = u{k}", indent)
        else:
            self.emit(f"al{i} = 0.0", indent)
        name = f"k{i}"
        self.known(phase, crank.link, crank.pivot, name, indent)
        self.frame(phase, crank.link, self.local(crank.link, crank.pivot), name, indent)

    def rrr(self, phase: str, n: int, g: RRR, indent: int) -> None:
        (b1, b2), (k1, k2) = g.links, g.points
        i1, i2 = self.rows[b1], self.rows[b2]
        l1 = math.dist(self.local(b1, k1), self.local(b1, g.joint))
        l2 = math.dist(self.local(b2, k2), self.local(b2, g.joint))
        self.known(phase, b1, k1, f"g{n}p", indent)
        self.known(phase, b2, k2, f"g{n}q", indent)
        # the second link's known point moved so that both reach the first link's joint
        self.add_shift(phase, f"g{n}q", self.between(b1, b2, g.joint), indent)
        r = f"g{n}"
        if phase == "p":
            self.emit(
                f"ok, {r}c1, {r}s1, {r}c2, {r}s2, {r}f1, {r}f2 = rrr_position("
                f"{r}px, {r}py, {r}qx, {r}qy, {_f(l1)}, {_f(l2)}, {_f(g.branch)})",
                indent,
            )
            self.emit("if not ok:", indent)
            self.emit(f"return {n + 1}", indent + 1)
            self.turn(
                b1, _sub(self.local(b1, g.joint), self.local(b1, k1)), f"{r}c1", f"{r}s1", indent
            )
            self.turn(
                b2, _sub(self.local(b2, g.joint), self.local(b2, k2)), f"{r}c2", f"{r}s2", indent
            )
        elif phase == "v":
            self.emit(
                f"w{i1}, w{i2} = rrr_velocity({r}c1, {r}s1, {r}c2, {r}s2, {r}f1, {r}f2, "
                f"{r}px, {r}py, {r}qx, {r}qy)",
                indent,
            )
        else:
            self.emit(
                f"al{i1}, al{i2} = rrr_acceleration({r}c1, {r}s1, {r}c2, {r}s2, {r}f1, {r}f2, "
                f"{_f(l1)}, {_f(l2)}, w{i1}, w{i2}, {r}px, {r}py, {r}qx, {r}qy)",
                indent,
            )
        self.frame(phase, b1, self.local(b1, k1), f"g{n}p", indent)
        # the second link's frame from its known point as it carries it
        self.known(phase, b2, k2, f"g{n}q", indent)
        self.frame(phase, b2, self.local(b2, k2), f"g{n}q", indent)

    def rrp(self, phase: str, n: int, g: RRP, indent: int) -> None:
        slider: Slider = self.linkage.bodies()[g.slider]
        i, js = self.rows[g.link], self.rows[g.slider]
        length = math.dist(self.local(g.link, g.point), self.local(g.link, slider.pin))
        gx, gy = (_f(v) for v in self.linkage.ground[slider.guide])
        ux, uy = _f(math.cos(slider.angle)), _f(math.sin(slider.angle))
        r = f"g{n}"
        self.known(phase, g.link, g.point, f"{r}d", indent)
        # the link's end reaches the slider's pin moved by the clearance vector between them
        self.add_shift(phase, f"{r}d", self.between(g.link, g.slider, slider.pin), indent, -1)
        if phase == "p":
            self.emit(
                f"ok, {r}c, {r}s, {r}e, {r}fw, {r}fs = rrp_position({r}dx, {r}dy, {gx}, {gy}, "
                f"{ux}, {uy}, {_f(length)}, {_f(g.branch)})",
                indent,
            )
            self.emit("if not ok:", indent)
            self.emit(f"return {n + 1}", indent + 1)
            self.turn(
                g.link,
                _sub(self.local(g.link, slider.pin), self.local(g.link, g.point)),
                f"{r}c",
                f"{r}s",
                indent,
            )
            self.emit(f"c{js} = {ux}", indent)
            self.emit(f"s{js} = {uy}", indent)
            self.emit(f"ox{js} = {gx} + {r}e * {ux}", indent)
            self.emit(f"oy{js} = {gy} + {r}e * {uy}", indent)
        elif phase == "v":
            self.emit(
                f"w{i}, {r}sv = rrp_velocity({r}c, {r}s, {r}fw, {r}fs, {ux}, {uy}, {r}dx, {r}dy)",
                indent,
            )
            self.emit(f"w{js} = 0.0", indent)
            self.emit(f"vx{js} = {r}sv * {ux}", indent)
            self.emit(f"vy{js} = {r}sv * {uy}", indent)
        else:
            self.emit(
                f"al{i}, {r}sa = rrp_acceleration({r}c, {r}s, {r}fw, {r}fs, {_f(length)}, "
                f"{ux}, {uy}, w{i}, {r}dx, {r}dy)",
                indent,
            )
            self.emit(f"al{js} = 0.0", indent)
            self.emit(f"ax{js} = {r}sa * {ux}", indent)
            self.emit(f"ay{js} = {r}sa * {uy}", indent)
        self.known(phase, g.link, g.point, f"{r}d", indent)
        self.frame(phase, g.link, self.local(g.link, g.point), f"{r}d", indent)

    def rpr(self, phase: str, n: int, g: RPR, indent: int) -> None:
        q = self.local
        a, b, pivot = q(g.guide, g.line[0]), q(g.guide, g.line[1]), q(g.guide, g.pivot)
        ux, uy = _sub(b, a)
        norm = math.hypot(ux, uy)
        offset = (-uy * (a[0] - pivot[0]) + ux * (a[1] - pivot[1])) / norm
        ig, ib = self.rows[g.guide], self.rows[g.block]
        r = f"g{n}"
        self.known(phase, g.guide, g.pivot, f"{r}p", indent)
        self.known(phase, g.block, g.pin, f"{r}q", indent)
        if phase == "p":
            self.emit(
                f"ok, {r}c, {r}s, {r}h, {r}f = rpr_position({r}px, {r}py, {r}qx, {r}qy, "
                f"{_f(offset)}, {_f(g.branch)})",
                indent,
            )
            self.emit("if not ok:", indent)
            self.emit(f"return {n + 1}", indent + 1)
            self.turn(g.guide, (ux, uy), f"{r}c", f"{r}s", indent)
            self.emit(f"c{ib} = c{ig}", indent)
            self.emit(f"s{ib} = s{ig}", indent)
        elif phase == "v":
            self.emit(
                f"w{ig}, {r}sv = rpr_velocity({r}c, {r}s, {_f(offset)}, {r}f, "
                f"{r}qx - {r}px, {r}qy - {r}py)",
                indent,
            )
            self.emit(f"w{ib} = w{ig}", indent)
        else:
            self.emit(
                f"al{ig}, {r}sa = rpr_acceleration({r}c, {r}s, {_f(offset)}, {r}f, w{ig}, "
                f"{r}vx, {r}vy, {r}qx - {r}px, {r}qy - {r}py)",
                indent,
            )
            self.emit(f"al{ib} = al{ig}", indent)
        self.frame(phase, g.guide, pivot, f"{r}p", indent)
        self.frame(phase, g.block, q(g.block, g.pin), f"{r}q", indent)

    def run(self, phase: str, indent: int) -> None:
        """Every crank and group in order, for one phase."""
        for k in range(self.nc):
            self.crank(phase, k, indent)
        solve: dict[type, Callable] = {RRR: self.rrr, RRP: self.rrp, RPR: self.rpr}
        for n, g in enumerate(self.linkage.groups):
            solve[type(g)](phase, n, g, indent)

    # -- stores ------------------------------------------------------------------------------------
    def store(self, phase: str, body_target: str, point_target: str, indent: int) -> None:
        """Store the bodies' centroids and angles (or rates) and the bearing centres into the
        arrays (``body_target`` e.g. "J[{b}, {r}, k]", "vel[{b}, {r}]")."""
        nb = len(self.rows)
        angle = {"p": "math.atan2(s{i}, c{i})", "v": "w{i}", "a": "al{i}"}[phase]
        for body, i in self.rows.items():
            if body in (MARKER, GROUND):
                continue
            part = self.linkage.bodies()[body]
            self.point(phase, body, part.centre_of_mass, f"m{i}", indent)
            self.emit(f"{body_target.format(b=i, r=0)} = m{i}x", indent)
            self.emit(f"{body_target.format(b=i, r=1)} = m{i}y", indent)
            self.emit(f"{body_target.format(b=i, r=2)} = {angle.format(i=i)}", indent)
        marker = self.rows[MARKER]
        if self.linkage.sliders:
            s = self.linkage.sliders[0]
            i = self.rows[s.name]
            gx, gy = self.linkage.ground[s.guide]
            ux, uy = _f(math.cos(s.angle)), _f(math.sin(s.angle))
            origin = {"p": ("ox", "oy"), "v": ("vx", "vy"), "a": ("ax", "ay")}[phase]
            x = f"{origin[0]}{i}" + (f" - {_f(gx)}" if phase == "p" else "")
            y = f"{origin[1]}{i}" + (f" - {_f(gy)}" if phase == "p" else "")
            self.emit(f"{body_target.format(b=marker, r=0)} = ({x}) * {ux} + ({y}) * {uy}", indent)
        else:
            self.emit(f"{body_target.format(b=marker, r=0)} = 0.0", indent)
        for b in (marker, nb - 1):
            for r in range(3):
                if (b, r) != (marker, 0):
                    self.emit(f"{body_target.format(b=b, r=r)} = 0.0", indent)
        for j, c in enumerate(self.joints):
            self.known(phase, c.bearing, c.joint, f"b{j}", indent)
            self.emit(f"{point_target.format(i=j, r=0)} = b{j}x", indent)
            self.emit(f"{point_target.format(i=j, r=1)} = b{j}y", indent)


def _sub(a, b) -> tuple[float, float]:
    return (a[0] - b[0], a[1] - b[1])


def _kinematics(linkage: Linkage) -> str:
    """The text of the generated ``kinematics``."""
    e = _Emitter(linkage)
    nq = e.nc + 2 * len(linkage.clearances)
    e.emit("@njit(cache=True)", 0)
    e.emit("def kinematics(q, qd, pos, pts, J, Jp, gam, gamp, vel, velp):", 0)
    e.emit(
        '"""Positions, Jacobians, velocities and bias accelerations of the bodies and bearing '
        "centres at (q, qd)\n    (layouts of workbench.models._record_types.Kinematics); 0, or "
        'the number (from 1) of the group\n    that does not close."""',
        1,
    )
    e.emit("# -- positions", 1)
    e.run("p", 1)
    e.store("p", "pos[{b}, {r}]", "pts[{i}, {r}]", 1)
    e.emit("# -- the Jacobian: the velocity pass for a unit rate of each coordinate", 1)
    e.emit(f"for k in range({nq}):", 1)
    for i in range(nq):
        e.emit(f"u{i} = 1.0 if k == {i} else 0.0", 2)
    e.run("v", 2)
    e.store("v", "J[{b}, {r}, k]", "Jp[{i}, {r}, k]", 2)
    e.emit("# -- velocities at qd", 1)
    for i in range(nq):
        e.emit(f"u{i} = qd[{i}]", 1)
    e.run("v", 1)
    e.store("v", "vel[{b}, {r}]", "velp[{i}, {r}]", 1)
    e.emit("# -- bias accelerations (qdd = 0)", 1)
    # the RPR's acceleration needs the relative velocity of its points at qd
    for n, g in enumerate(linkage.groups):
        if isinstance(g, RPR):
            e.emit(f"g{n}vx = g{n}qx - g{n}px", 1)
            e.emit(f"g{n}vy = g{n}qy - g{n}py", 1)
    e.run("a", 1)
    e.store("a", "gam[{b}, {r}]", "gamp[{i}, {r}]", 1)
    e.emit("return 0", 1)
    return "\n".join(e.lines) + "\n"


_HEADER = """# Compiled hooks of a declared mechanism, generated from its declaration by
# workbench.models._declared_source (regenerated from it, never edited): {name}

import math

from numba import njit

from workbench.models._assur import (
    rpr_acceleration,
    rpr_position,
    rpr_velocity,
    rrp_acceleration,
    rrp_position,
    rrp_velocity,
    rrr_acceleration,
    rrr_position,
    rrr_velocity,
)
from workbench.models._layout import layout
from workbench.models._mechanism_hooks import mechanism_hooks
from workbench.models._mechanism_layouts import (
    CODE_ASSEMBLY,
    FRICTION,
    JOINT,
    index_fields,
    record_fields,
    work_fields,
)
from workbench.models._record import evaluate_mechanism, kinematic_arrays
from workbench.models._record_types import MechanismLayout, Slider

N_Q = {nq}
N_CRANKS = {nc}
N_JOINTS = {nj}
N_BODIES = {nb}
N_POINTS = {nj}
P = layout(
    "DeclaredParameters",
    [
        ("mass", N_BODIES),
        ("inertia", N_BODIES),
        ("gx", 1),
        ("gy", 1),
        ("omega", 1),
        ("joint", N_JOINTS * JOINT.size),
        ("friction", FRICTION.size),
    ],
)
IP = layout("DeclaredIndices", index_fields(N_JOINTS))
_RECORD_FIELDS = record_fields(N_Q, N_CRANKS, N_JOINTS)
RECORD = layout("DeclaredRecord", _RECORD_FIELDS)
W = layout("DeclaredWork", [*_RECORD_FIELDS, *work_fields(N_Q, N_BODIES, N_POINTS)])
WORK_SIZE = W.size
MECHANISM = MechanismLayout(
    P=P,
    IP=IP,
    W=W,
    RECORD=RECORD,
    journal={journal},
    bearing={bearing},
    bearing_point={points},
)

"""

_EVALUATE = '''

@njit(cache=True)
def evaluate(t, y, p, ip, aux, work):
    """Everything the model knows at (t, y) into work[:RECORD.size]; 0 or a failure code."""
    omega = p[P.omega]
    nf = ip[IP.nf]
    kin = kinematic_arrays(work, W, N_Q, N_BODIES, N_POINTS)
    q, qd, pos, pts, J, Jp, gam, gamp, vel, velp = kin
    q[:] = 0.0
    qd[:] = 0.0
{cranks}
    for i in range(nf):
        q[ip[IP.free + i]] = y[i]
        qd[ip[IP.free + i]] = y[nf + i]
    if kinematics(q, qd, pos, pts, J, Jp, gam, gamp, vel, velp) != 0:
        return CODE_ASSEMBLY
    slider = Slider(body={marker}, sign=1.0, offset={offset})
    return evaluate_mechanism(y, p, ip, aux, work, MECHANISM, kin, slider)


evaluate_many, rhs_reference, event_values, apply_event = mechanism_hooks(
    __name__, evaluate, MECHANISM
)
rhs = rhs_reference
'''


def generated_source(linkage: Linkage) -> str:
    """The text of the compiled hooks' module of ``linkage`` (see the module's docstring).

    Parameters
    ----------
    linkage : Linkage
        A declaration whose loops close (:func:`workbench.models._declare.declare`).

    Returns
    -------
    str
        Python source defining ``P``, ``IP``, ``W``, ``RECORD``, ``MECHANISM``,
        ``kinematics``, ``evaluate``, ``evaluate_many``, ``rhs``, ``rhs_reference``,
        ``event_values`` and ``apply_event``.
    """
    rows = {name: i for i, name in enumerate(body_rows(linkage))}
    nc, nj = len(linkage.cranks), len(linkage.clearances)
    slowest = min(abs(c.omega) for c in linkage.cranks)
    cranks = []
    for k, c in enumerate(linkage.cranks):
        ratio = _f(c.omega / slowest)
        cranks.append(f"    q[{k}] = {_f(c.angle0)} + {ratio} * omega * t")
        cranks.append(f"    qd[{k}] = {ratio} * omega")
    offset = linkage.sliders[0].offset if linkage.sliders else 0.0
    header = _HEADER.format(
        name=repr(linkage.name),
        nq=nc + 2 * nj,
        nc=nc,
        nj=nj,
        nb=len(rows),
        journal=tuple(rows[c.journal] for c in linkage.clearances),
        bearing=tuple(rows[c.bearing] for c in linkage.clearances),
        points=tuple(range(nj)),
    )
    evaluate = _EVALUATE.format(cranks="\n".join(cranks), marker=rows[MARKER], offset=_f(offset))
    return header + "\n" + _kinematics(linkage) + evaluate
