"""The shipped archives in data/ are what the code writes now (issue 26 item 2): the archive
format, the status vocabulary, and the variables, coordinates and attributes of a run (or a
campaign) of the same stored scene made now, on a short horizon. When this fails, the code
writes something else than the notebooks and users open: run ``make data`` (and
``make notebooks``), and say in CHANGELOG.md what changed.

The numbers themselves are not compared: a chaotic run's values move with any rounding-level
change of the code; the notebooks' numbers are checked against the API by test_notebooks.py.
"""

import math
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import workbench
from workbench._processor import processor_attrs
from workbench.archive._format import decode_time
from workbench.campaign._block import STATUS_ATTRS

DATA = Path(__file__).resolve().parents[2] / "data"
RUNS = ("ninebar_default.nc", "chaos_run.nc")
#: global attributes whose value is the code's, not the run's: equal in the shipped archive
STATIC_ATTRS = ("Conventions", "format_version", "model", "forcing_period_units")


def _raw(name: str) -> xr.Dataset:
    """The archive as stored (not upgraded by open_run), its simulated time read as open_run
    reads it (seconds since t = 0: workbench.archive._format)."""
    with xr.open_dataset(DATA / name, decode_times=False) as ds:
        return decode_time(ds.load())


def _same_structure(shipped: xr.Dataset, fresh: xr.Dataset, name: str) -> None:
    assert set(shipped.data_vars) == set(fresh.data_vars), name
    assert set(shipped.coords) == set(fresh.coords), name
    for var in [*fresh.data_vars, *fresh.coords]:
        a, b = shipped[var], fresh[var]
        assert a.dims == b.dims, (name, var)
        assert a.dtype.kind == b.dtype.kind, (name, var)
        assert set(a.attrs) == set(b.attrs), (name, var)
        for key, value in b.attrs.items():
            if isinstance(value, np.ndarray):
                np.testing.assert_array_equal(a.attrs[key], value, err_msg=f"{name} {var} {key}")
            else:
                assert a.attrs[key] == value, (name, var, key)
    # the processor a run was computed on (0.6.0 on): an archive computed before has none
    # (nobody recorded it), one regenerated since says which machine that was
    machine = set(processor_attrs())
    assert set(shipped.attrs) - machine == set(fresh.attrs) - machine, (
        name,
        (set(shipped.attrs) - machine) ^ (set(fresh.attrs) - machine),
    )
    for key in STATIC_ATTRS:
        assert shipped.attrs.get(key) == fresh.attrs.get(key), (name, key)


@pytest.mark.parametrize("name", RUNS)
def test_shipped_run_is_what_the_code_writes(name, tmp_path):
    shipped = _raw(name)
    assert shipped.attrs["format_version"] == workbench.FORMAT_VERSION
    assert workbench.Status.from_label(shipped.attrs["run_status"]) is workbench.Status.OK
    scene = workbench.scene_from_toml(shipped.attrs["scene"])
    fresh = workbench.simulate(scene.replace(run={"cycles": 1, "transient_cycles": 0}))
    fresh = workbench.open_run(workbench.save_run(fresh, tmp_path / name))
    _same_structure(shipped, fresh, name)


def test_shipped_campaign_is_what_the_code_writes(tmp_path):
    name = "bifurcation_speed.nc"
    shipped = _raw(name)
    assert shipped.attrs["format_version"] == workbench.FORMAT_VERSION
    assert shipped.status.attrs["flag_meanings"] == STATUS_ATTRS["flag_meanings"]
    np.testing.assert_array_equal(shipped.status.attrs["flag_values"], STATUS_ATTRS["flag_values"])
    scene = workbench.scene_from_toml(shipped.attrs["scene"])
    omega = shipped.omega.values[:2].tolist()
    short = scene.replace(run={"cycles": 2, "transient_cycles": 1}, sweep={"omega": omega})
    fresh = workbench.run_campaign(short, tmp_path / name, workers=1)
    _same_structure(shipped, fresh, name)


def test_a_stale_archive_fails_the_check(tmp_path):
    """The check can fail: an archive of the old vocabulary or without a variable's units."""
    shipped = _raw(RUNS[0])
    scene = workbench.scene_from_toml(shipped.attrs["scene"])
    fresh = workbench.simulate(scene.replace(run={"cycles": 1, "transient_cycles": 0}))
    stale = shipped.copy()
    del stale["slider_position"].attrs["units"]
    with pytest.raises(AssertionError):
        _same_structure(stale, fresh, "stale")
    stale = shipped.copy()
    stale.attrs["format_version"] = np.int32(1)
    with pytest.raises(AssertionError):
        _same_structure(stale, fresh, "stale")


