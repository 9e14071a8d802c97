"""What a benchmark measured, appended to ``benchmarks/RESULTS.md`` with when, at which commit
and on which machine (issue 26: measured results live in a file the benchmarks write, not in
the README).

Each benchmark runs its ``main()`` inside :func:`recording`: what it prints still goes to the
terminal, and is appended, as printed, to RESULTS.md under a heading with the date (UTC), the
commit (``-dirty`` with uncommitted changes), the command, the machine (CPU model, cores,
memory) and the load average before and after, with the process's CPU and wall times. Set
``WORKBENCH_RESULTS=0`` to run a benchmark without recording it, or ``WORKBENCH_RESULTS=PATH``
to record elsewhere.
"""

from __future__ import annotations

import contextlib
import datetime
import io
import os
import platform
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

__all__ = ["machine", "recording", "results_path"]

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "RESULTS.md"
HEADER = """# Benchmark results

Appended by the scripts in `benchmarks/` (`benchmarks/_results.py`): each entry is one run, as
it printed, with its date, commit, command and machine. Timings on a shared machine drift with
its load (given before and after each run); step and evaluation counts are exact. The newest
entry of a benchmark is its current figure; older ones are history.
"""


def results_path() -> Path | None:
    """Where to record (None: ``WORKBENCH_RESULTS=0``)."""
    target = os.environ.get("WORKBENCH_RESULTS", "")
    if target == "0":
        return None
    return Path(target) if target else RESULTS


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


def _load() -> str:
    with contextlib.suppress(OSError, AttributeError):
        return " / ".join(f"{v:.1f}" for v in os.getloadavg())
    return "unknown"


class _Tee(io.TextIOBase):
    def __init__(self, stream):
        self.stream, self.buffer = stream, io.StringIO()

    def write(self, text: str) -> int:
        self.buffer.write(text)
        return self.stream.write(text)

    def flush(self) -> None:
        self.stream.flush()


@contextlib.contextmanager
def recording(script: str) -> Iterator[None]:
    """Run the body with its stdout copied, then append the entry of ``script`` (its path) to
    RESULTS.md; a body that raises is recorded as failed and the error goes on."""
    path = results_path()
    started = datetime.datetime.now(datetime.UTC)
    measured = commit()  # the code that runs: the tree may move on during a long run
    load_before, cpu0, wall0 = _load(), time.process_time(), time.perf_counter()
    tee = _Tee(sys.stdout)
    outcome = "completed"
    try:
        with contextlib.redirect_stdout(tee):
            yield
    except BaseException as exc:
        outcome = f"failed: {type(exc).__name__}: {exc}"
        raise
    finally:
        if path is not None:
            name = Path(script).name
            command = " ".join(["python", f"benchmarks/{name}", *sys.argv[1:]])
            entry = (
                f"\n## {name}: {started:%Y-%m-%d %H:%M} UTC, commit {measured}\n\n"
                f"- command: `{command}` ({outcome})\n"
                f"- machine: {machine()}\n"
                f"- load average (1/5/15 min) before: {load_before}, "
                f"after: {_load()}\n"
                f"- CPU time {time.process_time() - cpu0:.1f} s, wall time "
                f"{time.perf_counter() - wall0:.1f} s\n\n"
                "```\n" + tee.buffer.getvalue().rstrip() + "\n```\n"
            )
            new = not path.exists()
            with open(path, "a") as f:
                if new:
                    f.write(HEADER)
                f.write(entry)
            print(f"recorded in {path}", file=sys.stderr)
