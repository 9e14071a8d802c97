"""What the benchmarks measured: one JSON record per run, and the page generated from them.

Each benchmark runs its ``main()`` inside :func:`recording` and hands its key figures to
:func:`record` as named numbers (nested dicts of numbers, strings, booleans and lists of
them). What it prints still goes to the terminal; when the run ends, it is written as one file,
``benchmarks/records/<benchmark>/<start>-<commit>.json``:

- ``benchmark`` (the script's name), ``command`` (as it was run), ``outcome`` ("completed" or
  "failed: ..."), ``note`` (said by hand about the run, else absent);
- ``started`` (UTC, ISO 8601), ``commit`` (short; ``-dirty`` with uncommitted changes: the
  code that ran), ``machine`` (processor, cores, memory, system, Python);
- ``load_before``, ``load_after`` (the load average over 1, 5 and 15 min: timings on a shared
  machine drift with it), ``cpu_seconds`` (the process's), ``wall_seconds``;
- ``figures``: what the script recorded; ``output``: what it printed.

Then ``benchmarks/RESULTS.md`` is generated anew from every record and the measurements made
by hand (``benchmarks/NOTES.md``): the newest run of each command, what it printed, and every
run. ``python benchmarks/_results.py`` generates it again (after a merge brought records from
elsewhere, or after NOTES.md changed); the suite checks that the page is current.
``WORKBENCH_RESULTS=0`` runs a benchmark without recording it, ``WORKBENCH_RESULTS=DIR`` records
into DIR (and leaves the page alone).

Why these records and not asv (airspeed velocity, the field's tool for benchmark histories):
the page says it, at its head (:data:`HEADER`).
"""

from __future__ import annotations

import contextlib
import datetime
import io
import json
import math
import os
import platform
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

__all__ = ["load_records", "machine", "record", "recording", "records_dir", "render"]

ROOT = Path(__file__).resolve().parents[1]
RECORDS = ROOT / "benchmarks" / "records"
NOTES = ROOT / "benchmarks" / "NOTES.md"
PAGE = ROOT / "benchmarks" / "RESULTS.md"

#: benchmarks whose script was replaced: their records stay (each names the commit whose script
#: made it), and the page says what replaced the script
RETIRED = {
    "fourbar_branch.py": "`declared_branch.py --system fourbar` (every label checked, not only "
    "the grazings)",
}

#: the figures of the recording under way (None outside one)
_figures: dict | None = None


def records_dir() -> Path | None:
    """Where runs are recorded (None: ``WORKBENCH_RESULTS=0``)."""
    target = os.environ.get("WORKBENCH_RESULTS", "")
    if target == "0":
        return None
    return Path(target) if target else RECORDS


def _git(*args: str) -> str:
    try:
        out = subprocess.run(
            ["git", *args], cwd=ROOT, capture_output=True, text=True, timeout=10, check=True
        )
    except (OSError, subprocess.SubprocessError):
        return ""
    return out.stdout.strip()


def commit() -> str:
    """The short commit of the working tree, with ``-dirty`` if it has uncommitted changes."""
    sha = _git("rev-parse", "--short", "HEAD") or "unknown"
    dirty = _git("status", "--porcelain", "--untracked-files=no")
    return f"{sha}-dirty" if dirty else sha


def machine() -> str:
    """CPU model, cores and memory of this machine, and the Python that ran."""
    cpu = platform.processor() or platform.machine()
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    memory = ""
    with contextlib.suppress(OSError, ValueError, IndexError):
        kb = int(Path("/proc/meminfo").read_text().split()[1])
        memory = f", {kb / 2**20:.0f} GiB"
    return (
        f"{cpu}, {os.cpu_count()} cores{memory}; {platform.system()} {platform.release()}; "
        f"Python {platform.python_version()}"
    )


def _load() -> list[float] | None:
    with contextlib.suppress(OSError, AttributeError):
        return [round(v, 2) for v in os.getloadavg()]
    return None


