"""The dask clusters workbench starts for campaigns: on this machine (:func:`local_cluster`) or
on a batch system (SLURM, PBS, ...: :func:`jobqueue_cluster`), closed to everyone but their user.

Closed (docs/security.md, "The cluster"):

* **TLS with credentials made for the cluster.** Scheduler, workers and client speak TLS and
  each presents a certificate the others check (mutual TLS): the certificates named in the
  user's dask config (``distributed.comm.tls.*``) when it names any, else a key and
  self-signed certificate made for this cluster (``distributed.Security.temporary()``), held
  in memory. A client without them is refused at the handshake. The jobs of a batch cluster
  read the temporary credentials from files of mode 0600 that dask-jobqueue writes into a
  directory of mode 0700 on shared storage (by default ``<cache_dir>/cluster-credentials``)
  and deletes with the cluster object; the job script holds their paths, not the key.
* **Addresses that are named.** A local cluster listens on the loopback interface only
  (127.0.0.1); a batch cluster on the network interface the user names (``interface=``, or
  dask-jobqueue's config), and refuses to start without one rather than listen on every
  interface (0.0.0.0). The workers' own HTTP servers listen on their loopback.
* **The dashboard on this host's loopback** (``localhost:8787``, reached from elsewhere
  through an SSH tunnel), or off (``dashboard=None``); on another interface only when its
  address is written out.

A batch cluster's jobs run ``cores // threads_per_worker`` worker processes of
``threads_per_worker`` threads (one thread per process by default; several once the kernels
release the GIL, which they do: one process then holds the kernel once for all its threads),
with

* ``WORKBENCH_CACHE_DIR`` set to a directory on shared storage, so that every worker loads the
  compiled kernel that :func:`workbench.campaign.warm_kernel` put there instead of compiling it
  (tens of seconds of CPU per model and worker otherwise: docs/cluster.md);
* numpy's BLAS and OpenMP pools at one thread (``OMP_NUM_THREADS=1`` and the like), so that the
  analysis a worker may run does not start a thread per core beside the other workers;
* dask's idle timers slowed (:data:`DASK_CONFIG`, exported as ``DASK_...`` variables);
* workbench imported by every worker as it starts (``--preload``), while the client waits for
  the workers, instead of at the campaign's first block.

Nothing is submitted until ``cluster.scale(jobs=...)``. Needs the ``cluster`` extra
(``pip install 'clearance-workbench[cluster]'``: dask-jobqueue, and cryptography for the
temporary credentials). See docs/cluster.md.
"""

from __future__ import annotations

import os
import shlex
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from workbench._checks import positive_int

__all__ = ["DASK_CONFIG", "SYSTEMS", "cluster_security", "jobqueue_cluster", "local_cluster"]

#: dask settings for a cluster that runs campaigns. dask's processes run timers whether or not
#: there is work: the statistical profiler of every worker (every 10 ms), the event loop's
#: tick (20 ms), the memory monitor of every worker and nanny (0.1 s) and the system monitor
#: (0.5 s); on a machine whose cores the workers fill, their CPU comes out of the campaign's.
#: :func:`workbench.campaign.local_cluster` sets them where its cluster starts, and
#: :func:`workbench.campaign.jobqueue_cluster` exports them to its jobs too. What an idle
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
DASHBOARD = "localhost:8787"  # the scheduler's dashboard: this host's loopback
CREDENTIALS = "cluster-credentials"  # beside the kernels in cache_dir: the jobs' TLS files
# a worker's own HTTP server (metrics, health): on its loopback, without dashboard pages
WORKER_HTTP = ["--no-dashboard", "--dashboard-address", "127.0.0.1:0"]
ROLES = ("scheduler", "worker", "client")


