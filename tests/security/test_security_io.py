"""Hostile outputs and inputs (issue 37, findings 4 and 5): every output of every command is
checked before any work (a directory where no file can be created, a device, a FIFO, a socket,
or a link to one: one line, exit code 2, nothing computed, nothing replaced); a write that fails
after the work keeps the result and says where; a scene that is not UTF-8 or nests 100 000
levels deep, the analysis of a failed run, a campaign whose ``status`` was removed or set to
NaN, an archive of format version -1 or 0, a variable that is all inf, and a delay read from
too short a series: each one line with the right exit code, or an honest result.

The devices are never written: the tests point outputs at a FIFO, a socket and symbolic links
to ``/dev/null`` and ``/dev/full`` in the test's own directory (replacing such a link would
replace the link, not the device), and at ``/sys`` and ``/proc``, where no file can be created
even by root (whom directory permissions do not stop)."""

import contextlib
import errno
import importlib
import os
import socket
import stat
import subprocess
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import workbench
from workbench.archive import (
    ArchiveError,
    DiskFull,
    WriteFailed,
    atomic_path,
    check_output_directory,
    check_output_file,
    save_run,
    write_text_atomic,
)
from workbench.archive._atomic import not_a_regular_file
from workbench.cli import main
from workbench.scene import SceneError

RUN = {"model": {"name": "duffing"}, "run": {"cycles": 20}, "record": {"samples_per_period": 8}}
SWEEP = {
    "model": {"name": "duffing"},
    "run": {"cycles": 20, "transient_cycles": 10},
    "record": {"samples_per_period": 1},
    "sweep": {"gamma": [0.25, 0.3, 0.35, 0.4]},
}
# a run that fails: written by `workbench run` itself (status max_steps, NaN after the failure)
FAILED = {"model": {"name": "duffing"}, "solver": {"max_steps": 400}, "run": {"cycles": 200}}


def write_scene(path: Path, spec: dict) -> str:
    path.write_text(workbench.load_scene(spec).to_toml())
    return str(path)


def run_cli(argv: list[str], capsys) -> tuple[int, str, str]:
    """Exit code, stdout and stderr of ``workbench ARGV``."""
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("workbench "), err
    assert ".tmp" not in lines[0], err  # the user's path, never a temporary file
    return lines[0]


@pytest.fixture(scope="module")
def archives(tmp_path_factory) -> dict[str, str]:
    """Scenes and archives every case reads (the kernel compiled once, here)."""
    d = tmp_path_factory.mktemp("archives")
    paths = {
        "scene": write_scene(d / "run.toml", RUN),
        "sweep": write_scene(d / "sweep.toml", SWEEP),
        "ninebar": write_scene(d / "ninebar.toml", {"model": {"name": "ninebar"}}),
        "failed_scene": write_scene(d / "failed.toml", FAILED),
        "run": str(d / "run.nc"),
        "campaign": str(d / "campaign.nc"),
    }
    save_run(workbench.simulate(RUN), paths["run"])
    workbench.run_campaign(SWEEP, paths["campaign"], workers=1, progress=False)
    return paths


# -- outputs checked before any work -------------------------------------------------------------
# The work each command does after its checks: none of it may run when an output is refused.
WORK = [
    "workbench.cli._console.compile_kernel",
    "workbench.cli._run.compile_kernel",
    "workbench.cli._accuracy.compile_kernel",
    "workbench.cli._study.compile_kernel",
    "workbench.run.simulate",
    "workbench.campaign.run_campaign",
    "workbench.continuation.chaos_map",
    "workbench.continuation.continue_orbit",
    "workbench.precision.accuracy",
    "workbench.analysis.wolf_lle",
    "workbench.plot.run_figures",
    "workbench.analysis.bifurcation_diagram",
    "workbench.study.run_study",
    "workbench.verification.verify",
]


