"""Series estimators over the parameter dims of a campaign (workbench.analysis._broadcast):
one result per point, equal to the estimator on that point alone, lazily on a chunked archive."""

import numpy as np
import pytest
import xarray as xr

import workbench
from workbench.analysis import _delay, delay_ami, zero_one_test
from workbench.analysis._broadcast import PROBES, over_parameters


def logistic(r: float, x0: float, n: int = 1500, skip: int = 500) -> np.ndarray:
    x = np.empty(n + skip)
    x[0] = x0
    for i in range(n + skip - 1):
        x[i + 1] = r * x[i] * (1 - x[i])
    return x[skip:]


@pytest.fixture(scope="module")
def maps() -> xr.DataArray:
    """Logistic-map series over (r, x0): r = 3.5 (a 4-cycle), 3.83 (the 3-cycle window) and
    3.97 (chaos), two starts each; one sample per second."""
    rs, x0s = [3.5, 3.83, 3.97], [0.3, 0.4]
    data = np.array([[logistic(r, x0) for x0 in x0s] for r in rs])
    t = np.arange(data.shape[-1], dtype=float)
    return xr.DataArray(
        data,
        dims=("r", "x0", "time"),
        coords={
            "r": ("r", rs, {"units": "1", "long_name": "growth rate"}),
            "x0": ("x0", x0s, {"units": "1", "long_name": "initial value"}),
            "time": ("time", t, {"units": "s"}),
        },
        name="x",
        attrs={"units": "1", "long_name": "population"},
    )


def test_zero_one_over_parameters_is_the_test_at_each_point(maps):
    out = zero_one_test(maps)
    assert out.K.dims == ("r", "x0") and out.K_c.dims == ("r", "x0", "c")
    assert out.K.attrs["units"] == "1" and out.r.attrs["long_name"] == "growth rate"
    assert out.c.attrs["units"] == "rad" and out.c.dims == ("c",)  # shared by every point
    for i in range(3):
        for j in range(2):
            alone = zero_one_test(maps.isel(r=i, x0=j))
            assert float(out.K[i, j]) == float(alone.K)  # the same call, the same number
            np.testing.assert_array_equal(out.K_c[i, j].values, alone.K_c.values)
    # known answers (Gottwald & Melbourne 2004): regular K ~ 0, chaotic K ~ 1
    assert (abs(out.K.sel(r=[3.5, 3.83])) < 0.1).all()
    assert (out.K.sel(r=3.97) > 0.9).all()
    assert (out.analysis_error == "").all() and (out.evidence_complete == 1).all()


def test_a_failed_point_is_flagged_and_the_others_stand(maps):
    x = maps.copy()
    x[1, 0] = np.nan  # a failed campaign point: all NaN
    out = zero_one_test(x)
    assert "all NaN" in str(out.analysis_error[1, 0].values)
    assert np.isnan(out.K[1, 0]) and int(out.evidence_complete[1, 0]) == 0
    assert float(out.K[2, 1]) == float(zero_one_test(maps.isel(r=2, x0=1)).K)


def test_a_dim_named_like_the_evidence_is_refused(maps):
    with pytest.raises(ValueError, match=r"dim\(s\) \['c'\].*rename"):
        zero_one_test(maps.rename(x0="c"))


def test_no_series_dim_is_refused(maps):
    with pytest.raises(ValueError, match="exactly one series dim"):
        zero_one_test(maps.rename(time="sample"))


@pytest.fixture(scope="module")
def campaign_archive(tmp_path_factory):
    """A Duffing campaign over the forcing frequency: strobe records, so each point has its own
    record times (record_time over omega and record) and its own sampling step, the period."""
    scene = workbench.load_scene(
        {
            "model": {"name": "duffing"},
            "parameters": {"delta": 0.3, "alpha": -1.0, "beta": 1.0, "gamma": 0.37},
            "run": {"cycles": 240, "transient_cycles": 60},
            "record": {"samples_per_period": 1},
            "sweep": {"omega": [1.0, 1.1, 1.2, 1.3]},
        }
    )
    path = tmp_path_factory.mktemp("bc") / "omega.nc"
    workbench.run_campaign(scene, path, workers=1)
    return path