def cluster_security(security=None):
    """The TLS credentials of a new cluster, for its scheduler, workers and client.

    Parameters
    ----------
    security : distributed.Security, optional
        Credentials to use; they must name a CA (``tls_ca_file``) and a certificate for each
        role (``tls_scheduler_cert``, ``tls_worker_cert``, ``tls_client_cert``; a key in the
        certificate's file, or in ``tls_<role>_key``). Default: the certificates of the dask
        config (``distributed.comm.tls.ca-file``, ``distributed.comm.tls.<role>.cert`` and
        ``.key``) when it names any, else a key and self-signed certificate made now for
        this cluster alone (``distributed.Security.temporary()``, in memory).

    Returns
    -------
    distributed.Security
        A copy, with encryption required (no plain-TCP connection is made or accepted).

    Raises
    ------
    ValueError
        ``security`` or the dask config lacks the CA or a role's certificate.
    ImportError
        Temporary credentials need ``cryptography`` (the ``cluster`` extra).
    """
    import copy

    import dask
    from distributed import Security

    if security is None:
        named = [dask.config.get("distributed.comm.tls.ca-file", None)]
        named += [dask.config.get(f"distributed.comm.tls.{r}.cert", None) for r in ROLES]
        if not any(named):
            try:
                return Security.temporary()
            except ImportError as exc:
                raise ImportError(
                    "a cluster's TLS credentials are made with cryptography: pip install "
                    "'clearance-workbench[cluster]' (or cryptography), or name certificates in "
                    "the dask config (distributed.comm.tls.*)"
                ) from exc
        security, where = Security(), "the dask config"
        keys = {"ca_file": "ca-file", **{r: f"{r}.cert" for r in ROLES}}
        keys = {k: f"distributed.comm.tls.{v}" for k, v in keys.items()}
    elif not isinstance(security, Security):
        raise ValueError(
            f"security={security!r} must be a distributed.Security with TLS certificates, or "
            "None (the dask config's certificates, else credentials made for the cluster)"
        )
    else:
        where = "security="
        keys = {"ca_file": "tls_ca_file", **{r: f"tls_{r}_cert" for r in ROLES}}
    missing = [keys["ca_file"]] if not security.tls_ca_file else []
    missing += [keys[r] for r in ROLES if not getattr(security, f"tls_{r}_cert")]
    if missing:
        raise ValueError(
            f"{where} lacks {', '.join(missing)}: a cluster's scheduler, workers and client "
            "each present a certificate signed by the CA that the others check; name them "
            "all, or none for credentials made for the cluster"
        )
    security = copy.copy(security)
    security.require_encryption = True
    for role in ROLES:  # a key inside the certificate's file: named as such for dask-worker
        if not getattr(security, f"tls_{role}_key"):
            setattr(security, f"tls_{role}_key", getattr(security, f"tls_{role}_cert"))
    return security


def dashboard_options(dashboard: str | None) -> dict[str, Any]:
    """The scheduler's dashboard options: ``None`` none (its HTTP server, for metrics, on the
    loopback); an address without a host (``":8787"``, which dask serves on every interface)
    on this host's loopback; an address with a host as written."""
    from distributed.utils import clean_dashboard_address

    if dashboard is None:
        return {"dashboard": False, "dashboard_address": "127.0.0.1:0"}
    if not isinstance(dashboard, str) or not dashboard.strip():
        raise ValueError(
            f"dashboard={dashboard!r} must be an address such as 'localhost:8787' (this host "
            "only), or None for no dashboard"
        )
    try:
        parts = clean_dashboard_address(dashboard)
    except ValueError:
        parts = []
    if not parts:
        raise ValueError(
            f"dashboard={dashboard!r} is not an address; give e.g. 'localhost:8787' (this host "
            "only), or None for no dashboard"
        )
    address = ",".join(f"{p['address'] or 'localhost'}:{p['port']}" for p in parts)
    return {"dashboard": True, "dashboard_address": address}


def _check_protocol(options: Mapping[str, Any]) -> None:
    protocol = options.get("protocol")
    if protocol is not None and str(protocol).rstrip(":/") != "tls":
        raise ValueError(
            f"protocol={protocol!r}: a workbench cluster speaks TLS only (tls://); leave "
            "protocol out"
        )


def local_cluster(
    workers: int | None = None,
    *,
    threads_per_worker: int = 1,
    dashboard: str | None = DASHBOARD,
    security=None,
    dask_config: Mapping[str, Any] = DASK_CONFIG,
    **options: Any,
):
    """A ``distributed.LocalCluster`` for campaigns, closed (see the module docstring).

    Its scheduler and workers listen on 127.0.0.1 only and speak TLS with credentials made for
    it (or the dask config's, see :func:`cluster_security`); ``Client(cluster)`` gets them
    from the cluster, a client without them is refused. Its workers import workbench as they
    start (``preload``) and run with :data:`DASK_CONFIG`. The local pool of
    :func:`workbench.run_campaign` (no ``client``) needs no cluster and listens on no network
    at all; this is for a campaign that wants dask's scheduler on one machine.

    Parameters
    ----------
    workers : int, optional
        Worker processes; default dask's (one per core, threads shared out).
    threads_per_worker : int
        Threads per worker process.
    dashboard : str or None
        Address of the scheduler's dashboard; default ``"localhost:8787"`` (this host only; a
        free port if taken). An address without a host (``":8787"``) is on the loopback too;
        another interface only when written out (``"0.0.0.0:8787"``: every interface, open to
        anyone who reaches it). ``None``: no dashboard.
    security : distributed.Security, optional
        TLS credentials (see :func:`cluster_security`).
    dask_config : mapping
        dask settings of the cluster; default :data:`DASK_CONFIG`; ``{}`` keeps dask's own.
    **options
        Passed to ``distributed.LocalCluster`` (``memory_limit``, ...; ``host`` moves the
        scheduler off the loopback).

    Returns
    -------
    distributed.LocalCluster

    Raises
    ------
    ValueError
        A ``dashboard`` that is not an address, a non-TLS ``protocol``, or ``security``
        without certificates.
    """
    import dask
    from distributed import LocalCluster

    _check_protocol(options)
    preload = [PRELOAD, *(options.pop("preload", None) or [])]
    options.setdefault("host", "127.0.0.1")
    scheduler = {**dashboard_options(dashboard), **(options.pop("scheduler_kwargs", None) or {})}
    with dask.config.set(dict(dask_config)):
        return LocalCluster(
            n_workers=workers,
            threads_per_worker=threads_per_worker,
            processes=True,
            protocol="tls://",
            security=cluster_security(security),
            scheduler_kwargs=scheduler,
            preload=preload,
            **options,
        )


