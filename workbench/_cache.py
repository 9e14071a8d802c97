"""On-disk caches: numba's compiled code and the generated per-model kernels.

Numba's cache does not notice when a function that a cached function calls lives in another file
and changes (numba issue #6845). To make stale machine code impossible, the cache directory is
keyed by a digest of the whole package source and of the numba version: any change of workbench
gives a fresh cache, and an unchanged package reuses it across processes (dask workers included).
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from functools import lru_cache
from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent


@lru_cache(maxsize=1)
def package_digest() -> str:
    """Short hex digest of every ``.py`` file of the package and of the numba version."""
    h = hashlib.sha256()
    for path in sorted(_PACKAGE_DIR.rglob("*.py")):
        h.update(str(path.relative_to(_PACKAGE_DIR)).encode())
        h.update(path.read_bytes())
    try:
        from importlib.metadata import version

        h.update(version("numba").encode())
    except Exception:  # pragma: no cover - numba is a hard dependency
        pass
    return h.hexdigest()[:16]


@lru_cache(maxsize=1)
def cache_root() -> Path:
    """Root of workbench's caches: ``$WORKBENCH_CACHE_DIR``, else ``~/.cache/workbench``, else a
    directory in the system temporary directory when the home directory is not writable."""
    candidates = []
    if os.environ.get("WORKBENCH_CACHE_DIR"):
        candidates.append(Path(os.environ["WORKBENCH_CACHE_DIR"]))
    candidates.append(Path.home() / ".cache" / "workbench")
    candidates.append(Path(tempfile.gettempdir()) / "workbench-cache")
    for c in candidates:
        try:
            c.mkdir(parents=True, exist_ok=True)
            probe = c / f".probe-{os.getpid()}"
            probe.write_text("")
            probe.unlink()
            return c
        except OSError:
            continue
    raise RuntimeError(f"no writable cache directory among {candidates!r}")


def configure_numba_cache() -> None:
    """Point numba's cache at a directory keyed by :func:`package_digest`, unless the user has set
    ``NUMBA_CACHE_DIR`` themselves."""
    if "NUMBA_CACHE_DIR" in os.environ:
        return
    path = cache_root() / "numba" / package_digest()
    path.mkdir(parents=True, exist_ok=True)
    os.environ["NUMBA_CACHE_DIR"] = str(path)
    import sys

    if "numba" in sys.modules:  # numba read its configuration already
        sys.modules["numba"].config.CACHE_DIR = str(path)
