"""The archives against the CF conventions 1.11 (issue 40 item 3), judged by the IOOS
compliance-checker itself (its API: what ``compliance-checker --test=cf:1.11 FILE`` reports as
errors): none on the shipped archives (data/*.nc) nor on a run, a campaign, a campaign whose
points have their own record times (a sweep over the forcing frequency, a continued sweep), a
chaos map and a branch of periodic orbits written now. Such a campaign runs its records along
``record`` with each point's times in the auxiliary coordinate ``record_time`` (archive format
4); format 3 ran them along a dimension ``time`` without a coordinate variable, which the
checker takes for a time axis without coordinates: such an archive is upgraded on reading and
by ``data/regenerate.py --upgrade`` (docs/archives.md).
"""

import importlib.util
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import workbench

pytest.importorskip("compliance_checker", reason="the 'test' extra has compliance-checker")

from compliance_checker.runner import CheckSuite  # noqa: E402

DATA = Path(__file__).resolve().parents[2] / "data"
SHIPPED = sorted(DATA.glob("*.nc"))
DUFFING = {"model": {"name": "duffing"}, "record": {"samples_per_period": 1}}
#: the checker's one error on an archive whose dimension ``time`` has no coordinate variable
NO_TIME_AXIS = "Dimension 'time' in variable '{}' is expected to be a coordinate axis but no variable with that name exists."  # noqa: E501
#: the check of compliance-checker 6.1 that raises on a string-valued coordinate variable
#: (numpy's diff of strings); CF defines coordinate variables as numeric, so it is done here on
#: the numeric ones
MONOTONIC = "check_coordinate_variables_strict_monotonicity"


def _monotonic_errors(nc) -> list[str]:
    """What the checker's monotonicity check says of the numeric coordinate variables."""
    errors = []
    for name, var in nc.variables.items():
        if var.dimensions == (name,) and np.issubdtype(var.dtype, np.number):
            step = np.diff(np.asarray(var[:], dtype=float))
            if not ((step > 0).all() or (step < 0).all()):
                errors.append(f'Coordinate variable "{name}" must be strictly monotonic')
    return errors


def cf_errors(path: Path) -> list[str]:
    """The errors (high-priority failures) of the checker's cf:1.11 suite on the file at
    ``path``, and a line for each check that raised (except the known one above)."""
    suite = CheckSuite()
    suite.load_all_available_checkers()
    nc = suite.load_dataset(str(path))
    try:
        groups, raised = suite.run_all(nc, ["cf:1.11"])["cf:1.11"]
        errors = [
            message
            for result in groups
            if result.weight == 3 and result.value[1] and result.value[0] < result.value[1]
            for message in result.msgs
        ]
        for check, (exc, _) in raised.items():
            strings = any(v.dtype is str for n, v in nc.variables.items() if v.dimensions == (n,))
            if check == MONOTONIC and strings:
                errors += _monotonic_errors(nc)
            else:
                errors.append(f"the check {check} raised {type(exc).__name__}: {exc}")
    finally:
        nc.close()
    return errors


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.name)
def test_shipped_archives_are_cf(path):
    assert cf_errors(path) == []


