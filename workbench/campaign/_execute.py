"""Running a campaign's block tasks: one dispatch loop for a local process pool and for a
``dask.distributed`` cluster.

Both are executors in the sense of :mod:`concurrent.futures` (``submit`` returns a future; a
``wait`` returns the finished ones): the stdlib :class:`~concurrent.futures.ProcessPoolExecutor`
on a fork server, or a :class:`distributed.Client`. The loop keeps as many tasks in flight as
there are workers, plus one waiting per worker (``PREFETCH``), and submits the next one, in the
list's (longest-first) order, when one finishes: the start order is the campaign's own on
either executor, whatever the scheduler's tie-breaking among independent tasks, and a worker
that finishes a block starts its next one at once instead of idling through the round trip to
the client (its result, the commit, the next submission: scheduling latencies of a loaded
machine; benchmarks/campaign_cluster.py reports the idle time between blocks, "dispatch").

The local pool is not a ``distributed.LocalCluster``, which imports dask's distributed machinery
and starts a scheduler and worker processes that each have to import workbench and load the
kernel; the pool's workers are forked from a server that has already imported workbench and
loaded the campaign's compiled kernel (``_preload``). The workers of a cluster get the same
before their first block from a worker plugin (``_cluster``).
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import json
import os
import signal
import socket
import sys
import threading
import uuid
from collections.abc import Callable, Iterator

from workbench._warnings import WarningKind, reraise, warnings_by_kind
from workbench.campaign._block import MODEL_ENV, PRELOAD_ENV, Task, run_block, worker_start
from workbench.campaign._lifeline import PARENT_ENV
from workbench.campaign._warm import kernel_cached, load_kernel
from workbench.scene import scene_from_toml

__all__ = ["PREFETCH", "available_workers", "execute"]

PREFETCH = 1  # tasks waiting per worker beside the one it runs


def available_workers(client, workers: int | None) -> int:
    """Tasks that can run at once: the client's threads, else ``workers``, else the CPUs."""
    if client is not None:
        info = client.scheduler_info()
        return max(1, sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()))
    if workers is not None:
        return workers
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - macOS, Windows
        return os.cpu_count() or 1


def execute(
    tasks: list[Task],
    *,
    client=None,
    workers: int,
    cid: str,
    on_done: Callable[[dict], None] | None = None,
    announce: bool = False,
    runner: Callable[[Task], dict] = run_block,
) -> list[dict]:
    """Run the block tasks, starting them in list order, ``workers`` at a time (and
    ``PREFETCH`` per worker waiting).

    Parameters
    ----------
    tasks : list of Task
        In the order they should start (longest first).
    client : distributed.Client, optional
        Run on this cluster; default a local pool of ``workers`` processes.
    workers : int
        Tasks in flight at once (the cluster's threads for a client).
    cid : str
        Campaign id (names the cluster's tasks).
    on_done : callable, optional
        Called with each task's summary as it finishes (the client commits the block there).
    announce : bool
        Print the dashboard link of a client.
    runner : callable
        What a worker does with a task (a module-level function, so that it pickles):
        :func:`run_block` by default (a continued sweep's segments: its own runner).

    Returns
    -------
    list of dict
        The tasks' summaries (the runner's; :func:`run_block`'s), in completion order.

    Raises
    ------
    RuntimeError
        A local worker process died (killed, out of memory); the finished blocks are kept.
    Exception
        The first error a task raised, after the tasks in flight were stopped.

    Warns
    -----
    Warning
        What the tasks warned about in their workers, and anything raised meanwhile here, once
        per kind at the end, with the count (:func:`workbench._warnings.warnings_by_kind`;
        except in a dask worker of several threads, where they go to the worker's log).
    """
    first = _first_point(tasks[0])
    # the module of a user's model, which each worker imports before it reads the scene
    model = (getattr(tasks[0], "model_module", ""), getattr(tasks[0], "model_directory", ""))
    if client is not None:
        if announce and getattr(client, "dashboard_link", None):
            print(f"campaign: dask dashboard at {client.dashboard_link}", file=sys.stderr)
        from distributed import wait

        from workbench.campaign._cluster import ready_workers

        ready_workers(client, first, *model)  # every worker imports and loads the kernel once
        token = uuid.uuid4().hex[:8]

        def submit(t: Task):
            key = f"campaign-{cid}-block-{t.block:05d}-{token}"
            return client.submit(_run_task, runner, t, _process(), key=key, pure=False)

        with warnings_by_kind():
            return _dispatch(submit, wait, tasks, workers * (1 + PREFETCH), on_done)
    if kernel_cached(scene_from_toml(first)) is False:
        # Compiled here, where Ctrl-C stops it at once, not in the fork server's start.
        load_kernel(first)
    with _local_pool(workers, first, model) as pool:

        def submit_local(t: Task):
            with _uninterrupted_start():
                return pool.submit(_run_task, runner, t, _process())

        window = workers * (1 + PREFETCH)
        with warnings_by_kind():
            return _dispatch(submit_local, concurrent.futures.wait, tasks, window, on_done)


def _process() -> str:
    """This process: host name and process id."""
    return f"{socket.gethostname()}:{os.getpid()}"


def _run_task(runner: Callable[[Task], dict], task: Task, client: str) -> dict:
    """``runner(task)`` in a worker, with the warnings it raised, by kind, in its summary
    (``warnings``: a list of :class:`workbench._warnings.WarningKind`; the client raises them
    again, so that a campaign says once per kind what its points warned about). Warnings are
    caught for the whole process, not per thread: a task in the client's
    process (``client``, :func:`_process`; a cluster of threads there) warns there directly,
    and one in a worker of several threads into the worker's log, as any warning would."""
    if _process() == client or not _one_task_at_a_time():
        return runner(task)
    kinds: list[WarningKind] = []
    with warnings_by_kind(show=kinds.append):
        summary = runner(task)
    return {**summary, "warnings": kinds}


