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
whose clearance is off keeps its vector at 0 (an ideal pin). A motor-driven crank (the only
crank) is a free coordinate, last among the free ones (``ip[IP.motor]``: its angle's index in
the state), with the motor's torque, compiled in, as generalised force.

A point of a body sits where the body that solved it first (its *owner*, or the ground) has it,
moved by the clearance vector d when a clearance joins the two bodies there: + d on the
journal's side, - d on the bearing's. So a group's known point, read as the body that the group
solves carries it, and a group's own joint (an RRR's common point, an RRP's slider pin) with a
clearance between its two bodies, are the dyad's inputs shifted by d (an RRR's second known
point by + d when its first link carries the journal, an RRP's known point by - d when its link
does).

Rows of the bodies (``pos``, ``J``, ...): the links, the sliders, then two rows without mass: a
marker whose x is the first slider's position along its guide (what the record reads as the
slider's, :class:`workbench.models._record_types.Slider`) and the ground (a bearing may be the
ground). Rows of the points: each clearance joint's bearing centre. Units: SI (m, rad, s, kg).
"""

from __future__ import annotations

import math
import re
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
        self.zero: set[str] = set()
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
    # A product with a zero is left out where it is known when generating (x * 0.0 is not folded
    # by the compiler, for NaN and signed zeros): a literal 0.0, or a name holding one
    # (``zero``: a ground point's rates, a crank's or a slider's angular acceleration, ...).
    def emit(self, line: str, indent: int) -> None:
        self.lines.append("    " * indent + line)
        m = _TARGET.match(line)
        if m:
            for name in m.group(1).split(","):
                self.zero.discard(name.strip())

    def assign(self, name: str, expr: str, indent: int) -> None:
        self.emit(f"{name} = {expr}", indent)
        if self.is_zero(expr):
            self.zero.add(name)

    def is_zero(self, expr: str) -> bool:
        return expr == "0.0" or expr in self.zero

    def scale(self, k: float, expr: str) -> str:
        """k expr, k a number known when generating."""
        if k == 0 or self.is_zero(expr):
            return "0.0"
        return expr if k == 1 else f"-{_paren(expr)}" if k == -1 else f"{_f(k)} * {_paren(expr)}"

    def mul(self, a: str, b: str) -> str:
        if self.is_zero(a) or self.is_zero(b):
            return "0.0"
        return f"{a} * {_paren(b)}"

    def add(self, *terms: tuple[int, str]) -> str:
        """The sum of sign * expr, the zeros left out."""
        parts = [(sign, e) for sign, e in terms if not self.is_zero(e)]
        if not parts:
            return "0.0"
        out = ""
        for k, (sign, e) in enumerate(parts):
            if k == 0:
                out = e if sign > 0 else f"-{_paren(e)}"
            else:
                out += f" + {e}" if sign > 0 else f" - {_paren(e)}"
        return out

    def rotated(self, i: int, local) -> tuple[str, str]:
        """R_i local: the body's rotation applied to a local vector (m)."""
        lx, ly = local
        rx = self.add((1, self.scale(lx, f"c{i}")), (-1, self.scale(ly, f"s{i}")))
        ry = self.add((1, self.scale(lx, f"s{i}")), (1, self.scale(ly, f"c{i}")))
        return rx, ry

    def point(self, phase: str, body: str, local, name: str, indent: int) -> None:
        """Emit ``{name}x, {name}y``: the position, velocity or bias acceleration (``phase``
        "p", "v", "a") of the point at ``local`` (m) of ``body``."""
        if body == GROUND:
            x, y = (_f(local[0]), _f(local[1])) if phase == "p" else ("0.0", "0.0")
            self.assign(f"{name}x", "0.0" if x in ("0.0", "-0.0") else x, indent)
            self.assign(f"{name}y", "0.0" if y in ("0.0", "-0.0") else y, indent)
            return
        i = self.rows[body]
        rx, ry = self.rotated(i, local)
        if phase == "p":
            x, y = self.add((1, f"ox{i}"), (1, rx)), self.add((1, f"oy{i}"), (1, ry))
        elif phase == "v":
            x = self.add((1, f"vx{i}"), (-1, self.mul(f"w{i}", ry)))
            y = self.add((1, f"vy{i}"), (1, self.mul(f"w{i}", rx)))
        else:
            w2 = "0.0" if self.is_zero(f"w{i}") else f"w{i} * w{i}"
            x = self.add((1, f"ax{i}"), (-1, self.mul(f"al{i}", ry)), (-1, self.mul(w2, rx)))
            y = self.add((1, f"ay{i}"), (1, self.mul(f"al{i}", rx)), (-1, self.mul(w2, ry)))
        self.assign(f"{name}x", x, indent)
        self.assign(f"{name}y", y, indent)

    def add_shift(self, phase: str, name: str, shifts, indent: int, sign: int = 1) -> None:
        """Add sign times the clearance vectors ``shifts`` (their rates in the velocity pass;
        nothing in the bias pass, at qdd = 0) to ``{name}x, {name}y``."""
        if phase == "a":
            return
        src = "q" if phase == "p" else "u"
        for s, j in shifts:
            k = self.nc + 2 * j
            op = "+" if s * sign > 0 else "-"
            self.emit(f"{name}x {op}= {src}[{k}]", indent)
            self.emit(f"{name}y {op}= {src}[{k + 1}]", indent)

    def known(self, phase: str, body: str, point: str, name: str, indent: int) -> None:
        """Emit the point ``point`` as ``body`` carries it, from its owner's."""
        owner = self.owner[point]
        self.point(phase, owner, self.local(owner, point), name, indent)
        self.add_shift(phase, name, self.shift(body, point), indent)

    def frame(self, phase: str, body: str, anchor_local, anchor: str, indent: int) -> None:
        """Emit body's origin (or its rates) from its rotation (or w, al) and the point
        ``anchor`` (emitted as ``{anchor}x, {anchor}y``) at its local ``anchor_local``."""
        i = self.rows[body]
        rx, ry = self.rotated(i, anchor_local)
        ax, ay = f"{anchor}x", f"{anchor}y"
        if phase == "p":
            self.assign(f"ox{i}", self.add((1, ax), (-1, rx)), indent)
            self.assign(f"oy{i}", self.add((1, ay), (-1, ry)), indent)
        elif phase == "v":
            self.assign(f"vx{i}", self.add((1, ax), (1, self.mul(f"w{i}", ry))), indent)
            self.assign(f"vy{i}", self.add((1, ay), (-1, self.mul(f"w{i}", rx))), indent)
        else:
            w2 = "0.0" if self.is_zero(f"w{i}") else f"w{i} * w{i}"
            x = self.add((1, ax), (1, self.mul(f"al{i}", ry)), (1, self.mul(w2, rx)))
            y = self.add((1, ay), (-1, self.mul(f"al{i}", rx)), (1, self.mul(w2, ry)))
            self.assign(f"ax{i}", x, indent)
            self.assign(f"ay{i}", y, indent)

    def turn(self, body: str, direction, c: str, s: str, indent: int) -> None:
        """Emit body's rotation taking its local ``direction`` to the world unit vector (c, s)."""
        i = self.rows[body]
        dx, dy = direction
        norm = math.hypot(dx, dy)
        dx, dy = dx / norm, dy / norm
        self.assign(f"c{i}", self.add((1, self.scale(dx, c)), (1, self.scale(dy, s))), indent)
        self.assign(f"s{i}", self.add((1, self.scale(dx, s)), (-1, self.scale(dy, c))), indent)

    # -- one pass ----------------------------------------------------------------------------------
    def crank(self, phase: str, k: int, indent: int) -> None:
        crank = self.linkage.cranks[k]
        i = self.rows[crank.link]
        if phase == "p":
            self.emit(f"c{i} = math.cos(q[{k}])", indent)
            self.emit(f"s{i} = math.sin(q[{k}])", indent)
        elif phase == "v":
            self.emit(f"w{i} = u[{k}]", indent)
        else:
            self.assign(f"al{i}", "0.0", indent)
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
            self.emit(f"return {n + 1}, _NO_STATE", indent + 1)
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
        cu, su = _unit(slider.angle)
        ux, uy = _f(cu), _f(su)
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
            self.emit(f"return {n + 1}, _NO_STATE", indent + 1)
            self.turn(
                g.link,
                _sub(self.local(g.link, slider.pin), self.local(g.link, g.point)),
                f"{r}c",
                f"{r}s",
                indent,
            )
            self.assign(f"c{js}", ux, indent)
            self.assign(f"s{js}", uy, indent)
            self.assign(f"ox{js}", self.add((1, gx), (1, self.scale(cu, f"{r}e"))), indent)
            self.assign(f"oy{js}", self.add((1, gy), (1, self.scale(su, f"{r}e"))), indent)
        elif phase == "v":
            self.emit(
                f"w{i}, {r}sv = rrp_velocity({r}c, {r}s, {r}fw, {r}fs, {ux}, {uy}, {r}dx, {r}dy)",
                indent,
            )
            self.assign(f"w{js}", "0.0", indent)
            self.assign(f"vx{js}", self.scale(cu, f"{r}sv"), indent)
            self.assign(f"vy{js}", self.scale(su, f"{r}sv"), indent)
        else:
            self.emit(
                f"al{i}, {r}sa = rrp_acceleration({r}c, {r}s, {r}fw, {r}fs, {_f(length)}, "
                f"{ux}, {uy}, w{i}, {r}dx, {r}dy)",
                indent,
            )
            self.assign(f"al{js}", "0.0", indent)
            self.assign(f"ax{js}", self.scale(cu, f"{r}sa"), indent)
            self.assign(f"ay{js}", self.scale(su, f"{r}sa"), indent)
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
            self.emit(f"return {n + 1}, _NO_STATE", indent + 1)
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

    # -- the passes' values ------------------------------------------------------------------------
    def values(self, phase: str, indent: int) -> list[str]:
        """Emit a pass's values and return them in order: per body row its centroid's x, y and
        angle (or their rates), then per clearance joint its bearing centre's x, y."""
        angle = {"p": "math.atan2(s{i}, c{i})", "v": "w{i}", "a": "al{i}"}[phase]
        out: list[str] = []
        for body, i in self.rows.items():
            if body in (MARKER, GROUND):
                continue
            part = self.linkage.bodies()[body]
            self.point(phase, body, part.centre_of_mass, f"m{i}", indent)
            out += [f"m{i}x", f"m{i}y", angle.format(i=i)]
        if self.linkage.sliders:
            s = self.linkage.sliders[0]
            i = self.rows[s.name]
            gx, gy = self.linkage.ground[s.guide]
            cu, su = _unit(s.angle)
            origin = {"p": ("ox", "oy"), "v": ("vx", "vy"), "a": ("ax", "ay")}[phase]
            x, y = f"{origin[0]}{i}", f"{origin[1]}{i}"
            if phase == "p":
                x, y = self.add((1, x), (-1, _f(gx))), self.add((1, y), (-1, _f(gy)))
            self.assign("marker", self.add((1, self.scale(cu, x)), (1, self.scale(su, y))), indent)
            out += ["marker", "0.0", "0.0"]
        else:
            out += ["0.0", "0.0", "0.0"]
        out += ["0.0", "0.0", "0.0"]  # the ground
        for j, c in enumerate(self.joints):
            self.known(phase, c.bearing, c.joint, f"b{j}", indent)
            out += [f"b{j}x", f"b{j}y"]
        return out