@pytest.fixture(scope="module")
def written(tmp_path_factory) -> dict[str, Path]:
    """Each kind of archive, small, written now."""
    from workbench.continuation import chaos_map, continue_orbit, continued_sweep

    out = tmp_path_factory.mktemp("cf")
    paths = {}
    paths["run"] = workbench.save_run(
        workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 2}}), out / "run.nc"
    )
    ninebar = {
        "model": {"name": "ninebar"},
        "run": {"cycles": 1, "transient_cycles": 0},
        "record": {"samples_per_period": 20},
    }
    paths["nine-bar run"] = workbench.save_run(workbench.simulate(ninebar), out / "ninebar.nc")
    run = {"cycles": 3, "transient_cycles": 2}
    shared = workbench.load_scene(dict(DUFFING, run=run, sweep={"gamma": [0.2, 0.3]}))
    paths["campaign"] = out / "campaign.nc"
    workbench.run_campaign(shared, paths["campaign"], workers=1, progress=False)
    own = workbench.load_scene(dict(DUFFING, run=run, sweep={"omega": [1.0, 1.2]}))
    paths["campaign over omega"] = out / "omega.nc"
    workbench.run_campaign(own, paths["campaign over omega"], workers=1, progress=False)
    sweep = {"gamma": {"start": 0.25, "stop": 0.27, "num": 3}, "continuation": "up"}
    continued = workbench.load_scene(dict(DUFFING, run=run, sweep=sweep))
    paths["continued sweep"] = out / "continued.nc"
    continued_sweep(continued, paths["continued sweep"], workers=1, progress=False)
    maps = {"gamma": [0.2, 0.5], "delta": [0.3]}
    mapped = workbench.load_scene(
        dict(DUFFING, run={"cycles": 60, "transient_cycles": 20}, sweep=maps)
    )
    paths["chaos map"] = out / "map.nc"
    with warnings.catch_warnings():  # 60 cycles: too short for a converged exponent
        warnings.simplefilter("ignore", workbench.analysis.ConvergenceWarning)
        chaos_map(mapped, paths["chaos map"], workers=1, progress=False)
    orbit = {
        "model": {"name": "duffing"},
        "parameters": {"gamma": 0.25},
        "run": {"transient_cycles": 100},
    }
    branch = continue_orbit(workbench.load_scene(orbit), "gamma", stop=0.26)
    paths["branch"] = workbench.save_run(branch, out / "branch.nc")
    return paths


KINDS = ["run", "nine-bar run", "campaign", "campaign over omega", "continued sweep"]


@pytest.mark.parametrize("kind", [*KINDS, "chaos map", "branch"])
def test_archives_written_now_are_cf(written, kind):
    assert cf_errors(written[kind]) == []


@pytest.mark.parametrize("kind", ["campaign over omega", "continued sweep"])
def test_each_points_record_times_along_record(written, kind):
    """A campaign whose points have their own record times: records along ``record`` (no
    ``time`` dim), each point's times the auxiliary coordinate ``record_time`` with the
    standard name time, stored as every simulated time is (s since the reference instant)."""
    ds = workbench.open_run(written[kind])
    assert "time" not in ds.dims and ds.x.dims[-1] == "record"
    assert ds.record_time.dims[-1] == "record" and "record" not in ds.variables
    assert ds.record_time.attrs["standard_name"] == "time"
    assert ds.record_time.attrs["units"] == "s"
    with xr.open_dataset(written[kind], decode_times=False) as raw:
        assert raw.record_time.attrs["units"] == "s since 1970-01-01 00:00:00"
        np.testing.assert_array_equal(raw.record_time.values, ds.record_time.values)


def _as_format_3(ds: xr.Dataset, path: Path) -> Path:
    """``ds`` (records along ``record``) written as workbench 0.6.0 wrote it in archive format
    3: along a dim ``time`` without a coordinate variable, ``record_time`` in "s" without a
    standard name."""
    old = ds.rename_dims(record="time")
    old.record_time.attrs.pop("standard_name")
    old.attrs["format_version"] = np.int32(3)
    encoding = {n: {"_FillValue": None} for n in old.dims if n in old.variables}
    old.to_netcdf(path, encoding=encoding)
    return path


