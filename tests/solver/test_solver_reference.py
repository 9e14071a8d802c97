"""Compiled DOP853/DOPRI5 against scipy's DOP853 on the reference systems."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import workbench
from workbench.models.duffing import rhs as duffing_rhs

LORENZ = {"model": {"name": "lorenz"}, "run": {"duration": 5.0}, "record": {"dt": 0.01}}
DUFFING = {
    "model": {"name": "duffing"},
    "parameters": {"gamma": 0.5},
    "run": {"cycles": 5},
    "record": {"samples_per_period": 50},
}


def _with(scene, **solver):
    return {**scene, "solver": solver}


@pytest.mark.parametrize("base", [LORENZ, DUFFING], ids=["lorenz", "duffing"])
@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_compiled_matches_scipy_dop853(base, method):
    ref = workbench.simulate(_with(base, method="scipy:DOP853", rtol=1e-12, atol=1e-12))
    ds = workbench.simulate(_with(base, method=method, rtol=1e-12, atol=1e-12))
    for var in ds.data_vars:
        err = float(np.max(np.abs(ds[var] - ref[var])))
        assert err < 1e-6, f"{var}: max abs difference {err:.3g} over the run"


@pytest.mark.parametrize("base", [LORENZ, DUFFING], ids=["lorenz", "duffing"])
@pytest.mark.parametrize("rtol", [1e-6, 1e-9, 1e-12])
def test_dop853_step_count_matches_scipy(base, rtol):
    ref = workbench.simulate(_with(base, method="scipy:DOP853", rtol=rtol, atol=rtol))
    ds = workbench.simulate(_with(base, method="dop853", rtol=rtol, atol=rtol))
    n, n_ref = ds.attrs["solver_steps"], ref.attrs["solver_steps"]
    assert abs(n - n_ref) <= 0.1 * n_ref, (n, n_ref)


def test_stroboscopic_records_are_exact():
    """Records at t0 + kT/spp carry no error beyond the dense output's (scipy t_eval)."""
    ds = workbench.simulate(_with(DUFFING, method="dop853", rtol=1e-12, atol=1e-12))
    T = ds.attrs["forcing_period"]
    spp = ds.attrs["samples_per_period"]
    strobe = ds.isel(time=slice(None, None, spp))
    np.testing.assert_allclose(
        strobe.time, np.arange(strobe.sizes["time"]) * T, rtol=0, atol=1e-12 * T
    )
    p = np.array([0.3, -1.0, 1.0, 0.5, 1.2])

    def f(t, y):
        out = np.empty(2)
        duffing_rhs(t, y, p, np.zeros(0, np.int64), np.zeros(0), np.zeros(1), out)
        return out

    sol = solve_ivp(
        f,
        (0, float(strobe.time[-1])),
        [1.0, 0.0],
        method="DOP853",
        rtol=1e-13,
        atol=1e-13,
        t_eval=strobe.time.values,
    )
    assert np.max(np.abs(sol.y[0] - strobe.x.values)) < 1e-9
    assert np.max(np.abs(sol.y[1] - strobe.v.values)) < 1e-9


def test_paused_run_is_bit_identical():
    """The progress bar splits the run into chunks; the numbers must not change."""
    from workbench.models import get_model
    from workbench.solver import integrate

    m = get_model("duffing")
    prob = m.problem(m.default_parameters(), {}, {}, ("x", "v"))
    t = np.linspace(0, 50, 501)
    a = integrate(prob, t, rtol=1e-9, atol=1e-9)
    b = integrate(prob, t, rtol=1e-9, atol=1e-9, progress=lambda _t: None)
    np.testing.assert_array_equal(a.Y, b.Y)
    assert a.stats["steps"] == b.stats["steps"]


def test_solver_statistics_recorded():
    ds = workbench.simulate(_with(LORENZ, method="dop853", rtol=1e-8, atol=1e-8))
    for key in (
        "method",
        "rtol",
        "atol",
        "steps",
        "rejected_steps",
        "rhs_evaluations",
        "events",
        "wall_time",
    ):
        assert f"solver_{key}" in ds.attrs
    assert ds.attrs["solver_steps"] > 0
    assert ds.attrs["solver_rhs_evaluations"] >= 12 * ds.attrs["solver_steps"]


def test_max_steps_raises_solver_error_with_time_and_state():
    with pytest.raises(workbench.SolverError, match=r"t = .* s.*max_steps") as info:
        workbench.simulate(_with(LORENZ, method="dop853", rtol=1e-10, atol=1e-10, max_steps=10))
    assert info.value.status is workbench.Status.MAX_STEPS
    assert set(info.value.state) == {"x", "y", "z"}
    assert 0 < info.value.time < 5.0
