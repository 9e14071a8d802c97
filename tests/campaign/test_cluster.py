"""Campaigns on a dask cluster (workbench's own: ``local_cluster``, closed by TLS): workers ready
before their first block (the worker plugin), and one worker's threads integrating points at once
(the kernels release the GIL)."""

import sys

import numpy as np
import pytest
from _scenes import DUFFING_SWEEP as SCENE

import workbench
from workbench.campaign import local_cluster, store_paths
from workbench.campaign._cluster import plugin_name, ready_workers

distributed = pytest.importorskip("distributed")


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
    """Two long points, one block each, on one worker of two threads: both threads hold a block
    at once (their spans overlap), and what lets their integrations run side by side holds:
    the compiled loop's entry points, which run the whole integration, release the GIL
    (``nogil``). A count and a property, not a speed-up: how much two threads gain is a
    benchmark's figure (benchmarks/campaign_cluster.py), which depends on the machine."""
    from workbench.models import get_model
    from workbench.solver._compile import kernel_for

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
    spans, threads = [], set()
    for path in store_paths(store)["blocks"].glob("block-*.nc"):
        b = workbench.open_run(path)
        start = float(b.attrs["block_started"])
        spans.append((start, start + float(b.attrs["block_wall_time"])))
        threads.add((int(b.attrs["worker_pid"]), int(b.attrs["worker_thread"])))
    assert len(threads) == 2  # one process, two threads
    (s1, e1), (s2, e2) = sorted(spans)
    assert s2 < e1  # both blocks were running at once
    np.testing.assert_array_less(0.0, ds.solver_wall_time.values)
    model = get_model("duffing")
    hooks = model.problem(model.default_parameters(), {}, {}, ("x", "v")).hooks
    kernel = kernel_for(hooks)
    for entry in ("start", "initial_step", "advance"):
        assert getattr(kernel, entry).targetoptions.get("nogil") is True, entry