def _unit(angle: float) -> tuple[float, float]:
    """(cos, sin) of an angle (rad), exact where the angle is a multiple of pi / 2 (the guides
    along the axes: no product with a rounded zero)."""
    c, s = math.cos(angle), math.sin(angle)
    return (0.0 if abs(c) < 1e-15 else c), (0.0 if abs(s) < 1e-15 else s)


def _paren(expr: str) -> str:
    """``expr`` in parentheses where it is a sum."""
    return f"({expr})" if " + " in expr or " - " in expr else expr


def _sub(a, b) -> tuple[float, float]:
    return (a[0] - b[0], a[1] - b[1])


_TARGET = re.compile(r"^\s*([A-Za-z_]\w*(?:\s*,\s*[A-Za-z_]\w*)*)\s*[-+]?=[^=]")


def _assigned(lines: list[str]) -> list[str]:
    """The names the lines assign, in order of their first assignment (``ok`` left out)."""
    out: dict[str, None] = {}
    for line in lines:
        m = _TARGET.match(line)
        if m:
            for name in m.group(1).split(","):
                if name.strip() != "ok":
                    out[name.strip()] = None
    return list(out)


def _tuple(names: list[str]) -> str:
    return "(" + ", ".join(names) + ",)"


def _passes(linkage: Linkage) -> tuple[str, list[str], list[str]]:
    """The text of the kinematics' pass functions, the names in the configuration tuple and the
    values of the placement pass."""
    e = _Emitter(linkage)
    e.run("p", 1)
    placement = e.values("p", 1)  # its temporaries go into the configuration
    state = _assigned(e.lines)
    configuration = e.lines
    e.lines = []
    e.run("v", 1)
    # the RPR's acceleration needs the relative velocity of its points at qd
    for n, g in enumerate(linkage.groups):
        if isinstance(g, RPR):
            e.emit(f"g{n}vx = g{n}qx - g{n}px", 1)
            e.emit(f"g{n}vy = g{n}qy - g{n}py", 1)
    inner = _assigned(e.lines)
    rates = e.values("v", 1)
    velocity = e.lines
    e.lines = []
    e.run("a", 1)
    bias = e.lines + [f"    return {_tuple(e.values('a', 1))}"]
    unpack = f"    {_tuple(state)} = state"
    text = [
        '@njit(cache=True, inline="always")',
        "def _configuration(q):",
        '    """Assemble the linkage at the coordinates q (a tuple): (0, state), or (the',
        '    number, from 1, of the group that does not close, zeros)."""',
        *configuration,
        f"    return 0, {_tuple(state)}",
        "",
        "",
        '@njit(cache=True, inline="always")',
        "def _placement(state):",
        '    """Positions: per body row its centroid x, y (m) and angle (rad), then the bearing',
        '    centres (m)."""',
        unpack,
        f"    return {_tuple(placement)}",
        "",
        "",
        '@njit(cache=True, inline="always")',
        "def _velocities(state, u):",
        '    """The velocity pass for the coordinate rates u (a tuple), laid out as',
        "    _placement (with a unit rate: a column of the Jacobian), and what the bias pass",
        '    needs of it."""',
        unpack,
        *velocity,
        f"    return {_tuple(rates)}, {_tuple(inner)}",
        "",
        "",
        '@njit(cache=True, inline="always")',
        "def _bias(state, inner):",
        '    """The accelerations at qdd = 0 for the rates of a velocity pass, laid out as',
        '    _placement."""',
        unpack,
        f"    {_tuple(inner)} = inner",
        *bias,
        "",
    ]
    return "\n".join(text) + "\n", state, placement


