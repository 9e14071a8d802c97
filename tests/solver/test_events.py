"""Event location with state updates: the bouncing ball against its closed-form bounce times."""

import numpy as np
import pytest

import workbench


def analytic_bounce_times(h0, g, e, n):
    t1 = np.sqrt(2 * h0 / g)
    v1 = g * t1
    flights = 2 * v1 * e ** np.arange(1, n) / g
    return np.concatenate([[t1], t1 + np.cumsum(flights)])


def check_bounce_times(method: str, max_step: float):
    """Ten bounces of a ball (e = 0.8, h0 = 1 m) by ``method``: the bounce times within 1e-9 s
    of the closed form, one event each. Returns the run."""
    e, g, h0 = 0.8, 9.81, 1.0
    expected = analytic_bounce_times(h0, g, e, 10)
    scene = {
        "model": {"name": "bouncing_ball"},
        "parameters": {"restitution": e, "g": g, "h0": h0},
        "solver": {"method": method, "rtol": 1e-10, "atol": 1e-12, "max_step": max_step},
        "run": {"duration": float(expected[-1] + 0.01)},
        "record": {"dt": 0.001},
    }
    ds = workbench.simulate(scene)
    times = np.unique(ds.last_bounce_time.values[~np.isnan(ds.last_bounce_time.values)])
    assert times.size == 10
    np.testing.assert_allclose(times, expected, rtol=0, atol=1e-9)
    assert ds.attrs["solver_events"] == 10
    return ds


@pytest.mark.parametrize("method", ["dop853", "dopri5", "scipy:DOP853"])
def test_bounce_times(method):
    ds = check_bounce_times(method, 0.01)
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


def test_crossing_sides_partition_at_zero():
    """g <= 0 is "before" and g > 0 "beyond": a state located exactly on g = 0 (a contact end)
    must not hide the next rising crossing (a contact that starts again at once)."""
    from workbench.solver._templates.integration_loop import _crossed

    assert _crossed(1, 0.0, 1e-9)  # from exactly zero upwards: an onset
    assert not _crossed(1, 0.0, 0.0)
    assert not _crossed(1, 1e-9, 2e-9)
    assert _crossed(-1, 1e-9, 0.0)  # down onto zero: an end
    assert not _crossed(-1, 0.0, -1e-9)  # already on the "before" side
    assert _crossed(0, -1e-9, 1e-9) and _crossed(0, 1e-9, -1e-9)


def test_every_contact_of_the_ninebar_has_a_located_onset():
    """Over two crank cycles of the default scene, every record in contact (e > c) carries the
    normal velocity of its located onset (aux > 0): the LN damping never falls back to the
    current normal velocity (a missed onset, e.g. right after an end located on g = 0)."""
    from workbench.run import derive, integrate, prepare, to_dataset

    scene = workbench.load_scene("studies/ninebar.toml").replace(
        run={"cycles": 2, "transient_cycles": 0},
        record={"samples_per_period": 80_000, "variables": ["eccentricity"]},
    )
    prepared = prepare(scene)
    result = integrate(prepared)
    derived, result = derive(prepared, result)
    ds = to_dataset(prepared, result, derived)
    e = ds.eccentricity.transpose("time", "joint").values
    in_contact = e > 0.5e-3
    assert in_contact.mean() > 0.3  # the check has something to check
    assert np.all(result.AUX[in_contact] > 0.0)