def _regenerate():
    spec = importlib.util.spec_from_file_location("regenerate", DATA / "regenerate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("kind", ["campaign over omega", "continued sweep"])
def test_format_3_is_upgraded(written, kind, tmp_path):
    """A format-3 archive of that kind fails the check (its dim ``time`` has no coordinate
    variable); open_run reads it in the current layout with the same numbers, and
    ``data/regenerate.py --upgrade`` rewrites it in place, without recomputing, CF-valid."""
    new = workbench.open_run(written[kind])
    old = _as_format_3(new, tmp_path / "old.nc")
    assert sorted(cf_errors(old)) == [NO_TIME_AXIS.format(v) for v in ("v", "x")]
    read = workbench.open_run(old)
    assert read.attrs.pop("upgraded_from_format") == 3
    assert read.identical(new)
    lazy = workbench.open_run(old, chunks={})
    assert lazy.x.dims == new.x.dims and lazy.record_time.attrs == new.record_time.attrs
    lazy.close()
    _regenerate().upgrade(old)
    assert cf_errors(old) == []
    again = workbench.open_run(old)
    assert "upgraded_from_format" not in again.attrs
    assert "archive format 3 -> 4" in again.attrs["history"]
    xr.testing.assert_identical(again.drop_attrs(), new.drop_attrs())


def test_readers_of_each_points_record_times(written, tmp_path):
    """The new layout read by the analyses: mapped over the points, each point's series runs
    along time with its own step (the forcing period); one point is a record in time; several
    points with different times, or times decoded to dates by plain xarray, are refused in one
    line, never read along the wrong axis."""
    from workbench.analysis import crossing_section, over_parameters, poincare_section
    from workbench.analysis._series import as_series

    ds = workbench.open_run(written["campaign over omega"])

    def step(x):
        assert x.dims == ("time",)
        return xr.Dataset({"dt": ((), as_series(x).dt, {"units": "s"})})

    np.testing.assert_allclose(over_parameters(step)(ds.x).dt, 2 * np.pi / ds.omega, rtol=1e-12)
    one = ds.x.sel(omega=1.2)
    np.testing.assert_allclose(as_series(one).dt, 2 * np.pi / 1.2, rtol=1e-12)
    section = poincare_section(ds, "x")
    assert section.strobe_time.dims == ("omega", "strobe")
    np.testing.assert_array_equal(section.strobe_time.values, ds.record_time.values)
    with pytest.raises(ValueError, match=r"select one point first, e\.g\. \.sel\(omega=") as e:
        as_series(ds.x)
    assert "\n" not in str(e.value)
    with pytest.raises(ValueError, match="select one point first"):
        crossing_section(ds, "x", 0.0)
    with xr.open_dataset(written["campaign over omega"]) as plain:  # CF times decoded: dates
        assert plain.record_time.dtype.kind == "M"
        with pytest.raises(ValueError, match="are dates, not seconds since t = 0"):
            over_parameters(step)(plain.x)
        with pytest.raises(ValueError, match="are dates, not seconds since t = 0"):
            as_series(plain.x.sel(omega=1.2))


def test_the_check_can_fail(tmp_path):
    """The same run written by xarray alone, as workbench 0.5 wrote it: ``_FillValue`` on the
    time coordinate and its units "s" without a reference instant."""
    ds = workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 2}})
    ds.to_netcdf(tmp_path / "plain.nc")
    errors = cf_errors(tmp_path / "plain.nc")
    assert "The coordinate variable 'time' must not have the _FillValue attribute." in errors
    assert any("since" in e for e in errors), errors


def test_the_time_axis_on_disk_and_in_memory(tmp_path):
    """On disk a CF time coordinate (seconds since a reference instant that stands for t = 0),
    which plain xarray decodes to dates; ``open_run`` reads seconds since t = 0, as simulated."""
    ds = workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 2}})
    assert ds.time.attrs == {"units": "s", "long_name": "time", "standard_name": "time"}
    path = workbench.save_run(ds, tmp_path / "run.nc")
    with xr.open_dataset(path) as plain:
        assert plain.time.encoding["units"] == "s since 1970-01-01 00:00:00"
        assert (
            plain.time.encoding["calendar"] == "standard"
            and "_FillValue" not in plain.time.encoding
        )
        elapsed = (plain.time - np.datetime64("1970-01-01")) / np.timedelta64(1, "s")
        # as dates, to the decoder's resolution (a microsecond with xarray 2026.9)
        np.testing.assert_allclose(elapsed, ds.time, rtol=0, atol=1e-6)
    with xr.open_dataset(path, decode_times=False) as raw:
        np.testing.assert_array_equal(raw.time.values, ds.time.values)  # the same numbers
    assert workbench.open_run(path).identical(ds)
    assert ds.attrs["references"].startswith("Duffing (1918)")
    assert "clearance-workbench" in ds.attrs["references"]
