"""Declared linkages (issue 42, first step): the declaration's checks, its TOML round trip, and
the ideal-joint kinematics against the closed-form four-bar (Freudenstein), the built-in
nine-bar's and slider-crank's kinematics, and a closed-form inverted slider-crank (RPR)."""

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
import tomli_w

from workbench._errors import SceneError
from workbench.models._declaration import (
    RPR,
    Crank,
    Link,
    Linkage,
    from_table,
    to_table,
)
from workbench.models._declare import declare, parse_mechanism
from workbench.models._declared_kinematics import kinematics

MECHANISMS = Path(__file__).resolve().parents[2] / "studies" / "mechanisms"
TURN = 3600  # samples per crank turn: every 0.1 deg


def table(name: str) -> dict:
    """The [mechanism] table of studies/mechanisms/NAME.toml."""
    with open(MECHANISMS / f"{name}.toml", "rb") as f:
        return tomllib.load(f)["mechanism"]


def wrap(angle):
    """Angles (rad) into (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(angle), 2 * np.pi)


def derivatives(f, x, h):
    """First and second derivatives of f at x by the five-point central stencils (errors
    O(h^4)); f returns arrays, and angles are differenced through ``wrap``."""
    f0 = f(x)
    d = {k: wrap(f(x + k * h) - f0) if f.angle else f(x + k * h) - f0 for k in (-2, -1, 1, 2)}
    first = (d[-2] - 8 * d[-1] + 8 * d[1] - d[2]) / (12 * h)
    second = (-d[-2] + 16 * d[-1] + 16 * d[1] - d[2]) / (12 * h * h)
    return first, second


# ================================================================================================
# the four-bar against Freudenstein's closed form
# ================================================================================================
O2O4, CRANK, COUPLER, ROCKER = 0.30, 0.08, 0.25, 0.20  # m, studies/mechanisms/fourbar.toml


def freudenstein(theta2):
    """Coupler and rocker angles (rad) of the open four-bar at the crank angle theta2 (rad), in
    the closed form of Freudenstein's equation K1 cos t4 - K2 cos t2 + K3 = cos(t2 - t4)
    (Norton, *Design of Machinery*, Eqs. 4.7-4.13: the half-angle substitution gives a
    quadratic in tan(t/2)); the minus root is the open branch, B above the frame line."""
    a, b, c, d = CRANK, COUPLER, ROCKER, O2O4
    k1, k2, k4 = d / a, d / c, d / b
    k3 = (a * a - b * b + c * c + d * d) / (2 * a * c)
    k5 = (c * c - d * d - a * a - b * b) / (2 * a * b)
    cos2, sin2 = np.cos(theta2), np.sin(theta2)
    qa = cos2 - k1 - k2 * cos2 + k3
    qb = -2 * sin2
    qc = k1 - (k2 + 1) * cos2 + k3
    theta4 = 2 * np.arctan2(-qb - np.sqrt(qb * qb - 4 * qa * qc), 2 * qa)
    qd = cos2 - k1 + k4 * cos2 + k5
    qe = -2 * sin2
    qf = k1 + (k4 - 1) * cos2 + k5
    theta3 = 2 * np.arctan2(-qe - np.sqrt(qe * qe - 4 * qd * qf), 2 * qd)
    return theta3, theta4


def fourbar_points(theta2):
    """A and B (m, arrays (n, 2)) of the closed-form four-bar."""
    theta3, theta4 = freudenstein(theta2)
    a = CRANK * np.stack([np.cos(theta2), np.sin(theta2)], axis=1)
    b_rocker = np.stack([O2O4 + ROCKER * np.cos(theta4), ROCKER * np.sin(theta4)], axis=1)
    b_coupler = a + COUPLER * np.stack([np.cos(theta3), np.sin(theta3)], axis=1)
    np.testing.assert_allclose(b_coupler, b_rocker, rtol=0, atol=1e-15)  # the loop closes
    return a, b_rocker


@pytest.fixture(scope="module")
def fourbar():
    linkage = parse_mechanism(table("fourbar"))
    omega = linkage.cranks[0].omega
    theta = np.arange(TURN) * (2 * np.pi / TURN)
    return linkage, omega, theta, kinematics(linkage, theta / omega)


def test_fourbar_positions_equal_freudensteins(fourbar):
    linkage, omega, theta, motion = fourbar
    a, b = fourbar_points(theta)
    theta3, theta4 = freudenstein(theta)
    np.testing.assert_allclose(motion.points["A"].position, a, rtol=0, atol=1e-12)
    np.testing.assert_allclose(motion.points["B"].position, b, rtol=0, atol=1e-12)
    for link, angle in (("coupler", theta3), ("rocker", theta4)):
        assert np.abs(wrap(motion.angles[link].position - angle)).max() < 1e-12
    np.testing.assert_allclose(motion.angles["crank"].position, theta, rtol=0, atol=1e-12)
    # the rocker rocks (Grashof crank-rocker): its angle stays inside an arc
    assert np.ptp(motion.angles["rocker"].position) < np.pi / 2


def _angles(theta):
    return np.stack(freudenstein(theta), axis=1)


def _positions(theta):
    return np.concatenate(fourbar_points(theta), axis=1)


_angles.angle = True
_positions.angle = False


def test_fourbar_rates_equal_the_closed_forms_derivatives(fourbar):
    """d/dt = omega d/dtheta at constant omega; h = 1e-3 rad: truncation ~h^4 and rounding
    ~1e-16 / h^2 leave errors below 1e-9 of omega L and omega^2 L (a wrong term is of order
    1 of them)."""
    linkage, omega, theta, motion = fourbar
    h = 1e-3
    scale = omega * COUPLER  # m s-1
    dp, ddp = derivatives(_positions, theta, h)
    for i, name in enumerate(("A", "B")):
        track = motion.points[name]
        np.testing.assert_allclose(
            track.velocity, omega * dp[:, 2 * i : 2 * i + 2], rtol=0, atol=1e-9 * scale
        )
        np.testing.assert_allclose(
            track.acceleration,
            omega**2 * ddp[:, 2 * i : 2 * i + 2],
            rtol=0,
            atol=1e-8 * omega * scale,
        )
    da, dda = derivatives(_angles, theta, h)
    for i, link in enumerate(("coupler", "rocker")):
        track = motion.angles[link]
        np.testing.assert_allclose(track.velocity, omega * da[:, i], rtol=0, atol=1e-9 * omega)
        np.testing.assert_allclose(
            track.acceleration, omega**2 * dda[:, i], rtol=0, atol=1e-8 * omega**2
        )
    # the centres of mass move with their links: the coupler's is the middle of AB
    for k in range(3):
        np.testing.assert_allclose(
            motion.centres["coupler"][k],
            0.5 * (motion.points["A"][k] + motion.points["B"][k]),
            rtol=0,
            atol=1e-12 * omega ** (2 * k),
        )


# ================================================================================================
# the nine-bar and the slider-crank against the built-ins
# ================================================================================================
def test_ninebar_equals_the_builtin_kinematics():
    from workbench.models.ninebar import _kinematics as K
    from workbench.models.ninebar._geometry import BODY_NAMES, geometry_array

    linkage = parse_mechanism(table("ninebar"))
    omega = linkage.cranks[1].omega  # crank 4 at +omega, crank 1 at -omega
    assert linkage.cranks[0].omega == -omega
    phase = np.arange(TURN) * (2 * np.pi / TURN)
    motion = kinematics(linkage, phase / omega)
    geo = geometry_array()
    points = {"A": K.PT_A, "B": K.PT_B, "P": K.PT_P, "C": K.PT_C, "D": K.PT_D, "E": K.PT_E}
    worst = dict.fromkeys(("position", "velocity", "acceleration", "angle", "slider"), 0.0)
    pos, pts = np.empty((8, 3)), np.empty((K.N_POINTS, 2))
    J, Jp = np.empty((8, 3, 6)), np.empty((K.N_POINTS, 2, 6))
    gam, gamp = np.empty((8, 3)), np.empty((K.N_POINTS, 2))
    for i, p in enumerate(phase):
        q = np.array([-p, p, 0.0, 0.0, 0.0, 0.0])
        qd = omega * np.array([-1.0, 1.0, 0.0, 0.0, 0.0, 0.0])
        assert K.positions(q, geo, pos, pts) == K.ASSEMBLED
        K.jacobian(q, geo, J, Jp)
        K.bias_acceleration(q, qd, geo, gam, gamp)
        vel, velp = J @ qd, Jp @ qd
        for name, row in points.items():
            track = motion.points[name]
            for k, (ours, theirs) in enumerate(
                ((track.position, pts), (track.velocity, velp), (track.acceleration, gamp))
            ):
                kind = ("position", "velocity", "acceleration")[k]
                worst[kind] = max(worst[kind], np.abs(ours[i] - theirs[row]).max())
        for b, body in enumerate(BODY_NAMES):
            centre = motion.centres[body]
            worst["position"] = max(
                worst["position"], np.abs(centre.position[i] - pos[b, :2]).max()
            )
            worst["velocity"] = max(
                worst["velocity"], np.abs(centre.velocity[i] - vel[b, :2]).max()
            )
            worst["acceleration"] = max(
                worst["acceleration"], np.abs(centre.acceleration[i] - gam[b, :2]).max()
            )
            if body != "slider9":  # the built-in gives the slider no angle, ours the guide's
                angle = motion.angles[body]
                worst["angle"] = max(
                    worst["angle"],
                    abs(wrap(angle.position[i] - pos[b, 2])),
                    abs(angle.velocity[i] - vel[b, 2]) / omega,
                    abs(angle.acceleration[i] - gam[b, 2]) / omega**2,
                )
        s = K.slider(q, qd, np.zeros(6), geo)
        slider = motion.sliders["slider9"]
        ours = (slider.position[i], slider.velocity[i] / omega, slider.acceleration[i] / omega**2)
        theirs = (s[0], s[1] / omega, s[2] / omega**2)
        worst["slider"] = max(
            worst["slider"], *(abs(a - b) for a, b in zip(ours, theirs, strict=True))
        )
    # m, m s-1, m s-2 (velocities ~ omega L = 2 m s-1, accelerations ~ omega^2 L = 20 m s-2),
    # rad (rates scaled by omega), m (the slider's rates scaled by omega)
    assert worst["position"] < 1e-10 and worst["slider"] < 1e-10 and worst["angle"] < 1e-10
    assert worst["velocity"] < 1e-10 * omega and worst["acceleration"] < 1e-10 * omega**2
    # the spec's numbers (docs/ninebar-parameters.md): S9 = 0.1066 m at the start, stroke 0.3722 m
    assert round(motion.sliders["slider9"].position[0], 4) == 0.1066
    assert round(np.ptp(motion.sliders["slider9"].position), 4) == 0.3722


def test_slider_crank_equals_the_builtin_kinematics():
    from workbench.models.slider_crank import _kinematics as K
    from workbench.models.slider_crank._geometry import BODY_NAMES, geometry_array

    linkage = parse_mechanism(table("slider_crank"))
    omega = linkage.cranks[0].omega
    theta = np.arange(TURN) * (2 * np.pi / TURN)
    motion = kinematics(linkage, theta / omega)
    geo = geometry_array()
    out = [
        np.empty(shape)
        for shape in ((3, 3), (K.N_POINTS, 2), (3, 3, 3), (K.N_POINTS, 2, 3))
        + ((3, 3), (K.N_POINTS, 2)) * 2
    ]
    pos, pts, _, _, gam, gamp, vel, velp = out
    scales = (1.0, omega, omega**2)
    for i, th in enumerate(theta):
        assert K.kinematics(np.array([th, 0, 0.0]), np.array([omega, 0, 0.0]), geo, *out) == 0
        for name, row in (("A", K.PT_A), ("B", K.PT_B)):
            for k, theirs in enumerate((pts, velp, gamp)):
                ours = motion.points[name][k][i]
                assert np.abs(ours - theirs[row]).max() < 1e-10 * scales[k]
        for b, body in enumerate(BODY_NAMES):
            for k, theirs in enumerate((pos, vel, gam)):
                ours = motion.centres[body][k][i]
                assert np.abs(ours - theirs[b, :2]).max() < 1e-10 * scales[k]
                turn = motion.angles[body][k][i] - theirs[b, 2]
                assert abs(wrap(turn) if k == 0 else turn) < 1e-10 * scales[k]
            slider = motion.sliders["slider"]
            for k, theirs in enumerate((pts, velp, gamp)):
                assert abs(slider[k][i] - theirs[K.PT_B, 0]) < 1e-10 * scales[k]


# ================================================================================================
# RPR: the inverted slider-crank against its closed form
# ================================================================================================
def inverted_slider_crank(offset: float, branch: int = 1) -> Linkage:
    """Crank O2A (0.1 m) whose tip A pins a block sliding along a guide link pivoted at O3, 0.3
    m below O2; the guide's line lies ``offset`` m from O3."""
    return declare(
        Linkage(
            name="inverted_slider_crank",
            ground={"O2": (0.0, 0.0), "O3": (0.0, -0.3)},
            links=(
                Link(
                    name="crank",
                    points={"O2": (0.0, 0.0), "A": (0.1, 0.0)},
                    mass=0.2,
                    inertia=2e-4,
                    centre_of_mass=(0.05, 0.0),
                ),
                Link(
                    name="guide",
                    points={"O3": (0.0, 0.0), "G0": (0.0, offset), "G1": (0.5, offset)},
                    mass=1.0,
                    inertia=2e-2,
                    centre_of_mass=(0.25, 0.0),
                ),
                Link(
                    name="block",
                    points={"A": (0.0, 0.0)},
                    mass=0.1,
                    inertia=1e-5,
                    centre_of_mass=(0.0, 0.0),
                ),
            ),
            cranks=(Crank(link="crank", pivot="O2", omega=20.0),),
            groups=(
                RPR(
                    name="guide_block",
                    guide="guide",
                    block="block",
                    pivot="O3",
                    pin="A",
                    line=("G0", "G1"),
                    branch=branch,
                ),
            ),
        ),
        samples_per_turn=360,
    )


