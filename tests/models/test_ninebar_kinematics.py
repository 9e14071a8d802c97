"""Nine-bar kinematics: the spec's numbers, loop closure, exact derivatives, assembly failures.

Reference values: ``docs/ninebar-parameters.md``, "Numbers to check" (ideal joints,
theta10 = theta40 = 0, theta1 = -omega t, theta4 = +omega t).
"""

import math

import numpy as np
import pytest
from helpers import IDEAL_SLIDER_PEAKS

from workbench.models.ninebar import _kinematics as K
from workbench.models.ninebar._geometry import (
    BODY_NAMES,
    DEFAULT_GEOMETRY,
    DERIVED_FIELDS,
    GEOMETRY_FIELDS,
    INERTIAS,
    MASSES,
    geometry_array,
)

GEO = geometry_array()
G = DEFAULT_GEOMETRY
O6 = np.array([G["O6x"], G["O6y"]])
PHI = 2  # column of the angle in pos, J, gam
CYCLE_STEP_DEG = 0.02  # sampling of one crank cycle


def kin(q, qd=None, geo=GEO):
    """All outputs of `kinematics` as a dict; asserts that the mechanism assembles."""
    q = np.asarray(q, float)
    qd = np.zeros(6) if qd is None else np.asarray(qd, float)
    out = {
        "pos": np.full((8, 3), np.nan),
        "pts": np.full((K.N_POINTS, 2), np.nan),
        "J": np.full((8, 3, 6), np.nan),
        "Jp": np.full((K.N_POINTS, 2, 6), np.nan),
        "gam": np.full((8, 3), np.nan),
        "gamp": np.full((K.N_POINTS, 2), np.nan),
        "vel": np.full((8, 3), np.nan),
        "velp": np.full((K.N_POINTS, 2), np.nan),
    }
    assert K.kinematics(q, qd, geo, *out.values()) == K.ASSEMBLED
    # the stored velocity pass is J qd to rounding
    np.testing.assert_allclose(out["vel"], out["J"] @ qd, rtol=0, atol=1e-14 * (1 + abs(qd).max()))
    np.testing.assert_allclose(
        out["velp"], out["Jp"] @ qd, rtol=0, atol=1e-14 * (1 + abs(qd).max())
    )
    return out


def drive(phase, omega=1.0):
    """Ideal joints at crank phase omega t (rad): q and qd."""
    return (
        np.array([-phase, phase, 0.0, 0.0, 0.0, 0.0]),
        omega * np.array([-1.0, 1.0, 0.0, 0.0, 0.0, 0.0]),
    )


def slider_position(pts):
    return G["S0"] - (pts[K.PT_E, 0] - G["O6x"])


def e(angle):
    return np.array([math.cos(angle), math.sin(angle)])


def cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


def wrap(angle):
    """Angles (rad) into (-pi, pi]."""
    return np.pi - np.mod(np.pi - angle, 2 * np.pi)


def fold_deg(angle):
    """Angle between two link directions (rad), folded into [0, 90] deg."""
    return np.degrees(np.arccos(np.abs(np.cos(angle))))


@pytest.fixture(scope="module")
def cycle():
    """One crank cycle of the ideal mechanism at omega = 1 rad/s (scale: v ~ omega, a ~ omega^2)."""
    phase = np.radians(np.arange(0.0, 360.0, CYCLE_STEP_DEG))
    s, v, a, phi = [], [], [], []
    for p in phase:
        q, qd = drive(p)
        o = kin(q, qd)
        s.append(slider_position(o["pts"]))
        v.append(-(o["J"][K.SLIDER9, 0] @ qd))  # dS9/dt = -dx_E/dt
        a.append(-o["gam"][K.SLIDER9, 0])  # qdd = 0
        phi.append(o["pos"][:, PHI])
    return {
        "deg": np.degrees(phase),
        "s": np.array(s),
        "v": np.array(v),
        "a": np.array(a),
        "phi": np.array(phi),
    }


