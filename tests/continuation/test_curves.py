"""Curves of bifurcations in two parameters (``workbench.continuation.continue_curve``) against
answers the code was not tuned on: the default Duffing oscillator's first period-doubling curve
in (gamma, omega) against a shooting code written here for the check alone (scipy's solve_ivp
with the variational equations, Newton's method on the orbit, root finding on det(M + I) = 0),
the grazing curve of the stop oscillator in closed form, the folds of a hardening Duffing
oscillator through their cusp against harmonic balance (slow), and the codimension-two tests
on maps whose multipliers are known in closed form; the dataset's layout, the figures, the
errors."""

import math

import numpy as np
import pytest
import xarray as xr
from _harmonic_balance import folds as hb_folds
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, newton

from workbench.archive import open_run, save_run
from workbench.continuation import CURVE_KINDS, StrobeMap, continue_curve, continue_orbit
from workbench.continuation._curve import _run, _Settings, _system
from workbench.continuation._strobe import MapValue
from workbench.models import get_model
from workbench.models.stop_oscillator import grazing_amplitude

DUFFING = {
    "model": {"name": "duffing"},
    "parameters": {"gamma": 0.25},
    "run": {"transient_cycles": 100},
}


@pytest.fixture(scope="module")
def pd_branch():
    """The default Duffing oscillator's period-1 branch over gamma 0.25 .. 0.27: its first
    period doubling at gamma = 0.2655818 (tests/continuation/test_continuation.py)."""
    return continue_orbit(DUFFING, "gamma", stop=0.27)


@pytest.fixture(scope="module")
def pd_curve(pd_branch):
    """That period doubling continued in omega from 1.0 to 1.4 (the scene's omega is 1.2)."""
    return continue_curve(pd_branch, "omega", start=1.0, stop=1.4)


# -- an independent shooting code, for the check alone ---------------------------------------
D = get_model("duffing").default_parameters()


def _period_map(x, omega, gamma):
    """The default Duffing's map over one forcing period and its Jacobian, by the variational
    equations (solve_ivp, DOP853, rtol 1e-12)."""
    delta, alpha, beta = D["delta"], D["alpha"], D["beta"]

    def f(t, z):
        u, v = z[0], z[1]
        Phi = z[2:].reshape(2, 2)
        A = np.array([[0.0, 1.0], [-alpha - 3.0 * beta * u * u, -delta]])
        rate = [v, gamma * math.cos(omega * t) - delta * v - alpha * u - beta * u**3]
        return np.concatenate([rate, (A @ Phi).ravel()])

    z0 = np.concatenate([x, np.eye(2).ravel()])
    z = solve_ivp(f, (0.0, 2 * math.pi / omega), z0, method="DOP853", rtol=1e-12, atol=1e-13).y
    return z[:2, -1], z[2:, -1].reshape(2, 2)


def _orbit(x, omega, gamma):
    """Newton's method on P(x) = x."""
    for _ in range(40):
        Px, M = _period_map(x, omega, gamma)
        if np.max(np.abs(Px - x)) < 1e-12:
            return x, M
        x = x - np.linalg.solve(M - np.eye(2), Px - x)
    raise AssertionError(f"no periodic orbit at omega = {omega}, gamma = {gamma}")


def _doubling(x, omega, gamma):
    """The gamma near ``gamma`` where the orbit through (about) x has a multiplier -1: the
    secant method on det(M + I), each value on the orbit found by Newton's method."""
    state = {"x": x}

    def det(g):
        state["x"], M = _orbit(state["x"], omega, g)
        return np.linalg.det(M + np.eye(2))

    g = newton(det, gamma, x1=gamma * 1.002, tol=1e-13, maxiter=50)
    return g, state["x"]


