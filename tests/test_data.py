"""The shipped archives in data/ are what the code writes now (issue 26 item 2): the archive
format, the status vocabulary, and the variables, coordinates and attributes of a run (or a
campaign) of the same stored scene made now, on a short horizon. When this fails, the code
writes something else than the notebooks and users open: run ``make data`` (and
``make notebooks``), and say in CHANGELOG.md what changed.

The numbers themselves are not compared: a chaotic run's values move with any rounding-level
change of the code; the notebooks' numbers are checked against the API by test_notebooks.py.
"""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import workbench
from workbench.campaign._block import STATUS_ATTRS

DATA = Path(__file__).resolve().parents[1] / "data"
RUNS = ("ninebar_default.nc", "chaos_run.nc")
#: global attributes whose value is the code's, not the run's: equal in the shipped archive
STATIC_ATTRS = ("Conventions", "format_version", "model", "forcing_period_units")


def _raw(name: str) -> xr.Dataset:
    """The archive as stored (not upgraded by open_run)."""
    with xr.open_dataset(DATA / name) as ds:
        return ds.load()


def _same_structure(shipped: xr.Dataset, fresh: xr.Dataset, name: str) -> None:
    assert set(shipped.data_vars) == set(fresh.data_vars), name
    assert set(shipped.coords) == set(fresh.coords), name
    for var in [*fresh.data_vars, *fresh.coords]:
        a, b = shipped[var], fresh[var]
        assert a.dims == b.dims, (name, var)
        assert a.dtype.kind == b.dtype.kind, (name, var)
        assert set(a.attrs) == set(b.attrs), (name, var)
        for key, value in b.attrs.items():
            if isinstance(value, np.ndarray):
                np.testing.assert_array_equal(a.attrs[key], value, err_msg=f"{name} {var} {key}")
            else:
                assert a.attrs[key] == value, (name, var, key)
    assert set(shipped.attrs) == set(fresh.attrs), (name, set(shipped.attrs) ^ set(fresh.attrs))
    for key in STATIC_ATTRS:
        assert shipped.attrs.get(key) == fresh.attrs.get(key), (name, key)


@pytest.mark.parametrize("name", RUNS)
def test_shipped_run_is_what_the_code_writes(name, tmp_path):
    shipped = _raw(name)
    assert shipped.attrs["format_version"] == workbench.FORMAT_VERSION
    assert workbench.Status.from_label(shipped.attrs["run_status"]) is workbench.Status.OK
    scene = workbench.scene_from_toml(shipped.attrs["scene"])
    fresh = workbench.simulate(scene.replace(run={"cycles": 1, "transient_cycles": 0}))
    fresh = workbench.open_run(workbench.save_run(fresh, tmp_path / name))
    _same_structure(shipped, fresh, name)


def test_shipped_campaign_is_what_the_code_writes(tmp_path):
    name = "bifurcation_speed.nc"
    shipped = _raw(name)
    assert shipped.attrs["format_version"] == workbench.FORMAT_VERSION
    assert shipped.status.attrs["flag_meanings"] == STATUS_ATTRS["flag_meanings"]
    np.testing.assert_array_equal(shipped.status.attrs["flag_values"], STATUS_ATTRS["flag_values"])
    scene = workbench.scene_from_toml(shipped.attrs["scene"])
    omega = shipped.omega.values[:2].tolist()
    short = scene.replace(run={"cycles": 2, "transient_cycles": 1}, sweep={"omega": omega})
    fresh = workbench.run_campaign(short, tmp_path / name, workers=1)
    _same_structure(shipped, fresh, name)


def test_a_stale_archive_fails_the_check(tmp_path):
    """The check can fail: an archive of the old vocabulary or without a variable's units."""
    shipped = _raw(RUNS[0])
    scene = workbench.scene_from_toml(shipped.attrs["scene"])
    fresh = workbench.simulate(scene.replace(run={"cycles": 1, "transient_cycles": 0}))
    stale = shipped.copy()
    del stale["slider_position"].attrs["units"]
    with pytest.raises(AssertionError):
        _same_structure(stale, fresh, "stale")
    stale = shipped.copy()
    stale.attrs["format_version"] = np.int32(1)
    with pytest.raises(AssertionError):
        _same_structure(stale, fresh, "stale")
