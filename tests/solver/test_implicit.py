"""The implicit Radau IIA method (order 5; Hairer & Wanner 1996, Sec. IV.8) and the automatic
switching between it and DOP853: tableau, order, stiff problems against scipy, events, pauses,
statistics."""

import math
from fractions import Fraction

import numpy as np
import pytest
import stiff_problems
from scipy.integrate import solve_ivp
from test_events import check_bounce_times

import workbench
from workbench.solver import Problem, integrate
from workbench.solver import _tableaux as tab

VAN_DER_POL, ROBERTSON, OSCILLATOR = 0, 1, 2


def _problem(kind, y0, p=(), scale=None):
    return Problem(
        hooks="stiff_problems",
        states=(),
        y0=np.array(y0, float),
        p=np.array(p, float),
        ip=np.array([kind]),
        atol_scale=scale,
    )


def _scipy(kind, p, y0, t_span, rtol, atol, t_eval=None):
    """scipy's Radau on the same compiled right-hand side and Jacobian."""
    p, ip = np.array(p, float), np.array([kind])
    aux, work = np.zeros(0), np.zeros(1)

    def fun(t, y):
        d = np.empty(y.size)
        stiff_problems.rhs(t, np.ascontiguousarray(y), p, ip, aux, work, d)
        return d

    def jac(t, y):
        J = np.empty((y.size, y.size))
        stiff_problems.jacobian(t, np.ascontiguousarray(y), p, ip, aux, work, J)
        return J

    return solve_ivp(fun, t_span, y0, method="Radau", rtol=rtol, atol=atol, jac=jac, t_eval=t_eval)


def test_radau_tableau():
    """The coefficients are Radau IIA's (collocation at the Radau points: the simplifying
    conditions C(3) and B(5) hold), T block-diagonalises A^-1 into gamma and alpha +- i beta,
    the error weights annihilate polynomials of degree <= 3 (the embedded 3rd-order method)
    and not of degree 4, and P interpolates the stages."""
    A, c = tab.RADAU_A, tab.RADAU_C
    for k in range(1, 4):  # C(3): sum_j a_ij c_j^(k-1) = c_i^k / k
        np.testing.assert_allclose(A @ c ** (k - 1), c**k / k, rtol=0, atol=1e-15)
    for k in range(1, 6):  # B(5) with b = last row of A (stiffly accurate)
        assert abs(A[2] @ c ** (k - 1) - float(Fraction(1, k))) < 1e-15
    assert abs(A[2] @ c**5 - 1 / 6) > 1e-3  # and not B(6): order 5 exactly
    T, TI = tab.RADAU_T, tab.RADAU_TI
    np.testing.assert_allclose(T @ TI, np.eye(3), atol=1e-14)
    L = TI @ np.linalg.inv(A) @ T
    g, a, b = tab.RADAU_GAMMA, tab.RADAU_ALPHA, tab.RADAU_BETA
    np.testing.assert_allclose(L, [[g, 0, 0], [0, a, b], [0, -b, a]], atol=1e-12)
    eig = np.sort_complex(np.linalg.eigvals(np.linalg.inv(A)))
    np.testing.assert_allclose(eig, np.sort_complex([g, a + 1j * b, a - 1j * b]), atol=1e-12)
    # error estimate h y'(0) + sum_i E_i (y(c_i h) - y(0)) for y = t^k, h = 1
    residual = [(k == 1) + tab.RADAU_E @ c**k for k in range(1, 5)]
    np.testing.assert_allclose(residual[:3], 0.0, atol=1e-13)
    assert abs(residual[3]) > 1e-2
    # P: the polynomial sum_k q_k x^(k+1) with q = P^T Z passes through (c_i, Z_i)
    Z = np.array([0.3, -1.2, 2.5])
    q = tab.RADAU_P.T @ Z
    np.testing.assert_allclose([q @ [x, x * x, x**3] for x in c], Z, atol=1e-13)