def test_the_duffing_period_doubling_curve_agrees_with_an_independent_shooting_code(pd_curve):
    """Issue 38 item 8: along omega 1.0 .. 1.4 the curve's gamma equals the independent code's
    (marched outward from omega = 1.2, each value from the one before) far within the 0.2 % the
    issue asks: both are converged solutions of one condition (1e-7 relative)."""
    # the independent start: the orbit after the scene's transient at (1.2, 0.25)
    x = np.array([D["x0"], D["v0"]])
    for _ in range(100):
        x = _period_map(x, 1.2, 0.25)[0]
    g0, x0 = _doubling(_orbit(x, 1.2, 0.25)[0], 1.2, 0.25)
    assert abs(g0 - 0.2655818) < 1e-7  # the value docs/continuation.md quotes
    omega, gamma = pd_curve.omega.values, pd_curve.gamma.values
    s = int(np.flatnonzero(pd_curve.label.values == 1)[0])  # 1: start
    checked = 0
    for order in (range(s, omega.size, 2), range(s, -1, -2)):
        g, x = g0, x0
        for i in order:
            g, x = _doubling(x, omega[i], g)
            assert abs(gamma[i] - g) < 1e-7 * g, (omega[i], gamma[i], g)
            checked += 1
    assert checked >= 10
    # the curve spans the range and its multiplier is -1 all along
    assert (omega[0], omega[-1]) == (1.0, 1.4)
    assert np.allclose(pd_curve.critical_real, -1.0, atol=1e-6)
    assert np.allclose(pd_curve.critical_imag, 0.0, atol=1e-9)


def test_the_curve_dataset_is_netcdf_ready_and_self_described(pd_curve, pd_branch, tmp_path):
    c = pd_curve
    for name, da in {**c.data_vars, **c.coords}.items():
        assert da.attrs.get("units") and da.attrs.get("long_name"), name
    assert c.gamma.attrs["units"] == "1" and c.omega.attrs["units"] == "rad s-1"
    assert c.kind.attrs["flag_meanings"].split() == list(CURVE_KINDS)
    assert (c.kind == CURVE_KINDS["period_doubling"]).all()
    assert c.attrs["continuation_parameter"] == "gamma" and c.attrs["curve_parameter"] == "omega"
    assert c.attrs["curve_kind"] == "period_doubling" and "continue_curve" in c.attrs["history"]
    assert "[parameters]" in c.attrs["scene"] and c.attrs["rtol"] == pd_branch.attrs["rtol"]
    # the start is the branch's period doubling, at the scene's omega
    s = np.flatnonzero(c.label.values == 1)
    assert s.size == 1 and float(c.omega[s[0]]) == 1.2
    pd = float(pd_branch.bifurcation_parameter[0])
    assert abs(float(c.gamma[s[0]]) - pd) < 1e-9
    # omega grows along the stored curve, and so does the tangent's component in it
    assert (np.diff(c.omega) > 0).all() and (c.test_second_parameter_turn > 0).all()
    # converged: Newton's residual below the branch's tolerance everywhere
    assert (c.residual < pd_branch.attrs["tolerance"]).all()
    assert c.attrs["curve_ended"].count("reached the end of its range") == 2
    path = save_run(c, tmp_path / "curve.nc")
    back = open_run(path)
    xr.testing.assert_allclose(back.gamma, c.gamma)
    assert back.kind.attrs["flag_meanings"] == c.kind.attrs["flag_meanings"]


def test_a_curve_from_a_scene_equals_the_curve_from_the_branch(pd_curve):
    """The same period doubling started from a scene near it (gamma 0.2656, Newton on the whole
    defining system) reaches the same point at omega = 1.4."""
    scene = dict(DUFFING, parameters={"gamma": 0.2656})
    c = continue_curve(scene, "omega", stop=1.4, parameter="gamma", kind="period_doubling")
    assert float(c.omega[0]) == 1.2 and float(c.omega[-1]) == 1.4
    assert abs(float(c.gamma[-1]) - float(pd_curve.gamma[-1])) < 1e-9


