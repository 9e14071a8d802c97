"""Campaigns on a dask cluster (workbench's own: ``local_cluster``, closed by TLS): workers ready
before their first block (the worker plugin), and one worker's threads integrating points at once
(the kernels release the GIL)."""

import sys

import numpy as np
import pytest

import workbench
from workbench.campaign import local_cluster, store_paths
from workbench.campaign._cluster import plugin_name, ready_workers

distributed = pytest.importorskip("distributed")

SCENE = {
    "model": {"name": "duffing"},
    "parameters": {"delta": 0.3, "alpha": -1.0, "beta": 1.0, "omega": 1.2},
    "run": {"cycles": 5, "transient_cycles": 5},
    "record": {"samples_per_period": 1},
    "sweep": {"gamma": [0.3, 0.4]},
}


def _kernels_loaded() -> list[str]:
    """The generated kernel modules imported in this (worker) process."""
    return sorted(m for m in sys.modules if m.startswith("workbench_kernels.kernel_"))


@pytest.mark.slow
def test_workers_load_the_kernel_before_their_first_block():
    scene = workbench.load_scene(SCENE)
    first = scene.with_parameters(gamma=0.3).to_toml()
    workbench.simulate(workbench.scene_from_toml(first))  # the kernel cached: workers load it
    with (
        local_cluster(1, dashboard=None) as cluster,
        distributed.Client(cluster) as client,
    ):
        assert all(v == [] for v in client.run(_kernels_loaded).values())  # a fresh worker
        name = ready_workers(client, first)
        assert name == plugin_name(first) and "duffing" in name
        loaded = client.run(_kernels_loaded)
        assert all(any("duffing" in m for m in v) for v in loaded.values()), loaded
        cluster.scale(2)  # a worker that joins later gets it too
        client.wait_for_workers(2)
        loaded = client.run(_kernels_loaded)
        assert len(loaded) == 2 and all(any("duffing" in m for m in v) for v in loaded.values())
        assert ready_workers(client, first) == name  # registered again: nothing new


@pytest.mark.slow
def test_one_worker_with_two_threads_integrates_two_points_at_once(tmp_path):
    """Two long points, one block each, on one worker of two threads: with kernels that hold
    the GIL the integrations take turns (their summed solver time is at most the task phase);
    released, they overlap (the sum approaches twice the phase)."""
    spec = {**SCENE, "run": {"cycles": 50, "transient_cycles": 30000}}
    scene = workbench.load_scene(spec)
    workbench.simulate(scene.with_parameters(gamma=0.3).replace(run={"cycles": 1}))
    store = tmp_path / "threads.nc"
    with (
        local_cluster(1, threads_per_worker=2, dashboard=None) as cluster,
        distributed.Client(cluster) as client,
    ):
        ds = workbench.run_campaign(scene, store, client=client, chunk=1)
    assert int(ds.status.sum()) == 0
    spans, solver, threads = [], 0.0, set()
    for path in store_paths(store)["blocks"].glob("block-*.nc"):
        b = workbench.open_run(path)
        start = float(b.attrs["block_started"])
        spans.append((start, start + float(b.attrs["block_wall_time"])))
        solver += float(b.solver_wall_time.sum())
        threads.add((int(b.attrs["worker_pid"]), int(b.attrs["worker_thread"])))
    assert len(threads) == 2  # one process, two threads
    phase = max(e for _, e in spans) - min(s for s, _ in spans)
    assert solver / phase > 1.5, (solver, phase)
    np.testing.assert_array_less(0.0, ds.solver_wall_time.values)
