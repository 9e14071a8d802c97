"""The grid of a campaign and its store on disk: manifest, block files, scene comparison.

Layout (``store`` is the path of the assembled archive, e.g. ``omega.nc``)::

    omega.nc                  assembled archive, written last (atomically)
    omega.nc.blocks/
        lock                  held (flock) by the one process writing the store; pid and host
        manifest.json         scene TOML, grid, chunk, campaign id (written first, atomically),
                              and the SHA-256 of every committed block (rewritten on each)
        block-00000.nc        points 0 .. chunk-1 (one file per task, written atomically;
                              netCDF-3 64-bit offset, half the write time of netCDF-4)
        block-00001.nc        ...

A block is *committed* when its checksum is in the manifest; on resume a block is reused only
if its file's SHA-256 matches, otherwise it is named and recomputed.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import re
import warnings
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from workbench._cache import package_digest
from workbench.archive import (
    StoreWarning,
    check_output_file,
    file_problem,
    mapping_diff,
    read_manifest,
    store_lock,
    write_text_atomic,
)
from workbench.models import get_model
from workbench.run import REALISATION_ATTRS
from workbench.scene import RUN_SWEEP_KEYS, Scene, SceneError, scene_from_toml

__all__ = ["CampaignError", "CampaignWarning", "Store", "SweepGrid", "expand_sweep"]

FORMAT = "workbench-campaign 2"  # 2: block checksums, lock
_BLOCK_RE = re.compile(r"^block-(\d{5,})\.nc$")
_TMP_RE = re.compile(r"^\.(block-\d{5,}\.nc|manifest\.json)\..*\.tmp$")


class CampaignError(ValueError):
    """A campaign cannot run as asked (e.g. its store holds a different campaign); the message
    says what differs and how to proceed."""


class CampaignWarning(StoreWarning):
    """Something about a campaign deserves attention (failed points, a changed package)."""


@dataclass(frozen=True)
class SweepGrid:
    """The points of a campaign: the outer product of the swept values, in C order (not to be
    confused with a run's record times, :func:`workbench.run.record_times`).

    Attributes
    ----------
    dims : tuple[str, ...]
        Swept parameter names, in the scene's ``[sweep]`` order (the dataset's leading dims).
    values : tuple[tuple[float, ...], ...]
        The values of each dim (SI units of the parameter).
    """

    dims: tuple[str, ...]
    values: tuple[tuple[float, ...], ...]

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for v in self.values)

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    def point(self, flat: int) -> dict[str, float]:
        """Parameter values of the point with flat (C-order) index ``flat``."""
        idx = np.unravel_index(flat, self.shape)
        return {
            d: self.values[k][int(i)] for k, (d, i) in enumerate(zip(self.dims, idx, strict=True))
        }

    def blocks(self, chunk: int) -> list[range]:
        """Flat point indices of each block of ``chunk`` points (the last may be shorter)."""
        return [range(s, min(s + chunk, self.size)) for s in range(0, self.size, chunk)]

    def as_dict(self) -> dict[str, list[float]]:
        return {d: list(v) for d, v in zip(self.dims, self.values, strict=True)}


def expand_sweep(scene: Scene) -> SweepGrid:
    """The grid of a scene's ``[sweep]`` (CampaignError if it has none)."""
    if not scene.sweep:
        raise CampaignError(
            "a campaign needs a [sweep] table naming at least one parameter, e.g. "
            "[sweep] gamma = {start = 0.2, stop = 0.5, num = 40}; this scene has none "
            "(run a single scene with workbench.simulate)"
        )
    dims = tuple(scene.sweep)
    return SweepGrid(dims, tuple(tuple(float(x) for x in scene.sweep[d]) for d in dims))


def forcing_period(scene: Scene, grid: SweepGrid, flat: int) -> float | None:
    """Forcing period (s) of the grid point ``flat`` (None for an autonomous model)."""
    params = dict(scene.resolved_parameters)
    params.update(grid.point(flat))
    return get_model(scene.model).forcing_period(params)