def test_radau_order_five_with_the_controller_off():
    """A linear oscillator (y1 = cos t; the analytic Jacobian makes the simplified Newton
    iteration exact), steps fixed by max_step at a tolerance no step exceeds: halving the step
    divides the error at t = 4 pi by 2^5 (measured orders 4.93, 5.05, 4.90), the error between
    steps (the collocation polynomial) by ~2^4. A 4th-order method would read 4, so the
    assertion band [4.6, 5.4] tells them apart."""
    t_end = 4.0 * math.pi
    prob = _problem(OSCILLATOR, [1.0, 0.0], [1.0])
    ends, mids = [], []
    for n in (16, 32, 64, 128):
        h = t_end / n
        t = np.linspace(0.0, t_end, 2 * n + 1)
        res = integrate(prob, t, method="radau", rtol=0.1, atol=0.1, max_step=h * (1 + 1e-12))
        assert res.stats["rejected_steps"] == 0 and res.stats["steps"] <= n + 2
        ends.append(abs(res.Y[-1, 0] - math.cos(t_end)))
        mids.append(np.max(np.abs(res.Y[1::2, 0] - np.cos(t[1::2]))))
    orders = np.log2(np.array(ends[:-1]) / ends[1:])
    assert np.all((orders > 4.6) & (orders < 5.4)), orders
    dense = np.log2(mids[0] / mids[-1]) / 3
    assert 3.5 < dense < 4.8, dense


