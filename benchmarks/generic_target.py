"""What compiling for numba's baseline processor costs: the nine-bar's default scene with kernels
compiled for this host and for ``NUMBA_CPU_NAME=generic`` (docs/cluster.md, "Mixed processors";
``make test-generic``).

Each target runs in a process of its own (the generic kernels in their own cache folder, as
``make test-generic`` keeps them): one run to compile or load the kernel, then ``--repeats``
runs of 2 transient + ``--cycles`` recorded cycles of studies/ninebar.toml (rtol 1e-6, DOP853),
CPU time per cycle (``time.process_time``: min and max over the repeats), and the steps per
cycle (exact). Printed: both, the ratio generic / host of the minima (the baseline is the host,
measured in the same run), and how far the two targets' final states lie apart, scaled by the
clearance (the motion is chaotic here: another rounding is another trajectory within its
attractor, not an error).

Run: ``python benchmarks/generic_target.py [--cycles N] [--repeats N]`` (about 1 min with the
kernels compiled; a cold generic cache compiles first, about 1-3 min).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

from _results import recording  # benchmarks/_results.py: a JSON record per run

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "studies" / "ninebar.toml"

_CHILD = r"""
import json, sys, time
import numpy as np
import workbench
from workbench._processor import compile_target

cycles, repeats, path = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
scene = workbench.load_scene(path).replace(
    run={"cycles": cycles, "transient_cycles": 2}, solver={"rtol": 1e-6, "atol": 1e-6}
)
workbench.simulate(scene.replace(run={"cycles": 1, "transient_cycles": 0}))  # compile or load
cpu = []
for _ in range(repeats):
    c0 = time.process_time()
    ds = workbench.simulate(scene)
    cpu.append((time.process_time() - c0) / (cycles + 2))
final = [float(v) for n in ("clearance_x", "clearance_y") for v in np.ravel(ds[n].values[-1])]
print(json.dumps({
    "target": " ".join(compile_target()), "cpu": cpu,
    "steps": ds.attrs["solver_steps"] / (cycles + 2), "final": final,
}))
"""


def measure(generic: bool, cycles: int, repeats: int) -> dict:
    """Run the child in a fresh process for one target; its JSON line as a dict."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_CPU")}
    if generic:
        env["NUMBA_CPU_NAME"] = "generic"
        env["WORKBENCH_CACHE_DIR"] = str(ROOT / ".cache" / "generic-cpu")  # as make test-generic
    done = subprocess.run(
        [sys.executable, "-c", _CHILD, str(cycles), str(repeats), str(SCENE)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cycles", type=int, default=10, help="recorded cycles per run")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per target")
    a = ap.parse_args()
    rows = {name: measure(name == "generic", a.cycles, a.repeats) for name in ("host", "generic")}
    print(f"studies/ninebar.toml, 2 + {a.cycles} cycles, rtol 1e-6, {a.repeats} repeats")
    for name, r in rows.items():
        print(
            f"  {name:8s} {r['target']}: {min(r['cpu']) * 1e3:.1f} .. {max(r['cpu']) * 1e3:.1f} "
            f"ms CPU per cycle, {r['steps']:.0f} steps per cycle"
        )
    ratio = min(rows["generic"]["cpu"]) / min(rows["host"]["cpu"])
    print(f"  generic / host (minima): {ratio:.2f}")
    h, g = rows["host"]["final"], rows["generic"]["final"]
    apart = max(abs(x - y) for x, y in zip(h, g, strict=True))
    print(f"  final clearance vectors apart by at most {apart:.3g} m (the two targets' roundings)")


if __name__ == "__main__":
    with recording(__file__):
        main()