def jobqueue_cluster(
    system: str = "slurm",
    *,
    cores: int,
    memory: str,
    cache_dir: str | os.PathLike,
    interface: str | None = None,
    threads_per_worker: int = 1,
    dashboard: str | None = DASHBOARD,
    security=None,
    dask_config: Mapping[str, Any] = DASK_CONFIG,
    **options: Any,
):
    """A dask-jobqueue cluster whose jobs run campaign workers, closed (see the module
    docstring).

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
        exported as ``WORKBENCH_CACHE_DIR`` in every job. The jobs' TLS credentials go to
        its ``cluster-credentials`` folder (see ``shared_temp_directory`` below).
    interface : str
        The network interface of the scheduler and the workers (``"ib0"``, ``"eth0"``: the
        one by which the compute nodes reach this host); default dask-jobqueue's config
        (``jobqueue.<system>.interface``). Required: the cluster does not listen on every
        interface. ``scheduler_options={"interface": ...}`` gives the scheduler another one.
    threads_per_worker : int
        Threads per worker process; must divide ``cores``. 1 (default): one process per core.
    dashboard : str or None
        Address of the scheduler's dashboard, as for :func:`local_cluster`: default
        ``"localhost:8787"``, this host only (reach it with ``ssh -L 8787:localhost:8787
        HOST``); ``None``: no dashboard.
    security : distributed.Security, optional
        TLS credentials (see :func:`cluster_security`); default the dask config's
        certificates, else credentials made for this cluster, which dask-jobqueue writes for
        the jobs into files of mode 0600 in ``shared_temp_directory`` (an option below).
    dask_config : mapping
        dask settings of the workers (exported to the jobs as ``DASK_...`` variables) and of
        the scheduler (in this process); default :data:`DASK_CONFIG` (dask's idle timers
        slowed); ``{}`` keeps dask's own.
    **options
        Passed to the dask_jobqueue class (``queue``, ``account``, ``walltime``,
        ``job_script_prologue`` (run after workbench's exports), ``job_extra_directives``,
        ``scheduler_options``, ...). ``shared_temp_directory``: where the jobs read temporary
        credentials, on storage every node mounts; default ``<cache_dir>/cluster-credentials``
        (made with mode 0700; a folder that another user owns or others may write is refused).

    Returns
    -------
    dask_jobqueue.JobQueueCluster
        Its ``job_script()`` shows what a job runs. ``cluster.scale(jobs=n)`` submits jobs.

    Raises
    ------
    ValueError
        Unknown ``system``, a relative ``cache_dir``, ``threads_per_worker`` that does not
        divide ``cores``, no ``interface`` or one this host lacks, a dashboard on every
        interface by default (``scheduler_options={"dashboard_address": ":8787"}``), a
        non-TLS ``protocol``, ``security`` without certificates, or a credentials folder
        that others may write.
    ImportError
        dask-jobqueue is not installed (the ``cluster`` extra).
    """
    if system not in SYSTEMS:
        raise ValueError(f"system={system!r}; allowed: {', '.join(SYSTEMS)}")
    for name, value in (("cores", cores), ("threads_per_worker", threads_per_worker)):
        positive_int(name, value)
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
    _check_protocol(options)
    dask_jobqueue = _import_dask_jobqueue()
    import dask

    name = options.get("config_name") or system  # dask-jobqueue's config section
    interface = interface or dask.config.get(f"jobqueue.{name}.interface", None)
    scheduler = options.pop("scheduler_options", None)
    if scheduler is None:
        scheduler = dask.config.get(f"jobqueue.{name}.scheduler-options", None) or {}
    _check_interface(interface, scheduler)
    _check_dashboard(scheduler)
    options["scheduler_options"] = {**dashboard_options(dashboard), **scheduler}
    security = cluster_security(security)
    if any("\n" in str(v) for v in security.get_tls_config_for_role("worker").values()):
        # in memory: dask-jobqueue writes them to files that the jobs read
        options["shared_temp_directory"] = _credentials_folder(
            options.get("shared_temp_directory")
            or dask.config.get(f"jobqueue.{name}.shared-temp-directory", None)
            or cache / CREDENTIALS
        )
    prologue = [f"export WORKBENCH_CACHE_DIR={shlex.quote(str(cache))}"]
    prologue += [f"export {v}=1" for v in SINGLE_THREADED]
    prologue += [f"export {_env_name(k)}={shlex.quote(str(v))}" for k, v in dask_config.items()]
    prologue += list(options.pop("job_script_prologue", None) or [])
    options.setdefault("python", sys.executable)  # the same environment on the nodes
    # each worker imports workbench as it starts, before a campaign needs it (dask's --preload)
    extra = list(options.pop("worker_extra_args", None) or [])
    options["worker_extra_args"] = ["--preload", PRELOAD, *WORKER_HTTP, *extra]
    cls = getattr(dask_jobqueue, SYSTEMS[system])
    with dask.config.set(dict(dask_config)):  # the scheduler starts here, in this process
        return cls(
            cores=cores,
            processes=cores // threads_per_worker,
            memory=memory,
            job_script_prologue=prologue,
            interface=interface,
            security=security,
            **options,
        )


