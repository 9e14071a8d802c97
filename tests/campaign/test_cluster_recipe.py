"""The cluster guide's recipe (docs/cluster.md), run as written: dask-jobqueue builds the SLURM
job script, and the script itself (run by bash, no batch system) starts the workers that compute
a campaign."""

import contextlib
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import dask
import distributed
import pytest

import workbench
from workbench._cache import cache_root
from workbench.campaign import jobqueue_cluster, store_paths

try:  # dask-jobqueue's import replaces the process's SIGINT handler: imported as workbench does
    from workbench.campaign._jobqueue import _import_dask_jobqueue

    _import_dask_jobqueue()
except ImportError:
    pytest.skip("the 'cluster' extra (dask-jobqueue) is not installed", allow_module_level=True)

GUIDE = Path(__file__).resolve().parents[2] / "docs" / "cluster.md"
SCENE = """\
[model]
name = "duffing"

[parameters]
delta = 0.3
alpha = -1.0
beta = 1.0

[run]
cycles = 20
transient_cycles = 10

[record]
samples_per_period = 1

[sweep]
gamma = [0.2, 0.3, 0.4, 0.5]
"""


def recipe() -> tuple[str, str]:
    """The guide's two python blocks of the SLURM recipe."""
    blocks = re.findall(r"```python\n(.*?)```", GUIDE.read_text(), re.S)
    first = next(b for b in blocks if b.startswith("# cluster_campaign.py"))
    second = next(b for b in blocks if b.startswith("# ... then the campaign"))
    return first, second


def _set(code: str, name: str, value: str) -> str:
    """Replace the assignment line ``name = ...`` of a block (it must exist)."""
    code, n = re.subn(rf"^{re.escape(name)} = .*$", f"{name} = {value}", code, flags=re.M)
    assert n == 1, f"{name} is not assigned once in the recipe"
    return code


def test_jobqueue_cluster_job_script(tmp_path):
    cache = tmp_path / "cache"
    cluster = jobqueue_cluster(
        "slurm",
        cores=8,
        memory="16GB",
        cache_dir=cache,
        interface="lo",
        queue="compute",
        walltime="01:00:00",
    )
    try:
        script = cluster.job_script()
    finally:
        cluster.close()
    assert "#SBATCH --cpus-per-task=8" in script and "#SBATCH -p compute" in script
    assert f"export WORKBENCH_CACHE_DIR={cache}" in script
    for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        assert f"export {v}=1" in script
    assert "export DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED=False" in script
    assert "export DASK_DISTRIBUTED__ADMIN__TICK__INTERVAL=1s" in script
    command = script.strip().splitlines()[-1]
    assert command.startswith(f"{sys.executable} -m distributed.cli.dask_worker tls://")
    assert "--nthreads 1" in command and "--nworkers 8" in command
    assert "--preload workbench.campaign._cluster" in command
    threaded = jobqueue_cluster(
        "pbs", cores=8, memory="16GB", cache_dir=cache, interface="lo", threads_per_worker=4
    )
    try:
        command = threaded.job_script().strip().splitlines()[-1]
        assert "#PBS" in threaded.job_script()
    finally:
        threaded.close()
    assert "--nthreads 4" in command and "--nworkers 2" in command


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"system": "torque"}, r"system='torque'; allowed: slurm, pbs"),
        ({"cache_dir": "cache"}, r"cache_dir='cache' must be an absolute path"),
        ({"threads_per_worker": 3}, r"threads_per_worker=3 must divide cores=8"),
        ({"cores": 0}, r"cores must be a positive integer, got 0"),
    ],
)
def test_jobqueue_cluster_refuses_bad_input(kwargs, match):
    args = {"system": "slurm", "cores": 8, "memory": "1GB", "cache_dir": "/shared/cache"}
    args["interface"] = "lo"
    with pytest.raises(ValueError, match=match):
        jobqueue_cluster(**{**args, **kwargs})


