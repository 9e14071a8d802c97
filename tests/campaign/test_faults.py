"""Fault injection (issues 18 and 23): kill -9, Ctrl-C, SIGTERM, corrupt blocks, two writers on
one store, failed points, a point that raises, a full disk, and bad arguments (the single run's
and the writes' cases: tests/run/test_faults_run.py, tests/archive/test_faults_output.py).
Each case runs on
the Duffing oscillator (or the test model) in well under 30 s, and every process a case starts
is gone when it ends."""

import contextlib
import errno
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from helpers import campaign_numbers as numbers

import workbench
from workbench.archive import ArchiveError, StoreLocked, StoreWarning, sha256_file
from workbench.campaign import CampaignWarning, store_paths
from workbench.campaign._block import RAISED
from workbench.campaign._store import Store
from workbench.cli import main

# About 0.1 s per point at rtol 1e-12 on an idle machine, 0.4 s under a load of 5 (5 000
# periods, one strobe sample each).
SLOW = {
    "model": {"name": "duffing"},
    "solver": {"rtol": 1e-12, "atol": 1e-12},
    "run": {"cycles": 5000},
    "record": {"samples_per_period": 1, "variables": ["x"]},
    "sweep": {"gamma": {"start": 0.2, "stop": 0.5, "num": 8}},
}
QUICK = {
    "model": {"name": "duffing"},
    "run": {"cycles": 20, "transient_cycles": 10},
    "record": {"samples_per_period": 1},
    "sweep": {"gamma": [0.25, 0.3, 0.35, 0.4]},
}


@pytest.fixture(scope="module", autouse=True)
def compiled():
    """The Duffing kernel in the on-disk cache, so that subprocesses only load it."""
    workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 1}})


