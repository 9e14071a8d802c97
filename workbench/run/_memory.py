"""The memory a run's records (or a campaign's archive) will take, estimated before anything is
allocated, and the limit it must stay under.

A scene asks for its records by their number (``run.cycles`` x ``record.samples_per_period``,
or ``run.duration`` / ``record.dt``), which a typo can make astronomical (``cycles =
1000000000``: 745 GiB of records). :func:`prepare <workbench.run.prepare>` counts the records
and the values per record from the scene and the model's problem, and refuses a run whose
records would exceed the limit with :class:`MemoryLimitError` (a :class:`SceneError` naming the
key to lower), before the record times, the solver's arrays or the dataset exist.

The limit: the ``max_memory`` keyword (bytes, or text such as ``"16 GiB"``), else the
environment variable ``WORKBENCH_MAX_MEMORY`` (same forms), else half of this machine's memory
(the smaller of the physical memory and a cgroup's ``memory.max``).
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from pathlib import Path

from workbench._errors import SceneError

__all__ = [
    "MEMORY_ENV",
    "MemoryLimitError",
    "check_memory",
    "format_bytes",
    "memory_limit",
    "parse_bytes",
    "record_count",
    "values_per_record",
    "what_to_lower",
]

MEMORY_ENV = "WORKBENCH_MAX_MEMORY"
_UNITS = {
    "": 1,
    "b": 1,
    "k": 1e3,
    "kb": 1e3,
    "m": 1e6,
    "mb": 1e6,
    "g": 1e9,
    "gb": 1e9,
    "t": 1e12,
    "tb": 1e12,
    "kib": 2**10,
    "mib": 2**20,
    "gib": 2**30,
    "tib": 2**40,
}
_BYTES_RE = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([a-zA-Z]*)\s*$")


class MemoryLimitError(SceneError):
    """The records of a run (or a campaign's archive) would exceed the memory limit. The message
    names the estimate, the limit and where it comes from, what to lower and how to raise it.

    Attributes
    ----------
    needed, limit : float
        Bytes.
    """

    def __init__(self, key: str, message: str, needed: float = math.nan, limit: float = math.nan):
        super().__init__(key, message)
        self.needed = needed
        self.limit = limit

    def __reduce__(self):  # keeps the numbers across processes (a campaign's workers)
        return (type(self), (self.key, str(self)[len(self.key) + 2 :], self.needed, self.limit))


def format_bytes(n: float) -> str:
    """``n`` bytes for a person: ``"745 GiB"``, ``"9.1 MiB"``, ``"512 B"``."""
    if not math.isfinite(n):
        return str(n)
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if abs(n) >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} B"


def parse_bytes(value: float | int | str, key: str) -> float:
    """A number of bytes from a number (bytes, > 0; ``inf``: no limit) or text such as
    ``"16 GiB"``, ``"500MB"``, ``"2e9"`` (units B, kB, MB, GB, TB, KiB, MiB, GiB, TiB; case
    ignored). ValueError naming ``key`` otherwise."""
    allowed = (
        "allowed: a number of bytes > 0, 'inf', or a size such as '16 GiB' or '500 MB' (units "
        "B, kB, MB, GB, TB, KiB, MiB, GiB, TiB)"
    )
    if isinstance(value, str):
        text = value.strip().lower()
        if text in ("inf", "infinity", "none"):
            return math.inf
        m = _BYTES_RE.match(text)
        if m is None or m.group(2) not in _UNITS:
            raise ValueError(f"{key}: got {value!r}; {allowed}")
        n = float(m.group(1)) * _UNITS[m.group(2)]
    elif isinstance(value, int | float) and not isinstance(value, bool):
        n = float(value)
    else:
        raise ValueError(f"{key}: got {value!r}; {allowed}")
    if not n > 0:  # NaN fails it too
        raise ValueError(f"{key}: got {value!r}; {allowed}")
    return n


def _machine_memory() -> float:
    """Bytes of memory this process may use: the physical memory, or a cgroup's limit if
    smaller (a container)."""
    try:
        total = float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        total = 8.0 * 2**30
    for path in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            text = Path(path).read_text().strip()
        except OSError:
            continue
        if text.isdigit() and 0 < int(text) < total:
            total = float(text)
    return total


def memory_limit(max_memory: float | int | str | None = None) -> tuple[float, str]:
    """The memory limit in bytes and where it comes from (for messages): ``max_memory`` if
    given, else the environment variable ``WORKBENCH_MAX_MEMORY``, else half of this machine's
    memory."""
    if max_memory is not None:
        return parse_bytes(max_memory, "max_memory"), "max_memory"
    env = os.environ.get(MEMORY_ENV)
    if env:
        return parse_bytes(env, MEMORY_ENV), MEMORY_ENV
    total = _machine_memory()
    return total / 2, f"half of this machine's {format_bytes(total)}"


def record_count(run: Mapping, record: Mapping, period: float | None) -> int:
    """The number of records of a run (the length of :func:`workbench.run.record_times`),
    computed without building them."""
    if period is not None and "cycles" in run:
        spp = record.get("samples_per_period")
        if spp is None:
            spp = max(1, round(period / record["dt"]))
        return int(run["cycles"]) * int(spp) + 1
    if "samples_per_period" in record and period is not None:
        dt = period / record["samples_per_period"]
    else:
        dt = record["dt"]
    n = run["duration"] / dt * (1 + 1e-12)
    return int(math.floor(n)) + 1 if math.isfinite(n) else 2**63


def values_per_record(model, effects: Mapping, variables, states=()) -> int:
    """Floats a record of ``variables`` holds: each variable's size (its model dims' lengths
    multiplied), the states among them counted once in ``states`` (the solver's record of the
    whole state; names), plus one for the time."""
    sizes = {d: len(v) for d, (v, _) in model.coords(effects).items()}
    declared = model.variables(effects)
    n = 1 + len(states)
    for name in variables:
        if name not in states:
            n += math.prod(sizes[d] for d in declared[name].dims)
    return n


def what_to_lower(run: Mapping, record: Mapping) -> tuple[str, str]:
    """The scene key that sets the number of records, and what to change to have fewer."""
    key = "run.cycles" if "cycles" in run else "run.duration"
    if "dt" in record:
        return key, f"lower {key} or raise record.dt"
    return key, f"lower {key} or record.samples_per_period"


def check_memory(
    needed: float,
    *,
    what: str,
    count: str,
    key: str,
    lower: str,
    max_memory: float | int | str | None = None,
) -> None:
    """Refuse (:class:`MemoryLimitError` naming ``key``) an estimate of ``needed`` bytes above
    the limit (:func:`memory_limit`). ``what`` names what takes the memory ("the records of
    this run"), ``count`` how it was counted, ``lower`` what to lower."""
    limit, source = memory_limit(max_memory)
    if needed <= limit:
        return
    raise MemoryLimitError(
        key,
        f"{what} would take {format_bytes(needed)} of memory ({count}), more than the limit of "
        f"{format_bytes(limit)} ({source}); {lower}, or record fewer variables "
        f"(record.variables); or raise the limit (max_memory=, --max-memory, or the "
        f"environment variable {MEMORY_ENV}, e.g. '64 GiB')",
        needed,
        limit,
    )
