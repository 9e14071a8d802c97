"""Regenerate the small reference archives in data/ (``make data``), which the notebooks open.

- ``ninebar_default.nc``: the default scene (studies/ninebar.toml), 2 transient + 1 recorded
  crank cycle at 500 samples per cycle;
- ``chaos_run.nc``: the chaos-identification scene (studies/chaos/chaos.toml), 100 recorded
  cycles at 100 samples per cycle, clearance coordinates and velocities only;
- ``bifurcation_speed.nc``: a 12-point campaign over omega = 1 pi .. 3 pi (c = 0.1 mm,
  c_f = 0.01), 20 transient + 30 stroboscopic samples per point.

Run: ``python data/regenerate.py`` (``make data``; a few minutes on 2 cores), then
``make notebooks``. ``tests/records/test_data.py`` fails when the archives no longer match what the
code writes.

- ``--upgrade``: where only how the archives are written changed (the archive format, the
  CF attributes, the name of a dimension: format 4's ``record``), not what they hold,
  rewrite each shipped archive in place with the current writer, its values untouched
  (checked), instead of recomputing it (the maps cost an hour
  each): read by ``open_run`` (an older format upgraded), given the global attributes every
  archive now carries that it lacks (``Conventions``, ``references``), the scalar
  coordinates of parameters the model declared since (at their defaults: a run whose scene
  set one is refused and must be recomputed), a line in
  ``history`` that says so, and written as it was (netCDF-3 for the maps and periodic_end.nc).

- ``<map>_map.nc``: a chaos map of ``studies/chaos_maps/<map>.toml`` (``make chaos-maps``
  computes both, each of order an hour of CPU; data/ ships both) without its strobe
  samples: the
  per-point indicators (strobe period, 0-1 K, largest exponent with its error, method, status
  and convergence flags), the points' status and solver statistics, and the cost of the run
  from its log (attributes ``measured_*``: the workers' time, the wall time of GNU
  ``time -v``, the 1-minute load before and after from ``uptime``). docs/continuation.md
  quotes them and ``tests/records/test_data.py`` checks those numbers against them. Run after
  ``make chaos-maps`` under ``/usr/bin/time -v`` with ``uptime`` before and after in LOG:
  ``python data/regenerate.py --chaos-map out/chaos_maps/clearance_friction.nc LOG`` (the
  archive is named after the map: ``data/<map>_map.nc``).
- ``periodic_end.nc``: the strobe period of every point of the continued sweep of
  ``studies/periodic_end.toml`` (omega 1.75-2 pi in steps of 0.01 pi, up and down, at the
  maps' clearances) and its cost; ``python data/regenerate.py --periodic-end`` (``make
  chaos-maps`` runs it; minutes on 2 workers).
- ``periodic_end_branch.nc``: the nine-bar's 40-event period-1 orbit continued to its end
  (a lift-off grazing typed a border collision), written by ``python
  studies/periodic_end_branch.py --start 1.86105 --stop 1.8612 -o data/periodic_end_branch.nc``
  (9 min of CPU).
- ``--map-figure``: the (omega, c) map's figure, ``docs/figures/chaos-map-omega_clearance.png``,
  drawn again from ``omega_clearance_map.nc`` with where ``periodic_end.nc``'s period-1 motion
  ends (per clearance and direction, to 0.01 pi) over it (``make chaos-maps`` runs it last).
- ``periodic_end_hunt_crossley.nc``: the same for ``studies/periodic_end_hunt_crossley.toml``
  (c = 100 um under the Hunt-Crossley law); ``python data/regenerate.py
  --periodic-end-hunt-crossley`` (minutes on 2 workers).
- ``fourbar_sweep.nc`` and ``fourbar_chaos_map.nc``: the declared four-bar of
  ``studies/mechanisms/fourbar.toml`` (Coulomb friction c_f = 0.1 at its clearance joint B), a
  continued sweep over the crank speed 30-70 rad/s up and down at c = 0.5 mm (strobe samples of
  the clearance vector) and a 3 x 3 chaos map over the crank speed and the clearance without
  its strobe samples; ``python data/regenerate.py --fourbar`` (``make data`` makes them too;
  a few minutes on 2 workers). notebooks/05_your_own_mechanism.ipynb opens them.
"""

