"""Fault injection on writes (issue 23 items 3 and 4): a file that appears while a result is
computed is never replaced (the result is kept beside it), a full disk is one line naming the
path, the bytes needed and the bytes free (and the computed run is kept where there is room), an
interrupted write leaves nothing, and a killed writer's temporary file is removed by the next
write of the same file. The full disk is simulated (an unprivileged fault injection), and once
on a real 1-MiB tmpfs where mounting one is allowed (root)."""

import errno
import os
import signal
import subprocess
import sys
import uuid
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from helpers import tiny_tmpfs

import workbench
from workbench.archive import (
    ArchiveError,
    DiskFull,
    OutputExists,
    StoreWarning,
    atomic_path,
    check_output_file,
    save_run,
    write_text_atomic,
)
from workbench.cli import main

RUN = {"model": {"name": "duffing"}, "run": {"cycles": 200}}  # 20 001 records, ~0.5 MiB


@pytest.fixture(scope="module")
def ds() -> xr.Dataset:
    return workbench.simulate(RUN)


def scene_file(tmp_path: Path) -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(workbench.load_scene(RUN).to_toml())
    return path


# -- no silent replace ---------------------------------------------------------------------------
def test_a_file_written_meanwhile_is_not_replaced_and_the_result_is_kept(ds, tmp_path):
    out = tmp_path / "same.nc"
    with pytest.raises(OutputExists) as info, atomic_path(out, overwrite=False) as tmp:
        tmp.write_text("this result")
        out.write_text("the other process's result")  # the check at the start saw nothing
    assert out.read_text() == "the other process's result"
    kept = Path(info.value.kept)
    assert kept.parent == tmp_path and kept.read_text() == "this result"
    assert f"was kept at {str(kept)!r}" in str(info.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([out.name, kept.name])
    save_run(ds, out, overwrite=True)  # asked for: replaced
    xr.testing.assert_identical(workbench.open_run(out), ds)


def test_two_cli_runs_onto_one_output_keep_both_results(tmp_path, capsys, monkeypatch):
    """The issue: two `workbench run ... -o same.nc` both printed "-> same.nc" and the file held
    only the second run. Here the other run's file appears while this one integrates."""
    import workbench.run as run_layer

    out = tmp_path / "same.nc"
    other = workbench.simulate({**RUN, "parameters": {"gamma": 0.3}})
    real = run_layer.simulate

    def simulate_while_another_writes(*args, **kwargs):
        result = real(*args, **kwargs)
        save_run(other, out)  # the other process finished first
        return result

    monkeypatch.setattr(run_layer, "simulate", simulate_while_another_writes)
    code = main(["run", str(scene_file(tmp_path)), "-o", str(out), "-q"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "appeared while this result was computed" in err[0]
    (kept,) = tmp_path.glob("same.kept-*.nc")
    assert str(kept) in err[0]
    xr.testing.assert_identical(workbench.open_run(out), other)
    assert workbench.open_run(kept).attrs["scene"] == workbench.load_scene(RUN).to_toml()


# -- a full disk ---------------------------------------------------------------------------------
def _fill_disk(monkeypatch, error: Exception, free: int = 0) -> None:
    """Every netCDF write fails with ``error`` after writing a few bytes, and the file system
    reports ``free`` bytes: what a full disk does (the netCDF library says "HDF error")."""
    real = xr.Dataset.to_netcdf

    def to_netcdf(self, path=None, *args, **kwargs):
        if path is not None and Path(path).name.startswith("."):  # a temporary file
            Path(path).write_bytes(b"\0" * 4096)
            raise error
        return real(self, path, *args, **kwargs)

    usage = type("usage", (), {"total": 10**9, "used": 10**9 - free, "free": free})
    monkeypatch.setattr(xr.Dataset, "to_netcdf", to_netcdf)
    monkeypatch.setattr("workbench.archive._atomic.shutil.disk_usage", lambda p: usage)


@pytest.mark.parametrize(
    "error",
    [RuntimeError("NetCDF: HDF error"), OSError(errno.ENOSPC, "No space left on device")],
    ids=["netCDF4 HDF error", "ENOSPC"],
)
def test_a_full_disk_is_one_line_with_the_bytes_needed_and_free(ds, tmp_path, monkeypatch, error):
    out = tmp_path / "run.nc"
    save_run(ds, out)  # a previous version, which a failed write leaves intact
    before = out.read_bytes()
    _fill_disk(monkeypatch, error, free=12_345)
    with pytest.raises(DiskFull) as info:
        save_run(ds, out)
    text = str(info.value)
    assert "\n" not in text
    assert f"cannot write {str(out)!r}: no space left" in text
    assert f"needs up to {workbench.run.format_bytes(ds.nbytes)}" in text
    assert "12.1 KiB free" in text
    assert info.value.needed == ds.nbytes and info.value.free == 12_345
    assert out.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]  # no temporary left


def test_cli_run_on_a_full_disk_keeps_the_run_where_there_is_room(tmp_path, capsys, monkeypatch):
    """The issue: "RuntimeError: NetCDF: HDF error", no word of space, and the run lost."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.setattr("tempfile.tempdir", str(elsewhere))
    real = xr.Dataset.to_netcdf

    def to_netcdf(self, path=None, *args, **kwargs):
        if path is not None and Path(path).parent.name == "full":
            raise RuntimeError("NetCDF: HDF error")
        return real(self, path, *args, **kwargs)

    full = tmp_path / "full"
    full.mkdir()
    monkeypatch.setattr(xr.Dataset, "to_netcdf", to_netcdf)
    monkeypatch.setattr(
        "workbench.archive._atomic._lack_of_space", lambda exc, d: Path(d).name == "full"
    )
    code = main(["run", str(scene_file(tmp_path)), "-o", str(full / "run.nc"), "-q"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    (kept,) = elsewhere.glob("run.kept-*.nc")
    assert "no space left" in err[0] and f"the computed run was kept at {str(kept)!r}" in err[0]
    assert np.isfinite(workbench.open_run(kept).x).all()
    assert not list(full.iterdir())


def test_a_real_full_file_system(ds, tmp_path):
    """The same on a real 1-MiB tmpfs (skipped where mounting is not allowed): the netCDF
    library's failure is named a full disk, the space it took is freed at once."""
    with tiny_tmpfs(tmp_path / "tiny") as tiny:
        (tiny / "fill").write_bytes(b"\0" * 700_000)
        with pytest.raises(DiskFull, match=r"no space left on its file system .*KiB free") as info:
            save_run(ds, tiny / "run.nc")
        assert sorted(p.name for p in tiny.iterdir()) == ["fill"]
        assert info.value.free > 200_000  # the failed file's space is back
        with pytest.raises(DiskFull):
            save_run(ds, tiny / "block.nc", classic=True)  # scipy's netCDF-3 writer: ENOSPC
        assert sorted(p.name for p in tiny.iterdir()) == ["fill"]


# -- interrupted and killed writes ---------------------------------------------------------------
def test_sigterm_during_a_write_leaves_no_temporary_file(ds, tmp_path):
    """The issue: SIGTERM during the write of `run` left a hidden 9 MB '.out.nc.*.tmp'. The
    command line turns SIGTERM into an interrupt; the write removes its temporary file."""
    from workbench.cli._signals import Terminated, signals_as_interrupts

    out = tmp_path / "out.nc"
    with pytest.raises(Terminated), signals_as_interrupts(), atomic_path(out) as tmp:
        tmp.write_bytes(b"\0" * 1000)
        os.kill(os.getpid(), signal.SIGTERM)
        for _ in range(10**6):  # Python runs the handler between two instructions
            pass
    assert not list(tmp_path.iterdir())


_KILLED_WRITER = """
import os, signal, sys
from workbench.archive import atomic_path
with atomic_path(sys.argv[1]) as tmp:
    tmp.write_bytes(b"half a file")
    os.kill(os.getpid(), signal.SIGKILL)
"""


def test_the_temporary_file_of_a_killed_writer_is_removed_by_the_next_write(ds, tmp_path):
    out = tmp_path / "out.nc"
    done = subprocess.run([sys.executable, "-c", _KILLED_WRITER, str(out)])
    assert done.returncode == -signal.SIGKILL
    (stale,) = tmp_path.glob(".out.nc.*.tmp")
    # a live writer's temporary file (this process's parent shell stands in for it) is left
    live = tmp_path / f".out.nc.{stale.name.split('.')[3].split('-')[0]}-{os.getppid()}-x1.tmp"
    live.write_bytes(b"in progress")
    other = tmp_path / f".other.nc.{uuid.uuid4().hex[:6]}-1-x1.tmp"
    other.write_bytes(b"not ours")
    with pytest.warns(StoreWarning, match=r"interrupted \(the process is gone\)") as record:
        save_run(ds, out)
    assert str(stale) in str(record[0].message)
    assert not stale.exists() and live.exists() and other.exists()
    # the next command on the same output removes it even when it refuses to run
    subprocess.run([sys.executable, "-c", _KILLED_WRITER, str(out)])
    (stale,) = set(tmp_path.glob(".out.nc.*.tmp")) - {live}
    with pytest.warns(StoreWarning), pytest.raises(ArchiveError, match="exists; pass --over"):
        check_output_file(out, "-o/--output")
    assert not stale.exists() and live.exists()
    write_text_atomic(tmp_path / "notes.txt", "a text file, written the same way")
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith(".")) == [
        "notes.txt",
        "out.nc",
    ]