#: the chaos maps whose archives data/ ships (``make chaos-maps``)
MAPS = ("omega_clearance", "clearance_friction")


def _map_quotes(maps: xr.Dataset) -> list[str]:
    """What docs/continuation.md says of a chaos map (``make chaos-maps``), from its archive:
    the strobe's periods, the 0-1 test's K and the exponents where there is no period, how many
    exponents did not converge and why (the bits of ``lle_unmet``), and what the map cost."""
    period = maps.strobe_period.values
    none = period == 0
    lle, unmet = maps.lle.values, maps.lle_unmet.values.astype(int)
    bits = dict(zip(maps.lle_unmet.attrs["flag_meanings"].split(),
                    maps.lle_unmet.attrs["flag_masks"], strict=True))  # fmt: skip
    K = maps.zero_one_K.values
    a = maps.attrs
    quotes = [
        f"{int((period >= 1).sum())} periodic",
        f"{int(none.sum())} with no period up to 16",
        f"{int((maps.lle_converged.values == 0).sum())} of the {maps.lle.size} exponents did "
        "not converge",
        f"{int((maps.lle_status.values == 2).sum())} upper bounds",
        f"{a['measured_worker_time'] / 60:.0f} min of the workers' time",
        f"{a['measured_wall_time'] / 60:.0f} min wall",
        f"load {a['measured_load_before']:.1f} before and {a['measured_load_after']:.1f} after",
    ]
    if none.any():
        quotes += [
            f"K {np.nanmin(K[none]):.2f}-{np.nanmax(K[none]):.2f}",
            f"exponents {np.nanmin(lle[none]):.0f}-{np.nanmax(lle[none]):.0f} 1/s",
        ]
    for name in ("error_target", "variants", "variational"):
        quotes.append(f"{name} {int(((unmet & bits[name]) != 0).sum())}")
    return quotes


