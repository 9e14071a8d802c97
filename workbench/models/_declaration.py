"""A planar linkage declared as data: ground points, links, sliders, driven cranks, the Assur
groups that close its loops, its clearance joints and gravity (SI units).

The same declaration is built from Python (keyword-only dataclasses) or read from a scene's
``[mechanism]`` table (:func:`from_table`; :func:`to_table` writes it back). Every class checks
its own fields when it is built and :class:`Linkage` checks how they refer to each other, each
with one line that names the link, slider, group or joint (a :class:`SceneError` keyed
``mechanism.links[crank].mass``, ...). Whether the loops close over a full crank turn needs the
kinematics: :func:`workbench.models._declare.parse_mechanism` and ``declare`` check it.

Conventions:

- A *point* is named; every body that carries a point of a name is joined there by a revolute
  joint (ground points are carried by the ground). A link gives its points in its own frame,
  whose angle is the link's angle (counter-clockwise from +X, rad).
- A *crank* turns a link about a ground point at a constant speed: the link's angle is
  ``angle0 + omega t``. The cranks' speeds are integer multiples of the slowest one's, so that
  the motion repeats after a turn of the slowest crank (its *cycle*). A crank declared with
  ``drive = "torque"`` is driven by a motor's torque instead (:class:`Crank`), ``omega`` its
  initial speed: its angle and speed are then states, and the motion has no period
  (:mod:`workbench.models._declared_model`).
- A *slider* translates along a fixed guide, the line through a ground point at the angle
  ``angle``; its frame sits at its pin (a point of its own) with +X along the guide, and its
  position is ``offset + (pin - guide point) . u``.
- The groups are solved in their order, after the cranks; each needs its known points solved
  before it (by the ground, a crank or an earlier group) and moves bodies that nothing moved:

  - ``RRR``: two links, each from a known point to their common joint; ``branch`` +1 puts the
    joint left of the first known point -> the second (cross product > 0), -1 right of it.
  - ``RRP``: a link from a known point to the pin of a slider; ``branch`` +1 puts the pin ahead
    of the known point's foot on the guide, along the guide's direction, -1 behind it.
  - ``RPR``: a guide link pivoted at a known point, whose line (through two of its points)
    passes through the known pin of a block that slides along it; the block turns with the
    guide (its frame keeps the guide's angle). ``branch`` +1 puts the pin ahead of the pivot's
    foot on the line, along the direction from the line's first point to its second.

- A clearance sits in a revolute joint between the journal's body and the bearing's body (a
  link, a slider or ``"ground"``), with its own radial clearance and contact and friction
  parameters, named and bounded as the built-in mechanisms name them
  (:func:`workbench.models._clearance.contact_parameters`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

from workbench._errors import SceneError
from workbench.models._clearance import contact_parameters, validate_joint

__all__ = [
    "DRIVES",
    "GROUND",
    "RPR",
    "RRP",
    "RRR",
    "Clearance",
    "Crank",
    "Link",
    "Linkage",
    "Slider",
    "from_table",
    "to_table",
]

#: the body that carries the ground points (a bearing may be the ground)
GROUND = "ground"
#: the contact and friction parameters of a clearance joint, each with its default and bounds
#: (the built-ins' names; a declared joint has no friction unless it declares a coefficient)
CONTACT_PARAMETERS = {
    p.name: p for p in contact_parameters(clearance=0.5e-3, friction_coefficient=0.0)
}
_D = {name: p.default for name, p in CONTACT_PARAMETERS.items()}


# -- field checks ----------------------------------------------------------------------------------
def _name(value: Any, key: str) -> str:
    if not isinstance(value, str) or not value:
        raise SceneError(key, f"got {value!r}; a name is a non-empty string")
    return value


def _number(value: Any, key: str, units: str, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SceneError(key, f"got {value!r}; must be a finite number ({units})")
    if positive and not value > 0:
        raise SceneError(key, f"got {value!r} {units}; must be positive")
    return float(value)


def _pair(value: Any, key: str) -> tuple[float, float]:
    if isinstance(value, (str, Mapping)) or not isinstance(value, Sequence) or len(value) != 2:
        raise SceneError(key, f"got {value!r}; must be a pair [x, y] of numbers (m)")
    return (_number(value[0], key, "m"), _number(value[1], key, "m"))


def _names(value: Any, key: str, count: int) -> tuple[str, ...]:
    if isinstance(value, (str, Mapping)) or not isinstance(value, Sequence) or len(value) != count:
        raise SceneError(key, f"got {value!r}; must be a list of {count} names")
    return tuple(_name(v, key) for v in value)


def _points(value: Any, key: str) -> dict[str, tuple[float, float]]:
    if not isinstance(value, Mapping) or not value:
        raise SceneError(key, f"got {value!r}; must map point names to pairs [x, y] (m)")
    return {_name(n, key): _pair(xy, f"{key}.{n}") for n, xy in value.items()}


def _branch(value: Any, key: str) -> int:
    if isinstance(value, bool) or value not in (1, -1):
        raise SceneError(key, f"got {value!r}; a branch is +1 or -1")
    return int(value)


def _set(obj: Any, **values: Any) -> None:
    for name, value in values.items():
        object.__setattr__(obj, name, value)


class _Part:
    """What every part of a declaration has: the key of its table in the scene,
    ``mechanism.<section>[<its name>]``, for the messages that name it."""

    section: ClassVar[str]
    named_by: ClassVar[str] = "name"

    @property
    def key(self) -> str:
        """Where the part's fields are, in the scene."""
        return f"mechanism.{self.section}[{getattr(self, self.named_by)}]"

    def _named(self) -> str:
        """Check the part's name; its key."""
        _name(getattr(self, self.named_by), f"mechanism.{self.section}.{self.named_by}")
        return self.key


