"""Campaigns: same numbers whatever the workers, resumable after a kill, failures as data."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest
import xarray as xr
from helpers import campaign_numbers

import workbench
from workbench.archive import DiskFull, StoreWarning
from workbench.campaign import CampaignError, CampaignWarning, store_paths, summary
from workbench.cli import main

BASE = {
    "model": {"name": "duffing"},
    "run": {"cycles": 4, "transient_cycles": 2},
    "record": {"samples_per_period": 4},
}
SWEEP = {"gamma": [0.3, 0.4, 0.5], "omega": [1.0, 1.1, 1.2, 1.3]}  # 12 points, two dims
# Attributes of one execution beyond helpers.CAMPAIGN_EXECUTION_ATTRS: how it was split, and
# what a call that reused every block records of itself
_RUN_ATTRS = (
    "resume_workers",
    "resume_compute_wall_time",
    "resume_wall_time",
    "campaign_chunk",
    "campaign_blocks",
    "campaign_id",
)


def numbers(ds: xr.Dataset) -> xr.Dataset:
    """The dataset without wall times and the attributes of one execution."""
    return campaign_numbers(ds, also=_RUN_ATTRS)


@pytest.fixture(scope="module")
def scene():
    s = workbench.load_scene({**BASE, "sweep": SWEEP})
    # Fill the on-disk numba cache once, so that worker processes only load compiled code.
    workbench.simulate(s.with_parameters(gamma=0.3, omega=1.0))
    return s


@pytest.fixture(scope="module")
def one_worker(scene, tmp_path_factory):
    return workbench.run_campaign(scene, tmp_path_factory.mktemp("one") / "c.nc", workers=1)


def test_a_campaign_names_the_processor_that_computed_its_points(one_worker):
    """Issue 36: one processor and compile target for every point -> the campaign's attributes
    (no per-point variable); blocks from different targets -> ``compiled_on`` per point."""
    from workbench._processor import processor_attrs
    from workbench.campaign._assemble import _compiled_on

    assert {k: one_worker.attrs[k] for k in processor_attrs()} == processor_attrs()
    assert "compiled_on" not in one_worker

    def block(points, **attrs):
        return xr.Dataset(coords={"point": ("point", np.array(points))}, attrs=attrs)

    host = processor_attrs()
    generic = {**host, "compile_target": "x86_64-unknown-linux-gnu generic"}
    blocks = [block([0, 1], **host), block([2, 5], **generic), block([3, 4])]
    var, attrs = _compiled_on(blocks, 6, (2, 3), ("gamma", "omega"))
    assert var.dims == ("gamma", "omega") and var.attrs["units"] == "1"
    np.testing.assert_array_equal(var.values, [[0, 0, 1], [2, 2, 1]])
    assert attrs["processor"].startswith("mixed")
    listing = var.attrs["compile_targets"].split("; ")
    assert listing[1].startswith("1: ") and "generic" in listing[1]
    assert listing[2] == "2: " + ", ".join(f"{a} not recorded" for a in host)


def test_same_numbers_with_one_or_two_workers_and_as_single_runs(scene, one_worker, tmp_path):
    two = workbench.run_campaign(scene, tmp_path / "c.nc", workers=2)
    assert one_worker.attrs["campaign_chunk"] != two.attrs["campaign_chunk"]  # other blocks too
    xr.testing.assert_identical(numbers(one_worker), numbers(two))
    for g in SWEEP["gamma"]:
        for w in SWEEP["omega"]:
            ref = workbench.simulate(scene.with_parameters(gamma=g, omega=w))
            pt = one_worker.sel(gamma=g, omega=w)
            for name in ("x", "v"):
                np.testing.assert_array_equal(pt[name].values, ref[name].values)
                assert pt[name].attrs == ref[name].attrs
            np.testing.assert_array_equal(pt.record_time.values, ref.time.values)
            for stat in ("steps", "rejected_steps", "rhs_evaluations", "events"):
                assert int(pt[f"solver_{stat}"]) == ref.attrs[f"solver_{stat}"]
            assert int(pt.status) == 0 and str(pt.failure.values) == ""
            assert float(pt.forcing_period) == ref.attrs["forcing_period"]


def test_one_engine_records_the_workers_cpu_and_the_package_exports_what_users_call(one_worker):
    """Issue 41 item 2: the grid campaign runs on the engine the continued sweep runs on (the
    workers' CPU time, which only the sweep recorded before, and the creating function in
    the provenance); ``workbench.campaign`` exports the names users call, not the engine's
    pieces (22 names before)."""
    import workbench.campaign as campaign

    assert one_worker.attrs["campaign_cpu_time"] > 0
    assert one_worker.attrs["history"].endswith("created by workbench.run_campaign")
    assert set(campaign.__all__) == {
        "DASK_CONFIG", "CampaignError", "CampaignWarning", "SweepGrid", "expand_sweep",
        "jobqueue_cluster", "local_cluster", "run_campaign", "store_paths", "summary",
        "warm_kernel",
    }  # fmt: skip


def test_dims_units_and_archive(scene, one_worker):
    ds = one_worker
    assert ds.x.dims == ("gamma", "omega", "record")  # parameter dims first; own record times
    assert ds.status.dims == ("gamma", "omega") and ds.status.dtype == np.int8
    meanings = [s.label for s in workbench.Status] + ["invalid_parameters", "error"]
    assert ds.status.attrs["flag_meanings"].split() == meanings
    np.testing.assert_array_equal(ds.status.attrs["flag_values"], range(len(meanings)))
    model = workbench.models.get_model("duffing")
    for d in ("gamma", "omega"):
        p = model.parameter(d)
        assert (ds[d].attrs["units"], ds[d].attrs["long_name"]) == (p.units, p.long_name)
    for name, v in ds.variables.items():
        assert "units" in v.attrs and "long_name" in v.attrs, name
    assert ds.sizes["record"] == 4 * 4 + 1  # only what the scene records
    assert workbench.scene_from_toml(ds.attrs["scene"]) == scene
    assert ds.attrs["campaign_dims"] == "gamma omega"
    assert ds.attrs["Conventions"] == "CF-1.11" and "numba=" in ds.attrs["package_versions"]
    paths = store_paths(ds.encoding["source"])
    xr.testing.assert_identical(workbench.open_run(paths["archive"]), ds)
    assert paths["manifest"].is_file()


@pytest.mark.slow
def test_distributed_client_gives_the_same_numbers(scene, one_worker, tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        ds = workbench.run_campaign(scene, tmp_path / "c.nc", client=client, progress=True)
    xr.testing.assert_identical(numbers(ds), numbers(one_worker))
    assert "pt" in capsys.readouterr().err  # the bar counts points


def test_failing_points_are_data_and_a_changed_scene_is_refused(tmp_path):
    spec = {
        "model": {"name": "duffing"},
        "solver": {"max_steps": 2000},  # enough for beta = 1, too few for the stiff beta = 1e6
        "run": {"cycles": 3},
        "record": {"samples_per_period": 4},
        "sweep": {"beta": [1.0, 1e6], "gamma": [0.3, 0.5]},
    }
    scene = workbench.load_scene(spec)
    store = tmp_path / "fail.nc"
    with pytest.warns(CampaignWarning, match="2 of 4 campaign points failed"):
        ds = workbench.run_campaign(scene, store, workers=1)
    np.testing.assert_array_equal(ds.status.values, [[0, 0], [2, 2]])  # ok, max_steps
    assert ds.attrs["failed_points"] == 2
    assert np.isnan(ds.x.sel(beta=1e6)).all() and np.isfinite(ds.x.sel(beta=1.0)).all()
    assert all(str(m).startswith("max_steps: ") for m in ds.failure.sel(beta=1e6).values)
    assert (ds.solver_steps.sel(beta=1e6) == 2000).all()  # up to the failure
    text = summary(ds)
    assert "2 ok; 2 max_steps" in text and "failed beta=1e+06, gamma=0.3: max_steps" in text
    # Same record times everywhere: a 1-D time coordinate, as from simulate; a point carries
    # every parameter as the run does (the swept ones selected, the others scalar)
    ref = workbench.simulate(scene.with_parameters(beta=1.0, gamma=0.5))
    xr.testing.assert_identical(ds.x.sel(beta=1.0, gamma=0.5), ref.x)
    assert all("units" in v.attrs and "long_name" in v.attrs for v in ds.variables.values())

    changed = workbench.load_scene({**spec, "solver": {"max_steps": 10**6}})
    with pytest.raises(CampaignError, match=r"(?s)different scene.*solver\.max_steps: 2000 -> "):
        workbench.run_campaign(changed, store)
    with pytest.raises(CampaignError, match="started with chunk=1 points per block, got chunk=3"):
        workbench.run_campaign(scene, store, chunk=3)
    again = workbench.run_campaign(changed, store, restart=True, workers=1)
    assert (again.status == 0).all() and np.isfinite(again.x).all()
    assert again.attrs["computed_blocks"] == again.attrs["campaign_blocks"] == 4
    assert again.attrs["reused_blocks"] == 0


def test_a_rerun_that_reuses_every_block_keeps_the_figures_of_the_call_that_computed_them(
    scene, tmp_path
):
    """A campaign run again on its finished store computes nothing: the archive keeps the
    workers and wall times of the call that computed the blocks and adds the rerun's as
    resume_* (issue 40: the rerun overwrote them, campaign_workers 0)."""
    store = tmp_path / "c.nc"
    first = workbench.run_campaign(scene, store, workers=2)
    names = ("campaign_workers", "campaign_compute_wall_time", "campaign_wall_time")
    original = {k: first.attrs[k] for k in names}
    assert original["campaign_workers"] == 2 and original["campaign_compute_wall_time"] > 0
    assert not any(k.startswith("resume_") for k in first.attrs)
    again = workbench.run_campaign(scene, store, workers=1)
    blocks = int(first.attrs["campaign_blocks"])
    assert (again.attrs["computed_blocks"], again.attrs["reused_blocks"]) == (0, blocks)
    for ds in (again, workbench.open_run(store)):
        assert {k: ds.attrs[k] for k in names} == original
        assert ds.attrs["resume_workers"] == 0
        assert 0 <= ds.attrs["resume_compute_wall_time"] <= ds.attrs["resume_wall_time"]
    text = summary(again)
    assert f"(0 computed, {blocks} reused), " in text and " s wall (computed before in " in text
    shutil.rmtree(store_paths(store)["blocks"])  # the archive alone, complete
    third = workbench.run_campaign(scene, store)
    assert {k: third.attrs[k] for k in names} == original and third.attrs["resume_workers"] == 0
    xr.testing.assert_identical(numbers(third), numbers(first))


def test_scene_without_sweep_and_bad_arguments_are_refused(scene, tmp_path):
    with pytest.raises(CampaignError, match=r"needs a \[sweep\]"):
        workbench.run_campaign(scene.replace(sweep={}), tmp_path / "c.nc")
    with pytest.raises(ValueError, match="workers must be a positive integer"):
        workbench.run_campaign(scene, tmp_path / "c.nc", workers=0)
    with pytest.raises(CampaignError, match="must be the path of a netCDF file"):
        workbench.run_campaign(scene, tmp_path)
    (tmp_path / "run.nc").write_bytes(b"")
    with pytest.raises(CampaignError, match="restart=True"):
        workbench.run_campaign(scene, tmp_path / "run.nc")


def test_an_error_stops_the_blocks_in_flight(tmp_path, monkeypatch):
    """An error outside the points (here the disk fills as a block is written) ends the
    campaign at once: the other worker's long block is stopped, not waited for, and writes no
    file. (A point that raises is a failed point: tests/campaign/test_faults.py.)"""
    import dask
    import failing_model

    import workbench.campaign._block as block_task

    scene = workbench.load_scene(
        {
            "model": {"name": "failing"},
            "run": {"duration": 1.0},
            "solver": {"max_step": 1e-7},  # 1e7 steps: minutes for the ok point
            "record": {"dt": 0.5},
            "sweep": {"mode": [failing_model.OK, failing_model.BUG]},  # BUG: at once
        }
    )
    store = tmp_path / "c.nc"
    # compile the model's kernel first (forked workers inherit it): the time bound below
    # tells a stopped block from one waited for (minutes), not a speed; not a cold compile
    workbench.simulate(scene.replace(sweep={}, run={"duration": 1e-3}, record={"dt": 5e-4}))

    def full_disk(ds, path, **kwargs):
        raise DiskFull(f"cannot write {str(path)!r}: no space left on its file system")

    monkeypatch.setattr(block_task, "save_run", full_disk)  # inherited by the forked workers
    t0 = time.monotonic()
    with (
        dask.config.set({"multiprocessing.context": "fork"}),  # the workers know the model
        pytest.raises(DiskFull, match="; no block was finished: free some space") as caught,
    ):
        workbench.run_campaign(scene, store, workers=2, chunk=1)
    assert time.monotonic() - t0 < 20
    assert not list(store_paths(store)["blocks"].glob("block-*.nc"))
    assert "kept" not in str(caught.value)  # issue 37: no folder of blocks that are not there


KILL = {
    "model": {"name": "duffing"},
    "solver": {"rtol": 1e-12, "atol": 1e-12},  # about 0.15 s per point
    "run": {"cycles": 6000},
    "record": {"samples_per_period": 1, "variables": ["x"]},
    "sweep": {"gamma": {"start": 0.2, "stop": 0.5, "num": 16}},
}


@pytest.mark.slow
def test_killed_campaign_resumes_without_recomputing(tmp_path):
    scene = workbench.load_scene(KILL)
    store = tmp_path / "kill.nc"
    blocks = store_paths(store)["blocks"]
    code = (
        "import workbench; workbench.run_campaign(workbench.scene_from_toml("
        f"{scene.to_toml()!r}), {str(store)!r}, workers=1, chunk=2)"
    )
    with open(tmp_path / "stderr.txt", "w") as err:
        proc = subprocess.Popen(
            [sys.executable, "-c", code],
            stdout=subprocess.DEVNULL,
            stderr=err,
            start_new_session=True,
        )
        try:
            deadline = time.monotonic() + 180
            while len(_checksums(store)) < 2:  # two blocks committed
                assert proc.poll() is None, (tmp_path / "stderr.txt").read_text()
                assert time.monotonic() < deadline, "no block written in time"
                time.sleep(0.01)
        finally:
            os.killpg(proc.pid, signal.SIGKILL)  # the process, its pool and its fork server
            proc.wait()
    committed = [f"block-{int(i):05d}.nc" for i in _checksums(store)]
    before = {n: ((blocks / n).stat().st_ino, (blocks / n).stat().st_mtime_ns) for n in committed}
    assert 2 <= len(before) < 8, "the campaign was not interrupted mid-way"
    assert not store.exists()  # nothing assembled, nothing half-written
    (blocks / ".block-00007.nc.x1y2z3.tmp").write_bytes(b"half")  # as left by a killed write

    with warnings.catch_warnings():  # the killed campaign's lock, blocks never committed
        warnings.simplefilter("ignore", CampaignWarning)
        warnings.simplefilter("ignore", StoreWarning)
        resumed = workbench.run_campaign(scene, store, workers=2)
    assert resumed.attrs["reused_blocks"] == len(before)
    assert resumed.attrs["computed_blocks"] == 8 - len(before)
    after = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in blocks.glob("block-*.nc")}
    assert len(after) == 8 and all(after[k] == v for k, v in before.items())
    assert not list(tmp_path.rglob("*.tmp"))
    for p in [store, *blocks.glob("*.nc")]:
        workbench.open_run(p)
    whole = workbench.run_campaign(scene, tmp_path / "whole.nc", workers=2, chunk=5)
    xr.testing.assert_identical(numbers(resumed), numbers(whole))


def _checksums(store) -> dict:
    """The committed blocks' checksums in a store's manifest (empty while it is unreadable)."""
    try:
        return json.loads(store_paths(store)["manifest"].read_text()).get("checksums", {})
    except (OSError, ValueError):
        return {}


SCENE_TOML = """
title = "Duffing bifurcation test"
[model]
name = "duffing"
[run]
cycles = 20
transient_cycles = 20
[record]
samples_per_period = 1
[sweep]
gamma = {start = 0.25, stop = 0.45, num = 6}
"""


def test_cli_campaign_and_bifurcation(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE_TOML)
    out = tmp_path / "c.nc"
    assert main(["campaign", str(scene), "-o", str(out), "--workers", "1", "-q"]) == 0
    text = capsys.readouterr().out
    assert "6 points in" in text and "6 ok" in text and str(out) in text
    ds = workbench.open_run(out)  # strobe samples only: one record per period, nothing dense
    assert ds.sizes["time"] == 20 + 1 and {"x", "v"} <= set(ds.data_vars)
    assert ds.x.dims == ("gamma", "time") and ds.time.attrs["units"] == "s"
    assert main(["campaign", str(scene), "-o", str(out), "-q"]) == 0
    assert "(0 computed, " in capsys.readouterr().out  # nothing missing: nothing recomputed
    shutil.rmtree(store_paths(out)["blocks"])  # the archive alone is enough once complete
    assert main(["campaign", str(scene), "-o", str(out), "-q"]) == 0
    assert "6 points in 3 blocks (0 computed, 3 reused)" in capsys.readouterr().out
    scene.write_text(SCENE_TOML.replace("cycles = 20\n", "cycles = 30\n", 1))
    assert main(["campaign", str(scene), "-o", str(out), "-q"]) == 2
    assert "run.cycles: 20 -> 30" in capsys.readouterr().err
    png = tmp_path / "bif.png"
    assert main(["bifurcation", str(out), "--var", "x", "-o", str(png)]) == 0
    assert png.stat().st_size > 0
    assert main(["bifurcation", str(out), "--var", "nope"]) == 2
    assert "no variable 'nope' over time" in capsys.readouterr().err


def test_longest_blocks_run_first(tmp_path):
    """A sweep over the forcing frequency: the blocks of low omega simulate the longest time
    (cycles x 2 pi / omega) and are started first (Graham's rule), whatever dask's own order of
    task names; with one worker the execution order is visible in each block file."""
    from workbench.campaign import expand_sweep
    from workbench.campaign._schedule import longest_first, simulated_spans

    scene = workbench.load_scene(
        {**BASE, "sweep": {"omega": [0.8, 1.0, 1.2, 1.4, 0.5, 2.0]}}  # slowest at flat 4
    )
    grid = expand_sweep(scene)
    assert simulated_spans(scene, grid)[4] == pytest.approx(6 * 2 * np.pi / 0.5, rel=1e-12)
    store = tmp_path / "c.nc"
    workbench.run_campaign(scene, store, workers=1, chunk=1)
    blocks = store_paths(store)["blocks"]
    started = {}
    for path in blocks.glob("block-*.nc"):
        b = workbench.open_run(path)
        started[int(b.point.values[0])] = int(b.attrs["worker_task_number"])
    by_start = [point for point, _ in sorted(started.items(), key=lambda kv: kv[1])]
    assert by_start == [4, 0, 1, 2, 3, 5]  # omega 0.5, 0.8, 1.0, 1.2, 1.4, 2.0
    assert by_start == [t.block for t in longest_first(scene, grid, _tasks(scene, grid))]


def _tasks(scene, grid):
    from workbench.campaign._block import BlockTask

    return [
        BlockTask(scene.to_toml(), grid.dims, (f,), grid.values, "", "", f)
        for f in range(grid.size)
    ]


def test_a_grid_above_the_limit_of_points_is_refused_before_anything_runs(tmp_path, capsys):
    """Issue 37: a grid of 10^7 points ran minutes of planning before any sign of life. A
    campaign has a limit on its points (10^6 by default), stated with how to raise it."""
    huge = {
        **BASE,
        "sweep": {
            "gamma": {"start": 0.2, "stop": 0.5, "num": 10000},
            "delta": {"start": 0.1, "stop": 0.4, "num": 1000},
        },
    }
    store = tmp_path / "huge.nc"
    with pytest.raises(CampaignError) as caught:
        workbench.run_campaign(huge, store, workers=1)
    assert str(caught.value) == (
        "the [sweep] grid has 10000000 points (gamma 10000 x delta 1000), more than the limit "
        "of 1000000 points per campaign; sweep fewer points, or raise the limit if this size "
        "is meant (max_points=10000000, CLI --max-points 10000000)"
    )
    assert not store_paths(store)["blocks"].exists()
    small = {**BASE, "sweep": {"gamma": [0.3, 0.4, 0.5]}}
    with pytest.raises(CampaignError, match="has 3 points .*limit of 2 points"):
        workbench.run_campaign(small, store, workers=1, max_points=2)
    with pytest.raises(ValueError, match="max_points must be a positive integer or None"):
        workbench.run_campaign(small, store, workers=1, max_points=0)

    scene = tmp_path / "s.toml"
    scene.write_text(workbench.load_scene(small).to_toml())
    argv = ["campaign", str(scene), "-o", str(store), "--workers", "1", "-q"]
    assert main([*argv, "--max-points", "2"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "limit of 2 points per campaign" in err[0], err
    assert "--max-points 3" in err[0] and not store.exists()
    assert main([*argv, "--max-points", "3"]) == 0
    assert workbench.open_run(store).sizes["gamma"] == 3


def test_an_interrupt_names_the_kept_blocks_only_when_there_are(tmp_path, capsys, monkeypatch):
    """Issue 37: SIGTERM during the planning of a huge grid said that blocks were kept in a
    folder that did not exist. The line names the folder only when it holds finished blocks."""
    import workbench.campaign as campaign

    scene = tmp_path / "s.toml"
    scene.write_text(SCENE_TOML)
    store = tmp_path / "c.nc"
    argv = ["campaign", str(scene), "-o", str(store), "--workers", "1", "-q"]

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    with monkeypatch.context() as m:  # before any block: nothing is kept
        m.setattr(campaign, "run_campaign", interrupted)
        assert main(argv) == 130
    assert capsys.readouterr().err.strip().splitlines() == ["workbench campaign: interrupted"]
    assert main(argv) == 0  # 3 blocks
    store.unlink()  # as if it had been stopped before the assembly
    capsys.readouterr()
    with monkeypatch.context() as m:
        m.setattr(campaign, "run_campaign", interrupted)
        assert main(argv) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"workbench campaign: interrupted; the finished blocks are kept in "
        f"'{store}.blocks/': run the same command again to compute the rest"
    ]
    assert store_paths(store)["blocks"].is_dir()


def test_a_large_grid_says_what_it_plans_before_planning(tmp_path, capsys, monkeypatch):
    """With progress on, a grid of a million points or more (here the threshold lowered to 3)
    says what is being planned before the planning starts, and then shows its progress."""
    import workbench.campaign._run as run_module

    monkeypatch.setattr(run_module, "_PLAN_NOTICE", 3)
    spec = {**BASE, "sweep": {"gamma": [0.3, 0.4, 0.5]}}
    workbench.run_campaign(spec, tmp_path / "c.nc", workers=1, progress=True)
    err = capsys.readouterr().err
    assert err.startswith("campaign: planning 3 points (gamma 3)\n"), err
    smaller = {**spec, "sweep": {"gamma": [0.3, 0.4]}}
    workbench.run_campaign(smaller, tmp_path / "d.nc", workers=1, progress=True)
    err = capsys.readouterr().err
    assert "campaign" in err and "planning" not in err  # the progress alone
