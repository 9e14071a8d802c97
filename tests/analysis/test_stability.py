"""Linear stability: Jacobian spectra along runs and Floquet multipliers (issue: the paper's
claims judged over many realisations, item 2)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import workbench
from workbench.analysis import floquet, floquet_sweep, jacobian_spectrum, poincare_section

DUFFING = {"delta": 0.3, "alpha": -1.0, "beta": 1.0, "omega": 1.2}


def test_damped_linear_oscillator_eigenvalues():
    """x'' + delta x' + alpha x = 0: -delta/2 +/- i sqrt(alpha - delta^2/4) at every state."""
    delta, alpha = 0.2, 4.0
    r = jacobian_spectrum(
        {
            "model": {"name": "duffing"},
            "parameters": {"delta": delta, "alpha": alpha, "beta": 0.0, "gamma": 0.0},
            "run": {"cycles": 2},
        }
    )
    w = math.sqrt(alpha - delta**2 / 4)
    np.testing.assert_allclose(r.eigenvalue_real.values, -delta / 2, atol=1e-12)
    expected = np.broadcast_to([-w, w], r.eigenvalue_imag.shape)
    np.testing.assert_allclose(np.sort(r.eigenvalue_imag.values, axis=1), expected, atol=1e-12)
    assert r.eigenvalue_real.attrs["units"] == "s-1"
    assert r.frequency.attrs["units"] == "Hz"
    from workbench.plot import jacobian_spectrum_figure

    fig = jacobian_spectrum_figure(r)
    assert fig.axes[0].get_ylabel() == "largest real part of an eigenvalue [1/s]"


def test_duffing_eigenvalues_follow_the_state():
    """J = [[0, 1], [-alpha - 3 beta x^2, -delta]]: lambda = -delta/2 +/- sqrt(delta^2/4 - alpha
    - 3 beta x^2), at every record of a chaotic run."""
    scene = {
        "model": {"name": "duffing"},
        "parameters": {**DUFFING, "gamma": 0.5},
        "run": {"cycles": 3},
        "record": {"samples_per_period": 50},
    }
    r = jacobian_spectrum(scene)
    x = workbench.simulate(scene).x.values
    disc = DUFFING["delta"] ** 2 / 4 - DUFFING["alpha"] - 3 * DUFFING["beta"] * x**2
    root = np.sqrt(disc.astype(complex))
    exact = np.stack([-DUFFING["delta"] / 2 + root, -DUFFING["delta"] / 2 - root], axis=1)
    exact = np.take_along_axis(exact, np.argsort(-exact.real, axis=1), axis=1)
    got = r.eigenvalue_real.values + 1j * r.eigenvalue_imag.values
    np.testing.assert_allclose(np.sort_complex(got), np.sort_complex(exact), atol=1e-9)


def _scipy_monodromy(x0, gamma, period):
    """The Duffing orbit's monodromy matrix by scipy: state and variational equations."""
    d, a, b, w = DUFFING["delta"], DUFFING["alpha"], DUFFING["beta"], DUFFING["omega"]

    def f(t, z):
        x, v = z[0], z[1]
        M = z[2:].reshape(2, 2)
        J = np.array([[0.0, 1.0], [-a - 3 * b * x * x, -d]])
        return np.concatenate(
            [[v, gamma * math.cos(w * t) - d * v - a * x - b * x**3], (J @ M).ravel()]
        )

    z = solve_ivp(f, (0, period), np.concatenate([x0, np.eye(2).ravel()]), method="DOP853",
                  rtol=1e-12, atol=1e-12).y[:, -1]  # fmt: skip
    return z[2:].reshape(2, 2)


def test_floquet_multipliers_of_a_duffing_orbit_match_scipy():
    """Period-1 orbit at gamma = 0.2 (stable): multipliers from the compiled variational run
    equal the eigenvalues of a scipy-integrated monodromy matrix to 1e-6; their product is
    det M = exp(-delta T) (Liouville)."""
    scene = {
        "model": {"name": "duffing"},
        "parameters": {**DUFFING, "gamma": 0.2},
        "initial": {"x": 1.0, "v": 0.0},
        "run": {"transient_cycles": 100},
    }
    r = floquet(scene)
    assert float(r.residual) < 1e-9 and bool(r.stable) and str(r.loss.values) == "stable"
    period = 2 * math.pi / DUFFING["omega"]
    M = _scipy_monodromy(r.orbit_state.values, 0.2, period)
    mu = np.linalg.eigvals(M)
    got = r.multiplier_real.values + 1j * r.multiplier_imag.values
    np.testing.assert_allclose(np.sort_complex(got), np.sort_complex(mu), atol=1e-6)
    assert np.prod(r.modulus.values) == pytest.approx(math.exp(-DUFFING["delta"] * period), 1e-8)


def test_floquet_says_which_method_integrates_the_monodromy_matrix():
    """An implicit method in the scene (radau) runs the transient, but the tangent system is
    integrated with DOP853: floquet warns, naming the method, and records the one it used; the
    multipliers equal those of the all-DOP853 call."""
    scene = {
        "model": {"name": "duffing"},
        "parameters": {**DUFFING, "gamma": 0.2},
        "initial": {"x": 1.0, "v": 0.0},
        "run": {"transient_cycles": 100},
    }
    with pytest.warns(UserWarning, match="DOP853, not with solver.method='radau'"):
        r = floquet({**scene, "solver": {"method": "radau"}})
    assert r.attrs["tangent_method"] == "dop853"
    ref = floquet(scene)
    assert ref.attrs["tangent_method"] == "dop853"
    np.testing.assert_allclose(r.modulus.values, ref.modulus.values, atol=1e-6)


def _strobe_points(gamma):
    ds = workbench.simulate(
        {
            "model": {"name": "duffing"},
            "parameters": {**DUFFING, "gamma": gamma},
            "initial": {"x": 1.0, "v": 0.0},
            "run": {"cycles": 16, "transient_cycles": 1500},
            "record": {"samples_per_period": 4},
            "solver": {"rtol": 1e-10, "atol": 1e-10},
        }
    )
    x = poincare_section(ds, "x")["x"].values
    return len(np.unique(np.round(x, 4)))


@pytest.mark.slow
def test_flip_bifurcation_located_within_one_percent_of_the_strobe_samples():
    """The period-1 orbit of Duffing's sweep over gamma loses stability by a flip (a multiplier
    through -1); continuation locates it, and the strobe samples of long runs go from one point
    to two there: bisection on gamma brackets their change within 0.5 %, and the two agree
    within 1 %."""
    gammas = np.linspace(0.25, 0.28, 16)
    sweep = floquet_sweep(
        {
            "model": {"name": "duffing"},
            "parameters": {**DUFFING, "gamma": 0.25},
            "initial": {"x": 1.0, "v": 0.0},
            "run": {"transient_cycles": 100},
        },
        "gamma",
        gammas,
    )
    assert sweep.attrs["first_loss_kind"] == "flip"
    g_flip = sweep.attrs["first_loss_value"]
    lo, hi = 0.25, 0.28
    assert _strobe_points(lo) == 1 and _strobe_points(hi) == 2
    while hi - lo > 0.005 * g_flip:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _strobe_points(mid) == 1 else (lo, mid)
    assert g_flip == pytest.approx(0.5 * (lo + hi), rel=0.01)
    assert sweep.gamma.attrs["units"] == "1"
    from workbench.plot import floquet_figure

    assert floquet_figure(sweep).axes[0].get_xlabel() == "forcing amplitude"