def test_radau_work_precision_slope_is_five():
    """With the step-size controller on (a nonlinear problem with the known solution
    u = sin t, z = cos 2t, finite-difference Jacobian): the error falls as steps^-p with p
    near 5 over rtol 1e-5 .. 1e-10, and stays within 30 tol (tolerance proportionality)."""
    prob = Problem(
        hooks="stiff_hooks",
        states=(),
        y0=np.array([0.0, 1.0]),
        p=np.array([1.0]),
        work_size=2,
        stiff_states=[1],
        stiff_slots=[0],
        implicit_slot=1,
    )
    steps, errors = [], []
    for tol in (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
        res = integrate(prob, np.array([0.0, 5.0]), method="radau", rtol=tol, atol=tol)
        err = max(abs(res.Y[-1, 0] - math.sin(5.0)), abs(res.Y[-1, 1] - math.cos(10.0)))
        assert err < 30 * tol, (tol, err)
        steps.append(res.stats["steps"])
        errors.append(err)
    slope = -np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert 4.3 < slope < 5.7, (slope, steps, errors)


def test_radau_van_der_pol_against_scipy():
    """Van der Pol at mu = 1e3 over two relaxation periods (stiff: DOP853 needs 874 608 steps
    at rtol 1e-6, 10.5 million evaluations): at rtol = atol = 1e-6 and 1e-8 the compiled Radau
    IIA is as accurate as scipy's Radau (errors at t = 3000 against scipy at 1e-12: 3.4e-7 and
    5.2e-9; scipy 7.2e-7 and 3.7e-9) with as many steps (883 and 2 779; scipy 919, 2 769), and
    at most 1.2x scipy's evaluations (6 939 and 20 687; scipy 7 702, 21 587)."""
    mu, t_end, y0 = 1e3, 3000.0, [2.0, 0.0]
    ref = _scipy(VAN_DER_POL, [mu], y0, (0.0, t_end), 1e-12, 1e-12).y[:, -1]
    for tol in (1e-6, 1e-8):
        prob = _problem(VAN_DER_POL, y0, [mu])
        ours = integrate(prob, [0.0, t_end], method="radau", rtol=tol, atol=tol)
        theirs = _scipy(VAN_DER_POL, [mu], y0, (0.0, t_end), tol, tol)
        err = np.max(np.abs(ours.Y[-1] - ref))
        err_scipy = np.max(np.abs(theirs.y[:, -1] - ref))
        assert err < 3.0 * err_scipy and err < 10 * tol, (tol, err, err_scipy)
        assert ours.stats["steps"] < 1.3 * (theirs.t.size - 1)
        assert ours.stats["rhs_evaluations"] < 1.2 * theirs.nfev
        assert ours.stats["jacobians"] > 0 and ours.stats["lu_decompositions"] > 0


def test_radau_robertson():
    """Robertson's reaction up to t = 4e10 (stiffness ratio ~1e11): every record within 3 tol
    of scipy's Radau at 1e-12 in the states scaled by their sizes (y2 ~ 1e-4 and below), and
    the sum y1 + y2 + y3 conserved to rounding (a Runge–Kutta method conserves linear
    invariants, and so does the simplified Newton iteration with a Jacobian that has them)."""
    scale = np.array([1.0, 1e-4, 1.0])
    t = np.array([0.0, 0.4, 40.0, 4e3, 4e5, 4e7, 4e9, 4e10])
    y0 = [1.0, 0.0, 0.0]
    ref = _scipy(ROBERTSON, [], y0, (0.0, t[-1]), 1e-12, 1e-14 * scale, t_eval=t).y.T
    for tol in (1e-6, 1e-8):
        res = integrate(_problem(ROBERTSON, y0, [], scale), t, method="radau", rtol=tol, atol=tol)
        bound = tol * scale + tol * np.abs(ref)
        assert np.all(np.abs(res.Y - ref) < 3 * bound), (tol, np.max(np.abs(res.Y - ref) / bound))
        assert np.max(np.abs(res.Y.sum(axis=1) - 1.0)) < 1e-14
        assert res.stats["steps"] < 1000


@pytest.mark.parametrize("max_step", [0.01, math.inf])
@pytest.mark.parametrize("method", ["radau", "auto"])
def test_bounce_times(method, max_step):
    """The closed-form bounce times to 1e-9 s, as DOP853 (tests/solver/test_events.py). Without
    max_step the free flights (parabolas, which the collocation polynomial reproduces) give
    steps longer than a flight: stages below the floor with both ends above it make the loop
    retry the step shorter (EVENT_INSIDE_STEP), so no bounce is stepped over."""
    check_bounce_times(method, max_step)


@pytest.mark.parametrize("method", ["radau", "auto"])
def test_pauses_are_invisible(method):
    """A run split into 100 pauses (the progress callback's chunks) takes the same steps and
    writes the same records as an unbroken one: the implicit method's Jacobian, LU factors,
    starting values and switching state live in the caller's arrays."""
    prob = _problem(VAN_DER_POL, [2.0, 0.0], [1e3])
    t = np.linspace(0.0, 3000.0, 301)
    one = integrate(prob, t, method=method, rtol=1e-6, atol=1e-6)
    seen = []
    split = integrate(prob, t, method=method, rtol=1e-6, atol=1e-6, progress=seen.append)
    assert len(seen) >= 50
    np.testing.assert_array_equal(one.Y, split.Y)
    for key in ("steps", "rhs_evaluations", "jacobians", "switches_to_implicit"):
        assert one.stats[key] == split.stats[key], key


def test_auto_switches_on_van_der_pol():
    """Van der Pol at mu = 1e3: the automatic method starts with DOP853, switches to Radau IIA
    on the slow stiff branches and back to DOP853 for the fast jumps (where the explicit steps
    are as long as the implicit ones), with the accuracy of either and < 0.1 % of DOP853's
    evaluations (10.5 million); every switch and the time in each method is counted."""
    prob = _problem(VAN_DER_POL, [2.0, 0.0], [1e3])
    ref = _scipy(VAN_DER_POL, [1e3], [2.0, 0.0], (0.0, 3000.0), 1e-12, 1e-12).y[:, -1]
    res = integrate(prob, [0.0, 3000.0], method="auto", rtol=1e-6, atol=1e-6)
    st = res.stats
    assert np.max(np.abs(res.Y[-1] - ref)) < 1e-5
    assert st["rhs_evaluations"] < 10_000
    assert st["switches_to_implicit"] >= 2 and st["switches_to_explicit"] >= 1
    assert st["implicit_time"] > 0.99 * 3000.0
    assert st["implicit_time"] + st["explicit_time"] == pytest.approx(3000.0)
    assert 0 < st["implicit_steps"] < st["steps"]
    assert 0 < st["implicit_rhs_evaluations"] < st["rhs_evaluations"]


def _overdamped(method, duration=20.0):
    """An overdamped Duffing scene (delta = 1e4 1/s, alpha = 1 1/s^2, beta = 0): eigenvalues
    -1e4 and -1e-4 1/s, a stiffness ratio of 1e8, the solution a slow response to the forcing."""
    scene = {
        "model": {"name": "duffing"},
        "parameters": {"delta": 1e4, "alpha": 1.0, "beta": 0.0, "gamma": 1.0, "omega": 1.0},
        "solver": {"method": method, "rtol": 1e-6, "atol": 1e-6},
        "run": {"duration": duration},
        "record": {"dt": 1.0},
    }
    return workbench.simulate(scene)


def test_auto_picks_radau_on_a_stiff_scene():
    """On the overdamped Duffing scene DOP853 is held at its stability bound (h |lambda| ~ 4:
    ~5e4 steps over 20 s); ``auto`` detects it within its first steps, switches to Radau IIA
    once and stays there (> 99 % of the simulated time implicit), at < 1/20 of DOP853's
    evaluations and with its accuracy (records within 1e-5 of DOP853's, |x| ~ 1e-4)."""
    auto, dop = _overdamped("auto"), _overdamped("dop853")
    a, d = auto.attrs, dop.attrs
    assert a["solver_switches_to_implicit"] == 1 and a["solver_switches_to_explicit"] == 0
    assert a["solver_implicit_time"] > 0.99 * 20.0
    assert a["solver_rhs_evaluations"] * 20 < d["solver_rhs_evaluations"]
    np.testing.assert_allclose(auto.x.values, dop.x.values, rtol=0, atol=1e-5)
    assert d["solver_switches_to_implicit"] == 0 and d["solver_implicit_time"] == 0.0


@pytest.mark.chaotic
@pytest.mark.slow
def test_auto_stays_explicit_on_the_default_scene():
    """The default scene (nine-bar, 0.5 mm, 2.5 pi, Coulomb, rtol 1e-6), first crank cycle:
    ``auto`` runs DOP853 (< 1 % of the time in Radau IIA: its few trials around contacts end
    after a step or two, the explicit method measured cheaper) and costs little more than DOP853:
    at most 25 % more evaluations (one processor measured 82 237 against 78 683, 4.5 %; the
    first cycle is chaotic, and the trials fall where another processor's trajectory puts its
    contacts)."""
    base = workbench.load_scene("studies/ninebar.toml")
    runs = {}
    for method in ("auto", "dop853"):
        scene = base.replace(
            solver={**base.solver, "method": method},
            run={"cycles": 1, "transient_cycles": 0},
            record={"samples_per_period": 100, "variables": ["clearance_x"]},
        )
        runs[method] = workbench.simulate(scene).attrs
    period = 2.0 / 2.5
    assert runs["auto"]["solver_implicit_time"] < 0.01 * period
    assert runs["auto"]["solver_rhs_evaluations"] < 1.25 * runs["dop853"]["solver_rhs_evaluations"]


def test_scene_names_the_implicit_methods():
    """``radau`` and ``auto`` are scene methods; a wrong name lists every allowed one."""
    for method in ("radau", "auto"):
        workbench.load_scene({"model": {"name": "duffing"}, "solver": {"method": method}})
    with pytest.raises(workbench.SceneError, match=r"got 'radau5'; allowed: .*ark548, radau, auto"):
        workbench.load_scene({"model": {"name": "duffing"}, "solver": {"method": "radau5"}})
