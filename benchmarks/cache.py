"""The edit-test cycle: what an edit costs in recompilation, with the kernel cache keyed by the
code a kernel is built from (this tree) against a baseline commit (by default 37099d8, whose
cache was keyed by a digest of the whole package), measured in the same run.

For each tree (a copy of its ``workbench/`` package in a temporary directory, with a cache of its
own) a fresh process simulates one cycle of ``--model`` after each step: an empty cache (cold),
an unchanged package (warm), then one edit at a time: a line of code appended to the analysis
layer, a docstring of the model's module edited, a line of code appended to another model, a line
of code appended to the model's module. Each row is the process's wall and CPU time (user + system,
load-insensitive) and whether the kernel was compiled (numba's cache index of the kernel's
``advance`` was empty before the run). A process that only loads takes a few seconds of imports.

Run: ``python benchmarks/cache.py [--model ninebar] [--baseline 37099d8]``; writes its table to
``benchmarks/results/cache-MODEL.md`` (with date, commit and machine) and prints it.
``--cold`` measures the first row alone (this tree, an empty cache: what a first run costs).
Either way the cold row is the model's record in ``workbench/campaign/compile_times.json``, which
the command line's notice before a first compile quotes (CPU and wall time, the machine's
cores and load).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import workbench.models

ROOT = Path(__file__).resolve().parents[1]

PROBE = """
import sys, time
import workbench
from workbench.run import prepare
scene = {"model": {"name": sys.argv[1]}, "run": {"cycles": 1}}
hooks = prepare(scene).problem.hooks
try:
    from workbench.solver._compile import kernel_for
    cached = bool(kernel_for(hooks).advance._cache._cache_file._load_index())
except Exception:
    cached = None