# -- the parts -----------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class Link(_Part):
    """A rigid link: its points in its own frame (m), mass (kg), moment of inertia about its
    centre of mass (kg m2) and centre of mass in its frame (m)."""

    section = "links"

    name: str
    points: Mapping[str, tuple[float, float]]
    mass: float
    inertia: float
    centre_of_mass: tuple[float, float]

    def __post_init__(self) -> None:
        key = self._named()
        _set(
            self,
            points=_points(self.points, f"{key}.points"),
            mass=_number(self.mass, f"{key}.mass", "kg", positive=True),
            inertia=_number(self.inertia, f"{key}.inertia", "kg m2", positive=True),
            centre_of_mass=_pair(self.centre_of_mass, f"{key}.centre_of_mass"),
        )


@dataclass(frozen=True, kw_only=True)
class Slider(_Part):
    """A body that translates along a fixed guide, the line through the ground point ``guide``
    at the angle ``angle`` (rad); ``pin`` names the point at its frame's origin, ``offset`` (m)
    shifts its position along the guide, ``centre_of_mass`` is in its frame (m, +X along the
    guide)."""

    section = "sliders"

    name: str
    pin: str
    guide: str
    angle: float
    mass: float
    offset: float = 0.0
    centre_of_mass: tuple[float, float] = (0.0, 0.0)

    @property
    def points(self) -> dict[str, tuple[float, float]]:
        """The slider's one point, its pin, at its frame's origin (m)."""
        return {self.pin: (0.0, 0.0)}

    def __post_init__(self) -> None:
        key = self._named()
        _set(
            self,
            pin=_name(self.pin, f"{key}.pin"),
            guide=_name(self.guide, f"{key}.guide"),
            angle=_number(self.angle, f"{key}.angle", "rad"),
            mass=_number(self.mass, f"{key}.mass", "kg", positive=True),
            offset=_number(self.offset, f"{key}.offset", "m"),
            centre_of_mass=_pair(self.centre_of_mass, f"{key}.centre_of_mass"),
        )


#: how a crank is driven: at its constant speed, or by a motor's torque
DRIVES = ("speed", "torque")