# -- the spec's numbers ----------------------------------------------------------------------------
def test_initial_configuration_matches_spec():
    o = kin(np.zeros(6))
    phi = np.degrees(o["pos"][:, PHI])
    bodies = [K.LINK2, K.LINK3, K.ROCKER6, K.PANEL7, K.LINK8]
    np.testing.assert_allclose(
        phi[bodies], [73.351, 141.065, -44.914, 22.206, -157.529], rtol=0, atol=0.01
    )
    pts = o["pts"]
    names = [K.PT_A, K.PT_B, K.PT_P, K.PT_C, K.PT_D, K.PT_E]
    expected = [
        [0.0450, 0.0],
        [0.5250, 0.0],
        [0.1384, 0.3123],
        [-0.1671, 0.1876],
        [-0.3231, 0.4784],
        [-0.6336, 0.3500],
    ]
    np.testing.assert_allclose(pts[names], expected, rtol=0, atol=1e-4)
    assert slider_position(pts) == pytest.approx(0.1066, abs=1e-4)


def test_slider_stroke_and_its_extremes(cycle):
    s = cycle["s"]
    assert s.max() - s.min() == pytest.approx(0.3722, abs=0.5e-3)
    assert cycle["deg"][np.argmin(s)] == pytest.approx(304.9, abs=0.5)
    assert cycle["deg"][np.argmax(s)] == pytest.approx(147.0, abs=0.5)
    assert s.min() == pytest.approx(0.0, abs=1e-4)  # S0 puts S9 = 0 at the +X dead centre


@pytest.mark.parametrize(("omega", "vmax", "amax"), IDEAL_SLIDER_PEAKS)
def test_ideal_slider_velocity_and_acceleration_peaks(cycle, omega, vmax, amax):
    # at constant crank speed v = J qd scales with omega and a = gam with omega^2
    assert np.abs(cycle["v"]).max() * omega == pytest.approx(vmax, rel=0.01)
    assert np.abs(cycle["a"]).max() * omega**2 == pytest.approx(amax, rel=0.01)


def test_minimum_transmission_angles(cycle):
    """Transmission angle = angle between the directions of the two links that meet at the
    joint, folded into [0, 90] deg: at P links 2 and 3 (the dyad A'-P-B'), at C rocker 6 and the
    panel side CP (the dyad O6-C-P). Link 2 or 3 against the panel side CP at P would give
    36.97 or 50.63 deg instead of the spec's 49.86."""
    phi = cycle["phi"]
    at_p = fold_deg(phi[:, K.LINK2] - phi[:, K.LINK3])
    at_c = fold_deg(phi[:, K.ROCKER6] - phi[:, K.PANEL7])
    assert at_p.min() == pytest.approx(49.86, abs=0.05)
    assert at_c.min() == pytest.approx(45.55, abs=0.05)


# -- closure and consistency -----------------------------------------------------------------------
def random_clearances(rng, n, radius=0.5e-3):
    """n clearance vectors (x1, y1, x2, y2) with |r| <= radius (m) at each joint."""
    r = radius * np.sqrt(rng.uniform(0, 1, (n, 2)))
    a = rng.uniform(-np.pi, np.pi, (n, 2))
    return np.stack([r * np.cos(a), r * np.sin(a)], axis=-1).reshape(n, 4)


def test_loop_closure_branches_and_centroids_over_the_torus():
    rng = np.random.default_rng(7)
    grid = np.radians(np.arange(0.0, 360.0, 15.0))
    th1, th4 = (a.ravel() for a in np.meshgrid(grid, grid))
    clear = random_clearances(rng, th1.size)
    clear[0] = 0.0  # the ideal mechanism too
    worst = 0.0
    for t1, t4, c in zip(th1, th4, clear, strict=True):
        q = np.concatenate([[t1, t4], c])
        o = kin(q)
        p = dict(zip(K.POINT_NAMES, o["pts"], strict=True))
        pos = o["pos"]
        th = pos[:, PHI]
        res = [
            p["A"] - G["L1"] * e(t1),
            p["B"] - (np.array([G["L5"], 0]) + G["L4"] * e(t4)),
            p["A'"] - p["A"] - c[:2],
            p["B'"] - p["B"] - c[2:],
            p["P"] - (p["A'"] + G["L2"] * e(th[K.LINK2])),
            p["P"] - (p["B'"] + G["L3"] * e(th[K.LINK3])),
            p["C"] - (O6 + G["L6"] * e(th[K.ROCKER6])),
            p["P"] - (p["C"] + G["L71"] * e(th[K.PANEL7])),
            p["D"] - (p["C"] + G["L72"] * e(th[K.PANEL7] + G["beta"])),
            p["E"] - (p["D"] + G["L8"] * e(th[K.LINK8])),
            [p["E"][1] - G["O6y"], 0.0],
            # centroids
            pos[K.CRANK1, :2] - G["Ls1"] * e(t1),
            pos[K.LINK2, :2] - (p["A'"] + G["Ls2"] * e(th[K.LINK2])),
            pos[K.LINK3, :2] - (p["B'"] + G["Ls3"] * e(th[K.LINK3])),
            pos[K.CRANK4, :2] - (np.array([G["L5"], 0]) + G["Ls4"] * e(t4)),
            pos[K.ROCKER6, :2] - (O6 + G["Ls6"] * e(th[K.ROCKER6])),
            pos[K.PANEL7, :2] - (p["C"] + p["P"] + p["D"]) / 3,
            pos[K.LINK8, :2] - (p["D"] + G["Ls8"] * e(th[K.LINK8])),
            pos[K.SLIDER9, :2] - p["E"],
        ]
        worst = max(worst, np.abs(res).max())
        assert th[K.CRANK1] == t1 and th[K.CRANK4] == t4 and th[K.SLIDER9] == 0.0
        # assembly branches
        assert cross(p["B'"] - p["A'"], p["P"] - p["A'"]) > 0
        assert cross(p["P"] - O6, p["C"] - O6) < 0
        assert p["E"][0] < p["D"][0]
    assert worst <= 1e-12