workbench.simulate(scene)
print("CACHED", cached)
"""

OTHER = {"ninebar": "models/lorenz.py", "duffing": "models/lorenz.py"}
MODULE = {"ninebar": "models/ninebar/_dynamics.py", "duffing": "models/duffing.py"}
RECORD = ROOT / "workbench" / "campaign" / "compile_times.json"


def _tree(rev: str | None, where: Path) -> Path:
    """A copy of the package at ``rev`` (None: this working tree) under ``where``."""
    where.mkdir(parents=True)
    if rev is None:
        shutil.copytree(
            ROOT / "workbench", where / "workbench", ignore=shutil.ignore_patterns("__pycache__")
        )
    else:
        archive = subprocess.run(
            ["git", "-C", str(ROOT), "archive", rev, "workbench"], check=True, capture_output=True
        ).stdout
        subprocess.run(["tar", "-x", "-C", str(where)], input=archive, check=True)
    return where


def _run(where: Path, model: str) -> tuple[float, float, str]:
    """One process of the probe in the copy at ``where``: wall and CPU seconds, and whether the
    kernel was loaded or compiled."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(WORKBENCH_CACHE_DIR=str(where / "cache"), PYTHONPATH=str(where))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    import time

    t0 = time.perf_counter()
    out = subprocess.run(
        [sys.executable, "-c", PROBE, model],
        cwd=where,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    cached = out.split("CACHED")[-1].strip()
    return wall, cpu, {"True": "loaded", "False": "compiled"}.get(cached, "?")


def _edit(where: Path, relative: str, docstring: bool = False) -> None:
    path = where / "workbench" / relative
    text = path.read_text()
    if docstring:
        text = text.replace('"""', '"""An edited docstring. ', 1)
    else:
        text += "\nX_EDITED = 1\n"
    path.write_text(text)


def measure(
    rev: str | None, model: str, scratch: Path, cold: bool = False
) -> list[tuple[str, float, float, str]]:
    """The rows of one tree (``cold``: the first alone)."""
    where = _tree(rev, scratch / (rev or "this"))
    if cold:
        return [("cold (empty cache)", *_run(where, model))]
    steps = [
        ("cold (empty cache)", None),
        ("warm (unchanged)", None),
        ("code line appended to analysis/_zero_one.py", ("analysis/_zero_one.py", False)),
        (f"docstring of {MODULE[model]} edited", (MODULE[model], True)),
        (f"code line appended to {OTHER[model]}", (OTHER[model], False)),
        (f"code line appended to {MODULE[model]}", (MODULE[model], False)),
    ]
    rows = []
    for label, edit in steps:
        if edit is not None:
            _edit(where, *edit)
        rows.append((label, *_run(where, model)))
    return rows


def record_cold(model: str, wall: float, cpu: float, load: tuple, command: str, head: str) -> None:
    """Write the cold row of ``model`` into workbench/campaign/compile_times.json (the other
    models' records stay)."""
    records = json.loads(RECORD.read_text()) if RECORD.exists() else {}
    records[model] = {
        "cpu_seconds": round(cpu, 1),
        "wall_seconds": round(wall, 1),
        "load": [round(load[0], 1), round(load[1], 1)],  # 1-min average before, after
        "cores": os.cpu_count(),
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d"),
        "commit": head,
        "command": command,
    }
    RECORD.write_text(json.dumps(dict(sorted(records.items())), indent=1) + "\n")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    # every model can be measured cold; the edit steps are defined for the models of MODULE
    ap.add_argument("--model", default="ninebar", choices=workbench.models.available_models())
    ap.add_argument("--baseline", default="37099d8", help="git revision of the baseline")
    ap.add_argument("--cold", action="store_true", help="the cold row of this tree alone")
    args = ap.parse_args()
    if args.model not in MODULE and not args.cold:
        ap.error(f"--model {args.model} is measured with --cold only")
    head = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    dirty = subprocess.run(
        ["git", "-C", str(ROOT), "status", "--porcelain", "--", "workbench"]
        + [f":(exclude){RECORD.relative_to(ROOT)}"],
        capture_output=True,
        text=True,
    ).stdout.strip()
    head += "-dirty" if dirty else ""
    command = f"python benchmarks/cache.py --model {args.model}" + (
        " --cold" if args.cold else f" --baseline {args.baseline}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        load0 = os.getloadavg()
        ours = measure(None, args.model, Path(tmp), cold=args.cold)
        record_cold(args.model, *ours[0][1:3], (load0[0], os.getloadavg()[0]), command, head)
        print(f"{ours[0][0]}: {ours[0][1]:.1f} s wall, {ours[0][2]:.1f} s CPU -> {RECORD}")
        if args.cold:
            return
        base = measure(args.baseline, args.model, Path(tmp))
    load = os.getloadavg()
    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    lines = [
        f"# Kernel cache: the edit-test cycle ({args.model})",
        "",
        f"`python benchmarks/cache.py --model {args.model} --baseline {args.baseline}` on {now}, "
        f"commit {head} (working tree) against {args.baseline}; {platform.machine()}, "
        f"{os.cpu_count()} CPUs, load {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}. One process "
        "per row: import, prepare, one simulated cycle; CPU = user + system time.",
        "",
        "| step | this tree: wall s | CPU s | kernel | baseline: wall s | CPU s | kernel |",
        "|---|---|---|---|---|---|---|",
    ]
    for (label, w, c, k), (_, bw, bc, bk) in zip(ours, base, strict=True):
        lines.append(f"| {label} | {w:.1f} | {c:.1f} | {k} | {bw:.1f} | {bc:.1f} | {bk} |")
    edits = slice(2, 5)
    ours_cpu = sum(r[2] for r in ours[edits])
    base_cpu = sum(r[2] for r in base[edits])
    lines += [
        "",
        f"The three edits outside the model's code: {ours_cpu:.1f} s CPU here against "
        f"{base_cpu:.1f} s in the baseline ({base_cpu / ours_cpu:.1f}x).",
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    out = ROOT / "benchmarks" / "results" / f"cache-{args.model}.md"
    out.write_text(text)
    print(f"-> {out}")


if __name__ == "__main__":
    main()