def test_the_flow_over_one_period_is_the_map_with_its_monodromy():
    """StrobeMap.flow (the state at any time with its Jacobian by copies) over a whole period
    is the strobe map, its Jacobian the tangent system's monodromy; at t0 it is the identity."""
    smap = StrobeMap(dict(DUFFING, parameters={"gamma": 0.26}), "gamma")
    y, aux = smap.initial(0.26)
    prep = smap.prepared(0.26)
    z, _, W, active = smap.flow(y, aux, 0.26, prep.problem.t0 + prep.period)
    v = smap(y, aux, 0.26)
    s = smap.scale()
    assert active.size == 0 and np.allclose(z, v.y1, rtol=0, atol=1e-8)
    assert np.allclose(W / s[:, None], v.M, rtol=0, atol=1e-6 * np.abs(v.M).max())
    z0, _, W0, _ = smap.flow(y, aux, 0.26, prep.problem.t0)
    assert np.array_equal(z0, y) and np.array_equal(W0, np.diag(s))


# -- grazing in closed form ------------------------------------------------------------------
STOP = {"damping": 0.1, "stop_stiffness": 100.0, "gap": 1.0, "force": 0.5}


def test_the_grazing_curve_of_the_stop_oscillator_against_the_closed_form():
    """The non-impacting orbit grazes the stop where F / sqrt((k - m w^2)^2 + (c w)^2) = g:
    the grazing located on a branch over omega continued in the force F from 0.3 to 0.7 lies
    on that curve (1e-9 relative), touching the stop (x = g, v = 0) once per period."""
    scene = {
        "model": {"name": "stop_oscillator"},
        "parameters": dict(STOP, omega=0.68),
        "run": {"transient_cycles": 100},
    }
    branch = continue_orbit(scene, "omega", stop=0.74, rtol=1e-10, tolerance=1e-9)
    c = continue_curve(branch, "force", start=0.3, stop=0.7, kind="grazing")
    assert (c.kind == CURVE_KINDS["grazing"]).all() and c.attrs["grazing_event"] == 0
    assert (float(c.force[0]), float(c.force[-1])) == (0.3, 0.7)
    model = {"mass": 1.0, "stiffness": 1.0, **STOP}
    for w, f in zip(c.omega.values, c.force.values, strict=True):
        exact = brentq(
            lambda x, f=f: grazing_amplitude({**model, "force": f, "omega": x}) - 1, 0.1, 0.99
        )
        assert abs(w - exact) < 1e-9 * exact, (f, w, exact)
    assert np.allclose(c.touch_x, STOP["gap"], rtol=0, atol=1e-9)
    assert np.allclose(c.touch_v, 0.0, atol=1e-9)
    # the linear orbit x = A cos(omega t - phi) touches where omega t = phi, its phase lag
    # atan2(c w, k - m w^2) (t0 = 0)
    phase = c.omega * c.touch_time
    expected = np.arctan2(0.1 * c.omega, 1.0 - c.omega**2)
    assert np.allclose(phase, expected, atol=1e-7)
    assert (c.test_degenerate_grazing < 0).all()  # a maximum of x - g: a contact appears


# -- codimension two on maps known in closed form --------------------------------------------
class Companion:
    """A map of the plane with the fixed point c = (p, q) / 10 whose Jacobian there is
    ``[[0, 1], [-det, trace]]`` (multipliers: roots of mu^2 - trace mu + det), plus a cubic
    term that vanishes at the fixed point."""

    periods, rtol, evaluations = 1, 1e-12, 0
    s0 = np.ones(2)
    q_name = "q"  # the second parameter's name (a curve's progress line names it)

    def __init__(self, trace, det):
        self.trace, self.det = trace, det

    def check(self, p, q):
        return None

    def __call__(self, y, aux, p, q, tangent=True):
        c = 0.1 * np.array([p, q])
        d = np.asarray(y, float) - c
        A = np.array([[0.0, 1.0], [-self.det(p, q), self.trace(p, q)]])
        r2 = float(d @ d)
        M = A + r2 * np.eye(2) + 2.0 * np.outer(d, d)
        return MapValue(c + A @ d + r2 * d, np.zeros(0), np.zeros(0, int), M, 0, {})