def scene_file(tmp_path: Path, spec: dict, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(workbench.load_scene(spec).to_toml())
    return path


def live_in_group(pgid: int) -> list[int]:
    """Processes of process group ``pgid`` that are alive (zombies are dead: not counted)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()  # after "pid (comm) "
        state, pgrp = fields[0], int(fields[2])
        if pgrp == pgid and state not in ("Z", "X"):
            found.append(int(entry.name))
    return found


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return ""


def wait_gone(pgid: int, limit: float) -> float:
    """Seconds until no process of the group is alive; fails after ``limit`` seconds."""
    t0 = time.monotonic()
    while live_in_group(pgid):
        assert time.monotonic() - t0 < limit, f"alive after {limit} s: {live_in_group(pgid)}"
        time.sleep(0.05)
    return time.monotonic() - t0


@contextlib.contextmanager
def cli_process(args: list[str], tmp_path: Path):
    """``workbench ARGS`` in its own process group (as from a terminal); killed if left over."""
    err = open(tmp_path / "stderr.txt", "w+")  # noqa: SIM115
    proc = subprocess.Popen(
        [sys.executable, "-m", "workbench.cli", *args],
        stdout=subprocess.DEVNULL,
        stderr=err,
        start_new_session=True,
    )
    try:
        yield proc
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        err.close()


def committed(store: Path) -> int:
    try:
        manifest = json.loads(store_paths(store)["manifest"].read_text())
    except (OSError, ValueError):
        return 0
    return len(manifest.get("checksums", {}))


def test_kill_9_leaves_no_process_and_the_resume_is_identical(tmp_path):
    scene = scene_file(tmp_path, SLOW)
    store = tmp_path / "kill.nc"
    args = ["campaign", str(scene), "-o", str(store), "--workers", "2", "--chunk", "1", "-q"]
    with cli_process(args, tmp_path) as proc:
        deadline = time.monotonic() + 25
        while committed(store) < 2:
            assert proc.poll() is None, (tmp_path / "stderr.txt").read_text()
            assert time.monotonic() < deadline, "no block committed in time"
            time.sleep(0.02)
        assert len(live_in_group(proc.pid)) >= 4  # campaign, fork server, 2 workers (+ tracker)
        os.kill(proc.pid, signal.SIGKILL)  # the campaign alone, not its group
        proc.wait()
        gone = wait_gone(proc.pid, 10.0)
    print(f"every process of the killed campaign ended {gone:.2f} s after it")
    done = committed(store)
    assert 2 <= done < 8, "the campaign was not interrupted mid-way"
    assert not store.exists()
    with pytest.warns(StoreWarning) as record:  # the dead campaign's lock is stale
        resumed = workbench.run_campaign(scene, store, workers=2)
    assert any(f"left by process {proc.pid} on host" in str(w.message) for w in record)
    assert resumed.attrs["reused_blocks"] == done
    assert resumed.attrs["computed_blocks"] == 8 - done
    whole = workbench.run_campaign(scene, tmp_path / "whole.nc", workers=2, chunk=1)
    xr.testing.assert_identical(numbers(resumed), numbers(whole))


def test_ctrl_c_while_the_workers_start_is_one_line(tmp_path):
    scene = scene_file(tmp_path, SLOW)
    args = ["campaign", str(scene), "-o", str(tmp_path / "c.nc"), "--workers", "2", "-q"]
    with cli_process(args, tmp_path) as proc:
        deadline = time.monotonic() + 20
        while not any("forkserver" in _cmdline(p) for p in live_in_group(proc.pid)):
            assert proc.poll() is None, (tmp_path / "stderr.txt").read_text()
            assert time.monotonic() < deadline, "no fork server started"
            time.sleep(0.005)
        # Python is up in the fork server, which imports workbench and loads the kernel for
        # its workers (2-4 s); the campaign waits for its first worker
        time.sleep(0.5)
        os.killpg(proc.pid, signal.SIGINT)  # what a terminal's Ctrl-C does
        assert proc.wait(timeout=20) == 130
        wait_gone(proc.pid, 10.0)
    err = (tmp_path / "stderr.txt").read_text()
    assert "Traceback" not in err, err
    assert "workbench campaign: interrupted" in err


def flip_values(path: Path, name: str) -> None:
    """Invert the bytes of variable ``name``'s data in a block file: the file still opens and
    belongs to its campaign, only the numbers are wrong (the issue's case: reused, with
    clearance_y at 8.3e180 m)."""
    data = path.read_bytes()
    raw = np.asarray(workbench.open_run(path)[name].values, ">f8").tobytes()  # netCDF-3
    at = data.index(raw)
    flipped = bytes(b ^ 0xFF for b in raw)
    path.write_bytes(data[:at] + flipped + data[at + len(raw) :])


def test_corrupt_truncated_and_deleted_blocks_are_named_and_recomputed(tmp_path):
    store = tmp_path / "c.nc"
    first = workbench.run_campaign(QUICK, store, workers=1, chunk=1)
    blocks = store_paths(store)["blocks"]
    files = sorted(blocks.glob("block-*.nc"))
    assert first.attrs["campaign_block_sha256"].split() == [sha256_file(p) for p in files]
    flip_values(files[0], "x")
    assert workbench.open_run(files[0]).attrs["campaign_id"] == first.attrs["campaign_id"]
    files[1].write_bytes(files[1].read_bytes()[:500])  # truncated
    files[2].unlink()
    with pytest.warns(CampaignWarning) as record:
        again = workbench.run_campaign(QUICK, store)
    messages = [str(w.message) for w in record]
    for expected in (
        "block 0 (block-00000.nc) is corrupt: checksum mismatch; recomputing",
        "block 1 (block-00001.nc) is corrupt: checksum mismatch; recomputing",
        "block 2 (block-00002.nc) is missing; recomputing",
    ):
        assert expected in messages, messages
    assert (again.attrs["computed_blocks"], again.attrs["reused_blocks"]) == (3, 1)
    xr.testing.assert_identical(numbers(again), numbers(first))
    files = sorted(blocks.glob("block-*.nc"))
    assert again.attrs["campaign_block_sha256"].split() == [sha256_file(p) for p in files]


def test_blocks_of_other_code_are_named_and_recomputed_never_mixed(tmp_path):
    """A resume under changed code (issue 23: 2 of 8 points of the old code were mixed in
    silently) recomputes the blocks that other code computed, says so, and the archive lists
    the one code digest it holds."""
    store = tmp_path / "c.nc"
    first = workbench.run_campaign(QUICK, store, workers=1, chunk=1)
    code = first.attrs["code_digests"]
    assert (
        len(code) == 16
        and workbench.open_run(sorted(store_paths(store)["blocks"].glob("block-*.nc"))[0]).attrs[
            "code_digest"
        ]
        == code
    )
    manifest_path = store_paths(store)["manifest"]
    manifest = json.loads(manifest_path.read_text())
    manifest["code_digests"]["1"] = "0123456789abcdef"  # block 1 from other code
    del manifest["code_digests"]["3"]  # block 3 from a store that did not record it
    manifest_path.write_text(json.dumps(manifest))
    with pytest.warns(CampaignWarning) as record:
        again = workbench.run_campaign(QUICK, store)
    messages = [str(w.message) for w in record]
    assert any(
        m.startswith(
            "2 of 4 blocks were computed by other code (code digest "
            "'0123456789abcdef' (1), 'unrecorded' (1); this code: " + repr(code)
        )
        for m in messages
    ), messages
    assert (again.attrs["computed_blocks"], again.attrs["reused_blocks"]) == (2, 2)
    assert again.attrs["code_digests"] == code
    xr.testing.assert_identical(numbers(again), numbers(first))


def test_a_second_writer_is_refused_and_a_stale_lock_taken_over(tmp_path):
    scene = scene_file(tmp_path, QUICK)
    store = tmp_path / "c.nc"
    with Store(store).lock():  # this process writes the store
        out = subprocess.run(
            [sys.executable, "-m", "workbench.cli", "campaign", str(scene), "-o", str(store)],
            capture_output=True,
            text=True,
            timeout=60,
        )
        with pytest.raises(StoreLocked) as refused:
            workbench.run_campaign(scene, store, workers=1)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("workbench campaign: error: "), out.stderr
    assert f"process {os.getpid()} on host {socket.gethostname()!r}" in lines[0]
    assert refused.value.pid == os.getpid() and refused.value.host == socket.gethostname()
    assert not store.exists()

    dead = subprocess.Popen(["true"])
    dead.wait()
    lock = store_paths(store)["blocks"] / "lock"
    lock.parent.mkdir(exist_ok=True)
    lock.write_text(json.dumps({"pid": dead.pid, "host": socket.gethostname()}))
    with pytest.warns(StoreWarning) as record:
        ds = workbench.run_campaign(scene, store, workers=1)
    assert any(f"left by process {dead.pid} on host" in str(w.message) for w in record)
    assert (ds.status == 0).all() and not lock.exists()


def test_restart_cannot_replace_a_store_in_use(tmp_path):
    """The issue's case: a second campaign with --restart and another scene silently replaced
    the first one's archive."""
    store = tmp_path / "c.nc"
    first = workbench.run_campaign(QUICK, store, workers=1)
    other = scene_file(tmp_path, {**QUICK, "sweep": {"gamma": [0.5, 0.6]}})
    with Store(store).lock():
        code = main(["campaign", str(other), "-o", str(store), "--restart", "-q"])
    assert code == 2
    xr.testing.assert_identical(workbench.open_run(store), first)


def test_a_campaign_whose_points_all_fail_exits_non_zero_with_the_count(tmp_path, capsys):
    scene = scene_file(tmp_path, {**QUICK, "solver": {"max_steps": 10}})
    code = main(["campaign", str(scene), "-o", str(tmp_path / "c.nc"), "--workers", "1", "-q"])
    assert code == 3  # max_steps (workbench/cli/_exit_codes.py)
    err = capsys.readouterr().err
    assert "workbench campaign: 4 of 4 points failed (4 max_steps); exit code 3" in err


def test_a_point_that_raises_is_a_failed_point_and_the_campaign_goes_on(tmp_path, capsys):
    """Issue 23 item 2: an exception inside one point (here the test model's bug) becomes its
    status 'error' with the exception in 'failure'; the other points run, and the command says
    how many failed."""
    import dask
    import failing_model

    spec = {
        "model": {"name": "failing"},
        "run": {"duration": 1.0},
        "record": {"dt": 0.5},
        "sweep": {"mode": [failing_model.OK, failing_model.BUG, failing_model.NON_FINITE]},
    }
    scene = scene_file(tmp_path, spec)
    with dask.config.set({"multiprocessing.context": "fork"}):  # the workers know the model
        code = main(["campaign", str(scene), "-o", str(tmp_path / "c.nc"), "--workers", "1"])
    ds = workbench.open_run(tmp_path / "c.nc")
    assert ds.status.values.tolist() == [0, RAISED, int(workbench.Status.NON_FINITE)]
    assert str(ds.failure.values[1]).startswith(
        "error: RuntimeError: a bug in the test model (raised at failing_model.py:"
    )
    assert np.isfinite(ds.y.values[0]).all() and np.isnan(ds.y.values[1]).all()
    assert code == 4  # the largest: non_finite 4 over error 1
    err = capsys.readouterr().err
    assert "2 of 3 points failed (1 non_finite, 1 error); exit code 4" in err


def test_the_issue_s_huge_initial_value_in_a_sweep_fails_one_point_only(tmp_path, capsys):
    """Issue 23: x0 = 1e50 in a sweep aborted the campaign (ZeroDivisionError, 65-line
    traceback, 1 of 4 blocks done)."""
    sweep = {**QUICK, "sweep": {"x0": [1.0, 1e50, 2.0, 3.0]}}
    code = main(["campaign", str(scene_file(tmp_path, sweep)), "-o", str(tmp_path / "c.nc"), "-q"])
    assert code == 4
    ds = workbench.open_run(tmp_path / "c.nc")
    assert ds.status.values.tolist() == [0, 4, 0, 0]
    assert "initial step cannot be formed" in str(ds.failure.values[1])
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["workbench campaign: 1 of 4 points failed (1 non_finite); exit code 4"], err


def test_sigterm_stops_a_campaign_in_one_line_and_keeps_its_blocks(tmp_path):
    """SIGTERM (a scheduler's or systemd's stop) does what Ctrl-C does: one line, exit 143,
    every process gone, the committed blocks kept, and the resume identical."""
    scene = scene_file(tmp_path, SLOW)
    store = tmp_path / "term.nc"
    args = ["campaign", str(scene), "-o", str(store), "--workers", "2", "--chunk", "1", "-q"]
    with cli_process(args, tmp_path) as proc:
        deadline = time.monotonic() + 25
        while committed(store) < 2:
            assert proc.poll() is None, (tmp_path / "stderr.txt").read_text()
            assert time.monotonic() < deadline, "no block committed in time"
            time.sleep(0.02)
        os.kill(proc.pid, signal.SIGTERM)  # the campaign alone, as `kill PID` does
        assert proc.wait(timeout=20) == 143
        wait_gone(proc.pid, 10.0)
    err = (tmp_path / "stderr.txt").read_text().strip().splitlines()
    assert len(err) == 1 and err[0].startswith("workbench campaign: terminated by SIGTERM; "), err
    assert f"'{store}.blocks/'" in err[0]
    done = committed(store)
    assert 2 <= done < 8
    resumed = workbench.run_campaign(scene, store, workers=2)  # identical: see the kill -9 case
    assert resumed.attrs["reused_blocks"] == done and (resumed.status == 0).all()


def test_a_full_disk_stops_a_campaign_in_one_line_and_the_resume_completes_it(
    tmp_path, capsys, monkeypatch
):
    """Issue 23: a 63-line worker traceback. The disk fills when block 2 is written (injected
    in the forked workers): one line naming the file, the bytes needed and free and where the
    finished blocks are; with space again the same command completes the campaign."""
    import dask

    import workbench.archive._atomic as atomic

    real = xr.Dataset.to_netcdf
    real_write = Path.write_bytes

    def to_netcdf(self, path=None, *args, **kwargs):
        if path is not None and ".block-00002.nc." in str(path):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, path, *args, **kwargs)

    def write_bytes(self, data):  # block files are serialised in memory, then written
        if ".block-00002.nc." in str(self):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(self, data)

    scene = scene_file(tmp_path, QUICK)
    store = tmp_path / "c.nc"
    argv = ["campaign", str(scene), "-o", str(store), "--workers", "1", "--chunk", "1", "-q"]
    with dask.config.set({"multiprocessing.context": "fork"}), monkeypatch.context() as m:
        m.setattr(xr.Dataset, "to_netcdf", to_netcdf)
        m.setattr(Path, "write_bytes", write_bytes)
        m.setattr(atomic, "_free_bytes", lambda directory: 5000.0)
        code = main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "block-00002.nc': no space left on its file system (the file needs up to" in err[0]
    assert "4.88 KiB free" in err[0] and "the finished blocks are kept in" in err[0]
    assert not list(store_paths(store)["blocks"].glob(".*.tmp"))
    assert main(argv) == 0
    whole = workbench.run_campaign(QUICK, tmp_path / "whole.nc", workers=1)
    xr.testing.assert_identical(numbers(workbench.open_run(store)), numbers(whole))


