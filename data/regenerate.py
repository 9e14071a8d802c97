"""Regenerate the small reference archives in data/ (``make data``), which the notebooks open.

- ``ninebar_default.nc``: the default scene (studies/ninebar.toml), 2 transient + 1 recorded
  crank cycle at 500 samples per cycle;
- ``chaos_run.nc``: the chaos-identification scene (studies/chaos/chaos.toml), 100 recorded
  cycles at 100 samples per cycle, clearance coordinates and velocities only;
- ``bifurcation_speed.nc``: a 12-point campaign over omega = 1 pi .. 3 pi (c = 0.1 mm,
  c_f = 0.01), 20 transient + 30 stroboscopic samples per point.

Run: ``python data/regenerate.py`` (``make data``; a few minutes on 2 cores), then
``make notebooks``. ``tests/test_data.py`` fails when the archives no longer match what the
code writes.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import workbench

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "data"


def main() -> None:
    base = workbench.load_scene(ROOT / "studies" / "ninebar.toml")
    default = base.replace(
        run={"cycles": 1, "transient_cycles": 2}, record={"samples_per_period": 500}
    )
    workbench.save_run(workbench.simulate(default), DATA / "ninebar_default.nc")
    print("ninebar_default.nc")

    chaos = workbench.load_scene(ROOT / "studies" / "chaos" / "chaos.toml")
    chaos = chaos.replace(run={"cycles": 100, "transient_cycles": 20})
    workbench.save_run(workbench.simulate(chaos), DATA / "chaos_run.nc")
    print("chaos_run.nc")

    sweep = workbench.load_scene(ROOT / "studies" / "bifurcation_speed" / "sweep.toml")
    sweep = sweep.replace(
        run={"cycles": 30, "transient_cycles": 20},
        sweep={"omega": {"start": math.pi, "stop": 3 * math.pi, "num": 12}},
    ).to_dict()
    sweep["title"] = (
        "Sec. 5.2, Fig. 32 on a coarse grid: bifurcation diagram over the driving speed "
        "pi-3 pi, 12 points (c = 0.1 mm, c_f = 0.01)"
    )
    sweep = workbench.load_scene(sweep)
    store = DATA / "bifurcation_speed.nc"
    workbench.run_campaign(sweep, store, restart=True)
    shutil.rmtree(store.with_name(store.name + ".blocks"), ignore_errors=True)
    print("bifurcation_speed.nc")


if __name__ == "__main__":
    main()