@pytest.mark.parametrize("name", MAPS)
def test_the_chaos_maps_the_docs_quote(name):
    """data/<map>_map.nc is the indicators of studies/chaos_maps/<map>.toml's chaos map
    (``make chaos-maps``, which runs data/regenerate.py --chaos-map) in today's vocabulary,
    and docs/continuation.md quotes its numbers and its cost."""
    from workbench.continuation._indicators import (
        LLE_CONVERGED,
        LLE_METHOD,
        LLE_STATUS,
        LLE_UNMET,
    )

    path = DATA / f"{name}_map.nc"
    maps = workbench.open_run(path)
    assert path.stat().st_size < 250_000  # small: the 41 x 21 map without its strobe samples
    scene = workbench.load_scene(DATA.parent / "studies" / "chaos_maps" / f"{name}.toml")
    assert workbench.scene_from_toml(maps.attrs["scene"]).to_toml() == scene.to_toml()
    checked = [("lle_status", LLE_STATUS), ("lle_method", LLE_METHOD)]
    if "lle_target" in maps.attrs:  # a map of the fast protocol: today's vocabulary throughout
        checked += [("lle_converged", LLE_CONVERGED), ("lle_unmet", LLE_UNMET)]
    else:
        # made before the map's own precision (issue 39): the full protocol at every point,
        # whose convergence flag had two values; its archive says so itself
        flags = maps.lle_converged.attrs
        assert flags["flag_meanings"] == "not_converged converged"
        assert set(np.unique(maps.lle_converged.values)) <= set(flags["flag_values"])
        assert "lle_full_protocol" not in maps
    for var, attrs in checked:
        assert set(maps[var].attrs) == set(attrs), var
        for key, value in attrs.items():
            np.testing.assert_array_equal(maps[var].attrs[key], value, err_msg=f"{var} {key}")
        assert maps[var].dtype.kind == "i", var  # CF flags are integers
    assert (maps.status.values == 0).all()
    text = " ".join((DATA.parent / "docs" / "continuation.md").read_text().split())
    section = text[text.index(f"`{name}`") :]
    for quote in _map_quotes(maps):
        assert quote in section[:2000], quote
    if name == "clearance_friction":  # what the docs say of its exponents in words
        lle = maps.lle.transpose("clearance", "friction_coefficient")
        rising = lle.sel(friction_coefficient=slice(0.05, None)).diff("friction_coefficient")
        assert (rising > 0).all()  # grows with c_f from 0.07 on at every c
        first = lle.isel(friction_coefficient=1) > lle.isel(friction_coefficient=0)
        assert first.clearance[~first].values.tolist() == [4e-5]  # ... from 0.01 but at 40 um
        assert (lle.sel(friction_coefficient=slice(0.18, None)) > 100).all()  # s-1
    if name == "omega_clearance":
        period = maps.strobe_period.transpose("clearance", "omega")
        w, um = np.round(period.omega.values / np.pi, 4), np.round(period.clearance.values * 1e6)
        last = {c: w[row > 0].max() for c, row in zip(um, period.values, strict=True)}
        first = {c: w[row == 0].min() for c, row in zip(um, period.values, strict=True)}
        late = [c for c in um if last[c] == 1.875]
        assert late == [20, 24, 28, 36] and all(first[c] == 1.9375 for c in late)
        assert all(last[c] == 1.8125 and first[c] == 1.875 for c in um if c not in late)
        assert "At 20-28 um and at 36 um the strobe is period-1 up to 1.875 pi" in section
        assert "from 40 um on it is period-1 up to 1.8125 pi and has none from 1.875 pi" in section
        assert int(period.sel(clearance=36e-6, omega=1.875 * np.pi, method="nearest")) == 4
        lle = maps.lle.transpose("clearance", "omega")
        odd = (period == 0) & (lle < 0)
        assert int(odd.sum()) == 1 and "-1.06 +- 0.2 1/s at 1.875 pi and 32 um" in section
        at = {k: lle.sel(omega=k * np.pi, method="nearest") for k in (2, 3)}
        assert f"from {at[2].min():.0f}-{at[2].max():.0f} 1/s at 2 pi" in section
        assert f"to {at[3].min():.0f}-{at[3].max():.0f} 1/s at 3 pi" in section
        r = np.corrcoef(at[3].clearance.values, at[3].values)[0, 1]
        assert f"grow with the clearance (correlation {r:.2f}" in section and r > 0.9
        assert (lle.values[period.values > 0] < 0).all()  # Floquet's, all negative
        bound = maps.lle_status.transpose("clearance", "omega") == 2
        assert f"{int(bound.sel(clearance=2e-5).sum())} of them at 20 um" in section
        a = maps.attrs
        assert f"The full protocol ran at {a['lle_full_points']} points" in section
        assert f"{a['lle_full_agreeing']:.0%} agree with the fast exponent" in section.replace(
            " %", "%"
        )
        assert f"{a['lle_full_same_verdict']:.0%} with the same verdict" in section.replace(
            " %", "%"
        )
        report = " ".join((DATA.parent / "studies" / "REPORT.md").read_text().split())
        assert "period-1 up to 1.86 pi and not at 1.87 pi" in report  # "between 1.86 and 1.87"
        assert "locates the end between 1.86 and 1.87 pi" in section
        # the c_f = 0.01 row of the other map (full protocol at every point) agrees at 2 pi
        other = workbench.open_run(DATA / "clearance_friction_map.nc")
        row = other.sel(friction_coefficient=0.01, method="nearest")
        mine = at[2].sel(clearance=row.clearance.values, method="nearest").values
        err = maps.lle_stderr.transpose("clearance", "omega").sel(
            omega=2 * np.pi, clearance=row.clearance.values, method="nearest"
        )
        diff = np.abs(mine - row.lle.values)
        combined = np.hypot(err.values, row.lle_stderr.values)
        agree = (diff <= 0.1 * np.abs(row.lle.values)) | (diff <= 2 * combined)
        assert agree.all() and f"({int(agree.sum())} of {agree.size})" in section