def parameter_attrs(scene: Scene, name: str) -> dict[str, str]:
    """``units`` and ``long_name`` of a model parameter (from its declaration), or of a swept
    ``[run]`` key (``realisation``)."""
    if name in RUN_SWEEP_KEYS:
        return dict(REALISATION_ATTRS)
    p = get_model(scene.model).parameter(name)
    return {"units": p.units, "long_name": p.long_name}


def format_point(point: Mapping[str, float]) -> str:
    return ", ".join(f"{k}={v:.6g}" for k, v in point.items())


def campaign_id(scene: Scene, chunk: int, per_point=None) -> str:
    """Digest of what fixes the content of every block: the scene, the chunk size and the
    function that measures each point (its qualified name; None: none)."""
    h = hashlib.sha256(scene.to_toml().encode())
    h.update(f"\nchunk={chunk}".encode())
    if per_point is not None:
        h.update(f"\nper_point={per_point.__module__}.{per_point.__qualname__}".encode())
    return h.hexdigest()[:16]


# -- the store -------------------------------------------------------------------------------------
class Store:
    """Paths and bookkeeping of one campaign store (see the module docstring)."""

    def __init__(self, archive: str | os.PathLike) -> None:
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

    def block_path(self, index: int) -> Path:
        return self.blocks_dir / f"block-{index:05d}.nc"

    # manifest
    def read_manifest(self) -> dict | None:
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
        return read_manifest(self.manifest_path, FORMAT, "the campaign", CampaignError)

    def write_manifest(self, scene: Scene, grid: SweepGrid, chunk: int, cid: str) -> dict:
        data = {
            "format": FORMAT,
            "campaign_id": cid,
            "scene": scene.to_toml(),
            "dims": list(grid.dims),
            "grid": grid.as_dict(),
            "chunk": chunk,
            "points": grid.size,
            "blocks": len(grid.blocks(chunk)),
            "package_digest": package_digest(),
            "checksums": {},
        }
        return self.save_manifest(data)

    def save_manifest(self, data: dict) -> dict:
        self.blocks_dir.mkdir(parents=True, exist_ok=True)
        write_text_atomic(self.manifest_path, json.dumps(data, indent=1) + "\n")
        return data

    def check_scene(self, stored_toml: str, scene: Scene, where: str) -> None:
        """CampaignError naming the differences if ``stored_toml`` is not ``scene``."""
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
        if manifest.get("package_digest") != package_digest():
            warnings.warn(
                CampaignWarning(
                    "the workbench package changed since this campaign started (source digest "
                    f"{manifest.get('package_digest')!r} -> {package_digest()!r}); blocks "
                    "computed before and after the change are combined. Pass restart=True for a "
                    "campaign computed by one version throughout."
                ),
                stacklevel=3,
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

    def verified_blocks(self, manifest: dict, blocks: list[range]) -> set[int]:
        """Indices of the committed blocks whose file is intact (its SHA-256 is the one in the
        manifest). Every other block is named in a CampaignWarning (missing, corrupt, or
        written but never committed) and will be recomputed; the manifest drops their
        checksums."""
        sums: dict[str, str] = manifest.setdefault("checksums", {})
        done, dropped = set(), False
        for i in range(len(blocks)):
            path = self.block_path(i)
            problem = file_problem(path, sums.get(str(i)))
            if problem is None:
                if str(i) in sums:
                    done.add(i)
                continue
            warnings.warn(
                CampaignWarning(f"block {i} ({path.name}) {problem}; recomputing"), stacklevel=3
            )
            if sums.pop(str(i), None) is not None:
                dropped = True
            with contextlib.suppress(OSError):
                path.unlink()
        if dropped:
            self.save_manifest(manifest)
        return done

    def commit(self, manifest: dict, block: int, sha256: str) -> None:
        """Record a finished block's checksum in the manifest (the block is then committed)."""
        manifest.setdefault("checksums", {})[str(block)] = sha256
        self.save_manifest(manifest)

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