from __future__ import annotations

import math
import re
import shutil
import sys
from pathlib import Path

import workbench
from workbench.archive import RECORD_DIM, RECORD_TIME, SERIES_DIMS

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

    print(*fourbar(), sep="\n")


def upgrade(path: Path) -> Path:
    """Rewrite the archive at ``path`` in place with the current writer, its values untouched
    (module docstring: ``--upgrade``)."""
    import datetime

    import netCDF4
    import numpy as np

    from workbench.run._dataset import references

    with netCDF4.Dataset(path) as nc:
        classic = nc.data_model.startswith("NETCDF3")
    ds = workbench.open_run(path)
    found = int(ds.attrs.pop("upgraded_from_format", ds.attrs["format_version"]))
    attrs = ds.attrs
    lacks = not {"Conventions", "references"} <= set(attrs)
    attrs.setdefault("Conventions", "CF-1.11")
    attrs.setdefault("references", references(attrs["model"]))
    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    line = (
        f"{now} rewritten by workbench {workbench.__version__} (data/regenerate.py --upgrade): "
        f"archive format {found} -> {workbench.FORMAT_VERSION}, values untouched"
    )
    added = _declared_since(ds)
    if found == workbench.FORMAT_VERSION and not added and not lacks:
        return path  # nothing to upgrade: left as it is
    if added:
        line += (
            f"; parameters declared since, added at their defaults (the run did not use them): "
            f"{', '.join(added)}"
        )
    attrs["history"] = f"{attrs['history']}\n{line}" if attrs.get("history") else line
    with_values = ds.copy(deep=True)
    workbench.save_run(ds, path, classic=classic)
    back = workbench.open_run(path)
    for name, var in with_values.variables.items():
        same = back[name].values == var.values
        if var.dtype.kind == "f":
            same |= np.isnan(back[name].values) & np.isnan(var.values)
        assert np.all(same) and back[name].dims == var.dims, f"{path.name}: {name} changed"
    assert back.identical(with_values), f"{path.name}: the attributes read back differ"
    return path


def _declared_since(ds) -> list[str]:
    """Add to ``ds`` (in place) the scalar coordinates of the model's parameters declared after
    the archive was written (e.g. ``hunt_crossley_damping``, 0.6.0), at the values the code
    would record for its scene: their defaults, which the stored run's effects did not use
    (checked: a scene naming one is refused). The attribute ``model_parameters`` lists them
    in the model's order. Returns their names."""
    from workbench.models import get_model
    from workbench.run import PARAMETERS_ATTR, parameter_coords

    if PARAMETERS_ATTR not in ds.attrs:  # an archive that records no parameters
        return []
    scene = workbench.scene_from_toml(ds.attrs["scene"])
    model = get_model(scene.model)
    listed = ds.attrs[PARAMETERS_ATTR].split()
    fresh = parameter_coords(model, scene.resolved_parameters, skip=ds.dims, taken=[])
    added = [name for name in fresh if name not in listed and name not in ds.coords]
    named = set(scene.to_dict().get("parameters", {}))
    assert not named & set(added), f"the scene sets {named & set(added)}: recompute the run"
    for name in added:
        ds.coords[name] = fresh[name]
    order = [p.name for p in model.parameters]
    for name in added:  # after the nearest parameter declared before it
        before = [n for n in order[: order.index(name)] if n in listed]
        listed.insert(listed.index(before[-1]) + 1 if before else len(listed), name)
    ds.attrs[PARAMETERS_ATTR] = " ".join(listed)
    return added


def without_samples(maps):
    """A chaos map without its strobe samples (every variable over ``time``): its indicators."""
    timed = [v for v in maps.data_vars if any(d in SERIES_DIMS for d in maps[v].dims)]
    return maps.drop_vars([*timed, *(c for c in ("time", RECORD_TIME) if c in maps.coords)])


