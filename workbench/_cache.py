"""On-disk caches: numba's compiled code of workbench's own functions and the generated per-model
kernels, each keyed by the code it is built from.

Numba's cache does not notice when a function that a cached function calls lives in another file
and changes (numba issue #6845). To make stale machine code impossible, the compiled code of a
workbench module is cached in a directory keyed by the digest of the code of that module and of
every workbench module it imports, transitively, with the versions of Python, numba and NumPy
(:func:`workbench._sources.code_digest`); the same digest replaces numba's own freshness stamp
(the file's modification time), so an edit of a docstring or comment recompiles nothing, an edit
of ``analysis/`` or ``plot/`` recompiles nothing, and an edit of one model recompiles that
model's code alone. A generated kernel module (:mod:`workbench.solver._compile`) carries the
digest of its own source and of what it imports in its name.

Only workbench's functions go there. :class:`WorkbenchCacheLocator` is a numba cache locator
(numba's per-function extension point, ``numba.core.caching.CacheImpl._locator_classes``) that
claims the functions whose module is part of the package or a generated kernel and declines every
other, which numba then caches as it always does. The process environment
(``NUMBA_CACHE_DIR``) and numba's configuration stay untouched, so other libraries' numba caches
are not redirected. Digests are computed on first use (the first compiled function looked up),
not at import.
"""

from __future__ import annotations

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
    "module_digest",
    "register_cache_locator",
]


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
    """Where the generated per-model kernel modules are written (see ``solver._compile``); their
    names carry the digest of their code."""
    return cache_root() / "kernels"


def module_digest(module: str) -> str:
    """The cache key of the compiled code of ``module``: the digest in a generated kernel's name
    (``<what>_<model>_<digest>``), else the digest of the module's code and imports."""
    if module.startswith(KERNEL_PACKAGE + "."):
        return module.rsplit("_", 1)[-1]
    from workbench._sources import code_digest

    return code_digest(module)


class WorkbenchCacheLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
    """Numba cache locator of workbench's own functions: ``cache_root()/numba/<digest>/``, with
    the digest of the function's module (:func:`module_digest`) as numba's freshness stamp.

    ``from_function`` returns None (numba tries its next locator) for a function that is not
    defined in a workbench module or a generated kernel (module ``workbench_kernels.*``).
    """

    def __init__(self, py_func, py_file: str) -> None:
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._digest = module_digest(py_func.__module__)
        subpath = self.get_suitable_cache_subpath(py_file)
        self._cache_path = str(cache_root() / "numba" / self._digest / subpath)

    def get_cache_path(self) -> str:
        return self._cache_path

    def get_source_stamp(self) -> str:
        """The code's digest instead of the file's modification time and size: a file touched
        or edited in its docstrings keeps its compiled code."""
        return self._digest

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