def _specials(fam, kind, p0, q0, ends):
    _, points, labels, halves = _run(
        fam, _system(kind, None), 0.1 * np.array([p0, q0]), np.zeros(0), p0, q0, [], ends,
        1.0, _Settings(tolerance=1e-10), None,
    )  # fmt: skip
    assert all("reached the end" in h.ended for h in halves), [h.ended for h in halves]
    special = {lab: (pt.ev.p, pt.ev.q) for pt, lab in zip(points, labels, strict=True)}
    return points, labels, special


def test_strong_resonances_on_a_neimark_sacker_curve():
    """det = 1 + p - q^2 / 10, trace = q: the Neimark-Sacker curve is p = q^2 / 10 with
    cos(theta) = q / 2: 1:2, 1:3, 1:4 and 1:1 resonance at q = -2, -1, 0, 2; beyond |q| = 2 the
    pair is real, mu and 1 / mu (a neutral saddle); the curve turns in p at q = 0."""
    fam = Companion(lambda p, q: q, lambda p, q: 1.0 + p - q * q / 10.0)
    points, labels, special = _specials(fam, "neimark_sacker", 0.025, 0.5, (-3.0, 3.0))
    where = {"resonance_1_2": -2.0, "resonance_1_3": -1.0, "resonance_1_4": 0.0}
    where.update(resonance_1_1=2.0, first_parameter_turn=0.0)
    assert set(special) == set(where) | {"start", "end", "regular"}
    for name, q in where.items():
        p, qq = special[name]
        assert abs(qq - q) < 1e-5 and abs(p - q * q / 10) < 1e-9, (name, p, qq)
    for pt in points:  # on the curve: two multipliers with product 1
        mu = pt.multipliers
        assert abs(mu[0] * mu[1] - 1.0) < 1e-9 and abs(pt.ev.p - pt.ev.q**2 / 10) < 1e-9
    from workbench.continuation._curve import _point_kind

    kinds = {_point_kind("neimark_sacker", pt.multipliers) for pt in points if abs(pt.ev.q) > 2.01}
    assert kinds == {"neutral_saddle"}
    inside = {_point_kind("neimark_sacker", pt.multipliers) for pt in points if abs(pt.ev.q) < 1.99}
    assert inside == {"neimark_sacker"}


def test_fold_flip_and_1_2_resonance_on_a_period_doubling_curve():
    """trace = p, det = q: a multiplier -1 on p = -1 - q; the other multiplier is -q, so it
    passes +1 at q = -1 (fold-flip) and -1 at q = 1 (1:2 resonance)."""
    fam = Companion(lambda p, q: p, lambda p, q: q)
    _, _, special = _specials(fam, "period_doubling", -1.5, 0.5, (-2.0, 2.0))
    assert set(special) == {"start", "end", "regular", "fold_flip", "resonance_1_2"}
    for name, q in (("fold_flip", -1.0), ("resonance_1_2", 1.0)):
        p, qq = special[name]
        assert abs(qq - q) < 1e-6 and abs(p + 1.0 + q) < 1e-6, (name, p, qq)


# -- the hardening Duffing's folds through their cusp (slow) ---------------------------------
HARDENING = {"alpha": 1.0, "beta": 0.1, "delta": 0.05, "gamma": 0.1}