@dataclass(frozen=True, kw_only=True)
class Crank(_Part):
    """A link driven about the ground point ``pivot`` (one of its points), counter-clockwise
    positive.

    ``drive = "speed"`` (the default): it turns at the constant speed ``omega`` (rad s-1), its
    angle is ``angle0 + omega t`` (rad). ``drive = "torque"``: a motor with the linear
    characteristic of a DC motor drives it, tau = stall_torque (1 - theta_dot / no_load_speed)
    (N m; ``no_load_speed`` rad s-1, infinite by default: a constant torque), ``omega`` being
    its speed at t = 0 (rad s-1); only a torque-driven crank has ``stall_torque`` and
    ``no_load_speed``.
    """

    section = "cranks"
    named_by = "link"

    link: str
    pivot: str
    omega: float
    angle0: float = 0.0
    drive: str = "speed"
    stall_torque: float | None = None
    no_load_speed: float | None = None

    @property
    def torque_driven(self) -> bool:
        """Whether a motor's torque drives the crank (its speed is then a state)."""
        return self.drive == "torque"

    def __post_init__(self) -> None:
        key = self._named()
        _set(
            self,
            pivot=_name(self.pivot, f"{key}.pivot"),
            omega=_number(self.omega, f"{key}.omega", "rad s-1"),
            angle0=_number(self.angle0, f"{key}.angle0", "rad"),
        )
        if self.omega == 0:
            raise SceneError(f"{key}.omega", "got 0 rad s-1; a driven crank turns (omega != 0)")
        if self.drive not in DRIVES:
            raise SceneError(
                f"{key}.drive",
                f"got {self.drive!r}; a crank's drive is one of {', '.join(map(repr, DRIVES))}",
            )
        if not self.torque_driven:
            for field in ("stall_torque", "no_load_speed"):
                if getattr(self, field) is not None:
                    raise SceneError(
                        f"{key}.{field}",
                        f"got {getattr(self, field)!r}; only a torque-driven crank has it "
                        '(set drive = "torque", or remove it)',
                    )
            return
        if self.stall_torque is None:
            raise SceneError(
                f"{key}.stall_torque",
                'missing; a crank with drive = "torque" declares its motor\'s stall torque (N m)',
            )
        _set(self, stall_torque=_number(self.stall_torque, f"{key}.stall_torque", "N m"))
        speed = math.inf if self.no_load_speed is None else self.no_load_speed
        if isinstance(speed, bool) or not isinstance(speed, (int, float)) or not speed > 0:
            raise SceneError(
                f"{key}.no_load_speed",
                f"got {speed!r}; a motor's no-load speed is positive (rad s-1), or inf for a "
                "constant torque",
            )
        _set(self, no_load_speed=float(speed))

    def motor_torque(self, speed: float) -> float:
        """The torque (N m) the crank's motor applies at the crank speed ``speed`` (rad s-1)."""
        return self.stall_torque * (1.0 - speed / self.no_load_speed)


@dataclass(frozen=True, kw_only=True)
class RRR(_Part):
    """RRR dyad: ``links[i]`` runs from the known point ``points[i]`` to the common ``joint``."""

    section = "groups"

    name: str
    links: tuple[str, str]
    points: tuple[str, str]
    joint: str
    branch: int

    kind = "RRR"

    def __post_init__(self) -> None:
        key = self._named()
        _set(
            self,
            links=_names(self.links, f"{key}.links", 2),
            points=_names(self.points, f"{key}.points", 2),
            joint=_name(self.joint, f"{key}.joint"),
            branch=_branch(self.branch, f"{key}.branch"),
        )

    def known(self) -> tuple[tuple[str, str], ...]:
        """(body, point) pairs the group needs solved before it."""
        return tuple(zip(self.links, self.points, strict=True))

    def moves(self) -> tuple[str, ...]:
        """The bodies the group solves."""
        return self.links


@dataclass(frozen=True, kw_only=True)
class RRP(_Part):
    """RRP dyad: ``link`` runs from the known ``point`` to the pin of ``slider``."""

    section = "groups"

    name: str
    link: str
    point: str
    slider: str
    branch: int

    kind = "RRP"

    def __post_init__(self) -> None:
        key = self._named()
        _set(
            self,
            link=_name(self.link, f"{key}.link"),
            point=_name(self.point, f"{key}.point"),
            slider=_name(self.slider, f"{key}.slider"),
            branch=_branch(self.branch, f"{key}.branch"),
        )

    def known(self) -> tuple[tuple[str, str], ...]:
        """(body, point) pairs the group needs solved before it."""
        return ((self.link, self.point),)

    def moves(self) -> tuple[str, ...]:
        """The bodies the group solves."""
        return (self.link, self.slider)