def test_the_end_of_the_periodic_motion_the_docs_quote():
    """data/periodic_end.nc is the strobe period of every point of studies/periodic_end.toml's
    continued sweep (``python data/regenerate.py --periodic-end``), and docs/continuation.md
    quotes where the periodic motion ends per clearance both ways, the one clearance whose end
    is not clean, and the sweep's cost."""
    ends = workbench.open_run(DATA / "periodic_end.nc")
    scene = workbench.load_scene(DATA.parent / "studies" / "periodic_end.toml")
    assert workbench.scene_from_toml(ends.attrs["scene"]).to_toml() == scene.to_toml()
    assert (ends.status.values == 0).all()
    assert ends.strobe_period.attrs["units"] == "1"
    omega = np.round(ends.omega.values / np.pi, 2)
    rows = {
        (d, round(float(c) * 1e6)): ends.strobe_period.sel(direction=d, clearance=c).values
        for d in ("up", "down")
        for c in ends.clearance.values
    }

    def end(row):
        """The last omega / pi of a clean end (period 1, then no period), else None."""
        k = int((row > 0).sum())
        return omega[k - 1] if (row[:k] == 1).all() and not row[k:].any() else None

    clean = [c for c in (20, 40, 60, 80, 100) if end(rows["up", c]) == end(rows["down", c])]
    clean = [c for c in clean if end(rows["up", c]) is not None]
    assert clean == [20, 40, 60, 100]
    text = " ".join((DATA.parent / "docs" / "continuation.md").read_text().split())
    section = text[text.index("`periodic_end`") :][:1800]
    listed = " / ".join(str(c) for c in clean)
    last = " / ".join(f"{end(rows['up', c]):.2f}" for c in clean)
    assert f"At c = {listed} um the strobe is period-1 up to {last} pi" in section
    assert end(rows["up", 100]) == 1.86 and end(rows["up", 100]) + 0.01 == omega[12]
    up, down = rows["up", 80], rows["down", 80]
    at = {w: int(np.flatnonzero(omega == w)[0]) for w in (1.84, 1.85, 1.86)}
    assert [int(up[at[w]]) for w in (1.84, 1.85, 1.86)] == [0, 1, 8]
    assert "no period at 1.84 pi, period 1 at 1.85 pi and period 8 at 1.86 pi" in section
    assert end(down) == 1.85 and "going down it is period-1 from 1.85 pi" in section
    a = ends.attrs
    wall, workers = a["measured_wall_time"] / 60, a["measured_workers"]
    assert f"took {wall:.0f} min wall on {workers} workers" in section
    assert f"{a['measured_worker_time'] / 60:.0f} min of the workers' CPU" in section


def test_the_end_under_hunt_crossley_the_docs_quote():
    """data/periodic_end_hunt_crossley.nc is studies/periodic_end_hunt_crossley.toml's continued
    sweep reduced to strobe periods (``python data/regenerate.py --periodic-end-hunt-crossley``);
    docs/continuation.md quotes where its periodic motion ends both ways, against LN's end at the
    same clearance (data/periodic_end.nc), and the sweep's cost."""
    hc = workbench.open_run(DATA / "periodic_end_hunt_crossley.nc")
    scene = workbench.load_scene(DATA.parent / "studies" / "periodic_end_hunt_crossley.toml")
    assert workbench.scene_from_toml(hc.attrs["scene"]).to_toml() == scene.to_toml()
    assert scene.effects["contact"] == "hunt_crossley" and (hc.status.values == 0).all()
    omega = np.round(hc.omega.values / np.pi, 2)
    up, down = (hc.strobe_period.sel(direction=d).values for d in ("up", "down"))
    np.testing.assert_array_equal(up, down)
    first_not = float(omega[np.argmax(up != 1)])
    last_periodic = float(omega[np.flatnonzero(up == 1)[-1]])
    assert (up[omega > last_periodic] == 0).all()
    ln = workbench.open_run(DATA / "periodic_end.nc").strobe_period.sel(
        direction="up", clearance=1e-4
    )
    ln_last = float(np.round(ln.omega.values / np.pi, 2)[np.flatnonzero(ln.values == 1)[-1]])
    assert last_periodic == ln_last  # "the end lies in the same 0.01 pi step as under LN"
    text = " ".join((DATA.parent / "docs" / "continuation.md").read_text().split())
    section = text[text.index("`periodic_end_hunt_crossley`") :][:1200]
    before = float(omega[np.argmax(up != 1) - 1])
    assert f"period-1 up to {before:.2f} pi, has no period at {first_not:.2f} pi" in section
    assert f"period-1 again at {last_periodic:.2f} pi" in section
    assert f"no period from {last_periodic + 0.01:.2f} pi on" in section
    assert f"{hc.attrs['measured_worker_time'] / 60:.0f} min of the workers' CPU" in section