def test_separate_functions_agree_with_the_combined_pass():
    rng = np.random.default_rng(3)
    for c in random_clearances(rng, 5):
        q = np.concatenate([rng.uniform(-np.pi, np.pi, 2), c])
        qd = rng.normal(size=6) * [6, 6, 0.05, 0.05, 0.05, 0.05]
        qdd = rng.normal(size=6) * [0, 0, 50, 50, 50, 50]
        o = kin(q, qd)
        pos, pts = np.empty((8, 3)), np.empty((K.N_POINTS, 2))
        J, Jp = np.empty((8, 3, 6)), np.empty((K.N_POINTS, 2, 6))
        gam, gamp = np.empty((8, 3)), np.empty((K.N_POINTS, 2))
        assert K.positions(q, GEO, pos, pts) == 0
        assert K.jacobian(q, GEO, J, Jp) == 0
        assert K.bias_acceleration(q, qd, GEO, gam, gamp) == 0
        for name, value in dict(pos=pos, pts=pts, J=J, Jp=Jp, gam=gam, gamp=gamp).items():
            np.testing.assert_array_equal(value, o[name], err_msg=name)
        s, v, a = K.slider(q, qd, qdd, GEO)
        assert s == pytest.approx(slider_position(pts), abs=1e-15)
        assert v == pytest.approx(-(J[K.SLIDER9, 0] @ qd), abs=1e-13)
        assert a == pytest.approx(-(J[K.SLIDER9, 0] @ qdd + gam[K.SLIDER9, 0]), abs=1e-11)


# -- exact derivatives against finite differences -------------------------------------------------
def sample_states(seed, n):
    """Random q with clearances |r| <= 0.5 mm, and realistic rates and accelerations."""
    rng = np.random.default_rng(seed)
    for c in random_clearances(rng, n):
        q = np.concatenate([rng.uniform(-np.pi, np.pi, 2), c])
        qd = rng.normal(size=6) * [8, 8, 0.05, 0.05, 0.05, 0.05]  # rad/s, m/s
        qdd = rng.normal(size=6) * [20, 20, 50, 50, 50, 50]  # rad/s2, m/s2
        yield q, qd, qdd


def assert_close(exact_pos, exact_pts, fd_pos, fd_pts, rtol, what):
    """Lengths (centroids and points) and angles separately: max|error| <= rtol * max|exact|,
    so that structural zeros and small entries are judged on the scale of their quantity."""
    for kind, exact, fd in (
        ("lengths", [exact_pos[:, :2], exact_pts], [fd_pos[:, :2], fd_pts]),
        ("angles", [exact_pos[:, PHI]], [fd_pos[:, PHI]]),
    ):
        exact = np.concatenate([x.ravel() for x in exact])
        fd = np.concatenate([x.ravel() for x in fd])
        scale = np.abs(exact).max()
        err = np.abs(exact - fd).max()
        assert err <= rtol * scale, f"{what}, {kind}: relative error {err / scale:.2e}"


