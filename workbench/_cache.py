"""On-disk caches: numba's compiled code of workbench's own functions and the generated per-model
kernels, each keyed by the code it is built from, and loaded only if it is what workbench
compiled there.

Numba's cache does not notice when a function that a cached function calls lives in another file
and changes (numba issue #6845). To make stale machine code impossible, the compiled code of a
workbench module is cached in a directory keyed by the digest of the code of that module and of
every workbench module it imports, transitively, with the versions of Python, numba and NumPy
(:func:`workbench._sources.code_digest`); the same digest replaces numba's own freshness stamp
(the file's modification time), so an edit of a docstring or comment recompiles nothing, an edit
of ``analysis/`` or ``plot/`` recompiles nothing, and an edit of one model recompiles that
model's code alone. The directory is named after the package, not after where its files
lie, so a copy of the same code elsewhere (another checkout, environment or node) loads what
another copy compiled. A generated kernel module (:mod:`workbench.solver._compile`) carries the
digest of its own source and of what it imports in its name.

Only workbench's functions go there. :class:`WorkbenchCacheLocator` is a numba cache locator
(numba's per-function extension point, ``numba.core.caching.CacheImpl._locator_classes``) that
claims the functions whose module is part of the package or a generated kernel and declines every
other, which numba then caches as it always does. The process environment
(``NUMBA_CACHE_DIR``) and numba's configuration stay untouched, so other libraries' numba caches
are not redirected. Digests are computed on first use (the first compiled function looked up),
not at import.

Loading compiled code runs it (numba's index and data files are pickles), so the cache is
trusted only as far as who can write it:

- The root (:func:`cache_root`) must belong to the user and not be writable by group or others,
  else :class:`CacheError` names it, its owner and mode, and the fix. A cache that a team
  shares is an explicit opt-in, ``WORKBENCH_SHARED_CACHE=1``: its owner and group, who can
  write it, are trusted (it must still not be writable by others).
- When the home directory is not writable, the root is a folder of the system's temporary
  directory made by :func:`tempfile.mkdtemp` (an unpredictable name, mode 0700) and found again
  by the next process among the folders of that prefix that are the user's alone (owner, mode
  0700, not a link); any other is ignored.
- Every file workbench writes into ``numba/`` is recorded in ``digests/`` (a folder as private as
  the root): the SHA-256 of its bytes under its path. A file is loaded, from the bytes read once,
  only if they match a record; otherwise it is compiled again, with one :class:`CacheWarning`
  per process. Generated kernel modules are not read back at all: they are executed from the
  text :mod:`workbench.solver._compile` generates (the file is written for numba and tracebacks).
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import os
import pickle
import stat
import tempfile
import threading
import warnings
from dataclasses import dataclass
from pathlib import Path

from numba.core import caching

from workbench._errors import WorkbenchError

__all__ = [
    "CACHE_ENV",
    "KERNEL_PACKAGE",
    "SHARED_ENV",
    "CacheError",
    "CacheWarning",
    "WorkbenchCacheLocator",
    "cache_root",
    "kernel_directory",
    "module_digest",
    "read_regular",
    "read_trusted",
    "record_written",
    "register_cache_locator",
]

CACHE_ENV = "WORKBENCH_CACHE_DIR"  # where the cache is (else ~/.cache/workbench)
SHARED_ENV = "WORKBENCH_SHARED_CACHE"  # "1": a cache writable by its group, which is trusted
RECORDS = "digests"  # the folder of the digests of what workbench wrote, inside the root
TEMPORARY_PREFIX = "workbench-cache-"  # + uid + "-": the fallback folders in the temp directory


class CacheError(WorkbenchError, ValueError):
    """The kernel cache (``$WORKBENCH_CACHE_DIR``, ``~/.cache/workbench``) is refused before
    anything runs: it is not the user's, or others can write it, so compiled code found there
    could be someone else's. One line that names the folder, its owner and mode, and the fix
    (the command line: exit code 2, invalid input)."""


class CacheWarning(UserWarning):
    """A file of the kernel cache is not what workbench recorded writing there and is compiled
    again instead of loaded, a folder named like a generated module is ignored, or the cache is
    in a temporary folder (the home directory is not writable)."""


@dataclass(frozen=True)
class _Location:
    path: Path  # the root
    shared: bool  # the WORKBENCH_SHARED_CACHE opt-in
    refusal: str | None  # why the root cannot be used (CacheError's message), or None
    notice: str | None  # said once, at the first use (the temporary fallback)
    fresh: bool  # the records were made by this process: nothing was recorded before


def _me() -> int:
    return os.geteuid()


def _owner(uid: int) -> str:
    """A user's name, else ``uid N``."""
    try:
        import pwd

        return pwd.getpwuid(uid).pw_name
    except (ImportError, KeyError):
        return f"uid {uid}"