@dataclass(frozen=True, kw_only=True)
class RPR(_Part):
    """RPR dyad: the link ``guide`` turns about its known point ``pivot``; its line through
    its points ``line[0]`` -> ``line[1]`` passes through the known ``pin`` of the link
    ``block``, which slides along it and turns with it."""

    section = "groups"

    name: str
    guide: str
    block: str
    pivot: str
    pin: str
    line: tuple[str, str]
    branch: int

    kind = "RPR"

    def __post_init__(self) -> None:
        key = self._named()
        _set(
            self,
            guide=_name(self.guide, f"{key}.guide"),
            block=_name(self.block, f"{key}.block"),
            pivot=_name(self.pivot, f"{key}.pivot"),
            pin=_name(self.pin, f"{key}.pin"),
            line=_names(self.line, f"{key}.line", 2),
            branch=_branch(self.branch, f"{key}.branch"),
        )

    def known(self) -> tuple[tuple[str, str], ...]:
        """(body, point) pairs the group needs solved before it."""
        return ((self.guide, self.pivot), (self.block, self.pin))

    def moves(self) -> tuple[str, ...]:
        """The bodies the group solves."""
        return (self.guide, self.block)


GROUP_KINDS = {cls.kind: cls for cls in (RRR, RRP, RPR)}
Group = RRR | RRP | RPR


@dataclass(frozen=True, kw_only=True)
class Clearance(_Part):
    """A radial clearance (m) in the revolute joint ``joint`` between the journal's body and
    the bearing's body, with its contact and friction parameters (names, units and bounds of
    the built-in mechanisms: :data:`CONTACT_PARAMETERS`)."""

    section = "clearances"
    named_by = "joint"

    joint: str
    journal: str
    bearing: str
    clearance: float
    bearing_radius: float = _D["bearing_radius"]
    youngs_modulus: float = _D["youngs_modulus"]
    poisson_ratio: float = _D["poisson_ratio"]
    contact_stiffness: float = _D["contact_stiffness"]
    contact_exponent: float = _D["contact_exponent"]
    restitution: float = _D["restitution"]
    impact_velocity_floor: float = _D["impact_velocity_floor"]
    hunt_crossley_damping: float = _D["hunt_crossley_damping"]
    max_penetration: float = _D["max_penetration"]
    friction_coefficient: float = _D["friction_coefficient"]
    coulomb_v0: float = _D["coulomb_v0"]
    coulomb_v1: float = _D["coulomb_v1"]
    lugre_mu_k: float = _D["lugre_mu_k"]
    lugre_mu_s: float = _D["lugre_mu_s"]
    lugre_sigma0: float = _D["lugre_sigma0"]
    lugre_sigma1: float = _D["lugre_sigma1"]
    lugre_damping_velocity: float = _D["lugre_damping_velocity"]
    lugre_sigma2: float = _D["lugre_sigma2"]
    lugre_stribeck_velocity: float = _D["lugre_stribeck_velocity"]
    lugre_stribeck_exponent: float = _D["lugre_stribeck_exponent"]

    def parameters(self) -> dict[str, float]:
        """The joint's contact and friction parameters by the built-ins' names (SI)."""
        return {name: getattr(self, name) for name in CONTACT_PARAMETERS}

    def __post_init__(self) -> None:
        key = self._named()
        _set(self, journal=_name(self.journal, f"{key}.journal"))
        _set(self, bearing=_name(self.bearing, f"{key}.bearing"))
        for name, p in CONTACT_PARAMETERS.items():
            value = _number(getattr(self, name), f"{key}.{name}", p.units)
            rule = p.check(value)
            if rule is not None:
                raise SceneError(f"{key}.{name}", f"got {value!r}; {rule}")
            _set(self, **{name: value})
        validate_joint(self.parameters(), self.clearance, f"{key}.clearance")
        if self.journal == self.bearing:
            raise SceneError(
                f"{key}.bearing",
                f"got {self.bearing!r}, the journal's body; a joint joins two bodies",
            )


