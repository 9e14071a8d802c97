"""A chaos map's own precision (issue 39): a run's dataset carries the state it ended in, a map
point's exponent starts there (no second run of the whole transient and records), stops on the
error target or on the sign, whichever holds first (and says which), and the full protocol
runs on a reproducible random subset of the map's points, whose agreement the map reports."""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import workbench
from workbench.analysis import ConvergenceWarning, lle_from_equations
from workbench.analysis._window import stopping_rule
from workbench.campaign import expand_sweep
from workbench.continuation import chaos_map, lle_cycles, point_exponent
from workbench.continuation._indicators import (
    FULL_LEAST,
    _map_point,
    full_subset,
    map_measurement,
    subset_key,
)
from workbench.run import integrate, prepare

ROOT = Path(__file__).resolve().parents[2]

DUFFING = {
    "model": {"name": "duffing"},
    "parameters": {"delta": 0.3},
    "run": {"cycles": 100, "transient_cycles": 150},
    "record": {"samples_per_period": 1},
}


def duffing(gamma: float, **tables):
    data = dict(DUFFING, **tables)
    data["parameters"] = dict(data["parameters"], gamma=gamma)
    return workbench.load_scene(data)


class StepCounter:
    """Sums the solver steps of every integration that the strobe map and the exponents'
    windows run (the transient included), by wrapping the solver's integrate where they call
    it."""

    def __init__(self, monkeypatch):
        import workbench.analysis._window as window
        import workbench.continuation._strobe as strobe
        import workbench.run._simulate as simulate

        self.steps = 0
        self.runs = 0
        for module, name in (
            (strobe, "integrate"),
            (window, "integrate"),
            (simulate, "_integrate"),
        ):
            monkeypatch.setattr(module, name, self.wrap(getattr(module, name)))

    def wrap(self, fn):
        def counted(*args, **kwargs):
            res = fn(*args, **kwargs)
            self.steps += int(res.stats["steps"])
            self.runs += 1
            return res

        return counted


