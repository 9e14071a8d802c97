"""On-disk caches: numba's compiled code of workbench's own functions and the generated per-model
kernels.

Numba's cache does not notice when a function that a cached function calls lives in another file
and changes (numba issue #6845). To make stale machine code impossible, workbench's functions are
cached in a directory keyed by a digest of the whole package source and of the numba version:
any change of workbench gives a fresh cache, and an unchanged package reuses it across processes
(dask workers included).

Only workbench's functions go there. :class:`WorkbenchCacheLocator` is a numba cache locator
(numba's per-function extension point, ``numba.core.caching.CacheImpl._locator_classes``) that
claims the functions whose source file lies in the package or in the generated-kernel directory
and declines every other, which numba then caches as it always does. The process environment
(``NUMBA_CACHE_DIR``) and numba's configuration stay untouched, so other libraries' numba caches
are not redirected. The digest is computed on first use (the first compiled function looked up),
not at import.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from functools import lru_cache
from pathlib import Path

from numba.core import caching

__all__ = [
    "KERNEL_PACKAGE",
    "WorkbenchCacheLocator",
    "cache_root",
    "kernel_directory",
    "package_digest",
    "register_cache_locator",
]

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


KERNEL_PACKAGE = "workbench_kernels"  # module prefix of the generated kernels


def kernel_directory() -> Path:
    """Where the generated per-model kernel modules are written (see ``solver._compile``)."""
    return cache_root() / "kernels" / package_digest()


class WorkbenchCacheLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
    """Numba cache locator of workbench's own functions: ``cache_root()/numba/<digest>/``.

    ``from_function`` returns None (numba tries its next locator) for a function that is not
    defined in a workbench module or a generated kernel (module ``workbench_kernels.*``).
    """

    def __init__(self, py_func, py_file: str) -> None:
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        subpath = self.get_suitable_cache_subpath(py_file)
        self._cache_path = str(cache_root() / "numba" / package_digest() / subpath)

    def get_cache_path(self) -> str:
        return self._cache_path

    @classmethod
    def from_function(cls, py_func, py_file: str):
        module = getattr(py_func, "__module__", None) or ""
        if module.split(".")[0] not in ("workbench", KERNEL_PACKAGE):
            return None
        return super().from_function(py_func, py_file)


def register_cache_locator() -> None:
    """Put :class:`WorkbenchCacheLocator` first among numba's locators (once). It must run
    before a workbench module defines a cached function: ``workbench/__init__`` calls it."""
    classes = caching.CacheImpl._locator_classes
    if WorkbenchCacheLocator not in classes:
        classes.insert(0, WorkbenchCacheLocator)