@pytest.mark.slow
def test_the_fold_curve_passes_its_cusp_and_agrees_with_harmonic_balance():
    """x'' + 0.05 x' + x + 0.1 x^3 = gamma cos(omega t): the jump-down fold at gamma = 0.1
    (omega = 1.1161418, harmonic balance) continued down in gamma turns at a cusp and comes
    back up as the jump-up fold (omega = 1.0761313 at gamma = 0.1). At every gamma both folds
    agree with harmonic balance with 7 harmonics (tests/_harmonic_balance.py) to 1e-6; the cusp
    is where the curve's gamma is least, and its normal-form coefficient changes sign there."""
    scene = {
        "model": {"name": "duffing"},
        "parameters": dict(HARDENING, omega=1.0),
        "initial": {"x": 0.0, "v": 0.0},
        "run": {"transient_cycles": 300},
    }
    branch = continue_orbit(scene, "omega", stop=1.25, rtol=1e-10, tolerance=1e-9)
    c = continue_curve(branch, "gamma", start=0.03, stop=0.15)
    assert (c.kind == CURVE_KINDS["fold"]).all()
    assert np.allclose(c.critical_real, 1.0, atol=1e-6)
    names = c.label.attrs["flag_meanings"].split()
    found = [names[int(k)] for k in c.special_label.values]
    assert sorted(found) == ["cusp", "first_parameter_turn", "second_parameter_turn"], found
    at = c.special_index.values
    cusp = float(c.gamma[at[0]])
    assert np.ptp(c.gamma.values[at]) < 1e-6 and abs(cusp - float(c.gamma.min())) < 1e-9
    assert abs(cusp - 0.0539311) < 1e-6, cusp  # the value docs/continuation.md quotes
    a = c.test_cusp.values
    assert (a[: at.min()] < 0).all() and (a[at.max() + 1 :] > 0).all()
    # each curve point on one of the two harmonic-balance folds at its gamma, both met
    met, compared = set(), 0
    for i in range(0, c.sizes["curve_point"], 6):
        g, w = float(c.gamma[i]), float(c.omega[i])
        if g < 0.06:  # the single-harmonic start of the balance needs both folds apart
            continue
        try:
            folds = hb_folds(**dict(HARDENING, gamma=g), H=7)
        except RuntimeError:  # the balance's own Newton from its one-harmonic start
            continue
        k = int(np.argmin(np.abs(np.array(folds) - w)))
        assert abs(w - folds[k]) < 1e-6, (g, w, folds)
        met.add(k)
        compared += 1
    assert met == {0, 1} and compared >= 4, (met, compared)
    start = int(np.flatnonzero(c.label.values == 1)[0])
    assert float(c.omega[start]) == pytest.approx(1.1161418, abs=1e-7)


# -- errors ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"kind": "hopf"}, "kind='hopf'; allowed"),
        ({"kind": "fold"}, "no fold point located on the branch over gamma (found: "),
        ({"bifurcation": 3}, "bifurcation=3: the branch has 1 located"),
        ({"second_parameter": "nope"}, "second_parameter='nope' is not a parameter"),
        ({"second_parameter": "gamma"}, "is the first parameter"),
        ({"start": 1.3}, "must contain the scene's value 1.2"),
        ({"value": 0.26}, "value= start a curve from a scene; a branch starts it at its own"),
    ],
)
def test_curve_errors_say_what_is_allowed(pd_branch, kwargs, message):
    args = {"second_parameter": "omega", "stop": 1.4, **kwargs}
    with pytest.raises(ValueError, match=None) as err:
        continue_curve(pd_branch, **args)
    assert message in str(err.value), str(err.value)


def test_a_scene_needs_the_first_parameter_and_the_kind():
    with pytest.raises(ValueError, match="needs parameter="):
        continue_curve(DUFFING, "omega", stop=1.3)
    with pytest.raises(ValueError, match="no 'continuation_parameter'"):
        continue_curve(xr.Dataset(attrs={"scene": "x"}), "omega", stop=1.3)