# -- the linkage -----------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class Linkage:
    """A planar linkage: ground points (m), links, sliders, driven cranks, the groups that close
    its loops (solved in order after the cranks), its clearance joints and gravity (m s-2,
    along ``gravity_angle`` rad counter-clockwise from +X). Checked when built, but for the
    closure of its loops over a cycle (``workbench.models._declare.declare``)."""

    name: str
    ground: Mapping[str, tuple[float, float]]
    links: tuple[Link, ...]
    cranks: tuple[Crank, ...]
    groups: tuple[Group, ...] = ()
    sliders: tuple[Slider, ...] = ()
    clearances: tuple[Clearance, ...] = ()
    gravity: float = 9.81
    gravity_angle: float = -math.pi / 2

    def __post_init__(self) -> None:
        _set(
            self,
            name=_name(self.name, "mechanism.name"),
            ground=_points(self.ground, "mechanism.ground"),
            links=tuple(self.links),
            cranks=tuple(self.cranks),
            groups=tuple(self.groups),
            sliders=tuple(self.sliders),
            clearances=tuple(self.clearances),
            gravity=_number(self.gravity, "mechanism.gravity", "m s-2"),
            gravity_angle=_number(self.gravity_angle, "mechanism.gravity_angle", "rad"),
        )
        if self.gravity < 0:
            raise SceneError(
                "mechanism.gravity", f"got {self.gravity!r} m s-2; must be >= 0 (its direction "
                "is gravity_angle)"
            )  # fmt: skip
        self._check_names()
        self._check_order()
        self._check_clearances()
        self.period()  # the cranks' speeds

    # -- lookups ---------------------------------------------------------------------------------
    def bodies(self) -> dict[str, Link | Slider]:
        """The moving bodies (links, then sliders) by name."""
        return {b.name: b for b in (*self.links, *self.sliders)}

    def points_of(self, body: str) -> Mapping[str, tuple[float, float]]:
        """The points of a body (or of the ground) in its frame (m)."""
        return self.ground if body == GROUND else self.bodies()[body].points

    def period(self) -> float:
        """The cycle (s): a turn of the slowest crank, after which every crank has turned a
        whole number of times."""
        slowest = min(abs(c.omega) for c in self.cranks)
        for c in self.cranks:
            ratio = abs(c.omega) / slowest
            if abs(ratio - round(ratio)) > 1e-9 * ratio:
                raise SceneError(
                    f"{c.key}.omega",
                    f"got {c.omega!r} rad s-1, {ratio:.6g} times the slowest crank's; the "
                    "cranks' speeds must be whole multiples of the slowest (a periodic motion)",
                )
        return 2 * math.pi / slowest

    # -- checks ------------------------------------------------------------------------------------
    def _check_names(self) -> None:
        for what, cls, parts in (
            ("links", Link, self.links),
            ("sliders", Slider, self.sliders),
            ("cranks", Crank, self.cranks),
            ("groups", (RRR, RRP, RPR), self.groups),
            ("clearances", Clearance, self.clearances),
        ):
            for part in parts:
                if not isinstance(part, cls):
                    raise SceneError(f"mechanism.{what}", f"got {part!r}; not one of the {what}")
        for what, parts in (
            ("links and sliders", (*self.links, *self.sliders)),
            ("groups", self.groups),
            ("cranks", self.cranks),
            ("clearances", self.clearances),
        ):
            seen = {GROUND} if what == "links and sliders" else set()
            for part in parts:
                n = getattr(part, part.named_by)
                if n in seen:
                    raise SceneError(
                        part.key,
                        f"the name {n!r} is used twice among the {what}"
                        + (" (the ground's)" if n == GROUND else "")
                        + "; names are unique",
                    )
                seen.add(n)
        if not self.cranks:
            raise SceneError("mechanism.cranks", "got none; a linkage is driven by a crank")

    def _body(self, name: str, key: str, sliders: bool = True) -> Link | Slider:
        body = self.bodies().get(name)
        if body is None or (isinstance(body, Slider) and not sliders):
            kind, kinds = ("link or slider", "links and sliders") if sliders else ("link", "links")
            names = [b.name for b in self.links] + ([s.name for s in self.sliders] * sliders)
            raise SceneError(
                key, f"got {name!r}, no {kind} of that name; the {kinds}: {', '.join(names)}"
            )
        return body

    def _point(self, body: str, point: str, key: str) -> None:
        points = self.points_of(body)
        if point in points:
            return
        everywhere = {p for b in (GROUND, *self.bodies()) for p in self.points_of(b)}
        known = "an unknown point" if point not in everywhere else "a point of another body"
        raise SceneError(
            key,
            f"references {known} {point!r}; the points of {body!r}: {', '.join(points)}",
        )

    def _check_order(self) -> None:
        """Cranks then groups in order: each needs its points known and moves new bodies."""
        moved: dict[str, str] = {}  # body -> what moves it
        known = set(self.ground)

        def move(body: str, by: str, key: str) -> None:
            if body in moved:
                raise SceneError(
                    key, f"moves {body!r}, which {moved[body]} moves already; a body moves once"
                )
            moved[body] = by
            known.update(self.points_of(body))

        for c in self.cranks:
            self._body(c.link, f"{c.key}.link", sliders=False)
            if c.pivot not in self.ground:
                raise SceneError(
                    f"{c.key}.pivot",
                    f"got {c.pivot!r}; a crank turns about a ground point: "
                    f"{', '.join(self.ground)}",
                )
            self._point(c.link, c.pivot, f"{c.key}.pivot")
            move(c.link, f"crank {c.link!r}", c.key)
        for s in self.sliders:
            if s.guide not in self.ground:
                raise SceneError(
                    f"{s.key}.guide",
                    f"got {s.guide!r}; a guide passes through a ground point: "
                    f"{', '.join(self.ground)}",
                )
        for g in self.groups:
            self._check_group(g)
            for body, point in g.known():
                if point not in known:
                    raise SceneError(
                        g.key,
                        f"needs the point {point!r} of {body!r}, which no crank or earlier "
                        "group solves; list the groups in the order they can be solved",
                    )
            for body in g.moves():
                move(body, f"group {g.name!r}", g.key)
        for body in self.bodies().values():
            if body.name not in moved:
                raise SceneError(
                    body.key,
                    f"{body.name!r} is moved by no crank or group; add the group that solves it",
                )

    def _check_group(self, g: Group) -> None:
        if isinstance(g, RRR):
            for link, point in g.known():
                self._body(link, f"{g.key}.links", sliders=False)
                self._point(link, point, f"{g.key}.points")
                self._point(link, g.joint, f"{g.key}.joint")
                if self.points_of(link)[point] == self.points_of(link)[g.joint]:
                    raise SceneError(
                        f"{g.key}.links",
                        f"link {link!r} has its points {point!r} and {g.joint!r} at one place; "
                        "they must lie apart",
                    )
            if g.links[0] == g.links[1]:
                raise SceneError(f"{g.key}.links", "names one link twice; an RRR joins two links")
        elif isinstance(g, RRP):
            self._body(g.link, f"{g.key}.link", sliders=False)
            slider = self._body(g.slider, f"{g.key}.slider")
            if not isinstance(slider, Slider):
                raise SceneError(f"{g.key}.slider", f"got {g.slider!r}, a link; name a slider")
            self._point(g.link, g.point, f"{g.key}.point")
            self._point(g.link, slider.pin, f"{g.key}.link")
            if self.points_of(g.link)[g.point] == self.points_of(g.link)[slider.pin]:
                raise SceneError(
                    f"{g.key}.link",
                    f"link {g.link!r} has {g.point!r} and the pin {slider.pin!r} at one place",
                )
        else:
            self._body(g.guide, f"{g.key}.guide", sliders=False)
            self._body(g.block, f"{g.key}.block", sliders=False)
            self._point(g.guide, g.pivot, f"{g.key}.pivot")
            self._point(g.block, g.pin, f"{g.key}.pin")
            for p in g.line:
                self._point(g.guide, p, f"{g.key}.line")
            points = self.points_of(g.guide)
            if points[g.line[0]] == points[g.line[1]]:
                raise SceneError(
                    f"{g.key}.line", f"got {list(g.line)!r}, one place; a line needs two"
                )
            if g.guide == g.block:
                raise SceneError(f"{g.key}.block", "is the guide; an RPR joins two links")

    def _check_clearances(self) -> None:
        for c in self.clearances:
            for role in ("journal", "bearing"):
                body = getattr(c, role)
                if body != GROUND:
                    self._body(body, f"{c.key}.{role}")
            if c.joint not in self.points_of(c.journal) or c.joint not in self.points_of(c.bearing):
                joints = sorted(
                    {p for p in self.points_of(c.journal) if p in self.points_of(c.bearing)}
                )
                raise SceneError(
                    c.key,
                    f"no joint {c.joint!r} between {c.journal!r} and {c.bearing!r}, which share "
                    + (f"the joints {', '.join(joints)}" if joints else "no joint"),
                )


