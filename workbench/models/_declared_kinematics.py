"""Kinematics of a declared linkage with ideal joints: the position, velocity and acceleration of
every point, link angle, centre of mass and slider over time.

The linkage (:mod:`workbench.models._declaration`) is solved as its declaration orders it: the
cranks turn at their constant speeds, then each Assur group solves its bodies from points solved
before it, in closed form (:mod:`workbench.models._assur`: the RRR, RRP and RPR dyads, whose
velocity and acceleration routines solve their differentiated closure equations). The dyads run
compiled over all samples; a body's frame then places its points, the rigid-body transfer
v = v_A + w perp(r), a = a_A + al perp(r) - w^2 r, vectorised in numpy over the samples.

Angles are counter-clockwise from +X (rad): a crank's is ``angle0 + omega t`` as it turns, the
others lie in (-pi, pi]. Units: m, rad, s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from workbench._errors import SceneError
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
from workbench.models._declaration import GROUND, RPR, RRP, RRR, Linkage, Slider

__all__ = ["JOINT_TOLERANCE", "Motion", "Track", "closure_failure", "kinematics"]

#: largest distance (m) between the places two bodies give one joint that counts as closed
JOINT_TOLERANCE = 1e-9


class Track(NamedTuple):
    """A quantity over the samples and its first two time derivatives: arrays (n,) for an
    angle (rad, rad s-1, rad s-2) or a slider position (m, m s-1, m s-2), (n, 2) for a point
    (m, m s-1, m s-2)."""

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray


@dataclass(frozen=True)
class Motion:
    """A linkage's motion at the sample times ``time`` (s, shape (n,)).

    Attributes
    ----------
    time : ndarray (n,)
        Sample times (s).
    points : dict of str to Track
        Every named point (the ground's too), arrays (n, 2).
    angles : dict of str to Track
        The angle of every link and slider frame, arrays (n,).
    centres : dict of str to Track
        The centre of mass of every link and slider, arrays (n, 2).
    sliders : dict of str to Track
        Every slider's position along its guide (``offset + (pin - guide point) . u``), (n,).
    """

    time: np.ndarray
    points: dict[str, Track]
    angles: dict[str, Track]
    centres: dict[str, Track]
    sliders: dict[str, Track]


# -- the dyads over the samples (compiled) ---------------------------------------------------------
@njit(cache=True)
def _rrr(p1, v1, a1, p2, v2, a2, l1, l2, side):
    """RRR dyad per sample: ok, and columns (c1, s1, c2, s2, w1, w2, al1, al2) (NaN where not
    ok)."""
    n = p1.shape[0]
    ok = np.zeros(n, np.bool_)
    out = np.full((n, 8), np.nan)
    for i in range(n):
        good, c1, s1, c2, s2, f1, f2 = rrr_position(
            p1[i, 0], p1[i, 1], p2[i, 0], p2[i, 1], l1, l2, side
        )
        if not good:
            continue
        w1, w2 = rrr_velocity(c1, s1, c2, s2, f1, f2, v1[i, 0], v1[i, 1], v2[i, 0], v2[i, 1])
        al1, al2 = rrr_acceleration(
            c1, s1, c2, s2, f1, f2, l1, l2, w1, w2, a1[i, 0], a1[i, 1], a2[i, 0], a2[i, 1]
        )
        ok[i] = True
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = c1, s1, c2, s2
        out[i, 4], out[i, 5], out[i, 6], out[i, 7] = w1, w2, al1, al2
    return ok, out


@njit(cache=True)
def _rrp(pd, vd, ad, gx, gy, ux, uy, length, side):
    """RRP dyad per sample: ok, and columns (c, s, sE, w, sdot, al, sddot)."""
    n = pd.shape[0]
    ok = np.zeros(n, np.bool_)
    out = np.full((n, 7), np.nan)
    for i in range(n):
        good, c, s, se, fw, fs = rrp_position(pd[i, 0], pd[i, 1], gx, gy, ux, uy, length, side)
        if not good:
            continue
        w, sdot = rrp_velocity(c, s, fw, fs, ux, uy, vd[i, 0], vd[i, 1])
        al, sddot = rrp_acceleration(c, s, fw, fs, length, ux, uy, w, ad[i, 0], ad[i, 1])
        ok[i] = True
        out[i, 0], out[i, 1], out[i, 2] = c, s, se
        out[i, 3], out[i, 4], out[i, 5], out[i, 6] = w, sdot, al, sddot
    return ok, out


@njit(cache=True)
def _rpr(p1, v1, a1, p2, v2, a2, offset, side):
    """RPR dyad per sample: ok, and columns (c, s, h, w, sdot, al, sddot)."""
    n = p1.shape[0]
    ok = np.zeros(n, np.bool_)
    out = np.full((n, 7), np.nan)
    for i in range(n):
        good, c, s, h, f = rpr_position(p1[i, 0], p1[i, 1], p2[i, 0], p2[i, 1], offset, side)
        if not good:
            continue
        vx = v2[i, 0] - v1[i, 0]
        vy = v2[i, 1] - v1[i, 1]
        w, sdot = rpr_velocity(c, s, offset, f, vx, vy)
        al, sddot = rpr_acceleration(
            c, s, offset, f, w, vx, vy, a2[i, 0] - a1[i, 0], a2[i, 1] - a1[i, 1]
        )
        ok[i] = True
        out[i, 0], out[i, 1], out[i, 2] = c, s, h
        out[i, 3], out[i, 4], out[i, 5], out[i, 6] = w, sdot, al, sddot
    return ok, out


# -- frames ----------------------------------------------------------------------------------------
class _Frame(NamedTuple):
    """A body's frame over the samples: rotation (cos, sin), angle track, origin track."""

    c: np.ndarray
    s: np.ndarray
    angle: Track
    origin: Track


def _perp(r: np.ndarray) -> np.ndarray:
    return np.stack([-r[:, 1], r[:, 0]], axis=1)


def _rotate(c: np.ndarray, s: np.ndarray, local) -> np.ndarray:
    x, y = local
    return np.stack([c * x - s * y, s * x + c * y], axis=1)


def _at(frame: _Frame, local) -> Track:
    """The track of the point at ``local`` (m) in a body's frame."""
    r = _rotate(frame.c, frame.s, local)
    w = frame.angle.velocity[:, None]
    al = frame.angle.acceleration[:, None]
    o = frame.origin
    return Track(
        o.position + r, o.velocity + w * _perp(r), o.acceleration + al * _perp(r) - w * w * r
    )


def _frame(c, s, angle: Track, anchor_local, anchor: Track) -> _Frame:
    """The frame with rotation (c, s) and angle track whose point ``anchor_local`` moves along
    the track ``anchor``."""
    r = _rotate(c, s, anchor_local)
    w = angle.velocity[:, None]
    al = angle.acceleration[:, None]
    origin = Track(
        anchor.position - r,
        anchor.velocity - w * _perp(r),
        anchor.acceleration - al * _perp(r) + w * w * r,
    )
    return _Frame(c, s, angle, origin)


def _turn(local_from, ex, ey, w, al) -> tuple[np.ndarray, np.ndarray, Track]:
    """Rotation taking the local direction ``local_from`` to the world unit vectors (ex, ey),
    and the angle track with rates w, al."""
    dx, dy = local_from
    norm = math.hypot(dx, dy)
    dx, dy = dx / norm, dy / norm
    c = dx * ex + dy * ey
    s = dx * ey - dy * ex
    return c, s, Track(np.arctan2(s, c), w, al)


def _direction(a, b) -> tuple[float, float]:
    return (b[0] - a[0], b[1] - a[1])


# -- the pass --------------------------------------------------------------------------------------
class _Pass:
    """One kinematic pass over the samples, solving the linkage as declared."""

    def __init__(self, linkage: Linkage, time: np.ndarray) -> None:
        self.linkage = linkage
        self.time = time
        n = time.size
        zero = np.zeros((n, 2))
        self.points = {
            p: Track(np.broadcast_to(np.array(xy, float), (n, 2)).copy(), zero, zero)
            for p, xy in linkage.ground.items()
        }
        self.owner = dict.fromkeys(linkage.ground, GROUND)
        self.frames: dict[str, _Frame] = {}
        self.sliders: dict[str, Track] = {}
        self.failure: tuple[str, int, str] | None = None  # key, sample, what

    def fail(self, key: str, bad: np.ndarray, what) -> None:
        """Record the first failing sample (the first failure in solving order wins)."""
        if self.failure is None and bad.any():
            i = int(np.argmax(bad))
            self.failure = (key, i, what(i))

    def place(self, body: str, frame: _Frame) -> None:
        self.frames[body] = frame
        for name, local in self.linkage.points_of(body).items():
            track = _at(frame, local)
            if name not in self.points:
                self.points[name], self.owner[name] = track, body
                continue
            gap = np.hypot(*(track.position - self.points[name].position).T)
            other = self.owner[name]
            self.fail(
                self.linkage.bodies()[body].key,
                ~(gap <= JOINT_TOLERANCE),
                lambda i, gap=gap, name=name, other=other: (
                    f"{other!r} and {body!r} put their joint {name!r} {gap[i]:.3g} m apart; no "
                    "group closes this loop (solve one of them by a group through the joint)"
                ),
            )

    def crank(self, crank) -> None:
        link = self.linkage.bodies()[crank.link]
        n = self.time.size
        angle = Track(crank.angle0 + crank.omega * self.time, np.full(n, crank.omega), np.zeros(n))
        c, s = np.cos(angle.position), np.sin(angle.position)
        pivot = link.points[crank.pivot]
        self.place(crank.link, _frame(c, s, angle, pivot, self.points[crank.pivot]))

    def rrr(self, g: RRR) -> None:
        (b1, b2), (k1, k2) = g.links, g.points
        q1, q2 = self.linkage.points_of(b1), self.linkage.points_of(b2)
        l1 = math.dist(q1[k1], q1[g.joint])
        l2 = math.dist(q2[k2], q2[g.joint])
        p1, p2 = self.points[k1], self.points[k2]
        ok, out = _rrr(*p1, *p2, l1, l2, float(g.branch))
        self.fail(
            g.key,
            ~ok,
            lambda i: (
                f"its links {b1!r} ({l1:.6g} m) and {b2!r} ({l2:.6g} m) cannot join {k1!r} and "
                f"{k2!r}, {math.dist(p1.position[i], p2.position[i]):.6g} m apart (they reach "
                f"{abs(l1 - l2):.6g} to {l1 + l2:.6g} m); change the lengths"
            ),
        )
        c, s, angle = _turn(
            _direction(q1[k1], q1[g.joint]), out[:, 0], out[:, 1], out[:, 4], out[:, 6]
        )
        self.place(b1, _frame(c, s, angle, q1[k1], p1))
        c, s, angle = _turn(
            _direction(q2[k2], q2[g.joint]), out[:, 2], out[:, 3], out[:, 5], out[:, 7]
        )
        self.place(b2, _frame(c, s, angle, q2[k2], p2))

    def rrp(self, g: RRP) -> None:
        slider: Slider = self.linkage.bodies()[g.slider]
        q = self.linkage.points_of(g.link)
        length = math.dist(q[g.point], q[slider.pin])
        gx, gy = self.linkage.ground[slider.guide]
        ux, uy = math.cos(slider.angle), math.sin(slider.angle)
        pd = self.points[g.point]
        # signed distance of D from the guide line, cross(u, D - G)
        dist = uy * (gx - pd.position[:, 0]) + ux * (pd.position[:, 1] - gy)
        ok, out = _rrp(*pd, gx, gy, ux, uy, length, float(g.branch))
        self.fail(
            g.key,
            ~ok,
            lambda i: (
                f"link {g.link!r} ({length:.6g} m) cannot reach the guide of {g.slider!r} from "
                f"{g.point!r}, {abs(dist[i]):.6g} m from it; change the length or the guide"
            ),
        )
        c, s, angle = _turn(
            _direction(q[g.point], q[slider.pin]), out[:, 0], out[:, 1], out[:, 3], out[:, 5]
        )
        self.place(g.link, _frame(c, s, angle, q[g.point], pd))
        u = np.array([ux, uy])
        n = self.time.size
        pin = Track(
            np.array([gx, gy]) + out[:, 2, None] * u, out[:, 4, None] * u, out[:, 6, None] * u
        )
        angle = Track(np.full(n, slider.angle), np.zeros(n), np.zeros(n))
        frame = _frame(np.full(n, ux), np.full(n, uy), angle, (0.0, 0.0), pin)
        self.sliders[g.slider] = Track(slider.offset + out[:, 2], out[:, 4], out[:, 6])
        self.place(g.slider, frame)

    def rpr(self, g: RPR) -> None:
        q = self.linkage.points_of(g.guide)
        a, b, pivot = q[g.line[0]], q[g.line[1]], q[g.pivot]
        ux, uy = _direction(a, b)
        norm = math.hypot(ux, uy)
        offset = (-uy * (a[0] - pivot[0]) + ux * (a[1] - pivot[1])) / norm  # perp(u0).(a - P1)
        p1, p2 = self.points[g.pivot], self.points[g.pin]
        ok, out = _rpr(*p1, *p2, offset, float(g.branch))
        self.fail(
            g.key,
            ~ok,
            lambda i: (
                f"the pin {g.pin!r} comes {math.dist(p1.position[i], p2.position[i]):.6g} m from "
                f"the pivot {g.pivot!r}, within the line's offset {abs(offset):.6g} m; move the "
                "line or the pin"
            ),
        )
        c, s, angle = _turn((ux, uy), out[:, 0], out[:, 1], out[:, 3], out[:, 5])
        self.place(g.guide, _frame(c, s, angle, pivot, p1))
        self.place(g.block, _frame(c, s, angle, self.linkage.points_of(g.block)[g.pin], p2))

    def run(self) -> Motion:
        for crank in self.linkage.cranks:
            self.crank(crank)
        solve = {RRR: self.rrr, RRP: self.rrp, RPR: self.rpr}
        for g in self.linkage.groups:
            solve[type(g)](g)
        bodies = self.linkage.bodies()
        return Motion(
            time=self.time,
            points=self.points,
            angles={b: f.angle for b, f in self.frames.items()},
            centres={b: _at(self.frames[b], bodies[b].centre_of_mass) for b in bodies},
            sliders=self.sliders,
        )


def _message(linkage: Linkage, time: np.ndarray, failure: tuple[str, int, str]) -> SceneError:
    key, i, what = failure
    crank = linkage.cranks[0]
    angle = math.degrees(crank.angle0 + crank.omega * time[i]) % 360.0
    return SceneError(
        key,
        f"the loop does not close at crank angle {angle:.2f} deg of crank {crank.link!r} "
        f"(t = {time[i]:.6g} s): {what}",
    )


def kinematics(linkage: Linkage, time) -> Motion:
    """The linkage's motion with ideal joints at the sample times ``time`` (s).

    Parameters
    ----------
    linkage : Linkage
        The declaration.
    time : array_like
        Sample times (s), a scalar or a 1-D array; the cranks' angles are
        ``angle0 + omega t``.

    Returns
    -------
    Motion
        Positions, velocities and accelerations of every point, angle, centre of mass and
        slider.

    Raises
    ------
    SceneError
        Where a loop does not close at a sample, naming the group, the crank angle and why.
    """
    time = np.atleast_1d(np.asarray(time, dtype=float))
    if time.ndim != 1:
        raise ValueError(f"time must be a scalar or a 1-D array, got shape {time.shape}")
    run = _Pass(linkage, time)
    motion = run.run()
    if run.failure is not None:
        raise _message(linkage, time, run.failure)
    return motion


def closure_failure(linkage: Linkage, samples_per_turn: int = 3600) -> SceneError | None:
    """The error of the first place where a loop does not close over one cycle of the linkage
    (:meth:`Linkage.period`), sampled every 1/``samples_per_turn`` of a turn of the fastest
    crank, or None where every loop closes at every sample."""
    period = linkage.period()
    turns = max(abs(c.omega) for c in linkage.cranks) * period / (2 * math.pi)
    n = int(round(samples_per_turn * turns))
    time = np.arange(n) * (period / n)
    run = _Pass(linkage, time)
    run.run()
    return None if run.failure is None else _message(linkage, time, run.failure)