def _plain(value, where: str = "figures"):
    """``value`` as JSON holds it: numpy scalars and arrays become numbers and lists, a
    non-finite number None; anything else than numbers, strings, booleans, None, lists and
    dicts (with string keys) is refused."""
    if hasattr(value, "tolist") and not isinstance(value, str | bytes):
        value = value.tolist()  # numpy scalars and arrays
    if value is None or isinstance(value, bool | str | int):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, list | tuple):
        return [_plain(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, dict):
        return {str(k): _plain(v, f"{where}[{k!r}]") for k, v in value.items()}
    raise TypeError(
        f"{where} is a {type(value).__name__}; a benchmark records numbers, strings, booleans, "
        "lists and dicts of them"
    )


def record(figures: dict) -> None:
    """Add named figures to the record of the run under way (nested dicts merge key by key);
    outside :func:`recording` they go nowhere."""
    if _figures is None:
        return

    def merge(into: dict, new: dict) -> None:
        for key, value in new.items():
            if isinstance(value, dict) and isinstance(into.get(key), dict):
                merge(into[key], value)
            else:
                into[key] = value

    merge(_figures, _plain(dict(figures)))


class _Tee(io.TextIOBase):
    def __init__(self, stream):
        self.stream, self.buffer = stream, io.StringIO()

    def write(self, text: str) -> int:
        self.buffer.write(text)
        return self.stream.write(text)

    def flush(self) -> None:
        self.stream.flush()


def _record_path(directory: Path, entry: dict) -> Path:
    """``<benchmark>/<start>-<commit>.json`` in ``directory``, numbered if taken."""
    stamp = entry["started"].replace("-", "").replace(":", "")
    base = directory / entry["benchmark"].removesuffix(".py") / f"{stamp}-{entry['commit']}"
    path, n = base.with_suffix(".json"), 1
    while path.exists():
        n += 1
        path = base.with_name(f"{base.name}-{n}.json")
    return path


def write_record(entry: dict, directory: Path) -> Path:
    """Write one run's record (atomically) and return its path."""
    path = _record_path(directory, entry)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(path.name + ".partial")
    partial.write_text(json.dumps(entry, indent=1, ensure_ascii=False) + "\n")
    partial.replace(path)
    return path


@contextlib.contextmanager
def recording(script: str | None = None) -> Iterator[None]:
    """Run the body with its stdout copied and :func:`record` collecting its figures, then
    write the run's record (``script``: the benchmark's path, by default the command's) and
    generate RESULTS.md anew; a body that raises is recorded as failed and the error goes on."""
    global _figures
    directory = records_dir()
    script = script or sys.argv[0]
    started = datetime.datetime.now(datetime.UTC)
    measured = commit()  # the code that runs: the tree may move on during a long run
    load_before, cpu0, wall0 = _load(), time.process_time(), time.perf_counter()
    tee = _Tee(sys.stdout)
    outcome = "completed"
    _figures = {}
    try:
        with contextlib.redirect_stdout(tee):
            yield
    except BaseException as exc:
        outcome = f"failed: {type(exc).__name__}: {exc}"
        raise
    finally:
        figures, _figures = _figures, None
        if directory is not None:
            name = Path(script).name
            entry = {
                "benchmark": name,
                "command": " ".join(["python", f"benchmarks/{name}", *sys.argv[1:]]),
                "outcome": outcome,
                "started": f"{started:%Y-%m-%dT%H:%M:%SZ}",
                "commit": measured,
                "machine": machine(),
                "load_before": load_before,
                "load_after": _load(),
                "cpu_seconds": round(time.process_time() - cpu0, 2),
                "wall_seconds": round(time.perf_counter() - wall0, 2),
                "figures": figures,
                "output": tee.buffer.getvalue().rstrip(),
            }
            path = write_record(entry, directory)
            print(f"recorded in {path}", file=sys.stderr)
            if directory == RECORDS:
                PAGE.write_text(render(load_records(directory), NOTES.read_text()))


def _finished(entry: dict) -> float:
    """When a run ended (s since the epoch): its start and wall time."""
    start = datetime.datetime.fromisoformat(entry["started"].replace("Z", "+00:00"))
    return start.timestamp() + entry["wall_seconds"]


def load_records(directory: Path | None = None, benchmark: str | None = None) -> list[dict]:
    """Every record in ``directory`` (default: benchmarks/records/; of one ``benchmark``, e.g.
    "lle.py", if given), in the order the runs ended; each with ``file``, its path relative to
    the repository."""
    found = []
    for path in sorted((directory or RECORDS).glob("*/*.json")):
        entry = json.loads(path.read_text())
        if benchmark is None or entry["benchmark"] == benchmark:
            with contextlib.suppress(ValueError):
                path = path.relative_to(ROOT)
            found.append(entry | {"file": str(path)})
    return sorted(found, key=_finished)


def _when(entry: dict) -> str:
    return entry["started"].replace("T", " ")[:16] + " UTC"


def _load_text(load: list[float] | None) -> str:
    return "unknown" if load is None else " / ".join(f"{v:.1f}" for v in load)


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


HEADER = """# Benchmark results

Generated by `python benchmarks/_results.py` from the records in `benchmarks/records/` (one
JSON file per run of a script in `benchmarks/`: its command, commit, machine, load, CPU and
wall time, the figures it recorded and what it printed) and the measurements made by hand in
`benchmarks/NOTES.md`; edit those, not this page. Timings on a shared machine drift with its
load (given before and after each run); step and evaluation counts are exact. The newest run of
a command is its current figure; older ones are history.

Why not asv (airspeed velocity, the field's tool for benchmark histories): asv builds a fresh
environment for each commit it measures and times small functions repeatedly, each within a
timeout (60 s by default). These benchmarks are long stateful scripts (minutes to most of an
hour) whose first run in a fresh environment compiles numba kernels for minutes; many of their
figures are counts, and estimates with errors, rather than timings; they run on a shared machine
whose load belongs in the record; and the docs quote runs of uncommitted working trees
(`-dirty`), which asv does not measure. A record holds what asv's results hold (commit,
machine, date, the numbers) as plain JSON that another tool can read.
"""


def render(entries: list[dict], notes: str) -> str:
    """The page: the newest run of each command with what it printed, every run of each
    benchmark, then the notes made by hand (``notes``, NOTES.md's text without its title)."""
    benchmarks = sorted({e["benchmark"] for e in entries})
    newest: dict[str, dict] = {}
    for e in entries:
        newest[e["command"]] = e
    lines = [HEADER, "## The newest run of each command", ""]
    lines += ["| command | started | commit | CPU | wall | load before; after |", "|---" * 6 + "|"]
    for e in sorted(newest.values(), key=lambda e: (e["benchmark"], e["command"])):
        lines.append(
            f"| `{_cell(e['command'])}` | {_when(e)} | {e['commit']} | {e['cpu_seconds']:.1f} s "
            f"| {e['wall_seconds']:.1f} s | {_load_text(e['load_before'])}; "
            f"{_load_text(e['load_after'])} |"
        )
    for name in benchmarks:
        runs = [e for e in entries if e["benchmark"] == name]
        lines += ["", f"## {name}", ""]
        if name in RETIRED:
            lines += [f"Retired: replaced by {RETIRED[name]}; its records stay.", ""]
        lines += ["What the newest run of each command printed:", ""]
        for e in [e for e in newest.values() if e["benchmark"] == name]:
            outcome = "" if e["outcome"] == "completed" else f" ({e['outcome']})"
            lines += [f"`{e['command']}`, {_when(e)}, {e['commit']}{outcome}:", ""]
            lines += ["```", e["output"], "```", ""]
        lines += ["Every run, in the order they ended:", ""]
        lines += ["| started | commit | command | CPU | wall | record |", "|---" * 6 + "|"]
        for e in runs:
            note = f" ({_cell(e['note'])})" if e.get("note") else ""
            failed = "" if e["outcome"] == "completed" else f" ({_cell(e['outcome'])})"
            lines.append(
                f"| {_when(e)} | {e['commit']} | `{_cell(e['command'])}`{failed}{note} "
                f"| {e['cpu_seconds']:.1f} s | {e['wall_seconds']:.1f} s | `{e['file']}` |"
            )
    body = notes.split("\n", 1)[1].lstrip("\n") if notes.startswith("# ") else notes
    lines += ["", "## Measured by hand", "", body.rstrip(), ""]
    return "\n".join(lines)


def main() -> None:
    """Generate RESULTS.md from the records and NOTES.md."""
    PAGE.write_text(render(load_records(), NOTES.read_text()))
    print(f"wrote {PAGE}")


if __name__ == "__main__":
    main()