@pytest.fixture
def no_work(monkeypatch):
    def forbidden(*args, **kwargs):
        raise AssertionError("the command started its work before refusing its output")

    modules = [importlib.import_module(name.rsplit(".", 1)[0]) for name in WORK]
    # all imported first: a module imported after the patch would bind the patched function
    for module, name in zip(modules, WORK, strict=True):
        monkeypatch.setattr(module, name.rsplit(".", 1)[1], forbidden)


# (name, argv with {file} or {dir} for the output under test, {ok} a writable file)
COMMANDS = [
    ("run", "run {scene} -o {file} --overwrite"),
    ("run --figures", "run {scene} -o {ok} --figures {dir} --overwrite"),
    ("campaign", "campaign {sweep} -o {file}"),
    ("chaos-map", "chaos-map {sweep} -o {file}"),
    ("chaos-map --figure", "chaos-map {sweep} -o {ok} --figure {file}"),
    ("orbit", "orbit {scene} -o {file} --param gamma --stop 0.4 --overwrite"),
    ("orbit --figure", "orbit {scene} -o {ok} --param gamma --stop 0.4 --figure {file} --state x"),
    ("accuracy", "accuracy {scene} -o {file} --overwrite"),
    ("analyse", "analyse {run} --var x -o {dir} --overwrite"),
    ("plot", "plot {run} -o {dir} --overwrite"),
    ("bifurcation", "bifurcation {campaign} --var x -o {file} --overwrite"),
    ("study", "study chaos --quick -o {dir}"),
    ("verify", "verify {ninebar} -o {file} --overwrite"),
]


@contextlib.contextmanager
def bad_output(kind: str, tmp_path: Path):
    """An output path of the kind named, and a check that it is unchanged afterwards."""
    if kind == "sys":  # EACCES, even for root
        yield Path("/sys/workbench-test-output"), None
    elif kind == "proc":  # no file can be created in /proc (ENOENT), nor a folder under it
        yield Path("/proc/workbench-test/output"), None
    elif kind == "fifo":
        path = tmp_path / "fifo"
        os.mkfifo(path)
        yield path, "a FIFO"
        assert stat.S_ISFIFO(os.lstat(path).st_mode)
    elif kind == "link to /dev/null":
        path = tmp_path / "null"
        path.symlink_to("/dev/null")
        yield path, "a symbolic link to a character device ('/dev/null')"
        assert os.readlink(path) == "/dev/null"
        assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
    else:  # pragma: no cover
        raise ValueError(kind)


@pytest.mark.parametrize("kind", ["sys", "proc", "fifo", "link to /dev/null"])
@pytest.mark.parametrize("name, argv", COMMANDS, ids=[c[0] for c in COMMANDS])
def test_every_output_of_every_command_is_checked_before_any_work(
    name, argv, kind, archives, tmp_path, capsys, no_work
):
    """The issue: `run -o /dev/full --overwrite` replaced the device; `run -o /sys/wb.nc`
    computed, then lost the run in a PermissionError traceback; `campaign -o` into an
    unwritable folder: a traceback from mkdir; `run --figures /proc/x` integrated first."""
    with bad_output(kind, tmp_path) as (path, what):
        fields = {**archives, "file": path, "dir": path, "ok": tmp_path / "ok.nc"}
        code, out, err = run_cli(argv.format(**fields).split(), capsys)
        line = one_line(err)
        assert code == 2, err
        assert repr(str(path)) in line, line
        if what is None:
            assert "no file can be created in" in line, line
        else:
            assert f"is {what}" in line, line
    assert not (tmp_path / "ok.nc").exists()


