"""The campaign engine: one store, one task loop, commits, progress, provenance and the final
write, for every plan of blocks over a sweep's grid.

A *plan* decides which blocks there are and what each computes: the grid campaign
(:func:`workbench.run_campaign`, ``_run``: blocks of independent points, dealt by cost) and
the continued sweep (:func:`workbench.continuation.continued_sweep`: segments of points run
in order, each from its neighbour's state, in rounds). Both hand :class:`Task` lists to
:meth:`Engine.run`, which computes the blocks not committed intact (the others are reused from
the store), commits each as it finishes, and shows the progress over points
(:class:`workbench._progress.Progress`); :meth:`Engine.finish` labels the assembled dataset
with the call's figures and writes the archive.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import xarray as xr

from workbench.archive import DiskFull, WriteFailed, open_run, save_run
from workbench.campaign._assemble import assemble_blocks, execution_attrs
from workbench.campaign._block import Task, run_block
from workbench.campaign._execute import available_workers, execute
from workbench.campaign._grid import SweepGrid
from workbench.campaign._store import Store
from workbench.scene import Scene

__all__ = ["Engine", "resumable"]


class Engine:
    """The execution of one campaign's plan over its store (held locked by the caller).

    Parameters
    ----------
    store : Store
    manifest : dict
        The store's manifest (:meth:`Store.write_manifest` or :meth:`Store.read_manifest`).
    blocks : int
        The number of blocks the plan may use (indices 0 .. blocks - 1).
    code : str
        Digest of the code that computes a block (:func:`workbench.campaign._grid.code_of`):
        a block computed by other code is recomputed.
    cid : str
        The campaign's id (names the tasks on a cluster).
    client, workers
        As :func:`workbench.run_campaign`.
    progress : bool or str
        Show a progress bar over ``total`` points; a string names what runs.
    total : int
        Points the plan's tasks run in all (the bar's length).
    runner : callable
        What a worker does with a task (module-level): :func:`run_block` by default.
    wall0 : float
        :func:`time.perf_counter` when the call started (s).
    by : str
        The function that creates the campaign (the archive's provenance, ``history``).
    """

    def __init__(
        self,
        store: Store,
        manifest: dict,
        *,
        blocks: int,
        code: str,
        cid: str,
        client=None,
        workers: int | None = None,
        progress: bool | str = False,
        total: int = 0,
        runner: Callable[[Task], dict] = run_block,
        wall0: float | None = None,
        by: str = "workbench.run_campaign",
    ) -> None:
        self.by = by
        self.store, self.manifest, self.cid = store, manifest, cid
        self.client, self.runner, self.progress = client, runner, progress
        self.wall0 = time.perf_counter() if wall0 is None else wall0
        store.remove_temporaries()
        self.done = store.verified_blocks(manifest, [range(0)] * blocks, code)
        self.workers = available_workers(client, workers)
        self.total = total
        self.computed: dict[int, xr.Dataset | None] = {}  # block -> its dataset (None: large)
        self.reused: set[int] = set()
        self.rounds = 0
        self.compute = 0.0  # s of wall time in the task loop
        self.cpu = 0.0  # s of the workers' CPU time for the blocks computed
        self.used_workers = 0
        self._bar = None

    def run(self, tasks: list[Task]) -> None:
        """Compute the blocks of ``tasks`` (in the order given: longest first) that are not
        committed intact, ``workers`` at a time; each is committed as it finishes. A failed
        write or a dead worker says where the finished blocks are kept."""
        reused = [t for t in tasks if t.block in self.done]
        self.reused.update(t.block for t in reused)
        todo = [t for t in tasks if t.block not in self.done and t.block not in self.computed]
        if self.progress and self._bar is None:
            from workbench._progress import Progress

            label = self.progress
            desc = label if isinstance(label, str) else "campaign"
            initial = sum(len(t.flat) for t in reused)
            self._bar = Progress(self.total, initial=initial, unit="pt", desc=desc)
        elif self._bar is not None and reused:
            self._bar.update(sum(len(t.flat) for t in reused))
        if not todo:
            return
        n = self.workers if self.client is not None else min(self.workers, len(todo))
        t0 = time.perf_counter()

        def commit(result: dict) -> None:
            self.store.commit(
                self.manifest, result["block"], result["sha256"], result["code_digest"]
            )
            self.computed[result["block"]] = result.get("dataset")
            self.cpu += result["cpu"]
            if self._bar is not None:
                self._bar.update(result["points"])

        try:
            results = execute(
                todo,
                client=self.client,
                workers=n,
                cid=self.cid,
                on_done=commit,
                announce=bool(self.progress) and self.rounds == 0,  # the dashboard link once
                runner=self.runner,
            )
        except WriteFailed as exc:  # a block's write (in a worker): a full disk, ...
            self.close()
            raise resumable(exc, self.store) from None
        except RuntimeError as exc:  # a worker died: say what is kept
            self.close()
            exc.add_note(self.store.kept_note() or "no block was finished")
            raise
        except BaseException:
            self.close()
            raise
        if len(results) != len(todo):  # pragma: no cover - guards the schedulers
            raise RuntimeError(f"{len(todo)} blocks were scheduled, {len(results)} came back")
        self.used_workers = max(self.used_workers, n)
        self.rounds += 1
        self.compute += time.perf_counter() - t0

    def assemble(self, scene: Scene, grid: SweepGrid, blocks: list[xr.Dataset]) -> xr.Dataset:
        """One dataset over ``grid`` from block datasets that hold each point once
        (:func:`workbench.campaign._assemble.assemble_blocks`), created by this campaign's
        function."""
        return assemble_blocks(scene, grid, blocks, by=self.by)

    def block(self, index: int) -> xr.Dataset:
        """Block ``index``: as its task returned it, else read from its file."""
        ds = self.computed.get(index)
        return ds if ds is not None else open_run(self.store.block_path(index))

    def close(self) -> None:
        """End the progress bar."""
        if self._bar is not None:
            self._bar.close()

    def checksums(self, blocks) -> str:
        """The SHA-256 of ``blocks`` (indices, in order), space separated."""
        return " ".join(self.manifest["checksums"][str(b)] for b in blocks)

    def finish(self, ds: xr.Dataset, blocks: list[int], attrs: dict) -> xr.Dataset:
        """Label the assembled dataset ``ds`` of ``blocks`` (indices, in order) with the
        campaign's bookkeeping (``campaign_id``, ``computed_blocks``, ``reused_blocks``, the
        call's workers, wall and CPU times: those of the call that computed the blocks, and
        this one's as ``resume_*`` when it computed none; the blocks' checksums and code
        digests) and ``attrs``, write it to the store's archive and return it as read back."""
        self.close()
        checksums = self.checksums(blocks)
        computed = len(self.computed)
        execution = {
            "campaign_workers": self.used_workers if computed else 0,
            "campaign_compute_wall_time": self.compute,
            "campaign_cpu_time": self.cpu,
            "campaign_wall_time": time.perf_counter() - self.wall0,
        }
        if not computed:  # every block reused: the figures of the call that computed them stay
            execution = execution_attrs(execution, self.store.assembled_attrs(checksums))
        codes = self.manifest["code_digests"]
        ds.attrs.update(
            campaign_id=self.cid,
            computed_blocks=computed,
            reused_blocks=len(self.reused),
            **attrs,
            **execution,
            campaign_block_sha256=checksums,
            code_digests=" ".join(sorted({codes[str(b)] for b in blocks})),
        )
        try:
            save_run(ds, self.store.archive)
        except WriteFailed as exc:
            raise resumable(exc, self.store) from None
        return open_run(self.store.archive)


def resumable(exc: WriteFailed, st: Store) -> WriteFailed:
    """A failed write during a campaign (a full disk, ...), with where its finished work is and
    how to resume."""
    fix = "free some space" if isinstance(exc, DiskFull) else "remove the cause"
    kept = st.kept_note()
    then = " to compute the rest and assemble the archive" if kept else ""
    return exc.reworded(
        f"{exc}; {kept or 'no block was finished'}: {fix} and run the campaign again{then}"
    )