def test_the_end_of_the_impacting_orbit_the_docs_quote():
    """data/periodic_end_branch.nc is ``studies/periodic_end_branch.py --start 1.86105 --stop
    1.8612``: the 40-event orbit of Fig. 32's scene continued to its end. docs/continuation.md
    quotes its points, the located grazing (value, label, transition, the period just past it),
    the stored grazing orbit's largest multiplier and the run's CPU."""
    from workbench.continuation import branch_bifurcations

    r = workbench.open_run(DATA / "periodic_end_branch.nc")
    assert r.attrs["command"].startswith(
        "python studies/periodic_end_branch.py --start 1.86105 --stop 1.8612"
    )
    found = branch_bifurcations(r, "omega")
    assert len(found) == 1
    (g,) = found
    assert g["type"] == "grazing" and g["resolved"] and g["transition"] == "border_collision"
    flags = r.label.attrs["flag_meanings"].split()
    labels = [flags[int(v)] for v in r.label.values]
    assert labels[0] == "start" and labels[-1] == "grazing" and g["index"] == len(labels) - 1
    assert (r.events_per_period.values == 40).all()
    largest = r.multiplier_modulus.values[:, 0]
    orbits = len(labels) - 1
    note = r.attrs["bifurcation_notes"]
    match = re.search(r"no period-1 orbit found past it; period (\d+) at ([0-9.]+)", note)
    assert match, note
    text = " ".join((DATA.parent / "docs" / "continuation.md").read_text().split())
    section = text[text.index("The package finds and types that end by itself") :][:1500]
    assert f"the map's noise check tightened it to {r.attrs['rtol']:.0e}" in section
    assert f"through {orbits} orbits" in section
    assert f"from {largest[0]:.3f} to {largest[orbits - 1]:.3f}" in section
    assert f"at fixed parameter values at {g['value'] / math.pi:.7f} pi" in section
    past = float(match.group(2))
    assert past > g["value"]
    assert f"at {past / math.pi:.7f} pi, has period {match.group(1)}" in section
    # the grazing orbit's monodromy on the orbit's side of the jump (one-sided copies)
    assert largest[-1] < 1.0 and f"has largest multiplier {largest[-1]:.3f}" in section
    assert f"took {r.attrs['measured_cpu_time'] / 60:.0f} min of CPU" in section


def _fourbar_scenes() -> tuple[workbench.Scene, workbench.Scene]:
    """The scenes data/regenerate.py gives the four-bar's archives (``fourbar_scenes``)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("regenerate", DATA / "regenerate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.fourbar_scenes()


def test_shipped_fourbar_sweep_is_what_the_code_writes(tmp_path):
    """data/fourbar_sweep.nc (notebook 05) is the continued sweep of the scene
    data/regenerate.py declares now, written as the code writes a continued sweep now (one
    made now of two speeds on a short horizon has its variables, coordinates and
    attributes)."""
    from workbench.continuation import continued_sweep

    name = "fourbar_sweep.nc"
    assert (DATA / name).stat().st_size < 1_000_000
    shipped = _raw(name)
    assert shipped.attrs["format_version"] == workbench.FORMAT_VERSION
    assert shipped.status.attrs["flag_meanings"] == STATUS_ATTRS["flag_meanings"]
    assert (shipped.status.values == 0).all()
    scene = workbench.scene_from_toml(shipped.attrs["scene"])
    assert scene.to_toml() == _fourbar_scenes()[0].to_toml()
    continuation = {**scene.continuation, "transient_cycles": 1}
    short = scene.replace(
        run={"cycles": 2, "transient_cycles": 1},
        sweep={"omega": shipped.omega.values[:2].tolist(), "continuation": continuation},
    )
    fresh = continued_sweep(short, tmp_path / name, workers=1)
    _same_structure(shipped, fresh, name)


def test_shipped_fourbar_chaos_map_is_in_todays_vocabulary():
    """data/fourbar_chaos_map.nc (notebook 05) is the chaos map of the scene data/regenerate.py
    declares now, its indicators in today's flags (as the nine-bar's maps are checked: a fresh
    map costs minutes)."""
    from workbench.continuation._indicators import (
        LLE_CONVERGED,
        LLE_METHOD,
        LLE_STATUS,
        LLE_UNMET,
    )

    path = DATA / "fourbar_chaos_map.nc"
    assert path.stat().st_size < 1_000_000
    maps = _raw(path.name)
    assert maps.attrs["format_version"] == workbench.FORMAT_VERSION
    scene = workbench.scene_from_toml(maps.attrs["scene"])
    assert scene.to_toml() == _fourbar_scenes()[1].to_toml()
    assert maps.status.attrs["flag_meanings"] == STATUS_ATTRS["flag_meanings"]
    assert (maps.status.values == 0).all()
    for var, attrs in (
        ("lle_status", LLE_STATUS),
        ("lle_method", LLE_METHOD),
        ("lle_converged", LLE_CONVERGED),
        ("lle_unmet", LLE_UNMET),
    ):
        assert set(maps[var].attrs) == set(attrs), var
        for key, value in attrs.items():
            np.testing.assert_array_equal(maps[var].attrs[key], value, err_msg=f"{var} {key}")
    assert not any("record" in maps[v].dims for v in maps.data_vars)  # no strobe samples