def test_a_socket_is_refused_and_devices_are_told_from_files(tmp_path):
    sock = socket.socket(socket.AF_UNIX)
    try:
        sock.bind(str(tmp_path / "s"))
        with pytest.raises(ArchiveError, match=r"'.*/s' is a socket, not a regular file"):
            check_output_file(tmp_path / "s", "-o/--output", overwrite=True)
    finally:
        sock.close()
    # only looked at: the check refuses before it writes anything
    for device in ("/dev/null", "/dev/full"):
        assert not_a_regular_file(device) == "a character device"
        with pytest.raises(ArchiveError, match="is a character device, not a regular file"):
            check_output_file(device, "-o/--output", overwrite=True)
    (tmp_path / "file.nc").write_text("x")
    (tmp_path / "link.nc").symlink_to(tmp_path / "file.nc")
    assert not_a_regular_file(tmp_path / "file.nc") is None
    assert not_a_regular_file(tmp_path / "link.nc") is None  # a link to a regular file
    assert not_a_regular_file(tmp_path / "absent.nc") is None
    check_output_file(tmp_path / "link.nc", "-o/--output", overwrite=True)


def test_a_figure_name_that_is_a_link_to_a_device_is_refused(archives, tmp_path, capsys):
    figures = tmp_path / "figures"
    figures.mkdir()
    from workbench.plot import run_figure_names

    first = run_figure_names("duffing", 2, strobe=True)[0]
    (figures / first).symlink_to("/dev/null")
    with pytest.raises(ArchiveError, match=f"/{first}' is a symbolic link to a character"):
        check_output_directory(figures, "--figures", [first], overwrite=True)
    code, _, err = run_cli(["plot", archives["run"], "-o", figures, "--overwrite"], capsys)
    assert code == 2 and "is a symbolic link to a character device" in one_line(err)
    assert os.readlink(figures / first) == "/dev/null"