@pytest.mark.slow
def test_the_guides_recipe_runs_a_campaign_on_the_job_scripts_workers(tmp_path, monkeypatch):
    first, second = recipe()
    scene = tmp_path / "sweep.toml"
    scene.write_text(SCENE)
    store = tmp_path / "sweep.nc"
    first = _set(first, "SCENE", repr(str(scene)))
    first = _set(first, "STORE", repr(str(store)))
    first = _set(first, "CORES, JOBS", "2, 1")
    first = _set(first, "INTERFACE", repr("lo"))  # the job runs on this host
    # the cache this test session has warmed, as the guide's shell would export it
    monkeypatch.setenv("WORKBENCH_CACHE_DIR", str(cache_root()))
    namespace: dict = {}
    exec(compile(first, "docs/cluster.md (recipe, block 1)", "exec"), namespace)
    cluster = namespace["cluster"]
    try:
        script = cluster.job_script()
        assert f"export WORKBENCH_CACHE_DIR={cache_root()}" in script
        assert "--nworkers 2" in script and "--nthreads 1" in script
        # closed: the job's workers reach the scheduler on the named interface, with TLS
        assert cluster.scheduler_address.startswith("tls://127.0.0.1:")
        assert "--interface lo --protocol tls://" in script and "--tls-key " in script
        # what sbatch would run: the job script itself, here by bash
        job = subprocess.Popen(
            ["bash", "-c", script],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        try:
            second = second.replace("cluster.scale(jobs=JOBS)", "pass  # the test ran the job")
            assert "pass  # the test ran the job" in second
            second = second.replace("cluster.close()", "pass")
            exec(compile(second, "docs/cluster.md (recipe, block 2)", "exec"), namespace)
            ds = namespace["ds"]
            assert ds.sizes["gamma"] == 4 and int(ds.status.sum()) == 0
            workers = _worker_environments(job.pid)
            assert len(workers) == 2, workers
            for env in workers.values():
                assert env.get("WORKBENCH_CACHE_DIR") == str(cache_root())
                assert env.get("OMP_NUM_THREADS") == "1"
                assert env.get("DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED") == "False"
            with distributed.Client(cluster) as client:
                profiling = client.run(dask.config.get, "distributed.worker.profile.enabled")
            assert profiling and not any(profiling.values())  # the setting reached the workers
            computed_by = set()
            for path in store_paths(store)["blocks"].glob("block-*.nc"):
                computed_by.add(int(workbench.open_run(path).attrs["worker_pid"]))
            assert computed_by and computed_by <= set(workers)
        finally:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(job.pid, signal.SIGTERM)
            try:
                job.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(job.pid, signal.SIGKILL)
                job.wait()
    finally:
        cluster.close()


def _worker_environments(root: int, timeout: float = 30.0) -> dict[int, dict[str, str]]:
    """The environments of the dask worker processes under process ``root`` (Linux /proc)."""
    import psutil

    deadline = time.monotonic() + timeout
    while True:
        found = {}
        for p in psutil.Process(root).children(recursive=True):
            with contextlib.suppress(psutil.Error):
                # the job's python runs the nannies, which spawn the workers
                if any("spawn_main" in part for part in p.cmdline()):
                    found[p.pid] = p.environ()
        if len(found) >= 2 or time.monotonic() > deadline:
            return found
        time.sleep(0.2)


RESULTS = Path(__file__).resolve().parents[2] / "benchmarks" / "results"


def guide_numbers() -> dict[str, str]:
    """The numbers docs/cluster.md quotes, as benchmarks/campaign_cluster.py measured them
    (benchmarks/results/campaign_cluster-*.json), formatted as the guide writes them."""
    import json

    def load(name):
        return json.loads((RESULTS / f"campaign_cluster-{name}.json").read_text())

    idle = load("idle")["median"]
    main = load("pool-cluster-lean")["summary"]
    threads = load("lean-threads")["summary"]
    eff = load("efficiency-2")
    ratio = {
        (label, what, mode): main[label][what][mode] / main[label][what]["pool"]
        for label in ("cold", "warm")
        for what in ("wall", "cpu")
        for mode in ("cluster", "lean")
    }
    growth = eff["many"]["solver_wall"] / eff["one"]["solver_wall"]
    warm = threads["warm"]["wall"]
    many = eff["many"]
    share = {
        "start": many["lead"],
        "per point": many["point_wall"] - many["solver_wall"],
        "tail": many["tail"],
    }
    busy = eff["args"]["workers"] * many["wall"]
    return {
        **{f"share {k}": f"{k} {v / busy:.1%}".replace("%", " %") for k, v in share.items()},
        "threads cpu": f"{threads['warm']['cpu']['threads'] / threads['warm']['cpu']['lean']:.2f}x",
        "idle default": f"{idle['default']:.3f}",
        "idle lean": f"{idle['lean']:.3f}",
        "lean warm wall": f"{ratio['warm', 'wall', 'lean']:.2f}x",
        "lean warm cpu": f"{ratio['warm', 'cpu', 'lean']:.2f}x",
        "lean cold wall": f"{ratio['cold', 'wall', 'lean']:.2f}x",
        "lean cold cpu": f"{ratio['cold', 'cpu', 'lean']:.2f}x",
        "default warm wall": f"{ratio['warm', 'wall', 'cluster']:.2f}x",
        "default warm cpu": f"{ratio['warm', 'cpu', 'cluster']:.2f}x",
        "default cold wall": f"{ratio['cold', 'wall', 'cluster']:.2f}x",
        "default cold cpu": f"{ratio['cold', 'cpu', 'cluster']:.2f}x",
        "threads wall": f"{warm['threads'] / warm['lean']:.2f}x",
        "threads overlap": f"{threads['overlap']['threads']:.2f}",
        "processes overlap": f"{threads['overlap']['lean']:.2f}",
        "speed-up": f"{eff['speedup']:.2f}",
        "growth": f"{growth:.2f}x",
        "simulated dealt": f"{eff['simulated']['16']['dealt']:.1%}".replace("%", " %"),
        "simulated contiguous": f"{eff['simulated']['16']['contiguous']:.1%}".replace("%", " %"),
    }


def test_the_guides_numbers_are_the_benchmarks():
    text = " ".join(GUIDE.read_text().split())
    missing = {k: v for k, v in guide_numbers().items() if v not in text}
    assert not missing, f"docs/cluster.md does not quote these measured numbers: {missing}"


def test_the_guides_lazy_analysis_runs_on_a_small_fig32_archive(tmp_path, monkeypatch):
    """The guide's lazy analysis block, as written, on a 3-point, 120-cycle version of the
    Fig. 32 sweep (studies/bifurcation_speed/sweep.toml) stored as fig32.nc: K over omega,
    computed only when asked."""
    block = re.search(
        r"<!-- run: lazy-analysis -->\n```python\n(.*?)```", GUIDE.read_text(), re.S
    ).group(1)
    root = Path(__file__).resolve().parents[2]
    scene = workbench.load_scene(root / "studies" / "bifurcation_speed" / "sweep.toml")
    small = scene.replace(
        run={"cycles": 120, "transient_cycles": 2},
        sweep={
            "omega": [3.0 * 3.141592653589793, 3.5 * 3.141592653589793, 4.0 * 3.141592653589793]
        },
    )
    workbench.run_campaign(small, tmp_path / "fig32.nc", workers=1)
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(block, "docs/cluster.md (lazy analysis)", "exec"), namespace)
    K = namespace["K"]
    assert K.K.chunks is not None  # lazy until computed
    k = K.K.compute()
    assert k.dims == ("omega",) and k.sizes["omega"] == 3
    assert k.attrs["units"] == "1" and bool(((k > -0.5) & (k < 1.5)).all())


def test_importing_dask_jobqueue_keeps_ctrl_c():
    """dask-jobqueue 0.9's SLURM module sets SIGINT to sys.exit in the importing process: after
    the import workbench does, Ctrl-C still raises KeyboardInterrupt (it raised SystemExit in
    every later test of the suite)."""
    import importlib
    import signal

    from workbench.campaign._jobqueue import _import_dask_jobqueue

    before = signal.getsignal(signal.SIGINT)
    for name in [m for m in sys.modules if m.startswith("dask_jobqueue")]:
        del sys.modules[name]  # imported afresh, as in a new session
    _import_dask_jobqueue()
    assert signal.getsignal(signal.SIGINT) is before
    assert importlib.import_module("dask_jobqueue.runner")  # the module that sets it, loaded