def test_lazy_over_a_chunked_campaign_archive(campaign_archive):
    calls = []

    def counted(x, **kw):
        calls.append(1)
        return _delay.delay_ami(x, **kw)

    estimator = over_parameters(counted)
    eager_ds = workbench.open_run(campaign_archive)
    with workbench.open_run(campaign_archive, chunks={}) as ds:
        assert ds.x.chunks is not None
        lazy = estimator(ds.x.chunk({"omega": 2}))
        assert len(calls) <= PROBES  # only the points that lay out the result
        assert lazy.delay.chunks == ((2, 2),) and lazy.ami.chunks[0] == (2, 2)
        computed = lazy.compute()
    assert len(calls) <= PROBES + 4
    eager = delay_ami(eager_ds.x)
    for name in ("delay", "delay_time", "ami", "found"):
        np.testing.assert_array_equal(computed[name].values, eager[name].values)
    # each point's own sampling step: the delay in seconds is the delay in samples times the
    # point's forcing period 2 pi / omega
    period = 2 * np.pi / eager.omega
    np.testing.assert_allclose(eager.delay_time, eager.delay * period, rtol=1e-12)
    assert eager.delay_time.attrs["units"] == "s" and eager.omega.attrs["units"] == "rad s-1"
    for k, omega in enumerate(eager.omega.values):
        alone = _delay.delay_ami(eager_ds.x.sel(omega=omega))
        assert int(eager.delay[k]) == int(alone.delay)


def _uneven(x):
    """A stand-in estimator whose evidence grows with the point (like an ACF up to its zero)
    and whose attribute differs between points."""
    n = int(round(float(x.values[0])))
    return xr.Dataset(
        {
            "value": ((), float(x.values.sum()), {"units": "m"}),
            "curve": ("lag", np.arange(n, dtype=float), {"units": "1"}),
        },
        coords={"lag": ("lag", np.arange(n), {"units": "1"})},
        attrs={"method": "stand-in", "note": f"n={n}"},
    )


def test_uneven_evidence_eager_pads_and_lazy_flags_a_cut():
    lengths = np.array([3.0, 2.0, 6.0, 4.0, 3.0])  # probes: points 0, 2, 4 -> layout of 6
    lengths[1] = 7.0  # longer than every probe: cut in the lazy layout
    x = xr.DataArray(np.repeat(lengths[:, None], 5, axis=1), dims=("p", "time"))
    estimator = over_parameters(_uneven)
    eager = estimator(x)
    assert eager.sizes["lag"] == 7 and (eager.evidence_complete == 1).all()
    np.testing.assert_array_equal(eager.curve[0].values[:3], [0, 1, 2])
    assert np.isnan(eager.curve[0].values[3:]).all()
    assert list(eager.note.values) == ["n=3", "n=7", "n=6", "n=4", "n=3"]  # per point
    assert eager.attrs["method"] == "stand-in" and "note" not in eager.attrs
    assert eager.value.attrs["units"] == "m"

    lazy = estimator(x.chunk({"p": 2})).compute()
    assert lazy.sizes["lag"] == 6
    np.testing.assert_array_equal(lazy.value.values, eager.value.values)  # scalars: all exact
    assert list(lazy.evidence_complete.values) == [1, 0, 1, 1, 1]
    np.testing.assert_array_equal(lazy.curve[1].values, np.arange(6.0))  # cut at the layout
    wider = estimator(x.chunk({"p": 2}), evidence_sizes={"lag": 8}).compute()
    assert (wider.evidence_complete == 1).all() and wider.sizes["lag"] == 8
