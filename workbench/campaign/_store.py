"""The store of a campaign on disk: manifest, block files, lock, scene comparison.

Layout (``store`` is the path of the assembled archive, e.g. ``omega.nc``)::

    omega.nc                  assembled archive, written last (atomically)
    omega.nc.blocks/
        lock                  held (flock) by the one process writing the store; pid and host
        manifest.json         scene TOML, grid, chunk, campaign id, the points of each block
                              (written first, atomically), and the SHA-256 of every committed
                              block (rewritten on each)
        block-00000.nc        up to chunk points, dealt by estimated cost (``_schedule``; one
                              file per task, written atomically; netCDF-3 64-bit offset,
                              without HDF5's per-variable overhead)
        block-00001.nc        ...

A block is *committed* when its checksum is in the manifest; on resume a block is reused only
if its file's SHA-256 matches, otherwise it is named and recomputed. The manifest also records,
per block, the digest of the code that computed it (:func:`workbench.campaign._grid.code_of`;
the block file carries it as the attribute ``code_digest``): a block computed by other code (a
model's default edited, a ``git pull``) is named and recomputed on resume, so an archive never
mixes results of two versions of the code. Its attribute ``code_digests`` lists the digests
it holds.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import tomllib
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from workbench.archive import (
    ArchiveError,
    check_output_file,
    file_problem,
    mapping_diff,
    open_run,
    read_manifest,
    store_lock,
    write_text_atomic,
)
from workbench.campaign._errors import CampaignError, CampaignWarning
from workbench.campaign._grid import SweepGrid, code_of
from workbench.scene import Scene, SceneError, scene_from_toml

__all__ = ["FORMAT", "Store"]

FORMAT = "workbench-campaign 3"  # 2: block checksums, lock; 3: the points of each block
READ = (FORMAT, "workbench-campaign 2")  # a format-2 store has contiguous blocks of chunk points
_BLOCK_RE = re.compile(r"^block-(\d{5,})\.nc$")
_TMP_RE = re.compile(r"^\.(block-\d{5,}\.nc|manifest\.json)\..*\.tmp$")


class Store:
    """Paths and bookkeeping of one campaign store (see the module docstring)."""

    def __init__(self, archive: str | os.PathLike) -> None:
        self.given = os.fspath(archive)  # as the caller named it, for messages
        self.archive = Path(archive).expanduser().resolve()
        if self.archive.is_dir():
            raise CampaignError(
                f"the campaign store must be the path of a netCDF file (e.g. 'sweep.nc'), got the "
                f"directory {str(self.archive)!r}; its blocks go to the sibling directory "
                "'sweep.nc.blocks/'"
            )
        check_output_file(self.archive, "store", overwrite=True)  # e.g. not under a file
        self.blocks_dir = self.archive.with_name(self.archive.name + ".blocks")
        self.manifest_path = self.blocks_dir / "manifest.json"
        self._points: tuple[object, str] = (None, "")  # block_points and their JSON text

    def assembled_attrs(self, checksums: str) -> dict | None:
        """The attributes of the archive at the store's path when it was assembled from the
        blocks whose SHA-256 are ``checksums`` (its ``campaign_block_sha256``); None when there
        is no archive, an unreadable one, or one of other blocks."""
        if not self.archive.is_file():
            return None
        try:
            with open_run(self.archive) as ds:
                attrs = dict(ds.attrs)
        except (OSError, ArchiveError):  # unreadable: the archive is rewritten anyway
            return None
        return attrs if attrs.get("campaign_block_sha256") == checksums else None

    def block_path(self, index: int) -> Path:
        """The file of block ``index`` in the store's blocks directory."""
        return self.blocks_dir / f"block-{index:05d}.nc"

    # manifest
    def read_manifest(self) -> dict | None:
        """The store's manifest, or None for a new store (CampaignError for block files
        without a manifest, or a manifest that cannot be read or has another format)."""
        if not self.manifest_path.is_file():
            if self.blocks_dir.is_dir() and any(
                _BLOCK_RE.match(p.name) for p in self.blocks_dir.iterdir()
            ):
                raise CampaignError(
                    f"{str(self.blocks_dir)!r} holds block files but no manifest.json, so what "
                    "they were computed from is unknown; pass restart=True (CLI --restart) to "
                    "discard them, or choose another output path"
                )
            return None
        return read_manifest(self.manifest_path, READ, "the campaign", CampaignError)

    def write_manifest(
        self,
        scene: Scene,
        grid: SweepGrid,
        chunk: int,
        cid: str,
        blocks: list[tuple[int, ...]],
        code: str | None = None,
    ) -> dict:
        """Start the manifest of a campaign: its blocks' points (``blocks``), and ``code``, the
        digest of the code that computes its blocks (default
        :func:`workbench.campaign._grid.code_of` of the scene)."""
        data = {
            "format": FORMAT,
            "campaign_id": cid,
            "scene": scene.to_toml(),
            "dims": list(grid.dims),
            "grid": grid.as_dict(),
            "chunk": chunk,
            "points": grid.size,
            "blocks": len(blocks),
            "block_points": [list(b) for b in blocks],
            "code_digest": code_of(scene) if code is None else code,
            "checksums": {},
            "code_digests": {},
        }
        return self.save_manifest(data)

    def blocks(self, manifest: dict, grid: SweepGrid) -> list[tuple[int, ...]]:
        """The flat indices of each block's points: as the manifest records them (format 3),
        or contiguous runs of ``chunk`` points (a store of format 2). CampaignError when they
        do not cover the grid's points once each."""
        if "block_points" not in manifest:
            return [tuple(r) for r in grid.blocks(int(manifest["chunk"]))]
        try:
            arrays = [np.asarray(b, np.int64) for b in manifest["block_points"]]
        except (TypeError, ValueError):  # not lists of integers
            arrays = [np.zeros((0, 0), np.int64)]
        flat = np.concatenate(arrays, axis=None) if arrays else np.zeros(0, np.int64)
        once = (
            all(b.ndim == 1 for b in arrays)
            and len(flat) == grid.size
            and (flat >= 0).all()
            and (flat < grid.size).all()
            and (np.bincount(flat, minlength=grid.size) == 1).all()
        )
        if not once or len(arrays) != manifest.get("blocks"):
            raise CampaignError(
                f"{str(self.manifest_path)!r} lists blocks that do not hold each of the "
                f"{grid.size} points of the grid once; pass restart=True (CLI --restart) to "
                "start afresh"
            )
        return [tuple(b.tolist()) for b in arrays]

    def save_manifest(self, data: dict) -> dict:
        """Write ``data`` as the store's manifest, atomically, and return it."""
        self.blocks_dir.mkdir(parents=True, exist_ok=True)
        write_text_atomic(self.manifest_path, self._manifest_text(data))
        return data

    def _manifest_text(self, data: dict) -> str:
        """The manifest as JSON, each block's points on one line (a campaign of millions of
        points would otherwise take a line per point); those lines are encoded once and reused
        by each commit's rewrite."""
        points = data.get("block_points")
        if points is None:
            return json.dumps(data, indent=1) + "\n"
        if self._points[0] is not points:
            lines = ",\n".join(f"  {json.dumps(b, separators=(',', ':'))}" for b in points)
            self._points = (points, f'"block_points": [\n{lines}\n ]')
        head = json.dumps({k: v for k, v in data.items() if k != "block_points"}, indent=1)
        return f"{head[:-2]},\n {self._points[1]}\n}}\n"

    def check_scene(self, stored_toml: str, scene: Scene, where: str) -> None:
        """CampaignError naming the differences if ``stored_toml`` is not ``scene``. The stored
        scene is data: a ``[model] module`` it names other than the given scene's is not
        imported but named as the difference (only the user's scene authorises a module)."""
        module = _stored_module(stored_toml)
        if module is not None and module != scene.model_module:
            given = repr(scene.model_module) if scene.model_module else "none"
            raise CampaignError(
                f"{where} holds a campaign of a different scene: it names the model module "
                f"{module!r} (given: {given}), which is not imported from stored data; to "
                f"resume it, give the scene file that names model.module = {module!r}, or pass "
                "restart=True (CLI --restart) to start afresh, or choose another output path"
            )
        try:
            stored = scene_from_toml(stored_toml)
        except SceneError as exc:
            raise CampaignError(
                f"{where} holds a campaign whose scene no longer loads ({exc}); pass "
                "restart=True (CLI --restart) to start afresh, or choose another output path"
            ) from None
        if stored == scene:
            return
        lines = mapping_diff(stored.to_dict(), scene.to_dict()) or ["(formatting only)"]
        shown = "\n  ".join(lines[:12]) + ("\n  ..." if len(lines) > 12 else "")
        raise CampaignError(
            f"{where} holds a campaign of a different scene; the scene may not change within a "
            f"campaign, so that old and new points never mix. Differences (stored -> given):\n"
            f"  {shown}\n"
            "Pass restart=True (CLI --restart) to discard the stored campaign and start afresh, "
            "or choose another output path."
        )

    def check_manifest(self, manifest: dict, scene: Scene, chunk: int | None) -> int:
        """Refuse a manifest of another scene or chunk size; return the stored chunk size."""
        self.check_scene(manifest["scene"], scene, repr(str(self.blocks_dir)))
        stored = int(manifest["chunk"])
        if chunk is not None and chunk != stored:
            raise CampaignError(
                f"{str(self.blocks_dir)!r} was started with chunk={stored!r} points per block, "
                f"got chunk={chunk!r}; the blocks of a campaign all have one size. Pass "
                f"chunk=None (or {stored}) to resume, or restart=True (CLI --restart) to start "
                "afresh with the new size."
            )
        return stored

    def clear(self) -> None:
        """Remove this store's files (archive, manifest, blocks, temporaries) and nothing else."""
        self.archive.unlink(missing_ok=True)
        if self.blocks_dir.is_dir():
            for p in self.blocks_dir.iterdir():
                if p.name == "manifest.json" or _BLOCK_RE.match(p.name) or _TMP_RE.match(p.name):
                    p.unlink(missing_ok=True)
            try:
                self.blocks_dir.rmdir()
            except OSError:  # something else lives there: leave it
                pass

    def remove_temporaries(self) -> list[Path]:
        """Delete the temporary files of writes that were interrupted (a killed process)."""
        removed = []
        if self.blocks_dir.is_dir():
            for p in self.blocks_dir.iterdir():
                if _TMP_RE.match(p.name):
                    p.unlink(missing_ok=True)
                    removed.append(p)
        for p in self.archive.parent.glob(f".{self.archive.name}.*.tmp"):
            p.unlink(missing_ok=True)
            removed.append(p)
        return removed

    def verified_blocks(self, manifest: dict, blocks: list, code: str) -> set[int]:
        """Indices of the committed blocks whose file is intact (its SHA-256 is the one in the
        manifest) and that the code of digest ``code`` computed. Every other block is named in a
        CampaignWarning (missing, corrupt, written but never committed, or computed by other
        code) and will be recomputed; the manifest drops their checksums."""
        sums: dict[str, str] = manifest.setdefault("checksums", {})
        codes: dict[str, str] = manifest.setdefault("code_digests", {})
        done, dropped, other = set(), False, {}
        for i in range(len(blocks)):
            path = self.block_path(i)
            problem = file_problem(path, sums.get(str(i)))
            if problem is None and str(i) in sums and codes.get(str(i)) != code:
                other.setdefault(codes.get(str(i), "unrecorded"), []).append(i)
                problem = "stale"
            elif problem is None:
                if str(i) in sums:
                    done.add(i)
                continue
            else:
                warnings.warn(
                    CampaignWarning(f"block {i} ({path.name}) {problem}; recomputing"),
                    stacklevel=3,
                )
            if sums.pop(str(i), None) is not None:
                dropped = True
            codes.pop(str(i), None)
            with contextlib.suppress(OSError):
                path.unlink()
        if other:
            n = sum(len(v) for v in other.values())
            was = ", ".join(f"{d!r} ({len(v)})" for d, v in other.items())
            warnings.warn(
                CampaignWarning(
                    f"{n} of {len(blocks)} blocks were computed by other code (code digest "
                    f"{was}; this code: {code!r}: the package, a model or the solver changed "
                    "since they ran); recomputing them, so that the archive holds the results "
                    "of one version of the code"
                ),
                stacklevel=3,
            )
        if dropped:
            self.save_manifest(manifest)
        return done

    def commit(self, manifest: dict, block: int, sha256: str, code: str) -> None:
        """Record a finished block's checksum and the digest of the code that computed it in
        the manifest (the block is then committed)."""
        manifest.setdefault("checksums", {})[str(block)] = sha256
        manifest.setdefault("code_digests", {})[str(block)] = code
        self.save_manifest(manifest)

    def kept_note(self) -> str | None:
        """Where the finished blocks of a stopped campaign are, as a clause for its message
        (``the finished blocks are kept in 'sweep.nc.blocks/'``, the store as the caller named
        it), or None when there are none: no block committed in the manifest has its file."""
        if not self.blocks_dir.is_dir():
            return None
        names = (_BLOCK_RE.match(p.name) for p in self.blocks_dir.iterdir())
        files = {int(m.group(1)) for m in names if m}
        try:
            committed = {int(k) for k in json.loads(self.manifest_path.read_text())["checksums"]}
        except (OSError, ValueError, TypeError, KeyError):  # no manifest: the files alone
            committed = files
        if not files & committed:
            return None
        return f"the finished blocks are kept in '{self.given}.blocks/'"

    @contextlib.contextmanager
    def lock(self) -> Iterator[dict]:
        """Hold the store's lock (one writing process at a time; see
        :func:`workbench.archive.store_lock`); yields the holder of a stale lock taken over (or
        {}). The blocks directory is removed on release if nothing else is left in it."""
        try:
            with store_lock(self.blocks_dir, f"campaign store {str(self.archive)!r}") as stale:
                yield stale
        finally:
            with contextlib.suppress(OSError):
                self.blocks_dir.rmdir()  # only if empty


def _stored_module(stored_toml: str) -> Any:
    """The ``[model] module`` a stored scene names (None if none, or not a scene's TOML)."""
    try:
        model = tomllib.loads(stored_toml).get("model")
    except (tomllib.TOMLDecodeError, TypeError):
        return None
    return model.get("module") if isinstance(model, dict) else None