def chaos_map_summary(source: Path, log: Path, target: Path) -> Path:
    """The chaos map at ``source`` without its strobe samples (every variable over ``time``),
    with the cost of its run from ``log`` (GNU ``time -v`` output and ``uptime`` lines) as
    attributes, written to ``target``."""
    maps = workbench.open_run(source)
    out = without_samples(maps)
    text = Path(log).read_text()

    loads = re.findall(r"load average: ([0-9.]+),", text)
    clock = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([0-9:.]+)", text)
    wall = sum(float(x) * 60**i for i, x in enumerate(reversed(clock.group(1).split(":"))))
    out.attrs.update(
        # GNU time's user and system time miss the workers (forkserver grandchildren, never
        # waited for by the timed process): the workers' time is the sum of the points' wall
        # times, which is their CPU where the machine has a core per worker
        measured_worker_time=float(maps.point_wall_time.sum()),
        measured_wall_time=wall,
        measured_load_before=float(loads[0]),
        measured_load_after=float(loads[-1]),
        measured_command=re.search(r"Command being timed: \"(.*)\"", text).group(1),
    )
    workbench.save_run(out, target, classic=True)  # a few kB: no HDF5 per-variable overhead
    return target


#: the global attributes of the continued sweep that periodic_end.nc keeps (and its own)
KEPT = (
    *("Conventions", "title", "history", "source", "references", "scene", "format_version"),
    *("package_versions", "model", "code_digest"),
)


def periodic_end(target: Path, workers: int = 2, study: str = "periodic_end") -> Path:
    """The continued sweep of studies/<study>.toml (up and down over omega, per clearance where
    it sweeps the clearance) reduced to the strobe period of every point
    (:func:`workbench.continuation.strobe_period` of its clearance coordinates at A and B), with
    the sweep's cost as attributes, written to ``target``."""
    import tempfile

    import numpy as np
    import xarray as xr

    from workbench.continuation import continued_sweep, strobe_period

    scene = workbench.load_scene(ROOT / "studies" / f"{study}.toml")
    with tempfile.TemporaryDirectory() as tmp:
        ds = continued_sweep(scene, Path(tmp) / "sweep.nc", workers=workers, progress=False)
    dims = tuple(d for d in ("direction", "omega", "clearance") if d in ds.dims)
    samples = xr.concat([ds.clearance_x, ds.clearance_y], "variable")
    samples = samples.transpose(*dims, RECORD_DIM, "joint", "variable")  # each point's times
    period = np.zeros([ds.sizes[d] for d in dims], dtype=np.int8)
    for index in np.ndindex(period.shape):
        s = samples.values[index].reshape(ds.sizes[RECORD_DIM], -1)
        period[index] = strobe_period(s[np.isfinite(s).all(axis=1)])
    out = xr.Dataset(
        {
            "strobe_period": (
                dims,
                period,
                {
                    "units": "1",
                    "long_name": "period of the strobe samples in forcing periods "
                    "(0: none up to 16)",
                },
            ),
            "status": ds.status.transpose(*dims),
        },
        coords={d: ds[d] for d in dims},
        attrs={k: v for k, v in ds.attrs.items() if k in KEPT or k.startswith("continuation_")},
    )
    out.attrs.update(
        measured_worker_time=float(ds.attrs["campaign_cpu_time"]),
        measured_wall_time=float(ds.attrs["campaign_wall_time"]),
        measured_workers=workers,
    )
    workbench.save_run(out, target, classic=True)
    return target


def map_figure(target: Path) -> Path:
    """The (omega, c) chaos map's figure from ``omega_clearance_map.nc`` with the end of the
    period-1 motion of ``periodic_end.nc`` drawn over it, written to ``target`` (PNG)."""
    from workbench.archive import save_figure
    from workbench.plot import chaos_map_figure

    maps = workbench.open_run(DATA / "omega_clearance_map.nc")
    ends = workbench.open_run(DATA / "periodic_end.nc")
    fig = chaos_map_figure(
        maps, scales={"omega": 1 / math.pi}, labels={"omega": "crank speed omega / pi"}, ends=ends
    )
    save_figure(fig, target, dpi=150, close=True)
    return target