def _kinematics(nq: int) -> str:
    """The text of the generated record-time ``kinematics``."""
    q = _tuple([f"q[{i}]" for i in range(nq)])
    qd = _tuple([f"qd[{i}]" for i in range(nq)])
    unit = _tuple([f"1.0 if k == {i} else 0.0" for i in range(nq)])
    return f'''

@njit(cache=True)
def kinematics(q, qd, pos, pts, J, Jp, gam, gamp, vel, velp):
    """Positions, Jacobians, velocities and bias accelerations of the bodies and bearing centres
    at (q, qd) (layouts of workbench.models._record_types.Kinematics); 0, or the number (from 1)
    of the group that does not close."""
    code, state = _configuration({q})
    if code != 0:
        return code
    store_pass(_placement(state), pos, pts)
    for k in range(N_Q):
        store_column(_velocities(state, {unit})[0], J, Jp, k)
    rates, inner = _velocities(state, {qd})
    store_pass(rates, vel, velp)
    store_pass(_bias(state, inner), gam, gamp)
    return 0
'''


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
from workbench.models._base import EVENT_INSIDE_STEP
from workbench.models._layout import layout
from workbench.models._mechanism_hooks import mechanism_hooks
from workbench.models._mechanism_layouts import (
    CODE_ASSEMBLY,
    CODE_NONFINITE,
    CODE_PENETRATION,
    CODE_SINGULAR,
    FRICTION,
    JOINT,
    JOINT_RECORD,
    index_fields,
    record_fields,
    work_fields,
)
from workbench.models._record import (
    evaluate_mechanism,
    kinematic_arrays,
    store_column,
    store_pass,
)
from workbench.models._record_types import MechanismLayout, Slider
from workbench.models._reduced import (
    column_force,
    dissipated_power,
    driver_power,
    friction_excess,
    friction_parameters,
    held_onset,
    joint_parameters,
    lean_joint,
    pass_term,
    spd4_solve,
)