# -- figures ---------------------------------------------------------------------------------
def test_curves_are_drawn_over_a_chaos_map_within_its_extent(pd_curve):
    from workbench.plot import chaos_map_figure, curve_figure

    gamma, omega = np.linspace(0.2, 0.3, 5), np.linspace(1.1, 1.3, 4)
    maps = xr.Dataset(
        {"strobe_period": (("gamma", "omega"), np.ones((5, 4), np.int8), {"units": "1"})},
        coords={
            "gamma": ("gamma", gamma, {"units": "1", "long_name": "forcing amplitude"}),
            "omega": ("omega", omega, {"units": "rad s-1", "long_name": "forcing frequency"}),
        },
        attrs={"campaign_dims": "gamma omega"},
    )
    fig = chaos_map_figure(maps, indicators=("strobe_period",), curves=[pd_curve])
    ax = fig.axes[0]
    line = next(l for l in ax.lines if l.get_label() == "PD curve")
    # in the map's display units (gamma a pure number, as the curve's)
    assert ax.get_xlabel() == "forcing amplitude"
    assert np.array_equal(line.get_xdata(), pd_curve.gamma.values)
    assert np.array_equal(line.get_ydata(), pd_curve.omega.values)
    # the map's extent is kept (the curve runs beyond it, omega 1.0 .. 1.4)
    assert ax.get_ylim()[0] > 1.0 and ax.get_ylim()[1] < 1.4
    # the other way round the axes swap
    swapped = maps.transpose("omega", "gamma").assign_attrs(campaign_dims="omega gamma")
    fig = chaos_map_figure(swapped, indicators=("strobe_period",), curves=[pd_curve])
    line = next(l for l in fig.axes[0].lines if l.get_label() == "PD curve")
    assert np.array_equal(line.get_xdata(), pd_curve.omega.values)
    assert np.array_equal(line.get_ydata(), pd_curve.gamma.values)
    other = maps.rename(omega="delta").assign_attrs(campaign_dims="gamma delta")
    with pytest.raises(ValueError, match="cannot be drawn on a map over"):
        chaos_map_figure(other, indicators=("strobe_period",), curves=[pd_curve])
    assert curve_figure([pd_curve]).axes[0].get_xlabel().startswith("forcing amplitude")


def test_where_a_continued_sweep_stops_being_period_1_is_drawn_over_a_chaos_map():
    """Per direction and clearance the marker sits at the last value of the run of period-1
    values from the bottom of omega (going up: period 1 up to 1.84 pi, then none; at the second
    clearance the run ends at 1.82 pi though 1.84 pi is period 1 again), with a bar to the next
    value; a clearance whose first value is not period-1 has none."""
    from workbench.plot import chaos_map_figure

    omega = np.array([1.8, 1.82, 1.84, 1.86]) * np.pi
    c = np.array([2e-5, 4e-5, 6e-5])
    up = np.array([[1, 1, 1], [1, 0, 1], [1, 1, 1], [0, 0, 0]], np.int8)  # (omega, clearance)
    down = up.copy()
    down[2, 0] = 0
    down[0, 2] = 0
    coords = {
        "omega": ("omega", omega, {"units": "rad s-1", "long_name": "crank speed"}),
        "clearance": ("clearance", c, {"units": "m", "long_name": "clearance"}),
    }
    ends = xr.Dataset(
        {"strobe_period": (("direction", "omega", "clearance"), np.stack([up, down]))},
        coords={**coords, "direction": ("direction", ["up", "down"])},
    )
    maps = xr.Dataset(
        {"strobe_period": (("omega", "clearance"), up, {"units": "1"})},
        coords=coords,
        attrs={"campaign_dims": "omega clearance"},
    )
    fig = chaos_map_figure(
        maps, indicators=("strobe_period",), scales={"omega": 1 / np.pi}, ends=ends
    )
    ax = fig.axes[0]
    lines = {l.get_label(): l for l in ax.lines}
    going_up, coming_down = lines["period 1 ends (sweep up)"], lines["period 1 ends (sweep down)"]
    assert np.allclose(going_up.get_xdata(), [1.84, 1.8, 1.84])
    assert np.allclose(going_up.get_ydata(), [0.02, 0.04, 0.06])  # mm
    assert np.allclose(coming_down.get_xdata(), [1.82, 1.8])  # none at 60 um
    assert np.allclose(coming_down.get_ydata(), [0.02, 0.04])
    bars = [l for l in ax.lines if l.get_label().startswith("_")]
    assert [tuple(np.round(b.get_xdata(), 6)) for b in bars[:3]] == [
        (1.84, 1.86), (1.8, 1.82), (1.84, 1.86)
    ]  # fmt: skip
