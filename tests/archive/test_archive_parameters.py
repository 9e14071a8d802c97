"""Archives a colleague can use without workbench: every resolved parameter of a run or a
campaign point is in the file with its units, so that plain xarray combines and selects runs by
them; ``open_run(chunks=...)`` opens an archive lazily (dask)."""

import dask.array
import numpy as np
import pytest
import xarray as xr

import workbench
from workbench.archive import ArchiveError
from workbench.models import get_model
from workbench.run import parameter_coords

DUFFING = {"model": {"name": "duffing"}, "run": {"cycles": 4}, "record": {"samples_per_period": 8}}


def duffing(gamma: float) -> xr.Dataset:
    return workbench.simulate({**DUFFING, "parameters": {"gamma": gamma}})


def test_a_run_stores_every_parameter_with_its_units(tmp_path):
    ds = duffing(0.31)
    model = get_model("duffing")
    names = [p.name for p in model.parameters]
    assert ds.attrs["model_parameters"].split() == names
    for p in model.parameters:
        coord = ds[p.name]
        assert coord.dims == () and p.name in ds.coords
        assert coord.attrs["units"] == p.units and coord.attrs["long_name"] == p.long_name
    assert float(ds.gamma) == 0.31 and float(ds.delta) == model.parameter("delta").default
    # what a reader without workbench sees: plain xarray on the file
    workbench.save_run(ds, tmp_path / "r.nc")
    with xr.open_dataset(tmp_path / "r.nc") as plain:
        assert float(plain.gamma) == 0.31 and plain.omega.attrs["units"] == "rad s-1"
        assert plain.x.attrs["rate_variable"] == "v"


def test_the_nine_bar_run_carries_its_masses_and_lengths():
    ds = workbench.simulate(
        {
            "model": {"name": "ninebar"},
            "run": {"cycles": 1, "transient_cycles": 0},
            "record": {"samples_per_period": 10, "variables": ["clearance_x"]},
            "parameters": {"mass_panel7": 4.5},
        }
    )
    model = get_model("ninebar")
    assert len(ds.attrs["model_parameters"].split()) == len(model.parameters) >= 60
    assert float(ds.mass_panel7) == 4.5 and ds.mass_panel7.attrs["units"] == "kg"
    assert float(ds.link2_length) == 0.326 and ds.link2_length.attrs["units"] == "m"


def test_runs_combine_and_select_by_parameter_with_plain_xarray(tmp_path):
    gammas = [0.28, 0.30, 0.32]
    paths = []
    for g in gammas:
        paths.append(workbench.save_run(duffing(g), tmp_path / f"gamma={g}.nc"))
    with xr.open_mfdataset(paths, combine="nested", concat_dim="gamma") as runs:
        assert runs.x.dims == ("gamma", "time")
        assert list(runs.gamma.values) == gammas and runs.gamma.attrs["units"] == "1"
        assert runs.delta.dims == ()  # the same in every run: stays a scalar
        one = runs.x.sel(gamma=0.30).values
    np.testing.assert_array_equal(one, duffing(0.30).x.values)


def test_a_campaign_has_its_swept_parameters_as_dims_and_the_others_as_scalars(tmp_path):
    runs = workbench.run_campaign(
        {**DUFFING, "parameters": {"delta": 0.25}, "sweep": {"gamma": [0.28, 0.32]}},
        tmp_path / "c.nc",
        workers=1,
    )
    model = get_model("duffing")
    assert runs.attrs["model_parameters"].split() == [
        "gamma",
        *(p.name for p in model.parameters if p.name != "gamma"),
    ]
    assert runs.gamma.dims == ("gamma",) and runs.delta.dims == () and float(runs.delta) == 0.25
    assert runs.alpha.attrs["units"] == "1"
    stored = workbench.open_run(tmp_path / "c.nc")
    np.testing.assert_array_equal(stored.x.sel(gamma=0.32).values, runs.x.sel(gamma=0.32).values)
    assert float(stored.beta) == 1.0


def test_a_parameter_named_like_a_variable_is_stored_beside_it():
    coords = parameter_coords(get_model("duffing"), {"gamma": 0.5, "x0": 1.0}, taken=["x0"])
    assert coords["parameter_x0"][2]["parameter"] == "x0" and "gamma" in coords


@pytest.mark.filterwarnings("ignore:The specified chunks separate the stored chunks")
def test_open_run_with_chunks_is_lazy(tmp_path):
    ds = duffing(0.3)
    path = workbench.save_run(ds, tmp_path / "r.nc")
    lazy = workbench.open_run(path, chunks={"time": 10})
    try:
        assert isinstance(lazy.x.data, dask.array.Array)
        assert lazy.x.chunks[0][:3] == (10, 10, 10)
        xr.testing.assert_identical(lazy.load(), ds)
    finally:
        lazy.close()
    whole = workbench.open_run(path)
    assert isinstance(whole.x.data, np.ndarray)
    (tmp_path / "bad.nc").write_bytes(b"not netcdf")
    with pytest.raises(ArchiveError, match="not a readable netCDF file"):
        workbench.open_run(tmp_path / "bad.nc", chunks={})