# -- tables ----------------------------------------------------------------------------------------
_PARTS = {"links": Link, "cranks": Crank, "sliders": Slider, "clearances": Clearance}


def _build(cls: type, table: Any, key: str) -> Any:
    """An instance of a part's class from its table; unknown and missing keys refused."""
    if not isinstance(table, Mapping):
        raise SceneError(key, f"got {table!r}; must be a table")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    named = table.get(cls.named_by)
    key = f"{key}[{named}]" if isinstance(named, str) else key
    for k in table:
        if k not in fields and k != "kind":
            raise SceneError(key, f"unknown key {k!r}; allowed: {', '.join(fields)}")
    missing = [
        n
        for n, f in fields.items()
        if n not in table
        and f.default is dataclasses.MISSING
        and f.default_factory is dataclasses.MISSING
    ]
    if missing:
        raise SceneError(key, f"missing {', '.join(map(repr, missing))}")
    return cls(**{k: v for k, v in table.items() if k != "kind"})


def _group(table: Any, key: str) -> Group:
    kind = table.get("kind") if isinstance(table, Mapping) else None
    if kind not in GROUP_KINDS:
        named = table.get("name") if isinstance(table, Mapping) else None
        where = f"{key}[{named}]" if isinstance(named, str) else key
        raise SceneError(
            f"{where}.kind", f"got {kind!r}; a group's kind is one of {', '.join(GROUP_KINDS)}"
        )
    return _build(GROUP_KINDS[kind], table, key)