def _one_task_at_a_time() -> bool:
    """Whether this process runs one task at a time: a local pool's worker (its main thread),
    or a dask worker of one thread."""
    if threading.current_thread() is threading.main_thread():
        return True
    try:
        from distributed import get_worker

        return get_worker().state.nthreads == 1
    except (ImportError, ValueError, AttributeError):  # no distributed, not a dask worker
        # (get_worker's ValueError), or a worker without that field
        return False


@contextlib.contextmanager
def _uninterrupted_start() -> Iterator[None]:
    """Start processes without Ctrl-C cutting a start in half (a process whose start the
    campaign abandoned would outlive the queues it was given, and fail with a traceback).

    SIGINT is blocked in this thread, so that the processes started here (the fork server, and
    the workers it forks) inherit the block: a terminal's Ctrl-C reaches the campaign alone,
    which stops them. A Ctrl-C that arrives meanwhile (possibly through another thread) is
    raised as KeyboardInterrupt once the start is done: after the fork server's start (it only
    loads the kernel, compiled beforehand) at most, a few seconds. SIGTERM and SIGHUP, which
    the command line turns into interrupts, are deferred likewise (not blocked).
    """
    previous = {}
    if threading.current_thread() is threading.main_thread():
        # the Python handlers of SIGINT and of the signals a command turns into interrupts
        # (SIGTERM, SIGHUP: workbench.cli._signals) are deferred; only SIGINT is blocked (the
        # processes started here must still die of the SIGTERM that stops them)
        for sig in _DEFERRED:
            handler = signal.getsignal(sig)
            if callable(handler):
                previous[sig] = handler
    caught: list[int] = []
    for sig in previous:
        signal.signal(sig, lambda signum, frame: caught.append(signum))
    old_mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if caught:
            previous[caught[0]](caught[0], None)  # raises (KeyboardInterrupt, Terminated)
            raise KeyboardInterrupt from None


_DEFERRED = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))


def _dispatch(submit: Callable, wait: Callable, tasks: list, window: int, on_done) -> list[dict]:
    """Keep ``window`` tasks in flight, submitting them in list order; cancel the rest on error."""
    queue = list(reversed(tasks))  # pop() takes them in list order
    running: set = set()
    results: list[dict] = []
    try:
        while queue or running:
            while queue and len(running) < window:
                running.add(submit(queue.pop()))
            done, running = wait(running, return_when="FIRST_COMPLETED")
            for fut in done:
                results.append(fut.result())  # re-raises the task's error
                for kind in results[-1].pop("warnings", ()):
                    reraise(kind)  # counted by kind (execute's warnings_by_kind)
                if on_done is not None:
                    on_done(results[-1])
    finally:
        for fut in running:
            fut.cancel()
    return results


def _first_point(task: Task) -> str:
    """Scene TOML of a task's first point: the local pool's fork server loads its kernel once."""
    point = dict(zip(task.dims, task.values[0], strict=True))
    return scene_from_toml(task.scene_toml).with_parameters(**point).to_toml()


@contextlib.contextmanager
def _local_pool(
    workers: int, preload: str, model: tuple[str, str] = ("", "")
) -> Iterator[concurrent.futures.ProcessPoolExecutor]:
    """A process pool whose workers stop with the campaign: on an error or Ctrl-C the blocks in
    flight are stopped at once (each worker reported its pid when it started), and if this
    process dies, they die with it (``_lifeline``)."""
    from concurrent.futures.process import BrokenProcessPool

    ctx = _mp_context(preload, model)
    with _uninterrupted_start():  # the queue's lock starts multiprocessing's resource tracker
        pids = ctx.SimpleQueue()
    pool = concurrent.futures.ProcessPoolExecutor(
        workers, mp_context=ctx, initializer=worker_start, initargs=(pids, os.getpid())
    )
    try:
        yield pool
    except BaseException as exc:
        # every worker: those that reported, and those still starting (the pool's own list)
        started = set(getattr(pool, "_processes", None) or ())
        while not pids.empty():
            started.add(pids.get())
        for pid in started:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGTERM)
        if isinstance(exc, BrokenProcessPool):
            raise RuntimeError(
                "a worker process of the local pool died (killed, out of memory, or the calling "
                "script lacks the `if __name__ == '__main__':` guard that process pools need); "
                "run the campaign again to compute the blocks not finished"
            ) from exc
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        os.environ.pop(PRELOAD_ENV, None)
        os.environ.pop(MODEL_ENV, None)
        os.environ.pop(PARENT_ENV, None)


def _mp_context(preload: str, model: tuple[str, str] = ("", "")):
    """The multiprocessing context of the local pool: dask's ``multiprocessing.context`` if set,
    else a fork server (else spawn). The fork server imports workbench once and, when this call
    starts it, loads the campaign's compiled kernel once (see ``_preload``): workers forked from
    it start in milliseconds with the machine code in memory, and exit as fast."""
    import multiprocessing

    import dask

    name = dask.config.get("multiprocessing.context", None)
    if name is not None:
        return multiprocessing.get_context(name)
    if "forkserver" not in multiprocessing.get_all_start_methods():  # pragma: no cover
        return multiprocessing.get_context("spawn")
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(["workbench.campaign._block", "workbench.campaign._preload"])
    os.environ[PRELOAD_ENV] = preload  # read by the server if this run starts it
    os.environ[MODEL_ENV] = json.dumps(list(model))  # the module it imports first
    os.environ[PARENT_ENV] = str(os.getpid())  # the server dies with this process
    return ctx
