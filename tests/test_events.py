"""Event location with state updates: the bouncing ball against its closed-form bounce times."""

import numpy as np
import pytest

import workbench


def analytic_bounce_times(h0, g, e, n):
    t1 = np.sqrt(2 * h0 / g)
    v1 = g * t1
    flights = 2 * v1 * e ** np.arange(1, n) / g
    return np.concatenate([[t1], t1 + np.cumsum(flights)])


@pytest.mark.parametrize("method", ["dop853", "dopri5", "scipy:DOP853"])
def test_bounce_times(method):
    e, g, h0 = 0.8, 9.81, 1.0
    expected = analytic_bounce_times(h0, g, e, 10)
    scene = {
        "model": {"name": "bouncing_ball"},
        "parameters": {"restitution": e, "g": g, "h0": h0},
        "solver": {"method": method, "rtol": 1e-10, "atol": 1e-12, "max_step": 0.01},
        "run": {"duration": float(expected[-1] + 0.01)},
        "record": {"dt": 0.001},
    }
    ds = workbench.simulate(scene)
    times = np.unique(ds.last_bounce_time.values[~np.isnan(ds.last_bounce_time.values)])
    assert times.size == 10
    np.testing.assert_allclose(times, expected, rtol=0, atol=1e-9)
    assert ds.attrs["solver_events"] == 10
    assert int(ds.bounces[-1]) == 10


def test_records_straddling_an_event_are_continuous():
    """The state just before and after a bounce: same height, reversed velocity."""
    ds = workbench.simulate(
        {
            "model": {"name": "bouncing_ball"},
            "solver": {"rtol": 1e-10, "atol": 1e-12, "max_step": 0.01},
            "run": {"duration": 0.6},
            "record": {"dt": 1e-4},
        }
    )
    assert float(ds.h.min()) > -1e-9
    tb = float(np.nanmax(ds.last_bounce_time))
    before = ds.sel(time=tb - 1e-4, method="nearest")
    after = ds.sel(time=tb + 1e-4, method="nearest")
    assert float(after.v) == pytest.approx(-0.8 * float(before.v), rel=2e-3)