def test_rpr_equals_the_inverted_slider_cranks_closed_form():
    """Offset 0: the guide points from O3 to A, at the angle atan2(A - O3); its rates by the
    derivatives of that closed form. Offset e: A lies e from the guide's line."""
    omega = 20.0
    theta = np.arange(720) * (2 * np.pi / 720)
    motion = kinematics(inverted_slider_crank(0.0), theta / omega)

    def guide_angle(th):
        return np.arctan2(0.1 * np.sin(th) + 0.3, 0.1 * np.cos(th))

    guide_angle.angle = True
    d1, d2 = derivatives(guide_angle, theta, 1e-3)
    track = motion.angles["guide"]
    assert np.abs(wrap(track.position - guide_angle(theta))).max() < 1e-12
    np.testing.assert_allclose(track.velocity, omega * d1, rtol=0, atol=1e-9 * omega)
    np.testing.assert_allclose(track.acceleration, omega**2 * d2, rtol=0, atol=1e-8 * omega**2)
    np.testing.assert_array_equal(motion.angles["block"].velocity, track.velocity)
    np.testing.assert_allclose(motion.angles["block"].velocity, track.velocity, atol=0)


def test_rpr_with_an_offset_keeps_the_pin_on_the_line_and_its_rates_are_derivatives():
    """The pin A lies on the guide's line, which lies the offset from the pivot; the rates are
    the time derivatives of the positions (five-point stencils in time)."""
    omega, offset = 20.0, 0.05
    linkage = inverted_slider_crank(offset)
    time = np.arange(720) * (2 * np.pi / 720 / omega)
    motion = kinematics(linkage, time)
    g0, g1, a = (motion.points[p].position for p in ("G0", "G1", "A"))
    u = (g1 - g0) / 0.5

    def distance(p):  # signed, from the line G0 -> G1 (m)
        return u[:, 0] * (p[:, 1] - g0[:, 1]) - u[:, 1] * (p[:, 0] - g0[:, 0])

    np.testing.assert_allclose(distance(a), 0.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(distance(np.zeros_like(a) + (0.0, -0.3)), -offset, atol=1e-15)

    def state(t):
        m = kinematics(linkage, t)
        return np.concatenate([m.points["G1"].position, m.angles["guide"].position[:, None]], 1)

    state.angle = False
    d1, d2 = derivatives(state, time, 1e-4)  # s
    ours = np.concatenate(
        [motion.points["G1"].velocity, motion.angles["guide"].velocity[:, None]], 1
    )
    np.testing.assert_allclose(ours, d1, rtol=0, atol=1e-8 * omega)
    ours = np.concatenate(
        [motion.points["G1"].acceleration, motion.angles["guide"].acceleration[:, None]], 1
    )
    np.testing.assert_allclose(ours, d2, rtol=0, atol=1e-8 * omega**2)


# ================================================================================================
# the declaration: round trip, and each error in one line naming the part
# ================================================================================================
def _subset(small, big, where="mechanism"):
    """Every value of ``small`` is in ``big`` with an equal value (tables recursively)."""
    if isinstance(small, dict):
        assert isinstance(big, dict), where
        for k, v in small.items():
            assert k in big, f"{where}.{k}"
            _subset(v, big[k], f"{where}.{k}")
    elif isinstance(small, list):
        assert isinstance(big, list) and len(big) == len(small), where
        for i, (a, b) in enumerate(zip(small, big, strict=True)):
            _subset(a, b, f"{where}[{i}]")
    else:
        assert type(small) is type(big) or {type(small), type(big)} == {int, float}, where
        assert small == big, where


@pytest.mark.parametrize("name", ["fourbar", "ninebar", "slider_crank"])
def test_a_declaration_round_trips_through_toml(name):
    source = table(name)
    linkage = from_table(source)
    written = to_table(linkage)
    _subset(source, written)  # every value the file gives, unchanged
    again = from_table(tomllib.loads(tomli_w.dumps({"mechanism": written}))["mechanism"])
    assert again == linkage
    assert to_table(again) == written


def test_an_rpr_declaration_round_trips_through_toml():
    linkage = inverted_slider_crank(0.05)
    written = to_table(linkage)
    assert written["groups"][0]["kind"] == "RPR" and written["groups"][0]["line"] == ["G0", "G1"]
    assert from_table(tomllib.loads(tomli_w.dumps({"mechanism": written}))["mechanism"]) == linkage


def test_python_builds_the_same_declaration_as_the_file():
    from workbench.models._declaration import RRR, Clearance

    def bar(name, ends, length, mass, inertia):
        return Link(
            name=name,
            points={ends[0]: (0.0, 0.0), ends[1]: (length, 0.0)},
            mass=mass,
            inertia=inertia,
            centre_of_mass=(length / 2, 0.0),
        )

    linkage = Linkage(
        name="fourbar",
        ground={"O2": (0.0, 0.0), "O4": (0.30, 0.0)},
        links=(
            bar("crank", ("O2", "A"), 0.08, 0.2, 1.0666666666666667e-4),
            bar("coupler", ("A", "B"), 0.25, 0.5, 2.6041666666666665e-3),
            bar("rocker", ("O4", "B"), 0.20, 0.4, 1.3333333333333333e-3),
        ),
        cranks=(Crank(link="crank", pivot="O2", omega=10 * math.pi),),
        groups=(
            RRR(
                name="coupler_rocker",
                links=("coupler", "rocker"),
                points=("A", "O4"),
                joint="B",
                branch=1,
            ),
        ),
        clearances=(Clearance(joint="B", journal="coupler", bearing="rocker", clearance=0.5e-3),),
    )
    assert linkage == from_table(table("fourbar"))


def _set(path, value):
    """A change of the four-bar's table: set the value at ``path`` (keys and list indices)."""

    def change(t):
        *head, last = path
        for k in head:
            t = t[k]
        t[last] = value

    return change


def _append(path, value):
    def change(t):
        for k in path:
            t = t[k]
        t.append(value)

    return change


COUPLER_TABLE = table("fourbar")["links"][1]
# (change of fourbar.toml's table, the key the message starts with, what it says)
ERRORS = {
    "loop_cannot_close": (
        # |A O4| reaches 0.38 m, beyond coupler + rocker = 0.35 m, from theta2 = 122.94 deg
        _set(("links", 1, "points", "B"), [0.15, 0.0]),
        "mechanism.groups[coupler_rocker]",
        "the loop does not close at crank angle 123.00 deg of crank 'crank'",
    ),
    "joint_that_no_group_closes": (
        # the coupler pinned to the ground at O4 as well: a redundant joint, no group closes it
        _set(("links", 1, "points", "O4"), [0.1, 0.0]),
        "mechanism.links[coupler]",
        "'ground' and 'coupler' put their joint 'O4' 0.",
    ),
    "mass_not_positive": (
        _set(("links", 2, "mass"), 0.0),
        "mechanism.links[rocker].mass",
        "got 0.0 kg; must be positive",
    ),
    "inertia_not_positive": (
        _set(("links", 0, "inertia"), -1e-4),
        "mechanism.links[crank].inertia",
        "must be positive",
    ),
    "clearance_on_no_joint": (
        _set(("clearances", 0, "joint"), "C"),
        "mechanism.clearances[C]",
        "no joint 'C' between 'coupler' and 'rocker', which share the joints B",
    ),
    "clearance_on_a_joint_of_other_bodies": (
        _set(("clearances", 0, "joint"), "A"),
        "mechanism.clearances[A]",
        "no joint 'A' between 'coupler' and 'rocker'",
    ),
    "clearance_on_an_unknown_body": (
        _set(("clearances", 0, "bearing"), "rocket"),
        "mechanism.clearances[B].bearing",
        "got 'rocket', no link or slider of that name",
    ),
    "group_references_an_unknown_point": (
        _set(("groups", 0, "points"), ["A", "Q"]),
        "mechanism.groups[coupler_rocker].points",
        "references an unknown point 'Q'",
    ),
    "group_references_an_unknown_link": (
        _set(("groups", 0, "links"), ["coupler", "rocket"]),
        "mechanism.groups[coupler_rocker].links",
        "got 'rocket', no link of that name",
    ),
    "duplicate_link_name": (
        _append(("links",), dict(COUPLER_TABLE)),
        "mechanism.links[coupler]",
        "the name 'coupler' is used twice among the links and sliders",
    ),
    "duplicate_group_name": (
        _append(("groups",), dict(table("fourbar")["groups"][0])),
        "mechanism.groups[coupler_rocker]",
        "the name 'coupler_rocker' is used twice among the groups",
    ),
    "body_moved_twice": (
        _append(("groups",), {**table("fourbar")["groups"][0], "name": "again"}),
        "mechanism.groups[again]",
        "moves 'coupler', which group 'coupler_rocker' moves already",
    ),
    "link_moved_by_nothing": (
        _set(("groups",), []),
        "mechanism.links[coupler]",
        "'coupler' is moved by no crank or group",
    ),
    "crank_about_a_moving_point": (
        _set(("cranks", 0, "pivot"), "A"),
        "mechanism.cranks[crank].pivot",
        "a crank turns about a ground point: O2, O4",
    ),
    "branch_not_a_sign": (
        _set(("groups", 0, "branch"), 0),
        "mechanism.groups[coupler_rocker].branch",
        "a branch is +1 or -1",
    ),
    "unknown_group_kind": (
        _set(("groups", 0, "kind"), "PPP"),
        "mechanism.groups[coupler_rocker].kind",
        "one of RRR, RRP, RPR",
    ),
    "unknown_key": (
        _set(("links", 2, "mas"), 1.0),
        "mechanism.links[rocker]",
        "unknown key 'mas'",
    ),
    "missing_key": (
        lambda t: t["links"][2].pop("inertia"),
        "mechanism.links[rocker]",
        "missing 'inertia'",
    ),
    "contact_parameter_out_of_range": (
        _set(("clearances", 0, "restitution"), 1.5),
        "mechanism.clearances[B].restitution",
        "must lie in (0, 1]",
    ),
    "clearance_not_below_the_bearing_radius": (
        _set(("clearances", 0, "clearance"), 0.02),
        "mechanism.clearances[B].clearance",
        "smaller than the bearing radius",
    ),
}


def test_the_cranks_turn_whole_multiples_of_the_slowest():
    t = copy.deepcopy(table("ninebar"))
    t["cranks"][1]["omega"] = 1.5 * 2.5 * math.pi
    with pytest.raises(SceneError, match=r"^mechanism\.cranks\[crank4\]\.omega: got .*1\.5 times"):
        parse_mechanism(t)
    t["cranks"][1]["omega"] = 2 * 2.5 * math.pi  # crank 4 turns twice per cycle: periodic
    assert parse_mechanism(t).period() == pytest.approx(2 * math.pi / (2.5 * math.pi))


@pytest.mark.parametrize("case", ERRORS)
def test_each_error_is_one_line_naming_the_part(case):
    change, key, says = ERRORS[case]
    t = copy.deepcopy(table("fourbar"))
    change(t)
    with pytest.raises(SceneError) as info:
        parse_mechanism(t)
    message = str(info.value)
    assert "\n" not in message
    assert info.value.key == key, message
    assert message.startswith(f"{key}: ") and says in message, message


def test_the_slider_crank_refuses_a_massless_slider():
    t = copy.deepcopy(table("slider_crank"))
    t["sliders"][0]["mass"] = 0
    with pytest.raises(SceneError, match=r"^mechanism\.sliders\[slider\]\.mass: got 0 kg"):
        parse_mechanism(t)


def test_kinematics_name_the_group_where_asked_outside_its_range():
    """A declaration built from Python without ``declare`` fails where its loop opens."""
    t = copy.deepcopy(table("fourbar"))
    t["links"][1]["points"]["B"] = [0.15, 0.0]
    linkage = from_table(t)  # parts checked, loop not yet
    kinematics(linkage, 0.0)  # closes at theta2 = 0
    with pytest.raises(SceneError, match=r"coupler_rocker.*180\.00 deg.*cannot join 'A' and 'O4'"):
        kinematics(linkage, [0.0, math.pi / linkage.cranks[0].omega])