def test_jacobian_matches_central_differences():
    # steps: 1e-6 rad and 1e-6 m against lengths of 0.045-0.5 m; truncation (h/L)^2 ~ 1e-9,
    # round-off 1e-16 / h ~ 1e-10
    h = 1e-6
    for q, _, _ in sample_states(11, 20):
        o = kin(q)
        for k in range(6):
            dq = np.zeros(6)
            dq[k] = h
            plus, minus = kin(q + dq), kin(q - dq)
            fd = (plus["pos"] - minus["pos"]) / (2 * h)
            fd[:, PHI] = wrap(plus["pos"][:, PHI] - minus["pos"][:, PHI]) / (2 * h)
            fdp = (plus["pts"] - minus["pts"]) / (2 * h)
            assert_close(o["J"][:, :, k], o["Jp"][:, :, k], fd, fdp, 1e-6, f"column {k}")


def second_derivative(q, qd, qdd, tau):
    """d2/dt2 at t = 0 of pos and pts along q(t) = q + qd t + qdd t^2 / 2: central second
    differences with steps tau and 2 tau, Richardson-extrapolated (error O(tau^4))."""

    def diff(step):
        m, c, p = (kin(q + qd * t + 0.5 * qdd * t * t) for t in (-step, 0.0, step))
        out = {key: (p[key] - 2 * c[key] + m[key]) / step**2 for key in ("pos", "pts")}
        dphi = wrap(p["pos"][:, PHI] - c["pos"][:, PHI]) - wrap(c["pos"][:, PHI] - m["pos"][:, PHI])
        out["pos"][:, PHI] = dphi / step**2
        return out

    fine, coarse = diff(tau), diff(2 * tau)
    return {key: (4 * fine[key] - coarse[key]) / 3 for key in fine}


def test_acceleration_matches_second_differences_of_positions():
    """The acceleration along q(t) = q + qd t + qdd t^2 / 2 is J qdd + gam; with qdd = 0 it is
    gam. Steps |qd| tau ~ 1e-3 rad: truncation ~1e-10, round-off ~1e-9 relative."""
    for q, qd, qdd in sample_states(12, 20):
        o = kin(q, qd)
        tau = 1e-3 / np.abs(qd[:2]).max()
        fd = second_derivative(q, qd, qdd, tau)
        acc_pos = o["J"] @ qdd + o["gam"]
        acc_pts = o["Jp"] @ qdd + o["gamp"]
        assert_close(acc_pos, acc_pts, fd["pos"], fd["pts"], 1e-6, "J qdd + gam")
        fd = second_derivative(q, qd, np.zeros(6), tau)
        assert_close(o["gam"], o["gamp"], fd["pos"], fd["pts"], 1e-6, "gam")


# -- assembly failures -----------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("q", "changes", "code"),
    [
        # absurd 1 m clearance vectors: A'B' too long, or P out of the rocker-panel's reach
        ([0, 0, -1.0, 0, 0, 0], {}, K.FAIL_LINKS_23),
        ([0, 0, 0, 0, 0, -1.0], {}, K.FAIL_LINKS_23),
        ([0, 0, 1.0, 0, 0, 0], {}, K.FAIL_ROCKER_PANEL),
        ([0, 0, 0, 0, 0, 0], {"L71": 0.05}, K.FAIL_ROCKER_PANEL),
        ([0, 0, 0, 0, 0, 0], {"L8": 0.05}, K.FAIL_LINK8),
        ([np.nan, 0, 0, 0, 0, 0], {}, K.FAIL_LINKS_23),
    ],
)
def test_assembly_failure_is_a_code_not_a_nan(q, changes, code):
    geo = geometry_array(changes)
    q = np.asarray(q, float)
    outs = [
        np.zeros((8, 3)),
        np.zeros((K.N_POINTS, 2)),
        np.zeros((8, 3, 6)),
        np.zeros((K.N_POINTS, 2, 6)),
        np.zeros((8, 3)),
        np.zeros((K.N_POINTS, 2)),
        np.zeros((8, 3)),
        np.zeros((K.N_POINTS, 2)),
    ]
    assert K.kinematics(q, np.ones(6), geo, *outs) == code
    assert K.positions(q, geo, *outs[:2]) == code
    assert K.jacobian(q, geo, *outs[2:4]) == code
    assert K.bias_acceleration(q, np.ones(6), geo, *outs[4:6]) == code
    for out in outs:  # left untouched
        assert not np.any(out)
    with pytest.raises(ValueError, match="does not assemble"):
        K.slider(q, np.zeros(6), np.zeros(6), geo)


