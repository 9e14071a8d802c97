"""netCDF round trip, atomic writes, and the command line."""

import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

import workbench
from workbench.cli import main

SCENE = """
title = "cli test"
[model]
name = "duffing"
[run]
cycles = 2
[record]
samples_per_period = 20
"""


def test_netcdf_round_trip_is_exact(tmp_path):
    ds = workbench.simulate(
        {"model": {"name": "bouncing_ball"}, "run": {"duration": 1.0}, "solver": {"max_step": 0.01}}
    )
    path = workbench.save_run(ds, tmp_path / "run.nc")
    back = workbench.open_run(path)
    xr.testing.assert_identical(back, ds)
    assert back.attrs["scene"] == ds.attrs["scene"]
    assert workbench.scene_from_toml(back.attrs["scene"]) == workbench.load_scene(
        {"model": {"name": "bouncing_ball"}, "run": {"duration": 1.0}, "solver": {"max_step": 0.01}}
    )


def test_atomic_write_leaves_no_temporary_and_keeps_old_file(tmp_path):
    ds = workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 1}})
    path = workbench.save_run(ds, tmp_path / "run.nc")
    bad = ds.copy()
    bad.attrs["unstorable"] = {"a": 1}  # netCDF cannot store a dict: the write fails
    with pytest.raises(TypeError, match="Invalid value for attr 'unstorable'"):
        workbench.save_run(bad, path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]
    xr.testing.assert_identical(workbench.open_run(path), ds)


def test_cli_run_writes_netcdf_and_summary(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE)
    out = tmp_path / "r.nc"
    assert main(["run", str(scene), "-o", str(out), "-q", "--figures", str(tmp_path / "fig")]) == 0
    line = capsys.readouterr().out
    assert "steps" in line and "rhs evaluations" in line
    ds = workbench.open_run(out)
    assert ds.sizes["time"] == 41
    assert np.isfinite(ds.x).all()
    assert (tmp_path / "fig" / "duffing_timeseries.png").stat().st_size > 10_000


def test_cli_reports_scene_errors(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.replace("cycles = 2", "cycles = -2"))
    assert main(["run", str(scene), "-o", str(tmp_path / "r.nc"), "-q"]) == 2
    assert "run.cycles" in capsys.readouterr().err


def test_cli_help_lists_commands():
    out = subprocess.run(
        [sys.executable, "-m", "workbench.cli", "--help"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    for cmd in ("run", "plot"):
        assert cmd in out


def test_nolds_imports():
    import nolds

    assert callable(nolds.lyap_r)


def test_saved_archive_has_ordinary_permissions(tmp_path):
    """An atomic write must not leave mkstemp's owner-only mode on a file meant for sharing."""
    import os
    import stat

    import workbench

    ds = workbench.simulate({"model": {"name": "lorenz"}, "run": {"duration": 0.1}})
    path = workbench.save_run(ds, tmp_path / "run.nc")
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask
