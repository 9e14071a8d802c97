"""The store of a work-precision study: each finished run kept, so that an interrupted study
resumes where it stopped, like a campaign.

Layout (``directory`` is e.g. ``wp.nc.runs/`` beside the study's archive ``wp.nc``)::

    lock              held (flock) by the one process writing the store; pid and host
    manifest.json     what the study is (scene, reference, horizon) and the SHA-256 of every
                      committed file
    reference-short.nc, reference-long.nc, twin.nc, probe.nc    the reference runs
    setting-<method>-<rtol>.json                                the measures of one setting

A file is reused only when its checksum matches the manifest; otherwise it is named in a
:class:`~workbench.archive.StoreWarning` and recomputed. The study's settings (methods,
tolerances) may change between calls; what they are measured against may not.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import xarray as xr

from workbench.archive import (
    ArchiveError,
    StoreWarning,
    file_problem,
    mapping_diff,
    open_run,
    read_manifest,
    save_run,
    sha256_file,
    store_lock,
    write_text_atomic,
)

__all__ = ["StudyStore", "study_store"]

FORMAT = "workbench-accuracy 1"
_FILE_RE = re.compile(r"^(manifest\.json|[\w.+-]+\.(nc|json))$|^\..*\.tmp$")


class StudyStore:
    """Runs of a work-precision study, kept on disk (``directory``) or only in memory (None)."""

    def __init__(self, directory: Path | None, identity: dict) -> None:
        self.directory = directory
        self.identity = json.loads(json.dumps(identity))  # as stored: lists, not tuples
        self.manifest: dict = {"format": FORMAT, "identity": identity, "checksums": {}}
        self.reused = 0

    # -- opening --------------------------------------------------------------------------------
    def _clear(self) -> None:
        for p in self.directory.iterdir():
            if _FILE_RE.match(p.name):
                p.unlink(missing_ok=True)

    def _open(self, restart: bool) -> None:
        if restart:
            self._clear()
        path = self.directory / "manifest.json"
        if not path.is_file():
            self._save()
            return
        stored = read_manifest(path, FORMAT, "the work-precision study")
        if stored.get("identity") != self.identity:
            lines = mapping_diff(stored.get("identity", {}), self.identity)
            shown = "\n  ".join(lines[:12]) + ("\n  ..." if len(lines) > 12 else "")
            raise ArchiveError(
                f"{str(self.directory)!r} holds the runs of a different work-precision study; "
                f"differences (stored -> given):\n  {shown}\nPass restart=True (CLI --restart) "
                "to discard them, or choose another output path."
            )
        self.manifest = stored

    def _save(self) -> None:
        if self.directory is not None:
            write_text_atomic(
                self.directory / "manifest.json", json.dumps(self.manifest, indent=1) + "\n"
            )

    # -- runs -----------------------------------------------------------------------------------
    def _reusable(self, name: str) -> bool:
        """Whether the committed file ``name`` is intact; warn and forget it otherwise."""
        sums = self.manifest["checksums"]
        problem = file_problem(self.directory / name, sums.get(name))
        if problem is None:
            return name in sums
        warnings.warn(StoreWarning(f"run file {name} {problem}; recomputing"), stacklevel=4)
        sums.pop(name, None)
        with contextlib.suppress(OSError):
            (self.directory / name).unlink()
        return False

    def _commit(self, name: str) -> None:
        self.manifest["checksums"][name] = sha256_file(self.directory / name)
        self._save()

    def committed(self, file: str) -> bool:
        """Whether ``file`` (a name with its suffix) is committed (not yet verified)."""
        return file in self.manifest["checksums"]

    def dataset(self, name: str, compute: Callable[[], xr.Dataset]) -> tuple[xr.Dataset, bool]:
        """The stored run ``name`` (``.nc``) if intact, else ``compute()``, stored; and whether
        it was reused."""
        if self.directory is None:
            return compute(), False
        file = f"{name}.nc"
        if self._reusable(file):
            self.reused += 1
            return open_run(self.directory / file), True
        ds = compute()
        save_run(ds, self.directory / file)
        self._commit(file)
        return ds, False

    def record(self, name: str, compute: Callable[[], dict]) -> tuple[dict, bool]:
        """The stored record ``name`` (``.json``) if intact, else ``compute()``, stored; and
        whether it was reused."""
        if self.directory is None:
            return compute(), False
        file = f"{name}.json"
        if self._reusable(file):
            self.reused += 1
            return json.loads((self.directory / file).read_text()), True
        data = compute()
        write_text_atomic(self.directory / file, json.dumps(data) + "\n")
        self._commit(file)
        return data, False

    def discard(self) -> None:
        """Remove the store (its runs are in the study's archive now)."""
        if self.directory is not None:
            self._clear()


@contextlib.contextmanager
def study_store(
    directory: str | os.PathLike | None, identity: dict, *, restart: bool = False
) -> Iterator[StudyStore]:
    """Open (or create) the store of a study at ``directory`` and hold its lock while inside;
    an in-memory store when ``directory`` is None.

    Raises
    ------
    workbench.archive.StoreLocked
        Another live process holds the store.
    workbench.archive.ArchiveError
        The store holds a different study (the differences are named) and ``restart`` is false.
    """
    if directory is None:
        yield StudyStore(None, identity)
        return
    directory = Path(directory)
    try:
        with store_lock(directory, f"accuracy store {str(directory)!r}"):
            store = StudyStore(directory, identity)
            store._open(restart)
            yield store
    finally:
        with contextlib.suppress(OSError):
            directory.rmdir()  # only if empty (a finished study discarded its runs)