# -- Assur groups on their own ---------------------------------------------------------------------
def test_rrr_dyad_on_a_3_4_5_triangle():
    # P1 = (0, 0), P2 = (5, 0), l1 = 3, l2 = 4: X = (1.8, +-2.4)
    for side in (1.0, -1.0):
        ok, c1, s1, c2, s2, f1, f2 = K.rrr_position(0.0, 0.0, 5.0, 0.0, 3.0, 4.0, side)
        assert ok
        np.testing.assert_allclose([3 * c1, 3 * s1], [1.8, side * 2.4], rtol=1e-15)
        np.testing.assert_allclose([5 + 4 * c2, 4 * s2], [1.8, side * 2.4], rtol=1e-15)
        # P2 moving along +X at 1 m/s: the joint angle of P1-X opens as d/dt acos((9+d2-16)/6d)
        w1, w2 = K.rrr_velocity(c1, s1, c2, s2, f1, f2, 0.0, 0.0, 1.0, 0.0)
        d = 5.0
        cos_a = (9 + d * d - 16) / (6 * d)
        dcos = (2 * d * 6 * d - (9 + d * d - 16) * 6) / (6 * d) ** 2
        assert w1 == pytest.approx(side * -dcos / math.sqrt(1 - cos_a**2), rel=1e-14)
    assert not K.rrr_position(0.0, 0.0, 8.0, 0.0, 3.0, 4.0, 1.0)[0]  # too far apart
    assert not K.rrr_position(0.0, 0.0, 0.5, 0.0, 3.0, 4.0, 1.0)[0]  # too close


def test_rrp_dyad_on_a_3_4_5_triangle():
    # D = (0, 3), guide y = 0 along +X, length 5: E = (-4, 0) behind, (4, 0) ahead of D
    for side in (1.0, -1.0):
        ok, c, s, se, fw, fs = K.rrp_position(0.0, 3.0, 0.0, 0.0, 1.0, 0.0, 5.0, side)
        assert ok
        assert se == pytest.approx(side * 4.0, rel=1e-15)
        np.testing.assert_allclose([5 * c, 5 * s], [side * 4.0, -3.0], rtol=1e-15)
        # D moving down at 1 m/s: E = sqrt(25 - y^2) moves out at y / sqrt(25 - y^2) = 3/4
        w, sdot = K.rrp_velocity(c, s, fw, fs, 1.0, 0.0, 0.0, -1.0)
        assert sdot == pytest.approx(side * 0.75, rel=1e-14)
    assert not K.rrp_position(0.0, 5.0, 0.0, 0.0, 1.0, 0.0, 5.0, 1.0)[0]


# -- parameter defaults ----------------------------------------------------------------------------
def test_geometry_defaults_and_mass_properties_follow_the_spec():
    assert len(GEOMETRY_FIELDS) == len(set(GEOMETRY_FIELDS)) == GEO.size - len(DERIVED_FIELDS)
    beta = GEO[GEOMETRY_FIELDS.index("beta")]
    np.testing.assert_array_equal(GEO[-2:], [math.cos(beta), math.sin(beta)])
    assert set(GEOMETRY_FIELDS) == set(DEFAULT_GEOMETRY)
    geo = geometry_array({"L8": 0.4})
    assert geo[GEOMETRY_FIELDS.index("L8")] == 0.4
    with pytest.raises(KeyError, match="Ls7"):
        geometry_array({"Ls7": 0.147})
    # derived: L73 = |PD| = 0.4905 m; panel centroid 0.147 m from C (Ls7)
    c, p, d = np.zeros(2), G["L71"] * e(0.0), G["L72"] * e(G["beta"])
    assert np.hypot(*(p - d)) == pytest.approx(0.4905, abs=1e-4)
    assert np.hypot(*((c + p + d) / 3)) == pytest.approx(0.147, abs=5e-4)
    assert len(BODY_NAMES) == len(MASSES) == len(INERTIAS) == K.N_BODIES
    rods = {"crank1": "L1", "link2": "L2", "link3": "L3", "crank4": "L4", "rocker6": "L6"}
    rods["link8"] = "L8"
    for b, body in enumerate(BODY_NAMES):
        if body in rods:
            assert INERTIAS[b] == pytest.approx(MASSES[b] * G[rods[body]] ** 2 / 12, rel=1e-3)
    sides = G["L71"] ** 2 + G["L72"] ** 2 + np.sum((p - d) ** 2)
    assert INERTIAS[K.PANEL7] == pytest.approx(MASSES[K.PANEL7] * sides / 36, rel=1e-3)