def fourbar_scenes() -> tuple[workbench.Scene, workbench.Scene]:
    """The scenes of ``fourbar_sweep.nc`` and ``fourbar_chaos_map.nc``: the four-bar of
    studies/mechanisms/fourbar.toml with Coulomb friction c_f = 0.1 at B, strobe samples of
    the clearance vector; a continued sweep over omega 30-70 rad/s in steps of 2 rad/s (c =
    0.5 mm, up and down, one segment each way) and a map over omega 35 / 50 / 65 rad/s and
    c = 0.1 / 0.3 / 0.5 mm."""
    import tomllib

    with open(ROOT / "studies" / "mechanisms" / "fourbar.toml", "rb") as f:
        table = tomllib.load(f)["mechanism"]
    common = {
        "mechanism": table,
        "effects": {"friction": "coulomb"},
        "parameters": {"friction_coefficient": 0.1},
        "solver": {"rtol": 1e-6, "atol": 1e-6},
        "record": {"samples_per_period": 1, "variables": ["clearance_x", "clearance_y"]},
    }
    sweep = {
        **common,
        "title": "Declared four-bar, c = 0.5 mm at B, c_f = 0.1: continued sweep over the "
        "crank speed 30-70 rad/s, up and down",
        "run": {"cycles": 40, "transient_cycles": 60},
        "sweep": {
            "omega": {"start": 30.0, "stop": 70.0, "num": 21},  # rad/s
            "continuation": {
                "direction": "both",
                "along": "omega",
                "segments": 1,
                "transient_cycles": 20,
            },
        },
    }
    chaos = {
        **common,
        "title": "Declared four-bar, c_f = 0.1: chaos map over the crank speed and the "
        "clearance at B",
        "run": {"cycles": 100, "transient_cycles": 40},
        "sweep": {
            "omega": [35.0, 50.0, 65.0],  # rad/s
            "clearance_B": [1e-4, 3e-4, 5e-4],  # m
        },
    }
    return workbench.load_scene(sweep), workbench.load_scene(chaos)


def fourbar(workers: int = 2) -> tuple[Path, Path]:
    """``fourbar_sweep.nc`` (the continued sweep whole: a few hundred kB) and
    ``fourbar_chaos_map.nc`` (the map's indicators) from :func:`fourbar_scenes`."""
    import tempfile

    from workbench.continuation import chaos_map, continued_sweep

    sweep, chaos = fourbar_scenes()
    swept, mapped = DATA / "fourbar_sweep.nc", DATA / "fourbar_chaos_map.nc"
    with tempfile.TemporaryDirectory() as tmp:
        ds = continued_sweep(sweep, Path(tmp) / "sweep.nc", workers=workers)
        workbench.save_run(ds, swept)
        maps = chaos_map(chaos, Path(tmp) / "map.nc", workers=workers)
        workbench.save_run(without_samples(maps), mapped, classic=True)
    return swept, mapped


if __name__ == "__main__":
    if sys.argv[1:2] == ["--fourbar"]:
        print(*fourbar(), sep="\n")
    elif sys.argv[1:2] == ["--periodic-end"]:
        print(periodic_end(DATA / "periodic_end.nc"))
    elif sys.argv[1:2] == ["--periodic-end-hunt-crossley"]:
        study = "periodic_end_hunt_crossley"
        print(periodic_end(DATA / f"{study}.nc", study=study))
    elif sys.argv[1:2] == ["--map-figure"]:
        print(map_figure(ROOT / "docs" / "figures" / "chaos-map-omega_clearance.png"))
    elif sys.argv[1:2] == ["--upgrade"]:
        for archive in sorted(DATA.glob("*.nc")):
            print(upgrade(archive))
    elif sys.argv[1:2] == ["--chaos-map"]:
        source = Path(sys.argv[2])
        print(chaos_map_summary(source, Path(sys.argv[3]), DATA / f"{source.stem}_map.nc"))
    else:
        main()