def _shared() -> tuple[bool, str | None]:
    value = os.environ.get(SHARED_ENV, "").strip()
    if value in ("", "0"):
        return False, None
    if value == "1":
        return True, None
    return False, f"{SHARED_ENV}: got {value!r}; allowed: 1 (a shared cache) or 0 (a private one)"


def _unsafe(path: Path, shared: bool, what: str = "the kernel cache") -> str | None:
    """Why folder ``path`` cannot hold compiled code that this process loads (one line with the
    fix), or None."""
    st = os.stat(path)
    mode = stat.S_IMODE(st.st_mode)
    if not stat.S_ISDIR(st.st_mode):
        return f"{what} {path} is not a folder; remove it, or set {CACHE_ENV} to another folder"
    found = f"{what} {path} (owner {_owner(st.st_uid)}, mode {mode:04o})"
    opt_in = f"; a cache shared with its group: {SHARED_ENV}=1 (docs/security.md)"
    if mode & stat.S_IWOTH:
        return (
            f"{found} is writable by every user, so compiled code found there could be anyone's; "
            f"chmod o-w {path} (go-w if it is yours alone), or set {CACHE_ENV} to a folder of "
            "your own"
        )
    if shared:
        return None
    if st.st_uid != _me():
        return (
            f"{found} is not yours (you are {_owner(_me())}), so compiled code found there "
            f"would be its owner's; set {CACHE_ENV} to a folder of your own{opt_in}"
        )
    if mode & stat.S_IWGRP:
        return (
            f"{found} is writable by its group, so compiled code found there could be theirs; "
            f"chmod go-w {path}, or set {CACHE_ENV} to a folder of your own{opt_in}"
        )
    return None


def _writable(path: Path) -> bool:
    """Whether folder ``path`` exists (made if needed, mode 0700) and a file can be written
    in it."""
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(dir=path, prefix=".probe-")
        os.close(fd)
        os.unlink(probe)
        return True
    except OSError:
        return False


def _temporary_root() -> tuple[Path, int]:
    """The user's folder in the system temporary directory: an existing one that is the user's
    alone (a folder, not a link, owned by the user, mode 0700), else a new one made by
    :func:`tempfile.mkdtemp` (unpredictable name, mode 0700). Also returns how many folders of
    the same prefix were ignored."""
    base = Path(tempfile.gettempdir())
    prefix = f"{TEMPORARY_PREFIX}{_me()}-"
    ignored = 0
    with os.scandir(base) as entries:
        candidates = sorted(e.name for e in entries if e.name.startswith(prefix))
    for name in candidates:
        try:
            st = os.lstat(base / name)
        except OSError:
            continue
        mine = stat.S_ISDIR(st.st_mode) and st.st_uid == _me()
        if mine and stat.S_IMODE(st.st_mode) == 0o700 and _writable(base / name):
            return base / name, ignored
        ignored += 1
    return Path(tempfile.mkdtemp(prefix=prefix, dir=base)), ignored


def _records(root: Path, shared: bool) -> tuple[str | None, bool]:
    """Check (make) the folder of digests in ``root``: (why it cannot be used, or None; whether
    this process made it)."""
    path = root / RECORDS
    fresh = False
    try:
        os.mkdir(path, 0o770 if shared else 0o700)
        fresh = True
    except FileExistsError:
        pass
    except OSError as exc:
        return f"the kernel cache's digests folder {path} cannot be made: {exc.strerror}", False
    if stat.S_ISLNK(os.lstat(path).st_mode):
        return f"the kernel cache's digests folder {path} is a link; remove it", False
    return _unsafe(path, shared, "the kernel cache's digests folder"), fresh


def _locate() -> _Location:
    """Where the cache is and whether it may be used (:func:`_location`: once per process)."""
    shared, refusal = _shared()
    candidates = [Path(os.environ[CACHE_ENV])] if os.environ.get(CACHE_ENV) else []
    with contextlib.suppress(RuntimeError):  # no home directory at all
        candidates.append(Path.home() / ".cache" / "workbench")
    notice = None
    for root in candidates:
        if _writable(root):
            break
    else:
        root, ignored = _temporary_root()
        shared = False  # the fallback is the user's alone
        notice = (
            f"the home directory is not writable: compiled code is cached in {root}, a folder "
            f"of yours alone (mode 0700) that later runs find again (set {CACHE_ENV} to choose "
            "another)"
        )
        if ignored:
            notice += f"; ignored {ignored} folder(s) named like it that are not yours alone"
    refusal = refusal or _unsafe(root, shared)
    fresh = False
    if refusal is None:
        refusal, fresh = _records(root, shared)
    return _Location(root, shared, refusal, notice, fresh)