def run_cli(argv: list[str], capsys) -> tuple[int, str]:
    """Exit code and stderr of ``workbench ARGV`` (argparse's errors exit via SystemExit)."""
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    return code, capsys.readouterr().err


@pytest.fixture
def files(tmp_path):
    """Scenes and archives for the bad-argument cases."""
    run = {"model": {"name": "duffing"}, "run": {"cycles": 2}, "record": {"samples_per_period": 4}}
    paths = {
        "scene": scene_file(tmp_path, run),
        "sweep": scene_file(tmp_path, {**run, "sweep": {"gamma": [0.3, 0.4]}}, "sweep.toml"),
        "huge": tmp_path / "huge.toml",
        "short": scene_file(
            tmp_path,
            {"model": {"name": "lorenz"}, "run": {"duration": 0.04}, "record": {"dt": 0.01}},
            "short.toml",
        ),
        "dir": tmp_path / "adir",
        "file": tmp_path / "file.nc",
        "truncated": tmp_path / "truncated.nc",
        "five": tmp_path / "five.nc",
        "norun": tmp_path / "norun.nc",
    }
    paths["huge"].write_text('[model]\nname = "duffing"\n[solver]\nmax_steps = 1e21\n')
    # the issue's cases, as given there
    paths["nan"] = tmp_path / "nan.toml"
    paths["nan"].write_text('[model]\nname="duffing"\n[initial]\nx=nan\n[run]\ncycles=5\n')
    paths["cycles"] = tmp_path / "cycles.toml"
    paths["cycles"].write_text('[model]\nname="duffing"\n[run]\ncycles=1000000000\n')
    paths["lorenz"] = tmp_path / "lorenz.toml"
    paths["lorenz"].write_text('[model]\nname="lorenz"\n[run]\nduration=1e6\n[record]\ndt=1e-6\n')
    paths["dir"].mkdir()
    workbench.save_run(workbench.simulate(run), paths["file"])
    paths["truncated"].write_bytes(paths["file"].read_bytes()[:3000])
    workbench.save_run(workbench.simulate(paths["short"]), paths["five"])
    workbench.save_run(xr.Dataset({"a": ((), 1.0)}), paths["norun"])
    return {k: str(v) for k, v in paths.items()}