# -- the end state --------------------------------------------------------------------------------
def test_a_run_carries_the_state_it_ended_in():
    """end_time, end_state (every state, the problem's order), end_state_names and
    end_discrete_state equal a fresh integration's end (the stop oscillator has a discrete
    state); a campaign archive does not copy them."""
    scene = workbench.load_scene(
        {
            "model": {"name": "stop_oscillator"},
            "parameters": {"omega": 0.8},
            "run": {"cycles": 5, "transient_cycles": 3},
            "record": {"samples_per_period": 4, "variables": ["x"]},  # v is not recorded
            "solver": {"rtol": 1e-10, "atol": 1e-10},
        }
    )
    run = workbench.simulate(scene)
    prep = prepare(scene)
    t_end = prep.problem.t0 + 8 * prep.period
    fresh = integrate(prep, [t_end])
    assert run.attrs["end_time"] == pytest.approx(t_end, rel=1e-14)
    assert run.attrs["end_state_names"] == "x v"
    np.testing.assert_allclose(run.attrs["end_state"], fresh.Y[-1], rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(run.attrs["end_discrete_state"], fresh.AUX[-1], atol=1e-10)
    assert float(run.x[-1]) == run.attrs["end_state"][0]  # the last record


def test_a_campaign_archive_does_not_carry_the_end_state(tmp_path):
    scene = workbench.load_scene(dict(DUFFING, run={"cycles": 3, "transient_cycles": 1},
                                      sweep={"gamma": [0.3, 0.4]}))  # fmt: skip
    ds = workbench.run_campaign(scene, tmp_path / "c.nc", workers=1)
    assert not [k for k in ds.attrs if k.startswith("end_")]


# -- Floquet from the end state -------------------------------------------------------------------
def test_a_periodic_points_exponent_from_where_its_run_ended(monkeypatch):
    """The period-1 point's Floquet exponent from the run's end state equals the full
    protocol's (Newton from the state integrated again), and its integrations take fewer
    steps than the run itself: the full protocol's integrate the run again (more)."""
    scene = duffing(0.2)
    run = workbench.simulate(scene)
    counter = StepCounter(monkeypatch)
    fast = point_exponent(
        scene,
        period=1,
        cycles=lle_cycles(scene),
        state=run.attrs["end_state"],
        start_time=run.attrs["end_time"],
        protocol="fast",
    )
    fast_steps = counter.steps
    counter.steps = 0
    full = point_exponent(scene, period=1, cycles=lle_cycles(scene), start_cycles=250)
    assert fast.method == full.method == "floquet" and fast.converged_code == 1
    assert abs(fast.value - full.value) <= 2 * math.hypot(fast.error, full.error) + 1e-9
    assert abs(fast.value + 0.15) < 1e-6  # -delta / 2
    run_steps = int(run.attrs["solver_steps"])
    assert fast_steps < 0.5 * run_steps < run_steps < counter.steps, (fast_steps, run_steps)


# -- the sequential stopping rule ------------------------------------------------------------------
def test_the_stopping_rule():
    assert stopping_rule(1.0, 0.05, 0.1, 3.0) == "error target"
    assert stopping_rule(1.0, 0.2, 0.1, 3.0) == "sign"  # 5 errors from zero
    assert stopping_rule(1.0, 0.5, 0.1, 3.0) == ""  # 2 errors: neither
    assert stopping_rule(-1.0, 0.2, 0.1, None) == ""  # no sign rule
    assert stopping_rule(1.0, math.nan, 0.1, 3.0) == ""


@pytest.mark.chaotic
def test_a_map_point_stops_on_the_sign_or_on_the_target_and_says_which():
    """The chaotic Duffing point (lambda ~ 0.1 1/s) from where its run ended: with a 1 % target
    its window cannot meet the target but decides the sign (beyond 3 errors) first, and is
    converged on the sign (lle_converged 2), not on the target; with a 50 % target it stops on
    the target (1); where neither rule can hold within the budget (a sign rule of 1000 errors)
    it is not converged and says error_target."""
    scene = duffing(0.5)
    run = workbench.simulate(scene)
    kw = {
        "period": 0,
        "cycles": lle_cycles(scene),
        "state": run.attrs["end_state"],
        "start_time": run.attrs["end_time"],
        "protocol": "fast",
    }
    sign = point_exponent(scene, target=0.01, **kw)
    assert sign.rule == "sign" and sign.converged_code == 2 and sign.unmet == ()
    assert sign.error > 0.01 * abs(sign.value) and abs(sign.value) > 3 * sign.error
    target = point_exponent(scene, target=0.5, **kw)
    assert target.rule == "error target" and target.converged_code == 1
    assert target.error <= 0.5 * abs(target.value)
    with pytest.warns(ConvergenceWarning, match="has not converged: error target"):
        neither = point_exponent(scene, target=0.01, sign=1000.0, **kw)
    assert neither.rule == "" and neither.converged_code == 0
    assert neither.unmet == ("error target",)
    assert neither.value > 0 and abs(neither.value - sign.value) < 3 * sign.error


def test_the_copies_start_where_the_run_ended():
    """The two-trajectory method from a given state: one start there (its window begins at the
    given time), the estimate's copy alone, and the stopping rule it met named."""
    scene = workbench.load_scene({"model": {"name": "lorenz"}, "run": {"duration": 20.0}})
    run = workbench.simulate(scene)
    start = (run.attrs["end_time"], run.attrs["end_state"], None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        r = lle_from_equations(
            scene, duration=50.0, starts=1, variants=False, check=False, start=start,
            target=0.1, sign=3.0,
        )  # fmt: skip
    assert r.sizes["variant"] == 1 and r.attrs["start_time"] == run.attrs["end_time"]
    assert r.attrs["stopped_by"] in ("error target", "sign")
    assert abs(float(r.lle) - 0.9056) < 3 * float(r.stderr) + 0.05  # Sprott (2003)
    assert "variants: not run" in r.attrs["failed"]
    with pytest.raises(ValueError, match="starts=4: a given start"):
        lle_from_equations(scene, starts=4, start=start)


# -- the subset of the full protocol --------------------------------------------------------------
def test_the_full_protocols_subset_is_reproducible_and_of_its_size():
    scene = workbench.load_scene(
        dict(
            DUFFING,
            sweep={
                "gamma": {"start": 0.2, "stop": 0.5, "num": 41},
                "delta": {"start": 0.2, "stop": 0.4, "num": 21},
            },
        )  # fmt: skip
    )
    grid = expand_sweep(scene)
    chosen, threshold = full_subset(grid, 0.05, 0)
    assert chosen.size == math.ceil(0.05 * 41 * 21) == 44
    again, _ = full_subset(expand_sweep(scene), 0.05, 0)
    np.testing.assert_array_equal(chosen, again)
    other, _ = full_subset(grid, 0.05, 1)
    assert other.size == 44 and set(other) != set(chosen)
    small = workbench.load_scene(dict(DUFFING, sweep={"gamma": [0.2, 0.3, 0.4, 0.5, 0.6]}))
    assert full_subset(expand_sweep(small), 0.05, 0)[0].size == FULL_LEAST == 3
    tiny = workbench.load_scene(dict(DUFFING, sweep={"gamma": [0.2, 0.3]}))
    assert full_subset(expand_sweep(tiny), 0.05, 0)[0].size == 2
    assert full_subset(grid, 0.0, 0)[0].size == 0
    # a worker decides from the point's own values what the client chose
    picked = {int(i) for i in chosen}
    for i in range(grid.size):
        point = grid.point(i)
        assert (subset_key(point, 0) <= threshold) == (i in picked)
    # the settings are the campaign's identity: another fraction is another measurement
    name = map_measurement(scene, 0.05, 0, 0.1, 3.0).__qualname__
    assert name == map_measurement(scene, 0.05, 0, 0.1, 3.0).__qualname__
    assert name != map_measurement(scene, 0.1, 0, 0.1, 3.0).__qualname__


def test_a_map_runs_the_full_protocol_on_its_subset_and_says_how_it_agrees(tmp_path):
    """A 2 x 2 Duffing map (two periodic, two chaotic points): three points (the least) run
    the full protocol too; its values sit beside the fast ones, NaN elsewhere, and the map's
    attributes say how they agree."""
    scene = workbench.load_scene(
        dict(
            DUFFING,
            run={"cycles": 100, "transient_cycles": 100},
            sweep={"gamma": [0.25, 0.5], "delta": [0.3, 0.25]},
        )  # fmt: skip
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        maps = chaos_map(scene, tmp_path / "map.nc", workers=1)
    flag = maps.lle_full_protocol
    assert flag.dtype == np.int8 and flag.attrs["flag_meanings"] == "fast_only full_protocol"
    assert int(flag.sum()) == 3
    chosen = flag.values == 1
    assert np.isfinite(maps.lle_full.values[chosen]).all()
    assert np.isnan(maps.lle_full.values[~chosen]).all()
    assert maps.lle_full.attrs["units"] == "s-1"
    stored = workbench.open_run(tmp_path / "map.nc")
    assert stored.attrs["lle_full_points"] == 3 and stored.attrs["lle_full_fraction"] == 0.05
    assert stored.attrs["lle_full_same_verdict"] == 1.0  # same verdict at every point
    assert 0 <= stored.attrs["lle_full_agreeing"] <= 1
    # the map's exponents are the fast protocol's, converged on one rule or another
    assert set(np.unique(maps.lle_converged.values)) <= {0, 1, 2}
    periodic = maps.sel(gamma=0.25, delta=0.3)
    assert int(periodic.lle_converged) == 1 and abs(float(periodic.lle) + 0.15) < 1e-6


def test_a_map_point_in_a_worker_picks_its_subset_from_its_values(monkeypatch):
    """_map_point decides from the point's own swept values (what a worker has)."""
    seen = []
    monkeypatch.setattr(
        "workbench.continuation._indicators.chaos_indicators",
        lambda scene, run, full_protocol, **rule: seen.append(full_protocol),
    )
    point = duffing(0.5)
    key = subset_key({"gamma": 0.5}, 7)
    kw = {"dims": ("gamma",), "subset_seed": 7, "target": 0.1, "sign": 3.0}
    _map_point(point, None, threshold=key, **kw)
    _map_point(point, None, threshold=key / 2, **kw)
    assert seen == [True, False]


# -- a map that carries state along an axis (issue 39 item 2) -----------------------------------
def test_a_seeded_newton_keeps_the_runs_orbit_and_falls_back_from_another():
    """Newton seeded by a neighbour's period-1 orbit finds this point's orbit (the same
    exponent as from the run's end, -delta / 2); a seed where Newton fails falls back to the
    run's end."""
    from workbench.continuation._exponent import floquet_exponent

    def ended(gamma):
        scene = duffing(gamma)
        run = workbench.simulate(scene)
        return scene, np.asarray(run.attrs["end_state"], float)

    near, y_near = ended(0.24)
    scene, y = ended(0.25)
    neighbour = floquet_exponent(near, period=1, state=y_near)
    assert neighbour.orbit is not None and not neighbour.seeded
    seeded = floquet_exponent(scene, period=1, state=y, seed=neighbour.orbit)
    plain = floquet_exponent(scene, period=1, state=y)
    assert seeded.seeded and abs(seeded.value - plain.value) < 1e-6
    assert abs(seeded.value + 0.15) < 1e-6 and np.allclose(seeded.orbit[0], plain.orbit[0])
    broken = (y * np.nan, neighbour.orbit[1])  # a seed Newton cannot start from
    fallback = floquet_exponent(scene, period=1, state=y, seed=broken)
    assert not fallback.seeded and abs(fallback.value - plain.value) < 1e-9


def test_a_map_along_an_axis_seeds_newton_from_the_previous_periodic_point(tmp_path):
    """Along gamma (upwards), each point starts from the state the previous one ended in, and
    Newton from the previous point's orbit; the exponents are those of the grid map (-delta /
    2 at each period-1 point), lle_seeded says where the seed was taken (not at the first
    point of the line), and the archive's history names chaos_map's engine function."""
    sweep = {"gamma": [0.2, 0.22, 0.24], "delta": [0.3]}
    scene = workbench.load_scene(dict(DUFFING, sweep=sweep))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        carried = chaos_map(scene, tmp_path / "along.nc", workers=1, along="gamma")
        grid = chaos_map(scene, tmp_path / "grid.nc", workers=1)
    assert carried.lle.dims == ("gamma", "delta") and "lle_seeded" not in grid
    assert (carried.strobe_period == 1).all() and (grid.strobe_period == 1).all()
    np.testing.assert_allclose(carried.lle.values, grid.lle.values, atol=1e-6)
    np.testing.assert_allclose(carried.lle.values, -0.15, atol=1e-6)
    assert carried.lle_seeded.values[:, 0].tolist() == [0, 1, 1]
    assert carried.lle_seeded.attrs["flag_meanings"] == "from_run_end from_neighbour"
    assert carried.seed.values[:, 0].tolist() == [1, 0, 0]  # brute force, then continued
    assert carried.attrs["history"].endswith("workbench.continuation.continued_sweep")
    assert carried.attrs["lle_full_points"] == 3
    with pytest.raises(ValueError, match="along='omega'"):
        chaos_map(scene, tmp_path / "x.nc", along="omega")


def test_a_settled_mechanism_points_floquet_exponent_takes_one_integration(monkeypatch):
    """Fast protocol, monodromy by copies: the nine-bar's period-1 orbit at omega = 1.5 pi, c =
    80 um (studies/chaos_maps/omega_clearance.toml). The run has settled (multiplier ~0.41 per
    cycle over 40 cycles), so Newton's step from its end is below SETTLED and the exponent comes
    from one integration of the copies (the monodromy and its check at a 100x larger forward
    step together). It equals the exponent of the orbit Newton finds from the same state at the
    map's full precision (rtol 1e-9, Newton to 1e-8, central differences, the check a second
    integration) within the fast check's error. From a state 1e-3 (scaled) off the orbit,
    Newton runs first and finds the same exponent."""
    from workbench.continuation import _strobe
    from workbench.continuation._exponent import SETTLED, floquet_exponent

    scene = workbench.load_scene(ROOT / "studies" / "chaos_maps" / "omega_clearance.toml")
    point = scene.replace(sweep={}, run={"cycles": 10, "transient_cycles": 40})
    point = point.with_parameters(omega=1.5 * math.pi, clearance=8e-5)
    run = workbench.simulate(point)
    y, aux = np.asarray(run.attrs["end_state"]), run.attrs["end_discrete_state"]
    counter = StepCounter(monkeypatch)
    fast = floquet_exponent(point, period=1, state=y, discrete_state=aux, fast=True)
    assert counter.runs == 1 and fast.evaluations == 1 and fast.converged
    full = floquet_exponent(point, period=1, state=y, discrete_state=aux)
    assert full.evaluations >= 2 and full.converged  # Newton's iterations, then the check
    assert 0 < fast.error < 0.01 * abs(fast.value)  # the forward pair's O(100 h) truncation
    assert abs(fast.value - full.value) <= 2 * math.hypot(fast.error, full.error)
    assert -0.7 < fast.value < -0.6  # ln 0.414 / (2 / 1.5 s)
    s = _strobe.StrobeMap(point, None).scale()
    off = floquet_exponent(
        point, period=1, state=y + 10 * SETTLED * s, discrete_state=aux, fast=True
    )
    assert off.evaluations >= 2
    assert abs(off.value - fast.value) <= 2 * math.hypot(off.error, fast.error)
    with pytest.raises(ValueError, match=r"check=0\.5: must be a factor > 1"):
        _strobe.StrobeMap(point, None, check=0.5)


@pytest.mark.slow  # ~10 s of CPU: one nine-bar point, its fast exponent and the full protocol's
def test_the_full_protocol_checks_a_periodic_point_on_the_orbit_its_run_ended_on():
    """The map's subset check of a periodic point: the full protocol's Newton starts where the
    point's run ended (the fast value's orbit, with the onset velocities it holds), so that the
    two measure one orbit. A lasting-contact orbit of the nine-bar is one of a family under
    Lankarani-Nikravesh contact (each contact holds its onset velocity), and integrated again
    from the scene's start the full protocol landed on another member: at omega = pi, c = 80
    um it read -2.651 1/s (held 0.675, 2.40 mm/s) against the fast -1.662 (held 1.11, 3.59
    mm/s; benchmarks/chaos_map_agreement.py --same-orbit)."""
    from workbench.continuation import chaos_indicators

    scene = workbench.load_scene(ROOT / "studies/chaos_maps/omega_clearance.toml")
    point = scene.with_parameters(omega=math.pi, clearance=8e-5)
    run = workbench.simulate(point)
    ind = chaos_indicators(point, run, full_protocol=True)
    assert int(ind.strobe_period) == 1 and int(ind.lle_method) == 0  # floquet
    fast, full = float(ind.lle), float(ind.lle_full)
    assert fast < 0 and abs(fast - full) <= 0.01 * abs(full)  # one orbit: -1.662 both here
    assert 0 < float(ind.lle_full_stderr) < 0.01 * abs(full)
