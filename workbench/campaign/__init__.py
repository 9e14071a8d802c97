"""Parameter campaigns: a scene's ``[sweep]`` grid run in parallel, resumable, one dataset.

>>> import workbench
>>> scene = workbench.load_scene({
...     "model": {"name": "duffing"},
...     "run": {"cycles": 3},
...     "record": {"samples_per_period": 1},
...     "sweep": {"gamma": [0.3, 0.5], "omega": [1.0, 1.2]},
... })
>>> from workbench.campaign import expand_sweep
>>> expand_sweep(scene).shape
(2, 2)

:func:`run_campaign` expands the sweep into a grid over the named parameters (several at once),
runs blocks of points as tasks (on a local process pool by default, on any
``dask.distributed.Client`` when given) and returns one :class:`xarray.Dataset` with the
parameter dims first, then ``time`` and the model's dims.

Modules: ``_engine`` (the one campaign engine: store, task loop, commits, progress,
provenance and the final write, for every plan), ``_run`` (the grid campaign's plan),
``_grid`` (the sweep's points, the campaign's identity and code digest), ``_store`` (the
store on disk), ``_errors``, ``_schedule`` (longest first), ``_execute`` (one dispatch loop for
both executors), ``_block`` (the one task type, :class:`~workbench.campaign._block.Task`, run in
a worker), ``_assemble`` (blocks -> one dataset), ``_warm`` (the kernel loaded once;
:func:`warm_kernel` compiles it into the cache before a cluster's workers start), ``_preload``
(the fork server), ``_cluster`` (the worker plugin of a dask cluster), ``_jobqueue`` (the
clusters workbench starts, closed: TLS, named interfaces: :func:`local_cluster`, and
:func:`jobqueue_cluster` for workers on a batch system, docs/cluster.md),
``_lifeline`` (processes that die with the campaign).

Store layout
------------
``store`` is the path of the assembled archive; everything else lives in a sibling directory::

    sweep.nc                 the assembled campaign (netCDF-4), written last, atomically
    sweep.nc.blocks/
        lock                 held (flock) by the one process writing the store: pid, host
        manifest.json        scene TOML, grid, chunk size, campaign id, code digest, the
                             points of each block (flat C-order indices over the grid), and
                             the SHA-256 and code digest of every committed block
        block-00000.nc       up to chunk points
        block-00001.nc       ...

* Blocks are dealt by estimated cost: the points ranked by their simulated time (transient +
  recorded cycles times the forcing period, or transient + duration) are dealt to the blocks
  like cards, in a snake order, so that every block holds one point of each tier of cost and
  the blocks cost about the same (a sweep over the forcing frequency cut into contiguous
  blocks would end waiting for its low-frequency block). They start longest first, the
  longest-processing-time rule (Graham 1969).
* Block files are netCDF-3 (64-bit offset, scipy's writer: small files without HDF5's
  per-variable overhead); the task also
  returns a small block (up to 32 MiB) to the client with its summary, so that the client
  assembles what this call computed without reading those files again. Only blocks of an
  earlier, interrupted call are read from disk.

* Each task owns one block file and writes it atomically (a temporary file beside it, then a
  rename), so a block file exists only when complete; only the client writes the manifest and
  the archive. Workers of a cluster must see the store's file system.
* A block is committed when the client records its file's SHA-256 in the manifest. Resuming:
  running the same campaign again computes only the blocks that are not committed intact (after
  Ctrl-C, ``kill -9``, a killed worker or a crashed machine); left-over temporary files are
  removed; a block that is missing, corrupt (its checksum differs) or was never committed is
  named in a CampaignWarning and recomputed. The archive records the checksums of its blocks
  (``campaign_block_sha256``). Once ``sweep.nc`` is written the blocks directory may be
  deleted: a re-run then returns the archive as is.
* A different scene (any key, the sweep included) or chunk size against an existing store is
  refused with the differences named; ``restart=True`` (CLI ``--restart``) discards the store.
* One campaign process per store at a time: it holds the store's lock for its lifetime; a
  second one is refused (:class:`workbench.archive.StoreLocked`, naming the holder's pid and
  host); the lock of a dead process is taken over with a warning.

When every point has the same record times they are the 1-D coordinate ``time`` (as from
:func:`workbench.simulate`); when they differ (a sweep over the forcing frequency: records at
``k T / samples_per_period``; a continued sweep), the records run along ``record`` (the
record's index in its point's run) and the auxiliary coordinate ``record_time`` (parameter dims,
record; s, ``standard_name`` "time") holds each point's times, NaN-padded if runs differ in
length (docs/archives.md).

Both executors run through one loop (``_execute``): as many blocks in flight as there are
workers, the next one submitted, longest first, when one finishes, so the start order is the
campaign's own whatever the scheduler. The local pool is a process pool on a fork server that
imports workbench and loads the campaign's compiled kernel once; its workers (one thread each)
start in milliseconds and stop with the campaign (on an error or Ctrl-C the blocks in flight are
stopped at once; if the campaign's process dies, whatever the signal, the fork server and the
workers die within a fraction of a second: ``_lifeline``).

The archive carries, per point, ``status`` (int8 with CF ``flag_values``/``flag_meanings``: the
codes of :class:`workbench.Status`, 0 ok, 1 terminated, 2 max_steps, 3 step_underflow,
4 non_finite, 5 model_failure, 6 invalid_parameters, and 7 error: the point raised an exception,
which never stops the campaign), ``failure`` (the message), solver
statistics (``solver_steps``, ``solver_rejected_steps``, ``solver_rhs_evaluations``,
``solver_events``, ``solver_wall_time``) and ``point_wall_time``; and in its attributes the scene
TOML, the grid (``campaign_grid``), provenance, ``computed_blocks`` and ``reused_blocks`` (by
the call that wrote it), and the workers and wall times of the call that computed the blocks
(``campaign_workers``, ``campaign_*_wall_time``; a later call that finds every block done keeps
them and adds its own as ``resume_*``). It
stores only what the scene records: ``record.samples_per_period = 1`` keeps strobe samples only.

Two plans run over the one engine (``_engine``): the grid campaign (:func:`run_campaign`: blocks
of independent points dealt by cost) and the continued sweep
(:func:`workbench.continuation.continued_sweep`: segments of points run in order, each from its
neighbour's state, in rounds). Both use the same task type, store, commits, progress bar and
provenance (the archive's ``history`` names the function that created it).

Command line: ``workbench campaign SCENE.toml -o sweep.nc [--workers N] [--scheduler ADDRESS]
[--chunk K] [--restart]`` and ``workbench bifurcation sweep.nc --var x [-o fig.png]``.
"""

from workbench.campaign._assemble import summary
from workbench.campaign._block import task_scene  # noqa: F401 (tests import it from here)
from workbench.campaign._errors import CampaignError, CampaignWarning
from workbench.campaign._grid import SweepGrid, expand_sweep
from workbench.campaign._jobqueue import DASK_CONFIG, jobqueue_cluster, local_cluster
from workbench.campaign._run import run_campaign, store_paths
from workbench.campaign._store import Store  # noqa: F401 (tests import it from here)
from workbench.campaign._warm import warm_kernel

__all__ = [
    "DASK_CONFIG",
    "CampaignError",
    "CampaignWarning",
    "SweepGrid",
    "expand_sweep",
    "jobqueue_cluster",
    "local_cluster",
    "run_campaign",
    "store_paths",
    "summary",
    "warm_kernel",
]