# (name, argv template, code, what the one line must say); {x} is a path of the `files` fixture,
# {out} a file that must not appear (nothing ran).
CASES = [
    ("max_steps 1e21", "run {huge} -o {out}", 2, "solver.max_steps"),
    ("initial nan", "run {nan} -o {out}", 2, "initial.x: got nan; must be a finite number"),
    ("cycles 1e9", "run {cycles} -o {out}", 2, "run.cycles: the records of this run would take"),
    ("lorenz dt 1e-6", "run {lorenz} -o {out}", 2, "run.duration: the records of this run"),
    (
        "max memory",
        "run {scene} -o {out} --max-memory 10XB",
        2,
        "--max-memory: got '10XB'; allowed: a number of bytes > 0",
    ),
    (
        "campaign archive",
        "campaign {sweep} -o {out} --max-memory 100B",
        2,
        "run.cycles: the campaign's archive would take",
    ),
    ("sweep to run", "run {sweep} -o {out}", 2, "'workbench campaign SCENE -o OUT.nc'"),
    ("workers 0", "campaign {sweep} -o {out} --workers 0", 2, "--workers: got 0; allowed"),
    ("workers -1", "campaign {sweep} -o {out} --workers -1", 2, "--workers: got -1; allowed"),
    ("chunk 0", "campaign {sweep} -o {out} --chunk 0", 2, "--chunk: got 0; allowed"),
    ("output a directory", "run {scene} -o {dir}", 2, "-o/--output: '{dir}' is a directory"),
    ("output under a file", "run {scene} -o {file}/x.nc", 2, "'{file}' is a file, not a dir"),
    ("figures a file", "run {scene} -o {out} --figures {file}", 2, "--figures: '{file}' is a file"),
    ("campaign under a file", "campaign {sweep} -o {file}/c.nc", 2, "is a file, not a directory"),
    ("existing output", "run {scene} -o {file}", 2, "'{file}' exists; pass --overwrite"),
    ("plot truncated", "plot {truncated} -o {dir}", 2, "is not a readable netCDF file"),
    ("bifurcation truncated", "bifurcation {truncated} --var x", 2, "not a readable netCDF"),
    ("analyse truncated", "analyse {truncated} --var x", 2, "is not a readable netCDF file"),
    ("plot not a run", "plot {norun} -o {dir}", 2, "has no variables over time"),
    ("analyse 5 points", "analyse {five} --var x -o {dir}", 2, "has 5 samples"),
    (
        "unreachable scheduler",
        "campaign {sweep} -o {out} --scheduler tcp://127.0.0.1:9 --scheduler-timeout 1",
        2,
        "--scheduler: cannot reach a dask scheduler at 'tcp://127.0.0.1:9' within 1 s",
    ),
    ("tolerances", "accuracy {scene} -o {out} --tolerances 1e-4,0", 2, "--tolerances: got '0'"),
    ("missing scene", "run {dir}/none.toml -o {out}", 2, "does not exist"),
]


@pytest.mark.timeout(120)  # a hang guard: each case answers at once
@pytest.mark.parametrize("name, argv, code, says", CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_one_line_before_anything_runs(
    name, argv, code, says, files, tmp_path, capsys
):
    out = tmp_path / "out.nc"
    fields = {**files, "out": str(out)}
    got, err = run_cli(argv.format(**fields).split(), capsys)
    lines = err.strip().splitlines()
    assert got == code, err
    assert len(lines) == 1, err
    assert lines[0].startswith("workbench"), err
    assert says.format(**fields) in lines[0], err
    assert not out.exists()


def test_open_run_names_a_truncated_file(files):
    with pytest.raises(ArchiveError, match="is not a readable netCDF file"):
        workbench.open_run(files["truncated"])


def test_overwrite_replaces_an_existing_run(files, capsys):
    assert main(["run", files["scene"], "-o", files["file"], "-q", "--overwrite"]) == 0
    assert np.isfinite(workbench.open_run(files["file"]).x).all()
