"""Campaign workers on a batch system (SLURM, PBS, ...): a dask-jobqueue cluster whose jobs run
workbench's workers as they should run.

Each job runs ``cores // threads_per_worker`` worker processes of ``threads_per_worker`` threads
(one thread per process by default; several once the kernels release the GIL, which they do:
one process then holds the kernel once for all its threads), with

* ``WORKBENCH_CACHE_DIR`` set to a directory on shared storage, so that every worker loads the
  compiled kernel that :func:`workbench.campaign.warm_kernel` put there instead of compiling it
  (30-90 s per model and worker otherwise);
* numpy's BLAS and OpenMP pools at one thread (``OMP_NUM_THREADS=1`` and the like), so that the
  analysis a worker may run does not start a thread per core beside the other workers;
* dask's idle timers slowed (:data:`DASK_CONFIG`, exported as ``DASK_...`` variables);
* workbench imported by every worker as it starts (``--preload``), while the client waits for
  the workers, instead of at the campaign's first block.

Nothing is submitted until ``cluster.scale(jobs=...)``. Needs the ``cluster`` extra
(``pip install 'clearance-workbench[cluster]'``: dask-jobqueue). See docs/cluster.md.
"""

from __future__ import annotations

import os
import shlex
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = ["DASK_CONFIG", "SYSTEMS", "jobqueue_cluster"]

#: dask settings for a cluster that runs campaigns. dask's processes run timers whether or not
#: there is work: the statistical profiler of every worker (every 10 ms), the event loop's
#: tick (20 ms), the memory monitor of every worker and nanny (0.1 s) and the system monitor
#: (0.5 s); on a machine whose cores the workers fill, their CPU comes out of the campaign's.
#: Set them where the cluster starts: ``with dask.config.set(DASK_CONFIG): LocalCluster(...)``,
#: or let :func:`workbench.campaign.jobqueue_cluster` export them to its jobs. What an idle
#: cluster costs with and without them: ``python benchmarks/campaign_cluster.py --idle``
#: (results in benchmarks/results/campaign_cluster-idle.json).
DASK_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.worker.memory.monitor-interval": "1s",
}


# batch system -> dask_jobqueue class
SYSTEMS = {
    "slurm": "SLURMCluster",
    "pbs": "PBSCluster",
    "sge": "SGECluster",
    "lsf": "LSFCluster",
    "htcondor": "HTCondorCluster",
    "oar": "OARCluster",
    "moab": "MoabCluster",
}
SINGLE_THREADED = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
PRELOAD = "workbench.campaign._cluster"  # imported by each worker as it starts


def jobqueue_cluster(
    system: str = "slurm",
    *,
    cores: int,
    memory: str,
    cache_dir: str | os.PathLike,
    threads_per_worker: int = 1,
    dask_config: Mapping[str, Any] = DASK_CONFIG,
    **options: Any,
):
    """A dask-jobqueue cluster whose jobs run campaign workers (see the module docstring).

    Parameters
    ----------
    system : str
        The batch system: one of :data:`SYSTEMS` (``"slurm"``, ``"pbs"``, ...).
    cores : int
        Cores per job (e.g. the cores of one node).
    memory : str
        Memory per job, e.g. ``"32GB"`` (shared by its workers).
    cache_dir : str or PathLike
        Absolute path, on storage every node mounts, of workbench's cache (compiled kernels);
        exported as ``WORKBENCH_CACHE_DIR`` in every job.
    threads_per_worker : int
        Threads per worker process; must divide ``cores``. 1 (default): one process per core.
    dask_config : mapping
        dask settings of the workers (exported to the jobs as ``DASK_...`` variables) and of
        the scheduler (in this process); default :data:`DASK_CONFIG` (dask's idle timers
        slowed); ``{}`` keeps dask's own.
    **options
        Passed to the dask_jobqueue class (``queue``, ``account``, ``walltime``,
        ``job_script_prologue`` (run after workbench's exports), ``job_extra_directives``, ...).

    Returns
    -------
    dask_jobqueue.JobQueueCluster
        Its ``job_script()`` shows what a job runs. ``cluster.scale(jobs=n)`` submits jobs.

    Raises
    ------
    ValueError
        Unknown ``system``, a relative ``cache_dir``, or ``threads_per_worker`` that does not
        divide ``cores``.
    ImportError
        dask-jobqueue is not installed (the ``cluster`` extra).
    """
    if system not in SYSTEMS:
        raise ValueError(f"system={system!r}; allowed: {', '.join(SYSTEMS)}")
    for name, value in (("cores", cores), ("threads_per_worker", threads_per_worker)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{name} must be a positive integer, got {value!r}")
    if cores % threads_per_worker:
        raise ValueError(
            f"threads_per_worker={threads_per_worker!r} must divide cores={cores!r} (each job "
            "runs cores / threads_per_worker worker processes)"
        )
    cache = Path(cache_dir).expanduser()
    if not cache.is_absolute():
        raise ValueError(
            f"cache_dir={str(cache_dir)!r} must be an absolute path on storage that every node "
            "mounts (the workers' WORKBENCH_CACHE_DIR)"
        )
    dask_jobqueue = _import_dask_jobqueue()
    import dask

    prologue = [f"export WORKBENCH_CACHE_DIR={shlex.quote(str(cache))}"]
    prologue += [f"export {v}=1" for v in SINGLE_THREADED]
    prologue += [f"export {_env_name(k)}={shlex.quote(str(v))}" for k, v in dask_config.items()]
    prologue += list(options.pop("job_script_prologue", None) or [])
    options.setdefault("python", sys.executable)  # the same environment on the nodes
    # each worker imports workbench as it starts, before a campaign needs it (dask's --preload)
    extra = list(options.pop("worker_extra_args", None) or [])
    options["worker_extra_args"] = ["--preload", PRELOAD, *extra]
    cls = getattr(dask_jobqueue, SYSTEMS[system])
    with dask.config.set(dict(dask_config)):  # the scheduler starts here, in this process
        return cls(
            cores=cores,
            processes=cores // threads_per_worker,
            memory=memory,
            job_script_prologue=prologue,
            **options,
        )


def _import_dask_jobqueue():
    """Import dask-jobqueue, keeping this process's Ctrl-C: its SLURM module imports
    ``dask_jobqueue.runner``, which replaces the SIGINT handler of whatever process imports it
    with ``sys.exit`` (dask-jobqueue 0.9), so that a KeyboardInterrupt became a SystemExit in
    every later computation of the session."""
    import signal
    import threading

    main = threading.current_thread() is threading.main_thread()
    previous = signal.getsignal(signal.SIGINT) if main else None
    try:
        import dask_jobqueue
    except ImportError as exc:
        raise ImportError(
            "jobqueue_cluster needs dask-jobqueue: pip install 'clearance-workbench[cluster]' (or "
            "dask-jobqueue)"
        ) from exc
    finally:
        if main and previous is not None:
            signal.signal(signal.SIGINT, previous)
    return dask_jobqueue


def _env_name(key: str) -> str:
    """The environment variable of a dask setting (``distributed.admin.tick.interval`` ->
    ``DASK_DISTRIBUTED__ADMIN__TICK__INTERVAL``), as dask reads them at import."""
    return "DASK_" + key.upper().replace(".", "__").replace("-", "_")