def _interfaces() -> str:
    """This host's network interfaces and their IPv4 addresses, for a message."""
    import socket

    import psutil

    found = []
    for nic, addresses in psutil.net_if_addrs().items():
        ips = [a.address for a in addresses if a.family == socket.AF_INET]
        found.append(f"{nic} {ips[0]}" if ips else nic)
    return ", ".join(found)


def _check_interface(interface: str | None, scheduler: Mapping[str, Any]) -> None:
    """One line unless the workers' interface is named, and the scheduler's exists here."""
    import psutil

    if not interface:
        raise ValueError(
            "jobqueue_cluster needs interface=, the network interface by which the compute "
            f"nodes reach this host (here: {_interfaces()}); the cluster does not listen on "
            "every interface"
        )
    own = scheduler.get("interface") or (None if scheduler.get("host") else interface)
    if own and own not in psutil.net_if_addrs():
        which = "scheduler_options interface" if scheduler.get("interface") else "interface"
        raise ValueError(
            f"{which}={own!r} is not a network interface of this host, where the scheduler "
            f"runs; it has: {_interfaces()}"
        )


def _check_dashboard(scheduler: Mapping[str, Any]) -> None:
    """One line for a scheduler_options dashboard address without a host: dask serves it on
    every interface."""
    from distributed.utils import clean_dashboard_address

    address = scheduler.get("dashboard_address")
    if address is None:
        return
    try:
        hostless = any(not p["address"] for p in clean_dashboard_address(address))
    except ValueError:  # dask's own message, later
        return
    if hostless:
        raise ValueError(
            f"scheduler_options dashboard_address={address!r} has no host, which dask serves "
            "on every interface; give dashboard='localhost:8787' (this host only, the "
            "default) or write the interface out, e.g. '0.0.0.0:8787'"
        )


def _credentials_folder(folder: str | os.PathLike) -> str:
    """The folder of the jobs' temporary TLS files, made with mode 0700 if absent; one line if
    another user owns it or others may write it (they could replace the files the workers
    trust). ``~`` and variables are left for the job to expand (dask-jobqueue's rule)."""
    local = Path(os.path.expandvars(os.path.expanduser(os.fspath(folder))))
    try:
        local.mkdir(mode=0o700, parents=True, exist_ok=True)
        st = local.stat()
    except OSError as exc:
        raise ValueError(
            f"shared_temp_directory={str(folder)!r}: cannot make it ({exc.strerror}); the "
            "jobs' TLS credentials go there: name a folder of yours on storage every node "
            "mounts"
        ) from None
    if st.st_uid != os.geteuid() or st.st_mode & 0o022:
        raise ValueError(
            f"shared_temp_directory={str(folder)!r} (mode {st.st_mode & 0o777:o}, owner uid "
            f"{st.st_uid}) must belong to you and be writable by you alone, since it holds the "
            f"jobs' TLS key: chmod go-w {shlex.quote(str(local))}, or name another folder"
        )
    return os.fspath(folder)


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