def _list(table: Mapping[str, Any], name: str) -> list[Any]:
    value = table.get(name, [])
    if isinstance(value, Mapping) or not isinstance(value, Sequence) or isinstance(value, str):
        raise SceneError(f"mechanism.{name}", f"got {value!r}; must be an array of tables")
    return list(value)


def from_table(table: Mapping[str, Any]) -> Linkage:
    """The linkage of a ``[mechanism]`` table (the dict that :mod:`tomllib` reads), checked as
    :class:`Linkage` checks (not yet the closure of its loops).

    Parameters
    ----------
    table : mapping
        Keys ``name``, ``ground`` (point name -> [x, y], m), ``links``, ``cranks``, ``groups``
        (each with its ``kind``: "RRR", "RRP" or "RPR"), ``sliders``, ``clearances`` (arrays of
        tables with the fields of their classes), ``gravity`` and ``gravity_angle``.

    Returns
    -------
    Linkage
        The declaration.

    Raises
    ------
    SceneError
        One line naming the key of what is wrong, its value and what is allowed.
    """
    if not isinstance(table, Mapping):
        raise SceneError("mechanism", f"got {table!r}; must be a table")
    allowed = {f.name for f in dataclasses.fields(Linkage)}
    for k in table:
        if k not in allowed:
            raise SceneError("mechanism", f"unknown key {k!r}; allowed: {', '.join(allowed)}")
    for k in ("name", "ground", "links", "cranks"):
        if k not in table:
            raise SceneError(f"mechanism.{k}", "missing; a linkage declares it")
    parts = {
        name: tuple(_build(cls, t, f"mechanism.{name}") for t in _list(table, name))
        for name, cls in _PARTS.items()
    }
    groups = tuple(_group(t, "mechanism.groups") for t in _list(table, "groups"))
    scalars = {k: table[k] for k in ("name", "ground", "gravity", "gravity_angle") if k in table}
    return Linkage(**scalars, **parts, groups=groups)


def _plain(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def to_table(linkage: Linkage) -> dict[str, Any]:
    """The ``[mechanism]`` table of a linkage, every field written (``from_table`` reads it
    back to an equal linkage; ``tomli_w`` writes it as TOML)."""
    out: dict[str, Any] = {
        "name": linkage.name,
        "gravity": linkage.gravity,
        "gravity_angle": linkage.gravity_angle,
        "ground": _plain(linkage.ground),
    }
    for name in ("links", "cranks", "groups", "sliders", "clearances"):
        rows = []
        for part in getattr(linkage, name):
            row = {"kind": part.kind} if name == "groups" else {}
            row.update({f.name: _plain(getattr(part, f.name)) for f in dataclasses.fields(part)})
            if name == "cranks" and not part.torque_driven:
                # a constant-speed crank's table as before the drive existed (the same digest)
                for field in ("drive", "stall_torque", "no_load_speed"):
                    del row[field]
            rows.append(row)
        out[name] = rows
    return out