def test_the_api_never_replaces_a_device_and_names_the_user_s_path(tmp_path):
    """save_run overwrites by default: a link to /dev/null or a FIFO at the path is refused
    before the write, and one that appears during the write is refused at the rename."""
    ds = xr.Dataset({"a": ("t", np.arange(3.0))})
    link = tmp_path / "null.nc"
    link.symlink_to("/dev/null")
    os.mkfifo(tmp_path / "fifo.nc")
    for path in (link, tmp_path / "fifo.nc"):
        with pytest.raises(WriteFailed, match=f"cannot write '{path}': it is a "):
            save_run(ds, path)
    assert os.readlink(link) == "/dev/null"
    target = tmp_path / "late.nc"
    with pytest.raises(WriteFailed, match="it is a FIFO"), atomic_path(target) as tmp:
        tmp.write_text("the result")
        os.mkfifo(target)  # put there while the result was written
    assert stat.S_ISFIFO(os.lstat(target).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo.nc", "late.nc", "null.nc"]
    with pytest.raises(WriteFailed, match=r"cannot write '/sys/wb-test.txt': EACCES") as info:
        write_text_atomic("/sys/wb-test.txt", "text")
    assert ".tmp" not in str(info.value) and info.value.errno == errno.EACCES


# -- a write that fails after the work -----------------------------------------------------------
def _fail_writes_in(monkeypatch, directory: Path, error: Exception) -> None:
    """Every netCDF write of a file in ``directory`` fails with ``error`` (its file name the
    temporary file's, as the operating system gives it)."""
    real = xr.Dataset.to_netcdf

    def to_netcdf(self, path=None, *args, **kwargs):
        if path is not None and Path(path).parent == directory:
            Path(path).write_bytes(b"\0" * 100)
            raise type(error)(*error.args, str(path)) if isinstance(error, OSError) else error
        return real(self, path, *args, **kwargs)

    monkeypatch.setattr(xr.Dataset, "to_netcdf", to_netcdf)


FAILURES = [
    (OSError(errno.EACCES, "Permission denied"), "EACCES: permission denied"),
    (OSError(errno.EROFS, "Read-only file system"), "EROFS: read-only file system"),
    (OSError(errno.EIO, "Input/output error"), "EIO: input/output error"),
    (RuntimeError("NetCDF: HDF error"), "NetCDF: HDF error"),  # with room: not a full disk
]


@pytest.mark.parametrize("error, says", FAILURES, ids=["EACCES", "EROFS", "EIO", "HDF error"])
def test_a_run_whose_write_fails_after_the_work_is_kept_and_the_line_says_where(
    archives, tmp_path, capsys, monkeypatch, error, says
):
    """The issue: `run -o /sys/wb.nc` computed, then a PermissionError traceback lost the run
    (only a full disk kept it)."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.setattr("tempfile.tempdir", str(elsewhere))
    bad = tmp_path / "bad"
    bad.mkdir()
    _fail_writes_in(monkeypatch, bad, error)
    code, _, err = run_cli(["run", archives["scene"], "-o", bad / "run.nc", "-q"], capsys)
    line = one_line(err)
    assert code == 2
    (kept,) = elsewhere.glob("run.kept-*.nc")
    assert f"cannot write '{bad / 'run.nc'}': {says}" in line, line
    assert f"the computed run was kept at {str(kept)!r}" in line, line
    assert "no space left" not in line
    kept = workbench.open_run(kept)
    assert kept.attrs["scene"] == workbench.load_scene(archives["scene"]).to_toml()
    assert np.isfinite(kept.x).all()
    assert not list(bad.iterdir())  # no temporary file left


def test_a_write_error_is_one_line_naming_the_path_in_the_api(tmp_path, monkeypatch):
    ds = xr.Dataset({"a": ("t", np.arange(3.0))})
    _fail_writes_in(monkeypatch, tmp_path, OSError(errno.EIO, "Input/output error"))
    monkeypatch.setattr(  # a nearly full disk does not make every failure a full disk
        "workbench.archive._atomic.shutil.disk_usage",
        lambda p: type("u", (), {"total": 10**9, "used": 10**9, "free": 0}),
    )
    with pytest.raises(WriteFailed) as info:
        save_run(ds, tmp_path / "out.nc")
    assert not isinstance(info.value, DiskFull)
    assert str(info.value) == f"cannot write '{tmp_path / 'out.nc'}': EIO: input/output error"
    assert info.value.errno == errno.EIO and info.value.path == str(tmp_path / "out.nc")


def test_a_read_only_file_system_after_the_work_keeps_the_run(archives, tmp_path, capsys):
    """The same on a real file system remounted read-only while the run integrates (needs
    root to mount; skipped elsewhere)."""
    from helpers import tiny_tmpfs

    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    with tiny_tmpfs(tmp_path / "fs", "4m") as fs, pytest.MonkeyPatch.context() as mp:
        mp.setattr("tempfile.tempdir", str(elsewhere))
        real = workbench.run.simulate

        def simulate_then_remount(*args, **kwargs):
            ds = real(*args, **kwargs)
            subprocess.run(["mount", "-o", "remount,ro", str(fs)], check=True)
            return ds

        mp.setattr("workbench.run.simulate", simulate_then_remount)
        code, _, err = run_cli(["run", archives["scene"], "-o", fs / "run.nc", "-q"], capsys)
        line = one_line(err)
        assert not list(fs.iterdir())
    assert code == 2
    (kept,) = elsewhere.glob("run.kept-*.nc")
    assert "EROFS: read-only file system" in line and str(kept) in line, line
    assert np.isfinite(workbench.open_run(kept).x).all()


def test_a_campaign_whose_archive_cannot_be_written_keeps_its_blocks(
    archives, tmp_path, capsys, monkeypatch
):
    out = tmp_path / "sweep.nc"
    real = xr.Dataset.to_netcdf

    def to_netcdf(self, path=None, *args, **kwargs):
        if path is not None and Path(path).name.startswith(".sweep.nc."):
            raise OSError(errno.EIO, "Input/output error", str(path))
        return real(self, path, *args, **kwargs)

    with monkeypatch.context() as mp:
        mp.setattr(xr.Dataset, "to_netcdf", to_netcdf)
        code, _, err = run_cli(["campaign", archives["sweep"], "-o", out, "-q"], capsys)
    line = one_line(err)
    assert code == 2
    assert f"cannot write '{out}': EIO: input/output error" in line, line
    assert f"the finished blocks are kept in '{out}.blocks/'" in line, line
    assert not out.exists() and len(list(Path(f"{out}.blocks").glob("block-*.nc"))) == 4
    code, stdout, _ = run_cli(["campaign", archives["sweep"], "-o", out, "-q"], capsys)
    assert code == 0 and "(0 computed, 4 reused)" in stdout


# -- inputs ----------------------------------------------------------------------------------------
def test_a_scene_that_is_not_utf8_is_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b'[model]\nname = "duffing"\n# \xff\xfe\n')
    code, _, err = run_cli(["run", bad, "-o", tmp_path / "out.nc"], capsys)
    assert code == 2
    assert f"scene file '{bad}' is not UTF-8 text: byte 0xff at line 3, column 3" in one_line(err)
    with pytest.raises(SceneError, match="is not UTF-8 text"):
        workbench.load_scene(bad)


def nested(levels: int, value: str = "1.0") -> str:
    return "[" * levels + value + "]" * levels


@pytest.mark.parametrize("levels", [100_000, 300, 40])
def test_a_value_nested_deep_is_one_line(tmp_path, capsys, levels):
    """100 000 levels: tomllib itself recursed out (RecursionError); 40: parsed, then the
    repr of the value in the error message did."""
    deep = tmp_path / "deep.toml"
    deep.write_text(f'[model]\nname = "duffing"\n[parameters]\ngamma = {nested(levels)}\n')
    code, _, err = run_cli(["run", deep, "-o", tmp_path / "out.nc"], capsys)
    line = one_line(err)
    assert code == 2
    assert "16 levels" in line, line


def test_a_deeply_nested_mapping_is_refused_naming_the_key():
    value = 1.0
    for _ in range(100_000):
        value = [value]
    with pytest.raises(SceneError, match=r"^parameters.gamma: nests tables or arrays more than"):
        workbench.load_scene({"model": {"name": "duffing"}, "parameters": {"gamma": value}})
    with pytest.raises(SceneError, match=r"^sweep.gamma: nests"):
        workbench.scene_from_toml(f'[model]\nname = "duffing"\n[sweep]\ngamma = {nested(17)}\n')
    # the deepest a scene uses is far from the limit
    workbench.load_scene({**SWEEP, "sweep": {"gamma": [0.3, 0.4], "continuation": "up"}})


@pytest.fixture(scope="module")
def failed_run(archives, tmp_path_factory) -> str:
    """A failed run written by `workbench run` itself (the issue's case)."""
    path = tmp_path_factory.mktemp("failed") / "failed.nc"
    assert main(["run", archives["failed_scene"], "-o", str(path), "-q"]) == 3
    return str(path)


def test_analyse_of_a_failed_run_uses_its_records_before_the_failure_and_says_so(
    failed_run, tmp_path, capsys
):
    """The issue: a traceback, "non-finite value at index 463"."""
    ds = workbench.open_run(failed_run)
    assert ds.attrs["run_status"] == "max_steps"
    finite = np.isfinite(ds.x.values)
    n = int(finite.argmin())
    assert 0 < n < finite.size and not finite[n:].any()
    code, out, err = run_cli(
        ["analyse", failed_run, "--var", "x", "-o", tmp_path, "--surrogates", "0"], capsys
    )
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0] == (
        f"x: the run failed (status max_steps): only its {n} records before the failure "
        f"(t = 0 to {float(ds.time[n - 1]):.6g} s) are analysed; the {finite.size - n} records "
        "after it (NaN) are left out"
    )
    assert lines[1].startswith(f"x: {n} samples")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x-embedding.png", "x-lle.png"]


def test_analyse_of_a_run_that_failed_at_once_is_one_line(archives, tmp_path, capsys):
    path = tmp_path / "early.nc"
    scene = write_scene(tmp_path / "early.toml", {**FAILED, "solver": {"max_steps": 20}})
    assert main(["run", scene, "-o", str(path), "-q"]) == 3
    capsys.readouterr()
    n = int(np.isfinite(workbench.open_run(path).x.values).sum())
    code, out, err = run_cli(["analyse", path, "--var", "x", "-o", tmp_path], capsys)
    assert code == 2
    assert f"x: the run failed (status max_steps): only its {n} records before" in out
    line = one_line(err)
    assert f"--var x: x ('x') has {n} samples, too few" in line and "record a longer" in line
    assert not list(tmp_path.glob("*.png"))


@pytest.fixture
def altered(archives, tmp_path):
    """Campaign archives altered as the issue did."""
    ds = workbench.open_run(archives["campaign"])
    paths = {}

    def write(name: str, d: xr.Dataset) -> None:
        paths[name] = str(tmp_path / f"{name}.nc")
        d.to_netcdf(paths[name])  # not save_run: it would stamp the format version

    write("no status", ds.drop_vars("status"))
    nan = ds.copy()
    nan["status"] = nan["status"].astype(float) * np.nan
    write("NaN status", nan)
    inf = ds.copy()
    inf["x"] = inf["x"] * np.inf
    write("x all inf", inf)
    for version in (-1, 0):
        d = ds.copy()
        d.attrs["format_version"] = np.int32(version)
        write(f"format {version}", d)
    return paths


BIFURCATION_CASES = [
    ("no status", "has no 'status' variable (the outcome of each point)"),
    ("NaN status", "4 of the 4 flags of its 'status' variable are not status codes (e.g. nan)"),
    ("x all inf", "no finite sample of 'x' to draw: its 84 samples are all inf or NaN (84 inf"),
    ("format -1", "has format_version -1; allowed: a whole number from 1"),
    ("format 0", "has format_version 0; allowed: a whole number from 1"),
]


@pytest.mark.parametrize("case, says", BIFURCATION_CASES, ids=[c[0] for c in BIFURCATION_CASES])
def test_an_altered_campaign_archive_is_one_line(altered, tmp_path, capsys, case, says):
    """The issue: a KeyError, a ValueError from plot/_failures.py, an empty diagram with exit
    code 0, and a format version below 1 read as format 1."""
    png = tmp_path / "diagram.png"
    code, _, err = run_cli(["bifurcation", altered[case], "--var", "x", "-o", png], capsys)
    assert code == 2
    assert says in one_line(err), err
    assert not png.exists()


@pytest.mark.parametrize("version", [-1, 0, 0.5, "two"])
def test_a_format_version_below_1_or_not_whole_is_refused(archives, tmp_path, version):
    ds = workbench.open_run(archives["run"])
    ds.attrs["format_version"] = version
    ds.to_netcdf(tmp_path / "run.nc")
    with pytest.raises(ArchiveError, match=r"has format_version .*; allowed: a whole number"):
        workbench.open_run(tmp_path / "run.nc")


def test_delay_acf_refuses_a_series_too_short_empty_or_constant():
    from workbench.analysis import delay_acf

    with pytest.raises(ValueError, match=r"has 3 samples; delay_acf needs at least 20"):
        delay_acf(np.array([1.0, 2.0, 1.0]))
    with pytest.raises(ValueError, match=r"has 0 samples; delay_acf needs at least 20"):
        delay_acf(np.array([]))
    with pytest.raises(ValueError, match=r"is constant: its autocorrelation is undefined"):
        delay_acf(np.ones(50))
    with pytest.raises(ValueError, match=r"max_lag=50; allowed: 1 <= max_lag < 50"):
        delay_acf(np.sin(np.arange(50.0)), max_lag=50)
    assert 1 <= int(delay_acf(np.sin(np.arange(20) * 0.3)).delay) <= 5  # the shortest allowed
