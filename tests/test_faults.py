"""Fault injection (issue 18): kill -9, Ctrl-C, corrupt blocks, two writers on one store, failed
points, and bad arguments. Each case runs on the Duffing oscillator in well under 30 s, and every
process a case starts is gone when it ends."""

import contextlib
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

import workbench
from workbench.archive import ArchiveError, StoreLocked, StoreWarning, sha256_file
from workbench.campaign import CampaignWarning, store_paths
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
EXECUTION_ATTRS = (
    "history",
    "computed_blocks",
    "reused_blocks",
    "campaign_wall_time",
    "campaign_compute_wall_time",
    "campaign_workers",
    "campaign_block_sha256",
)


def numbers(ds: xr.Dataset) -> xr.Dataset:
    """The data of a campaign without wall times and the attributes of one execution."""
    out = ds.drop_vars(["point_wall_time", "solver_wall_time"])
    out.attrs = {k: v for k, v in ds.attrs.items() if k not in EXECUTION_ATTRS}
    return out


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


@pytest.mark.parametrize("name, argv, code, says", CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_one_line_before_anything_runs(
    name, argv, code, says, files, tmp_path, capsys
):
    out = tmp_path / "out.nc"
    fields = {**files, "out": str(out)}
    t0 = time.monotonic()
    got, err = run_cli(argv.format(**fields).split(), capsys)
    lines = err.strip().splitlines()
    assert got == code, err
    assert len(lines) == 1, err
    assert lines[0].startswith("workbench"), err
    assert says.format(**fields) in lines[0], err
    assert not out.exists()
    assert time.monotonic() - t0 < 15


def test_open_run_names_a_truncated_file(files):
    with pytest.raises(ArchiveError, match="is not a readable netCDF file"):
        workbench.open_run(files["truncated"])


def test_overwrite_replaces_an_existing_run(files, capsys):
    assert main(["run", files["scene"], "-o", files["file"], "-q", "--overwrite"]) == 0
    assert np.isfinite(workbench.open_run(files["file"]).x).all()