_found: list[_Location] = []  # the location of this process, once found
_finding = threading.Lock()  # threads that look it up first find one (the fallback: one folder)


def _location() -> _Location:
    """:func:`_locate`, once per process."""
    with _finding:
        if not _found:
            _found.append(_locate())
        return _found[0]


_announced: set[str] = set()  # the notices said in this process
_lock = threading.Lock()


def _say_once(key: str, message: str) -> None:
    with _lock:
        if key in _announced:
            return
        _announced.add(key)
    warnings.warn(CacheWarning(message), stacklevel=3)


def cache_root() -> Path:
    """Root of workbench's caches: ``$WORKBENCH_CACHE_DIR``, else ``~/.cache/workbench``, else the
    user's folder in the system temporary directory when neither can be written. Raises
    :class:`CacheError` (one line: the path, its owner and mode, the fix) when
    the root or its digests folder could hold someone else's code: not the user's, or writable
    by group or others (with ``WORKBENCH_SHARED_CACHE=1``: writable by others)."""
    location = _location()
    if location.refusal is not None:
        raise CacheError(location.refusal)
    if location.notice:
        _say_once("notice", location.notice)
    return location.path


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


def read_regular(path: str | os.PathLike) -> bytes | None:
    """The bytes of ``path`` if it is a regular file (not a link, a folder, a FIFO or a device:
    read without following a link or blocking); None if there is no such file; OSError if it is
    something else."""
    try:
        if not stat.S_ISREG(os.lstat(path).st_mode):
            raise OSError(f"{path} is not a regular file")
    except FileNotFoundError:
        return None
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    fd = os.open(path, flags)
    with os.fdopen(fd, "rb") as f:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(f"{path} is not a regular file")
        return f.read()


def _record(root: Path, path: str | os.PathLike, data: bytes) -> Path:
    """The record of ``data`` written at ``path``: named by the digest of the path (relative to
    ``root``) and of the bytes, so that every version workbench wrote there is known."""
    relative = os.path.relpath(path, root)
    key = hashlib.sha256(f"{relative}\0{hashlib.sha256(data).hexdigest()}".encode()).hexdigest()
    return root / RECORDS / key[:2] / key[2:]


def record_written(path: str | os.PathLike, data: bytes) -> None:
    """Record that workbench writes ``data`` at ``path`` (a file under the cache root), before
    it writes it."""
    root = cache_root()
    record = _record(root, path, data)
    if record.exists():
        return
    record.parent.mkdir(mode=0o770 if _location().shared else 0o700, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=record.parent, prefix=".tmp-")
    with os.fdopen(fd, "w") as f:
        f.write(f"{hashlib.sha256(data).hexdigest()}  {os.path.relpath(path, root)}\n")
    os.replace(tmp, record)


def read_trusted(path: str | os.PathLike) -> bytes | None:
    """The bytes of cache file ``path`` if they are what workbench recorded writing there
    (:func:`record_written`); None if there is no file, and None with one
    :class:`CacheWarning` per process if it is anything else (the caller compiles anew)."""
    root = cache_root()
    try:
        data = read_regular(path)
    except OSError:
        data = b""  # a link, a folder, a FIFO, unreadable: never a recorded file
        found = False
    else:
        if data is None:
            return None
        found = _record(root, path, data).exists()
    if found:
        return data
    if not _location().fresh:  # a cache from before the records: nothing to warn about
        _say_once(
            "mismatch",
            f"{path} in the kernel cache does not match the digest recorded when workbench "
            "compiled it (changed since, or not written by workbench): compiling it again "
            "instead of loading it (further mismatches in this process are not reported)",
        )
    return None


_CLAIMED: set[str] = set()  # the cache paths of workbench's functions (WorkbenchCacheLocator)


class WorkbenchCacheLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
    """Numba cache locator of workbench's own functions: ``cache_root()/numba/<digest>/<package>``
    (the name of the function's package, wherever its files lie; a generated kernel's folder as
    numba names it), with the digest of the function's module (:func:`module_digest`) as
    numba's freshness stamp.

    ``from_function`` returns None (numba tries its next locator) for a function that is not
    defined in a workbench module or a generated kernel (module ``workbench_kernels.*``); it
    never declines one of them (numba's own locators would cache it unchecked).
    """

    def __init__(self, py_func, py_file: str) -> None:
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        module = py_func.__module__
        self._digest = module_digest(module)
        if module.startswith(KERNEL_PACKAGE + "."):  # its file lies in the cache: numba's way
            subpath = self.get_suitable_cache_subpath(py_file)
        else:
            # the package's name, not numba's hash of the folder: the digest keys the code, so
            # a copy of the package elsewhere (another checkout, environment or node) loads what
            # another copy of the same code compiled
            subpath = module.rpartition(".")[0] or module
        # the root unchecked: a function is decorated at import; loads and saves check it
        self._cache_path = str(_location().path / "numba" / self._digest / subpath)
        _CLAIMED.add(self._cache_path)

    def get_cache_path(self) -> str:
        return self._cache_path

    def get_source_stamp(self) -> str:
        """The code's digest instead of the file's modification time and size: a file touched
        or edited in its docstrings keeps its compiled code."""
        return self._digest

    def ensure_cache_path(self) -> None:
        """Make the folder where it can be (not in a refused root); never fail (the save does)."""
        if _location().refusal is None:
            with contextlib.suppress(OSError):
                super().ensure_cache_path()

    @classmethod
    def from_function(cls, py_func, py_file: str):
        module = getattr(py_func, "__module__", None) or ""
        if module.split(".")[0] not in ("workbench", KERNEL_PACKAGE):
            return None
        locator = cls(py_func, py_file)
        locator.ensure_cache_path()
        return locator


class CheckedIndexDataCacheFile(caching.IndexDataCacheFile):
    """Numba's index and data files, read and written as numba does, except those of workbench's
    functions (:class:`WorkbenchCacheLocator`'s paths): each is recorded when written
    (:func:`record_written`) and unpickled only from bytes that match a record
    (:func:`read_trusted`); anything else reads as not cached, and numba compiles anew."""

    def __init__(self, cache_path, filename_base, source_stamp) -> None:
        super().__init__(cache_path, filename_base, source_stamp)
        self._checked = cache_path in _CLAIMED

    def _load_index(self):
        if not self._checked:
            return super()._load_index()
        data = read_trusted(self._index_path)
        if data is None:
            return {}
        stream = io.BytesIO(data)
        if pickle.load(stream) != self._version:  # another numba's: not unpickled further
            return {}
        stamp, overloads = pickle.loads(stream.read())
        return overloads if stamp == self._source_stamp else {}

    def _load_data(self, name):
        if not self._checked:
            return super()._load_data(name)
        path = self._data_path(name)
        data = read_trusted(path)
        if data is None:  # numba's load() takes an OSError for "not cached"
            raise FileNotFoundError(path)
        return pickle.loads(data)

    def save(self, key, data):
        """Numba's save; for workbench's functions, a file that cannot be written (a full disk,
        a shared cache whose folders the group cannot write) leaves the function uncached, with
        one notice per process, instead of failing the run."""
        if not self._checked:
            return super().save(key, data)
        try:
            super().save(key, data)
        except OSError as exc:
            _say_once(
                "save",
                f"compiled code cannot be written to the kernel cache in {self._cache_path} "
                f"({exc.strerror or exc}): it is compiled again by the next process",
            )

    @contextlib.contextmanager
    def _open_for_write(self, filepath):
        if not self._checked:
            with super()._open_for_write(filepath) as f:
                yield f
            return
        buffer = io.BytesIO()
        yield buffer
        data = buffer.getvalue()
        record_written(filepath, data)
        with super()._open_for_write(filepath) as f:
            f.write(data)


def register_cache_locator() -> None:
    """Put :class:`WorkbenchCacheLocator` first among numba's locators, and numba's index and
    data files of workbench's functions under :class:`CheckedIndexDataCacheFile` (once). It must
    run before a workbench module defines a cached function: ``workbench/solver/__init__``
    calls it (models import the solver first)."""
    classes = caching.CacheImpl._locator_classes
    if WorkbenchCacheLocator not in classes:
        classes.insert(0, WorkbenchCacheLocator)
    if not issubclass(caching.IndexDataCacheFile, CheckedIndexDataCacheFile):
        caching.IndexDataCacheFile = CheckedIndexDataCacheFile