N_Q = {nq}
N_CRANKS = {nc}
N_JOINTS = {nj}
N_BODIES = {nb}
N_POINTS = {nj}
N_STATE = {nstate}  # the configuration tuple's length
_NO_STATE = (0.0,) * N_STATE
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
'''


def _centroids(rows: int, placement: list[str], state: list[str]) -> str:
    """The text of ``_centroids``: per body row (``rows`` of them) its centroid (x, y), then the
    bearing centres, from the ``placement`` pass's values (names in the configuration
    ``state``)."""
    names = [v for k, v in enumerate(placement[: 3 * rows]) if k % 3 != 2]
    names += placement[3 * rows :]
    return "\n".join(
        [
            '@njit(cache=True, inline="always")',
            "def _centroids(state):",
            '    """Per body row its centroid x, y (m), then the bearing centres (m)."""',
            f"    {_tuple(state)} = state",
            f"    return {_tuple(names)}",
            "",
        ]
    )


def _lean_rhs(linkage: Linkage, cranks: list[tuple[str, str]], motor: str | None = None) -> str:
    """The text of the lean right-hand side ``rhs`` (see :func:`generated_source`); ``cranks``:
    per crank the expressions of its angle and rate at t; ``motor``: the expression of the
    torque (N m) of the motor that drives the first crank, whose angle and speed are then free
    coordinates after the clearance vectors (None: every crank turns at its speed)."""
    e = _Emitter(linkage)
    nj, nc, nb = len(linkage.clearances), e.nc, len(e.rows)
    nq = nc + 2 * nj
    nm = 0 if motor is None else 1
    lines: list[str] = []

    def say(line: str = "", indent: int = 1) -> None:
        lines.append("    " * indent + line if line else "")

    say('@njit(cache=True, error_model="numpy", _nrt=False)', 0)
    say("def rhs(t, y, p, ip, aux, work, dydt):", 0)
    say('"""dy/dt at (t, y) (the solver\'s hook): equal to rhs_reference to rounding, computing')
    say('only what the integration reads (the free columns, the contact forces, a 4 x 4 solve)."""')
    say("omega = p[P.omega]")
    say("nf = ip[IP.nf]")
    if motor is not None:
        say("im = ip[IP.motor]")
    for k, (angle, rate) in enumerate(cranks):
        say(f"th{k} = {angle}")
        say(f"om{k} = {rate}")
    if motor is not None:
        say(f"tau = {motor}")
    for j in range(nj):
        say(f"k{j} = ip[IP.slot + {j}]")
        say(f"h{j} = 1.0 if k{j} >= 0 else 0.0")
        say(f"k{j} = max(k{j}, 0)")
        say(f"cx{j} = h{j} * y[k{j}]")
        say(f"cy{j} = h{j} * y[k{j} + 1]")
        say(f"cvx{j} = h{j} * y[nf + k{j}]")
        say(f"cvy{j} = h{j} * y[nf + k{j} + 1]")
        say(f"iz{j} = ip[IP.z + {j}]")
        say(f"z{j} = y[max(iz{j}, 0)]  # read only under LuGre friction")
    q = [f"th{k}" for k in range(nc)] + [v for j in range(nj) for v in (f"cx{j}", f"cy{j}")]
    qd = [f"om{k}" for k in range(nc)] + [v for j in range(nj) for v in (f"cvx{j}", f"cvy{j}")]
    say(f"code, state = _configuration({_tuple(q)})")
    say("if code != 0:")
    say("return CODE_ASSEMBLY", 2)
    say(f"rates, inner = _velocities(state, {_tuple(qd)})")
    say("acc = _bias(state, inner)")
    say("cen = _centroids(state)")
    for f in range(4):
        if f < 2 * nj + nm:
            say(f"f{f} = ip[IP.free + {f}]")
            unit = _tuple([f"1.0 if f{f} == {i} else 0.0" for i in range(nq)])
            say(f"c{f} = _velocities(state, {unit})[0]")
        else:
            say(f"c{f} = _velocities(state, {_tuple(['0.0'] * nq)})[0]")
    say("gx = p[P.gx]")
    say("gy = p[P.gy]")
    say("hg = work[W.hg]")
    say("friction = ip[IP.friction]")
    say("fp = friction_parameters(p, P.friction)")
    forces = []
    for j, c in enumerate(linkage.clearances):
        journal, bearing = e.rows[c.journal], e.rows[c.bearing]
        b = 2 * nb + 2 * j
        say(f"onset{j} = held_onset(aux, {j})")
        say(f"jp{j} = joint_parameters(p, P.joint + {j} * JOINT.size)")
        say(
            f"d{j}, dd{j}, fd{j}, ft{j}, mu{j}, vt{j}, z{j}, zdot{j}, decay{j}, jx{j}, jy{j}, "
            f"bx{j}, by{j}, fx{j}, fy{j}, arm{j}, barm{j} = lean_joint(cx{j}, cy{j}, cvx{j}, "
            f"cvy{j}, onset{j}, z{j}, friction, jp{j}, fp, hg, rates, cen, {journal}, {bearing}, "
            f"(cen[{b}], cen[{b + 1}]))"
        )
        forces.append(f"column_force({{c}}, {journal}, fx{j}, fy{j}, arm{j})")
        if c.bearing != GROUND:
            forces.append(f"column_force({{c}}, {bearing}, -fx{j}, -fy{j}, barm{j})")
    deep = " or ".join(f"d{j} > jp{j}[JOINT.dmax]" for j in range(nj))
    say(f"if {deep}:")
    say("return CODE_PENETRATION", 2)
    moving = [
        e.rows[b.name]
        for b in (*linkage.links, *linkage.sliders)
        if not any(
            c.link == b.name and not c.torque_driven and not e.shift(c.link, c.pivot)
            for c in linkage.cranks
        )
    ]
    if motor is not None:  # the motor's generalised force: its torque on the crank's link
        forces.append(f"column_force({{c}}, {e.rows[linkage.cranks[0].link]}, 0.0, 0.0, tau)")

    def mass(a: str, c: str) -> str:
        return " + ".join(f"pass_term(p, P, {a}, {c}, {b}, 0.0, 0.0)" for b in moving)

    def residual(c: str) -> str:
        inertia = " + ".join(f"pass_term(p, P, {c}, acc, {b}, gx, gy)" for b in moving)
        return " + ".join(f.format(c=c) for f in forces) + f" - ({inertia})"

    if motor is None:
        pad = "pad = 1.0 if nf < 4 else 0.0  # a single joint's 2 x 2 system padded with identity"
        say(f"{pad} rows")
        pads = {2: "pad", 3: "pad"}
    else:
        say("# the system of the nf free coordinates padded with identity rows")
        pads = {r: f"pad{r}" for r in range(1, 4)}
        for r in pads:
            say(f"pad{r} = 1.0 if nf <= {r} else 0.0")
    say("ok, a0, a1, a2, a3 = spd4_solve(")
    for r in range(4):
        for col in range(r + 1):
            pad = f" + {pads[r]}" if r == col and r in pads else ""
            say(f"{mass(f'c{r}', f'c{col}')}{pad},", 2)
    for r in range(4):
        say(f"{residual(f'c{r}')},", 2)
    say(")")
    say("if not ok:")
    say("return CODE_SINGULAR", 2)
    diss = " + ".join(f"dissipated_power(fd{j}, dd{j}, ft{j}, vt{j})" for j in range(nj))
    say(f"p_diss = {diss}")
    zdots = " + ".join(f"zdot{j}" for j in range(nj))
    say(f"if not math.isfinite(a0 + a1 + a2 + a3 + {zdots} + p_diss):")
    say("return CODE_NONFINITE", 2)
    say("for i in range(nf):")
    say("dydt[i] = y[nf + i]", 2)
    say("dydt[nf] = a0")
    if motor is None:
        say("dydt[nf + 1] = a1")
        say("if nf == 4:")
        say("dydt[nf + 2] = a2", 2)
        say("dydt[nf + 3] = a3", 2)
    else:
        for r in range(1, 4):
            say(f"if nf > {r}:")
            say(f"dydt[nf + {r}] = a{r}", 2)
    for j in range(nj):
        say(f"if iz{j} >= 0:")
        say(f"y[iz{j}] = z{j}  # solved in an implicit stage (unchanged otherwise)", 2)
        say(f"dydt[iz{j}] = zdot{j}  # bristles frozen out of contact (reset at onsets)", 2)
        say(f"work[W.joint + {j} * JOINT_RECORD.size + JOINT_RECORD.decay] = decay{j}", 2)
        say(f"im{j} = ip[IP.mu + {j}]")
        say(f"if im{j} >= 0:")
        say(f"dydt[im{j}], dydt[im{j} + 1] = friction_excess(mu{j}, vt{j}, fp)", 2)
    say("iw = ip[IP.w]")
    say("if iw >= 0:")
    driven = _tuple([f"om{k}" for k in range(nc)] + ["0.0"] * (2 * nj))
    masses = _tuple([f"p[P.mass + {b}]" for b in range(nb)])
    inertias = _tuple([f"p[P.inertia + {b}]" for b in range(nb)])
    joint_forces = _tuple(
        [_tuple([f"jx{j}", f"jy{j}", f"bx{j}", f"by{j}", f"fx{j}", f"fy{j}"]) for j in range(nj)]
    )
    if motor is None:
        say(f"power = driver_power({masses}, {inertias}, gx, gy,", 2)
        say(f"_velocities(state, {driven})[0], cen, acc, (c0, c1, c2, c3), (a0, a1, a2, a3),", 3)
        say(f"{joint_forces}, MECHANISM.journal, MECHANISM.bearing)", 3)
    else:
        say("power = tau * om0  # the motor's power, W", 2)
    say("if not math.isfinite(power):", 2)
    say("return CODE_NONFINITE", 3)
    say("dydt[iw] = power", 2)
    say("dydt[iw + 1] = p_diss", 2)
    inside = " or ".join(f"(d{j} > 0.0 and onset{j} == 0.0)" for j in range(nj))
    say(f"if {inside}:")
    say("return EVENT_INSIDE_STEP  # in contact, with no onset velocity held (held_onset)", 2)
    say("return 0")
    return "\n".join(lines) + "\n"


def _motor(crank, speed: str) -> str:
    """The expression of the torque (N m) of a crank's motor at the crank speed ``speed``."""
    if math.isinf(crank.no_load_speed):
        return _f(crank.stall_torque)
    return f"{_f(crank.stall_torque)} * (1.0 - {speed} / {_f(crank.no_load_speed)})"


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
    angles = []
    cranks = []
    motor = None
    for k, c in enumerate(linkage.cranks):
        if c.torque_driven:  # the first and only crank (declared_model checks)
            angles.append(("y[im]", "y[nf + im]"))
            motor = _motor(c, "om0")
            continue
        ratio = _f(c.omega / slowest)
        angles.append((f"{_f(c.angle0)} + {ratio} * omega * t", f"{ratio} * omega"))
        cranks.append(f"    q[{k}] = {angles[-1][0]}")
        cranks.append(f"    qd[{k}] = {angles[-1][1]}")
    offset = linkage.sliders[0].offset if linkage.sliders else 0.0
    passes, state, placement = _passes(linkage)
    header = _HEADER.format(
        name=repr(linkage.name),
        nq=nc + 2 * nj,
        nc=nc,
        nj=nj,
        nb=len(rows),
        nstate=len(state),
        journal=tuple(rows[c.journal] for c in linkage.clearances),
        bearing=tuple(rows[c.bearing] for c in linkage.clearances),
        points=tuple(range(nj)),
    )
    evaluate = _EVALUATE.format(cranks="\n".join(cranks), marker=rows[MARKER], offset=_f(offset))
    if motor is not None:
        header = header.replace(
            'IP = layout("DeclaredIndices", index_fields(N_JOINTS))',
            'IP = layout(\n    "DeclaredIndices",\n'
            '    [*index_fields(N_JOINTS)[:-1], ("free", 2 * N_JOINTS + 1), ("motor", 1)],\n)',
        ).replace("    evaluate_mechanism,\n", "    evaluate_driven,\n")
        evaluate = evaluate.replace(
            "    return evaluate_mechanism(y, p, ip, aux, work, MECHANISM, kin, slider)",
            f"    tau = {_motor(linkage.cranks[0], 'qd[0]')}\n"
            "    return evaluate_driven(y, p, ip, aux, work, MECHANISM, kin, slider, 0, tau)",
        )
    return (
        "\n\n".join(
            [
                header.rstrip("\n"),
                passes.rstrip("\n"),
                _centroids(len(rows), placement, state).rstrip("\n"),
                _kinematics(nc + 2 * nj).strip("\n"),
                evaluate.strip("\n"),
                _lean_rhs(linkage, angles, motor).rstrip("\n"),
            ]
        ).replace("\n\n@njit", "\n\n\n@njit")
        + "\n"
    )
