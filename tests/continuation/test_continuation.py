"""Continuation against answers it was not tuned on: the folds of a hardening Duffing oscillator
(harmonic balance, the jumps of a quasi-static sweep), the period-doubling cascade of the
default Duffing oscillator (the strobe's periods either side, Feigenbaum's constant), a grazing
bifurcation in closed form; and the continued sweep's own guarantees (hysteresis both ways,
the same numbers whatever the workers, seams chained where they disagree, resumable)."""

import math
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from _harmonic_balance import folds as hb_folds
from helpers import agrees
from scipy.optimize import brentq

import workbench
from workbench.analysis import ConvergenceWarning
from workbench.campaign import CampaignError
from workbench.cli import main
from workbench.continuation import (
    StrobeMap,
    chaos_map,
    continue_orbit,
    continued_sweep,
    lle_cycles,
    periodic_orbit,
    point_exponent,
    strobe_period,
)
from workbench.models.stop_oscillator import grazing_amplitude

# x'' + 0.05 x' + x + 0.1 x^3 = 0.1 cos(omega t): a hysteresis window omega ~ 1.076 .. 1.116
HARDENING = {"alpha": 1.0, "beta": 0.1, "delta": 0.05, "gamma": 0.1}
FEIGENBAUM = 4.669201609102990  # Feigenbaum (1978)
ROOT = Path(__file__).resolve().parents[2]


def hardening(**tables):
    data = {
        "model": {"name": "duffing"},
        "parameters": dict(HARDENING, omega=1.0),
        "initial": {"x": 0.0, "v": 0.0},
        "run": {"transient_cycles": 300},
    }
    data.update(tables)
    return workbench.load_scene(data)


@pytest.fixture(scope="module")
def response():
    """The hardening oscillator's period-1 branch over omega 1.0 .. 1.25 (both folds)."""
    return continue_orbit(hardening(), "omega", stop=1.25, rtol=1e-10, tolerance=1e-9)


def fold_values(branch):
    kinds = branch.bifurcation_label.values
    return np.sort(branch.bifurcation_parameter.values[kinds == 3])  # 3: fold


def test_folds_agree_with_harmonic_balance(response):
    """Harmonic balance with 7 and 9 harmonics agree to 1e-12 (converged); the shooting folds
    (located to 1e-7 of the range) agree with them to 1e-7."""
    h7, h9 = hb_folds(**HARDENING, H=7), hb_folds(**HARDENING, H=9)
    assert np.allclose(h7, h9, rtol=0, atol=1e-12)
    # the values docs/continuation.md quotes (and the single-harmonic ones)
    assert np.allclose(h9, [1.0761313, 1.1161418], rtol=0, atol=5e-8)
    assert np.allclose(hb_folds(**HARDENING, H=1), [1.0760671, 1.1155084], rtol=0, atol=5e-8)
    up, down = fold_values(response)
    assert abs(up - h9[0]) < 1e-7 and abs(down - h9[1]) < 1e-7, (up, down, h9)
    # along the branch: stable up to the first fold, unstable between the folds (the middle
    # branch), stable after the second
    at = np.flatnonzero(response.label.values == 3)
    stable = response.stable.values
    assert (stable[: at[0]] == 1).all() and (stable[at[1] + 1 :] == 1).all()
    assert at[1] - at[0] > 5 and (stable[at[0] + 1 : at[1]] == 0).all()
    # the critical multiplier is +1 at both folds
    crit = response.critical_real.values[response.bifurcation_label.values == 3]
    assert np.allclose(crit, 1.0, atol=1e-4)


def test_folds_bracket_the_jumps_of_a_quasi_static_sweep(response, tmp_path):
    """A continued sweep with omega steps of 0.001 (100 periods per point) jumps down going up
    and up going down past each fold, within one step of it (slow passage: just past a fold
    the orbit's ghost holds the motion for a time ~ 1 / sqrt(distance); Strogatz 1994,
    Sec. 4.3)."""
    scene = hardening(
        solver={"rtol": 1e-9, "atol": 1e-11},
        run={"cycles": 2, "transient_cycles": 300},
        record={"samples_per_period": 32},
        sweep={
            "omega": {"start": 1.06, "stop": 1.13, "num": 71},
            "continuation": {"direction": "both", "segments": 1, "transient_cycles": 100},
        },
    )
    ds = continued_sweep(scene, tmp_path / "qs.nc", workers=2)
    amplitude = np.abs(ds.x).max("record")  # each point's own record times
    up_fold, down_fold = fold_values(response)
    omega = ds.omega.values
    step = omega[1] - omega[0]
    for direction, fold, sign in (("up", down_fold, 1), ("down", up_fold, -1)):
        a = amplitude.sel(direction=direction).values[::sign]
        w = omega[::sign]
        jump = np.flatnonzero(np.abs(np.diff(a)) > 0.3)
        assert jump.size == 1, (direction, a)
        old, new = w[jump[0]], w[jump[0] + 1]
        assert sign * (new - fold) > 0 and sign * (old - fold) < step, (direction, old, new)
    # hysteresis: between the folds the two directions sit on different branches
    inside = (ds.omega > up_fold + 0.002) & (ds.omega < down_fold - 0.002)
    gap = amplitude.sel(direction="up") - amplitude.sel(direction="down")
    assert (gap.where(inside, drop=True) > 0.5).all()


@pytest.fixture(scope="module")
def cascade():
    """The default (double-well) Duffing oscillator's period-1 branch in gamma from 0.25 and
    three switches to the doubled branch: period 1, 2, 4, 8."""
    scene = {
        "model": {"name": "duffing"},
        "parameters": {"gamma": 0.25},
        "run": {"transient_cycles": 100},
    }
    return continue_orbit(
        scene, "gamma", stop=0.2922, doublings=3, rtol=1e-11, tolerance=1e-9, max_step=0.02
    )


def test_period_doubling_cascade_and_feigenbaum_ratio(cascade):
    kinds = cascade.bifurcation_label.values
    assert (kinds == 5).all() and kinds.size == 4, kinds  # 5: period_doubling, one per branch
    assert (cascade.bifurcation_branch.values == np.arange(4)).all()
    assert np.allclose(cascade.critical_real.values, -1.0, atol=1e-4)
    g = cascade.bifurcation_parameter.values
    # the values README.md and docs/continuation.md quote
    assert np.allclose(g, [0.2655818, 0.2866932, 0.2910899, 0.2920310], rtol=0, atol=2e-7), g
    d1 = (g[1] - g[0]) / (g[2] - g[1])
    d2 = (g[2] - g[1]) / (g[3] - g[2])
    assert (round(d1, 2), round(d2, 2)) == (4.80, 4.67)
    # the ratios of a flow's first doublings approach Feigenbaum's constant (geometrically)
    assert abs(d1 - FEIGENBAUM) < 0.05 * FEIGENBAUM, d1
    assert abs(d2 - FEIGENBAUM) < 0.01 * FEIGENBAUM, d2
    assert abs(d2 - FEIGENBAUM) < abs(d1 - FEIGENBAUM)
    # each branch is stable between its birth and its doubling
    for b in range(4):
        on = (cascade.branch == b) & (cascade.gamma > (g[b - 1] if b else 0.25) + 1e-5)
        on &= cascade.gamma < g[b] - 1e-5
        assert (cascade.stable[on] == 1).all(), b


def distinct_strobe_points(gamma: float) -> int:
    """Distinct strobe samples of x over 64 periods after 1500 (tolerance 1e-6)."""
    ds = workbench.simulate(
        {
            "model": {"name": "duffing"},
            "parameters": {"gamma": gamma},
            "solver": {"rtol": 1e-10, "atol": 1e-12},
            "run": {"cycles": 64, "transient_cycles": 1500},
            "record": {"samples_per_period": 1},
        }
    )
    x = np.sort(ds.x.values)
    return 1 + int(np.sum(np.diff(x) > 1e-6))


def test_strobe_periods_either_side_of_each_doubling(cascade):
    g = cascade.bifurcation_parameter.values
    probes = [g[0] - 0.005] + [0.5 * (a + b) for a, b in zip(g[:-1], g[1:], strict=True)]
    assert [distinct_strobe_points(x) for x in probes] == [1, 2, 4, 8]


def test_grazing_against_the_closed_form():
    """The non-impacting orbit of the forced oscillator with a stop at g grazes where its
    linear amplitude F / sqrt((k - m w^2)^2 + (c w)^2) equals g."""
    params = {"damping": 0.1, "stop_stiffness": 100.0, "gap": 1.0, "force": 0.5}
    scene = {
        "model": {"name": "stop_oscillator"},
        "parameters": dict(params, omega=0.5),
        "run": {"transient_cycles": 100},
    }
    model = {"mass": 1.0, "stiffness": 1.0, **params}
    exact = brentq(lambda w: grazing_amplitude({**model, "omega": w}) - 1.0, 0.3, 0.99)
    r = continue_orbit(scene, "omega", stop=0.8, rtol=1e-10, tolerance=1e-9)
    grazing = r.bifurcation_parameter.values[r.bifurcation_label.values == 7]  # 7: grazing
    assert grazing.size == 1
    assert abs(grazing[0] - exact) < 1e-6 * exact, (grazing, exact)
    assert round(exact, 7) == 0.7106874  # as docs/continuation.md quotes
    # the stop's square-root singularity: a period doubling right past the grazing (the page
    # quotes its distance)
    doubling = r.bifurcation_parameter.values[r.bifurcation_label.values == 5]
    assert doubling.size >= 1 and f"{doubling[0] - grazing[0]:.1e}" == "2.3e-06", doubling
    assert (r.events_per_period[r.omega < grazing[0]] == 0).all()
    # one onset and one end per period; contacts shallower than ~1e-4 m (within ~2e-5 rad/s
    # past grazing) last a few ms and fall inside one solver step: their events are not seen
    assert (r.events_per_period[r.omega > grazing[0] + 1e-4] == 2).all()
    # the orbit's largest event value (x - g, m) is its distance from the stop: negative below
    # grazing, zero at the located point, positive past it
    top = r.event_max.isel(event=0)
    assert top.attrs["units"] == "m"
    at = int(np.argmin(np.abs(r.omega.values - grazing[0])))
    assert abs(float(top[at])) < 1e-6
    below, above = r.omega < grazing[0] - 1e-3, r.omega > grazing[0] + 1e-3
    assert (top[below] < 0).all() and (top[above] > 0).all()


def test_periodic_orbit_of_the_linear_oscillator_is_exact():
    """Below the stop the orbit is the linear one: multipliers exp((-c/2m +- i w_d) T)."""
    scene = {
        "model": {"name": "stop_oscillator"},
        "parameters": {"omega": 0.5, "force": 0.2},
        "run": {"transient_cycles": 20},
    }
    r = periodic_orbit(scene, rtol=1e-11, tolerance=1e-10)
    T = 2 * math.pi / 0.5
    expected = math.exp(-0.05 * T)  # |mu| = exp(-c T / 2m)
    assert np.allclose(r.multiplier_modulus.values, expected, rtol=1e-7)
    amp = np.hypot(r.orbit_x, r.orbit_v / 0.5).item()
    exact = grazing_amplitude(
        {"mass": 1, "damping": 0.1, "stiffness": 1, "force": 0.2, "omega": 0.5}
    )
    assert abs(amp - exact) < 1e-8


def test_the_shooting_says_which_integrator_it_used(tmp_path, capsys):
    """A scene solved by Radau (or auto) is shot with DOP853 (the tangent and copies systems
    need an explicit compiled method): the map says so and the dataset records both methods,
    and the orbit is the one a DOP853 scene gives."""
    scene = {
        "model": {"name": "duffing"},
        "parameters": {"gamma": 0.2},
        "run": {"transient_cycles": 50},
        "solver": {"method": "radau", "rtol": 1e-8, "atol": 1e-8},
    }
    smap = StrobeMap(scene)
    assert (smap.method, smap.scene_method, smap.method_replaced) == ("dop853", "radau", True)
    r = periodic_orbit(scene)
    assert (r.attrs["integration_method"], r.attrs["scene_method"]) == ("dop853", "radau")
    explicit = dict(scene, solver=dict(scene["solver"], method="dopri5"))
    assert not StrobeMap(explicit).method_replaced
    r5 = periodic_orbit(explicit)
    assert (r5.attrs["integration_method"], r5.attrs["scene_method"]) == ("dopri5", "dopri5")
    assert abs(float(r.orbit_x[0]) - float(r5.orbit_x[0])) < 1e-7
    path = tmp_path / "radau.toml"
    path.write_text(workbench.load_scene(scene).to_toml())
    out = str(tmp_path / "b.nc")
    assert main(["orbit", str(path), "-o", out, "--param", "gamma", "--stop", "0.205"]) == 0
    assert "integrated by dop853 in place of the scene's radau" in capsys.readouterr().out


# -- the continued sweep's guarantees ----------------------------------------------------------
def down_sweep(segments: int, **extra):
    return hardening(
        initial={"x": 2.0, "v": 0.0},
        run={"cycles": 4, "transient_cycles": 300},
        record={"samples_per_period": 1},
        sweep={
            "omega": {"start": 1.08, "stop": 1.12, "num": 17},
            "continuation": {"direction": "down", "segments": segments, "transient_cycles": 60},
        },
        **extra,
    )


def test_a_disagreeing_seam_is_chained_and_equals_the_sequential_sweep(tmp_path):
    """Going down from 1.12 the continuation stays on the small-amplitude branch; the second
    segment's brute-force seed (from x = 2) lands on the large one: its seam disagrees and the
    segment is run again from the first segment's last state, which is what one sequential
    sweep does: the numbers are the same to the bit."""
    one = continued_sweep(down_sweep(1), tmp_path / "one.nc", workers=1)
    two = continued_sweep(down_sweep(2), tmp_path / "two.nc", workers=2)
    assert int(two.seam_chained.item()) == 1 and two.seam_distance.item() > 0.05
    assert two.attrs["continuation_rounds"] == 2
    assert two.x.equals(one.x) and two.v.equals(one.v)
    # the seeds differ only where the chained segment starts (chained_seed = 2)
    assert (two.seed.values != one.seed.values).sum() == 1 and 2 in two.seed.values


def test_continued_sweep_numbers_do_not_depend_on_workers_and_resume(tmp_path):
    scene = down_sweep(4)
    a = continued_sweep(scene, tmp_path / "a.nc", workers=1)
    b = continued_sweep(scene, tmp_path / "b.nc", workers=2)
    assert a.x.equals(b.x) and a.final_x.equals(b.final_x)
    # the engine names the function that created the archive (no text replaced afterwards)
    assert a.attrs["history"].endswith("created by workbench.continuation.continued_sweep")
    # interrupted after its blocks: the archive goes, the blocks stay; a re-run reuses them
    (tmp_path / "b.nc").unlink()
    c = continued_sweep(scene, tmp_path / "b.nc", workers=2)
    assert c.attrs["computed_blocks"] == 0 and c.attrs["reused_blocks"] > 0
    assert c.x.equals(a.x)
    # run again on its finished store: the figures of the call that computed it stay (issue 40)
    again = continued_sweep(scene, tmp_path / "a.nc", workers=2)
    assert again.attrs["computed_blocks"] == 0 and again.attrs["resume_workers"] == 0
    for name in ("campaign_workers", "campaign_cpu_time", "campaign_wall_time"):
        assert again.attrs[name] == a.attrs[name], name
    assert again.attrs["campaign_workers"] == 1 and again.attrs["resume_cpu_time"] == 0


def test_campaign_refuses_a_continued_sweep_and_the_cli_runs_it(tmp_path, capsys):
    scene = down_sweep(2)
    with pytest.raises(CampaignError, match="continued_sweep"):
        workbench.run_campaign(scene, tmp_path / "no.nc")
    path = tmp_path / "sweep.toml"
    path.write_text(scene.to_toml())
    assert main(["campaign", str(path), "-o", str(tmp_path / "s.nc"), "-q", "--workers", "2"]) == 0
    assert "17 points" in capsys.readouterr().out
    assert main(["campaign", str(path), "-o", str(tmp_path / "t.nc"), "--chunk", "3"]) == 2


@pytest.mark.parametrize(
    ("spec", "key"),
    [
        ("sideways", "sweep.continuation.direction"),
        ({"direction": "up", "along": "beta"}, "sweep.continuation.along"),
        ({"direction": "up", "segments": 99}, "sweep.continuation.segments"),
        ({"direction": "up", "overlap": 0}, "sweep.continuation.overlap"),
        ({"direction": "up", "transient": 3.0}, "sweep.continuation.transient"),
        ({"direction": "up", "seam_tolerance": 2.0}, "sweep.continuation.seam_tolerance"),
        (3, "sweep.continuation"),
    ],
)
def test_continuation_settings_are_validated(spec, key):
    with pytest.raises(workbench.SceneError) as info:
        workbench.load_scene(
            {
                "model": {"name": "duffing"},
                "sweep": {"gamma": [0.2, 0.3, 0.4], "continuation": spec},
            }
        )
    assert info.value.key == key


# -- chaos maps ----------------------------------------------------------------------------------
def test_strobe_period_finds_the_least_period():
    t = np.arange(40)
    assert strobe_period(np.c_[np.cos(np.pi * t)]) == 2
    assert strobe_period(np.c_[np.ones(40), np.cos(2 * np.pi * t / 3)]) == 3
    assert strobe_period(np.c_[np.sin(0.7 * t)]) == 0  # quasi-periodic
    assert strobe_period(np.c_[np.cos(np.pi * t)][:8]) == 0  # too short to tell
    settling = np.c_[1 + 0.5**t * np.cos(np.pi * t)]  # a period-1 orbit approached
    assert strobe_period(settling) == 1 and strobe_period(settling[:10]) == 0


def test_chaos_map_indicators_against_floquet_and_a_chaotic_point(tmp_path):
    """Over gamma x delta of the default Duffing oscillator: the period-1 point's exponent is
    ln|mu| / T of its Floquet multipliers (-delta / 2 for a complex pair: the trace of the
    Jacobian is -delta), the chaotic point has K near 1 and a positive exponent."""
    scene = workbench.load_scene(
        {
            "model": {"name": "duffing"},
            "run": {"cycles": 500, "transient_cycles": 150},  # exponents over 100 cycles
            "record": {"samples_per_period": 1},
            "sweep": {"gamma": [0.2, 0.5], "delta": [0.3, 0.35]},
        }
    )
    maps = chaos_map(scene, tmp_path / "map.nc", workers=2)
    assert maps.lle.dims == ("gamma", "delta") and maps.lle.attrs["units"] == "s-1"
    periodic = maps.sel(gamma=0.2, delta=0.3)
    assert int(periodic.strobe_period) == 1 and float(periodic.zero_one_K) == 0.0
    orbit = periodic_orbit(scene.with_parameters(gamma=0.2, delta=0.3))
    T = 2 * math.pi / 1.2
    expected = math.log(float(orbit.multiplier_modulus.max())) / T
    assert abs(expected + 0.15) < 1e-6  # -delta / 2
    assert abs(float(periodic.lle) - expected) < 3 * float(periodic.lle_stderr) + 1e-3
    chaotic = maps.sel(gamma=0.5, delta=0.3)
    assert int(chaotic.strobe_period) == 0 and float(chaotic.zero_one_K) > 0.8
    assert float(chaotic.lle) > 3 * float(chaotic.lle_stderr) > 0
    assert (maps.lle_status == 0).all()


@pytest.mark.chaotic
def test_a_chaos_map_says_which_exponents_converged(tmp_path):
    """Over 100 cycles (the exponent over 20 from where the run ended, its window grown to at
    most 160) the default Duffing's chaotic point at gamma = 0.5 has its sign decided beyond
    three standard errors before its error reaches the map's 10 % target: lle_converged says
    converged_on_sign (2), lle_unmet is 0; the full protocol (both points of this map are in
    its subset) with its 3 % target is not converged there, and says error target; the
    period-1 point's Floquet exponent (-delta / 2 = -0.15 1/s, the same at rtol / 100) is
    converged (1). Over 3000 cycles (its window 600) the chaotic point meets the map's target
    and is converged (1):
    the variational spectrum's tolerance check, which a map does not run, is left out and said
    so. Before, a map stored no such flag and showed both exponents alike."""
    from workbench.continuation import chaos_indicators

    base = {
        "model": {"name": "duffing"},
        "parameters": {"delta": 0.3},
        "run": {"cycles": 100, "transient_cycles": 150},
        "record": {"samples_per_period": 1},
    }
    maps = chaos_map(
        workbench.load_scene(dict(base, sweep={"gamma": [0.2, 0.5]})),
        tmp_path / "map.nc",
        workers=1,
    )
    flags = maps.lle_converged.attrs["flag_meanings"].split()
    assert maps.lle_converged.attrs["units"] == "1"
    assert flags == ["not_converged", "converged", "converged_on_sign"]
    # CF flags are integers in the archive as in the worker (they were stored as float64)
    for name, dtype in [("lle_converged", np.int8), ("lle_unmet", np.int16),
                        ("lle_status", np.int8), ("lle_method", np.int8),
                        ("strobe_period", np.int16)]:  # fmt: skip
        assert (
            maps[name].dtype == dtype and xr.open_dataset(tmp_path / "map.nc")[name].dtype == dtype
        )
    periodic, chaotic = maps.sel(gamma=0.2), maps.sel(gamma=0.5)
    assert int(periodic.strobe_period) == 1 and int(periodic.lle_converged) == 1
    assert int(periodic.lle_unmet) == 0 and abs(float(periodic.lle) + 0.15) < 1e-6
    assert int(chaotic.strobe_period) == 0 and int(chaotic.lle_status) == 0  # an estimate...
    assert int(chaotic.lle_converged) == 2 and int(chaotic.lle_unmet) == 0  # ... on the sign
    assert 3 * float(chaotic.lle_stderr) < float(chaotic.lle)
    assert float(chaotic.lle_stderr) > 0.1 * float(chaotic.lle)  # not on the target
    assert (maps.lle_full_protocol == 1).all()  # a map of fewer than 3 points: all of them
    assert agrees(float(chaotic.lle), float(chaotic.lle_stderr),
                  float(chaotic.lle_full), float(chaotic.lle_full_stderr))  # fmt: skip
    short = workbench.load_scene(dict(base, parameters={"delta": 0.3, "gamma": 0.5}))
    with pytest.warns(ConvergenceWarning, match="has not converged: error target"):
        point_exponent(short, period=0, cycles=lle_cycles(short))
    long = workbench.load_scene(dict(base, parameters={"delta": 0.3, "gamma": 0.5},
                                     run={"cycles": 3000, "transient_cycles": 150}))  # fmt: skip
    with warnings.catch_warnings():  # converged: no warning, also not for the skipped check
        warnings.simplefilter("error", ConvergenceWarning)
        ind = chaos_indicators(long, workbench.simulate(long))
    assert int(ind.lle_converged) == 1 and int(ind.lle_unmet) == 0
    assert float(ind.lle) >= 10 * float(ind.lle_stderr) > 0  # the map's 10 % target
    assert ind.attrs["lle_detail"] == "tolerance check: not run (check=False)"


def test_an_exponents_unmet_conditions():
    """Which conditions of an estimator's ``failed`` text count against a map's exponent: all
    but those the map leaves out on purpose (the run at rtol / 100); a bound and
    a failed run are never converged; an unknown condition is 'other', not ignored."""
    from workbench.analysis._exponent import NOT_RUN, UNMET, _unmet
    from workbench.continuation import PointExponent

    text = "variants: spread 6.1 %\ntolerance check: not run (check=False)"
    assert _unmet(text, NOT_RUN["copies"]) == ("variants",)
    assert _unmet("tolerance check: not run (check=False)", NOT_RUN["copies"]) == ()
    assert _unmet("a new check: no", NOT_RUN["copies"]) == ("other",)
    disagree = "variational: the variational exponent on the same trajectories reads 30 1/s"
    assert _unmet(disagree, NOT_RUN["copies"]) == ("variational",)
    assert PointExponent(30.0, 5.0, "copies", unmet=("variational",)).unmet_code == 1 << 8
    assert UNMET[7] == "other"  # the bits of archive format 2 keep their meaning
    assert PointExponent(-1.0, 0.01, "floquet").converged
    bound = PointExponent(-3.8, math.nan, "floquet", bound=True)
    assert not bound.converged and bound.unmet == ("upper bound",) and bound.unmet_code == 32
    failed = PointExponent(math.nan, math.nan, "copies", True)
    assert not failed.converged and failed.unmet == ("failed",)
    with pytest.raises(ValueError, match="unmet=.*'wrong'"):
        PointExponent(1.0, 0.1, "copies", unmet=("wrong",))


@pytest.mark.parametrize(
    ("scene", "value", "rtol"),
    [
        ({"model": {"name": "duffing"}, "parameters": {"gamma": 0.3}}, 0.3, 1e-8),
        # an impacting orbit (two events per period; the stop's force has a kink)
        ({"model": {"name": "stop_oscillator"}, "parameters": {"omega": 0.8}}, 0.8, 1e-4),
    ],
)
def test_monodromy_by_copies_agrees_with_the_tangent_system(scene, value, rtol):
    scene = dict(scene, run={"transient_cycles": 100})
    param = next(iter(scene["parameters"]))
    a = StrobeMap(scene, param, rtol=1e-10, monodromy="tangent")
    b = StrobeMap(scene, param, rtol=1e-10, monodromy="copies")
    y, aux = a.initial(value)
    va, vb = a(y, aux, value), b(y, aux, value)
    assert np.abs(va.y1 - vb.y1).max() < 1e-9
    assert np.abs(va.M - vb.M).max() < rtol * np.abs(va.M).max(), (va.M, vb.M)
    assert va.events == vb.events


def test_the_tangent_system_of_a_mechanism_takes_more_steps_than_its_copies():
    """Why ``monodromy="auto"`` takes copies for the mechanisms: on the nine-bar's orbit in
    lasting contact at omega = 1.5 pi (Fig. 32's scene) the tangent system, whose Jacobian is
    differenced along every column (two model evaluations per column and evaluation), takes
    more steps per crank cycle than the bare model, where the copies take about the bare
    model's. Neither may take fewer: each step holds the model's own states to the tolerance
    (:attr:`workbench.solver.Problem.error_blocks`). docs/continuation.md quotes the counts."""
    import re

    scene = workbench.load_scene(ROOT / "studies" / "bifurcation_speed" / "sweep.toml")
    scene = scene.replace(sweep={}, solver=dict(scene.solver, method="dop853"))
    w = 1.5 * math.pi
    steps = {}
    for monodromy in ("tangent", "copies"):
        strobe = StrobeMap(scene, "omega", monodromy=monodromy)
        y, aux = strobe.initial(w)
        steps["bare"] = int(strobe(y, aux, w, tangent=False).stats["steps"])
        steps[monodromy] = int(strobe(y, aux, w).stats["steps"])
    assert steps["tangent"] > 1.2 * steps["bare"]
    assert 0.9 * steps["bare"] < steps["copies"] < 1.1 * steps["bare"]
    page = " ".join((ROOT / "docs" / "continuation.md").read_text().split())
    quoted = re.search(r"1\.5 pi, ([\d ]+) against ([\d ]+) steps per crank cycle, where the "
                       r"copies take ([\d ]+) \(", page)  # fmt: skip
    for text, key in zip(quoted.groups(), ("tangent", "bare", "copies"), strict=True):
        assert abs(int(text.replace(" ", "")) / steps[key] - 1) < 0.02, (key, steps)


def test_a_maps_jacobian_is_in_its_own_scale_at_every_parameter_value():
    """The monodromy is the derivative of the residual Newton drives to zero, in the same
    scaled unknowns, at every value of the parameter, also where the states' characteristic
    sizes depend on it (c omega for the nine-bar's rates). Fig. 32's scene (its own omega 2 pi)
    at 1.5 pi: a column of M equals the central difference of the map along that unknown in
    the map's scale. In the scale at 1.5 pi instead (the copies' own, before), every rate's row
    of a position's column reads 2 / 1.5 of it: Newton's matrix was that far off, it converged
    linearly and the branch from pi stalled at 1.73 pi."""
    scene = workbench.load_scene(ROOT / "studies" / "bifurcation_speed" / "sweep.toml")
    smap = StrobeMap(scene.replace(sweep={}), "omega")
    w = 1.5 * math.pi
    assert smap.value == 2 * math.pi
    y, aux = smap.initial(w)
    v = smap(y, aux, w)
    s, eps = smap.scale(), 1e-4
    for j in (1, 5):  # y_A (m) and vy_A (m s-1)
        d = np.zeros(y.size)
        d[j] = eps * s[j]
        up, down = smap(y + d, aux, w, tangent=False), smap(y - d, aux, w, tangent=False)
        column = (up.y1 - down.y1) / (2 * eps) / s
        assert np.abs(v.M[: y.size, j] - column).max() < 1e-3 * np.abs(column).max(), (j, v.M)


def test_detection_rules_of_the_branch():
    """Which sign changes between two branch points name which bifurcation (grazings come from
    the contact sequences: tests/continuation/test_grazing.py)."""
    from workbench.continuation._branch import _detect

    base = {"size": 2, "fold": 1.0, "pd": 1.0, "ns": 0, "turn": 0.5}
    assert _detect(base, dict(base, fold=-1.0, turn=-0.5)) == ["fold"]
    assert _detect(base, dict(base, fold=-1.0)) == ["branch_point"]
    assert _detect(base, dict(base, pd=-1.0)) == ["period_doubling"]
    assert _detect(base, dict(base, ns=2)) == ["neimark_sacker"]
    assert _detect(base, dict(base, turn=-0.5)) == ["nonsmooth_fold"]  # no multiplier at +1
    assert _detect(base, dict(base, size=3, fold=-1.0)) == []  # other unknowns: not compared


def test_a_turn_where_det_m_minus_i_keeps_its_sign_is_no_fold():
    """Along one curve of a continuous map the tangent's parameter component has the sign of
    det(M - I) (Feigin's rule at a border collision): a turn between two orbits with the same
    sign is a jump, never labelled a fold; with opposite signs it can be one."""
    from workbench.continuation._branch import _turn_without_fold

    assert _turn_without_fold(-0.5, 1.0) == ""
    why = _turn_without_fold(2.78, 0.071)
    assert why.startswith("the tangent turns but det(M - I) keeps its sign (2.78 and 0.071 at")
    assert "Feigin" in why and _turn_without_fold(-1.0, -2.0)


def test_a_step_back_against_the_tangent_with_no_fold_between_is_refused():
    """A corrected point behind the last one in the parameter, against its tangent, with
    det(M - I) of one sign at both (here every multiplier 0.5), is refused: no curve of a
    continuous map turns so. Past a multiplier through +1 (a fold), or across a change of the
    events (a grazing: not Lipschitz there), it is not."""
    from workbench.continuation._branch import BranchSettings, _went_back
    from workbench.continuation._newton import OrbitPoint
    from workbench.continuation._strobe import MapValue

    def point(p, mu, events=0):
        v = MapValue(np.zeros(2), np.zeros(0), np.zeros(0, int), np.diag([mu, 0.5]), events, {})
        return OrbitPoint(p, np.zeros(2), np.zeros(0), v, 0, 0.0, tau=np.array([0.6, 0, 0.8]))

    cfg = BranchSettings(pscale=1.0, bounds=(0.0, 10.0), tolerance=1e-6)
    A = point(1.0, 0.5)
    assert _went_back(A, point(0.999, 0.5), cfg)
    assert not _went_back(A, point(1.001, 0.5), cfg)  # ahead
    assert not _went_back(A, point(1.0 - 1e-7, 0.5), cfg)  # within Newton's tolerance
    assert not _went_back(A, point(0.999, 1.5), cfg)  # a multiplier through +1: a fold
    assert not _went_back(A, point(0.999, 0.5, events=2), cfg)  # a grazing between


@pytest.mark.chaotic
def test_a_contracting_nine_bar_orbit_gets_a_floquet_bound_not_the_noise_rate():
    """The nine-bar at omega = 0.5 pi, c = 20 um (studies/chaos_maps/omega_clearance.toml) is on
    a period-1 orbit that contracts beyond what differences resolve. The two-trajectory method
    read it as +3.34e4 +- 53 1/s: its copies shrink onto the orbit down to the integration's
    noise, and the noise's rate is what it measured. The copies' monodromy at step 1e-6 is
    noise too (largest multiplier ~1.7e-5; at step 1e-4 it falls ~70x, as noise / step does):
    the map says so (lle_status upper_bound) and gives the bound from the larger step. The
    variational monodromy (workbench.analysis.floquet(point, rtol=1e-8), run once: 3.5 min of
    CPU, too long for the suite) puts ln |mu_max| / T at -75.93 1/s, below the bound."""
    from workbench.continuation import chaos_indicators

    scene = workbench.load_scene(ROOT / "studies" / "chaos_maps" / "omega_clearance.toml")
    point = scene.replace(
        sweep={},
        run={"cycles": 10, "transient_cycles": 20},
        solver=dict(scene.solver, method="dop853"),  # the old code's trajectory path
    ).with_parameters(omega=0.5 * math.pi, clearance=2e-5)
    with pytest.warns(ConvergenceWarning, match="has not converged: upper bound"):
        ind = chaos_indicators(point, workbench.simulate(point))
    assert int(ind.strobe_period) == 1
    assert ind.lle_method.attrs["flag_meanings"].split()[int(ind.lle_method)] == "floquet"
    assert ind.lle_status.attrs["flag_meanings"].split()[int(ind.lle_status)] == "upper_bound"
    assert int(ind.lle_converged) == 0 and int(ind.lle_unmet) == 32  # a bound, not an estimate
    # docs/continuation.md quotes the bound, -3.8 1/s: the rate of the copies' noise over the
    # 4-s period, which another processor's rounding moves (within 1/s: noise within e^4)
    assert abs(float(ind.lle) - -3.8) < 1.0 and np.isnan(float(ind.lle_stderr))
    assert -75.93 < float(ind.lle)


def test_an_implicit_scene_method_still_gets_an_exponent():
    """A chaos map of a scene solved by an implicit method (radau, auto) measures its exponent
    with DOP853 (the estimators refuse an implicit method, whose stages use the model's
    Jacobian, not the tangent system's): before, every such point failed (lle_status 1)."""
    from workbench.continuation import chaos_indicators

    point = workbench.load_scene(
        {
            "model": {"name": "duffing"},
            "parameters": {"gamma": 0.5},
            "solver": {"method": "radau", "rtol": 1e-8, "atol": 1e-8},
            "run": {"cycles": 100, "transient_cycles": 50},
            "record": {"samples_per_period": 1},
        }
    )
    ind = chaos_indicators(point, workbench.simulate(point))
    assert int(ind.strobe_period) == 0 and int(ind.lle_status) == 0
    assert int(ind.lle_converged) in (1, 2)  # the error target or the sign
    assert ind.lle_method.attrs["flag_meanings"].split()[int(ind.lle_method)] == "variational"
    assert float(ind.lle) > 3 * float(ind.lle_stderr) > 0


@pytest.mark.slow  # ~30 s of CPU: a 60-cycle transient and three Newton solves on the nine-bar
def test_a_held_onset_velocity_makes_a_family_of_lasting_contact_orbits():
    """A contact lasting through the orbit keeps its onset velocity, which the LN damping
    divides by: the nine-bar's lasting-contact orbit at omega = 1.8 pi is one orbit per held
    velocity, on the same path and with different multipliers (docs/continuation.md quotes
    them). Both joints' velocities are set to each value; Newton starts from the state after 60
    cycles."""
    from workbench.continuation import StrobeMap
    from workbench.continuation._newton import orbit_at

    scene = workbench.load_scene(ROOT / "studies" / "bifurcation_speed" / "sweep.toml")
    point = scene.replace(sweep={}, run={"cycles": 1, "transient_cycles": 60})
    smap = StrobeMap(point.with_parameters(omega=1.8 * math.pi), "omega", rtol=1e-8)
    y, aux = smap.initial(smap.value)
    largest, positions = [], []
    for v0 in (1e-4, 1e-3, 1e-2):  # m/s
        pt = orbit_at(smap, y, np.full_like(aux, v0), smap.value, tolerance=1e-7)
        assert pt.value.events == 0 and pt.value.live.size == 0  # held: not an unknown
        largest.append(float(np.abs(pt.multipliers).max()))
        positions.append(pt.y[:4])  # clearance vectors at A and B, m
    assert [round(m, 2) for m in largest] == [0.01, 0.24, 0.72]  # docs: 0.013, 0.24, 0.72
    assert round(largest[0], 3) == 0.013
    spread = np.ptp(np.array(positions), axis=0).max()
    assert 1e-7 < spread < 1e-6, spread  # m (6.3e-7 measured): within 1 % of c = 1e-4 m


@pytest.mark.chaotic
@pytest.mark.slow  # ~3 min of CPU: the copies alone (4 x 40 cycles, then at rtol 1e-8), the map's
def test_the_copies_alone_agree_on_the_chaotic_nine_bar_once_shallow_contacts_are_monitored():
    """At omega = 2.2 pi (Fig. 32's scene, c = 0.1 mm, c_f = 0.01) the two-trajectory copies
    integrated alone read 30.4 +- 5.0 1/s with separation and growth variants spread by more
    than 20 % after 4 x 40 cycles while the kernel saw a contact only where a step ended
    inside it (0.5.x). With every event function monitored inside the steps they agree with
    the estimate of copies and tangent vector together (what a map point and a route exponent run:
    point_exponent, converged within 4 x 10 cycles), their variants within 20 %, and with the
    copies alone at rtol 1e-8. docs/continuation.md quotes the three (~3 min of CPU)."""
    from workbench.analysis import lle_from_equations

    scene = workbench.load_scene(ROOT / "studies" / "bifurcation_speed" / "sweep.toml")
    point = scene.replace(
        sweep={},
        solver=dict(scene.solver, method="dop853"),
        run={"cycles": 40, "transient_cycles": 30},
    ).with_parameters(omega=2.2 * math.pi)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        alone = lle_from_equations(
            point, cycles=40, budget=160, check=False, tighten=False, variational=False
        )
    assert float(alone.spread) < 0.2
    # the page's figures (one processor's): another rounds differently and its chaotic run
    # goes elsewhere, so each is checked within its own and the quoted standard error
    assert agrees(float(alone.lle), float(alone.stderr), 36.1, 0.8), alone
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)
        e = point_exponent(point, period=0, cycles=40)
    assert e.method == "copies" and e.converged and e.unmet == ()
    assert agrees(e.value, e.error, 35.8, 0.9), e
    assert agrees(float(alone.lle), float(alone.stderr), e.value, e.error)
    # why: the copies' differences are only as accurate as the step control holds the states
    # (rtol of their size, not of the separation); at a 100x tighter tolerance the copies alone
    # agree with the tangent vector's estimate, their variants within 5 %
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        tight = lle_from_equations(
            point, cycles=40, budget=160, check=False, tighten=False, variational=False, rtol=1e-8
        )
    assert float(tight.spread) < 0.05
    assert agrees(float(tight.lle), float(tight.stderr), e.value, e.error)
    assert agrees(float(tight.lle), float(tight.stderr), 36.1, 0.8), tight
    page = " ".join((ROOT / "docs" / "continuation.md").read_text().split())
    assert "read 36.1 +- 0.8 1/s after 4 x 40 cycles" in page
    assert "together read 35.8 +- 0.9 1/s" in page and "36.1 +- 0.8 1/s at rtol 1e-8" in page


def test_a_correction_onto_another_part_of_the_solution_set_is_not_taken(monkeypatch):
    """Newton can converge far from its prediction, on another part of the solution set
    (branch jumping), and a turn of the tangent or a change of a test function between the two
    parts would be labelled a bifurcation that is not there. A corrected point more than two
    steps from the last one is refused and the step halved: here the corrector is made to land
    ten steps off once, and that point is not on the branch, which goes on."""
    import workbench.continuation._branch as branch_module

    real = branch_module._at
    jumped = {}

    def jumping(smap, A, sigma, cfg):
        B = real(smap, A, sigma, cfg)
        if not jumped and A.p > 1.02:
            B.y = B.y + 10.0 * sigma * smap.scale() * np.array([1.0, 0.0])
            jumped["x"] = float(B.y[0])
        return B

    monkeypatch.setattr(branch_module, "_at", jumping)
    r = continue_orbit(hardening(), "omega", stop=1.06, rtol=1e-10, tolerance=1e-9)
    assert jumped, "the branch never stepped past omega = 1.02"
    assert not np.isclose(r.orbit_x.values, jumped["x"], rtol=0, atol=1e-9).any()
    assert float(r.omega[-1]) == pytest.approx(1.06) and (r.omega.diff("point") > 0).all()


def test_a_newton_iterate_the_model_cannot_start_from_is_said_so():
    """The four-bar of studies/mechanisms (a mechanism the continuation tests do not use) is not
    near a period-1 orbit after 50 transient cycles at 300 rpm, and Newton's fourth iterate
    asks the joint for a penetration beyond its limit. The error says that Newton left the
    states the map can start from and how to start closer, not only the model's "the contact
    is too soft" (which named the symptom of a wild iterate as the cause)."""
    from workbench.continuation._newton import NewtonFailure

    scene = workbench.load_scene(ROOT / "studies" / "mechanisms" / "fourbar.toml").replace(
        run={"transient_cycles": 50, "cycles": 1}
    )
    with pytest.raises(NewtonFailure, match="left the states the map can start from") as info:
        continue_orbit(scene, "omega", stop=60.0, max_points=5)
    assert "strobe_period" in str(info.value) and "max_penetration" in str(info.value)


def test_a_branch_counts_every_evaluation_of_its_map(monkeypatch):
    """``map_evaluations`` is every evaluation the map received: Newton's iterations, the
    parameter derivatives, the failed corrections, the grazing's search at fixed parameter
    values and the typing of what lies past it (the impact oscillator's grazing: its steps fail
    at the border collision). Before, only the converged points' Newton work and the located
    bifurcations' were counted: 132 of the 596 evaluations of this branch."""
    calls = [0]
    evaluate = StrobeMap.__call__

    def counted(self, *args, **kwargs):
        calls[0] += 1
        return evaluate(self, *args, **kwargs)

    monkeypatch.setattr(StrobeMap, "__call__", counted)
    params = {"mass": 1.0, "damping": 2.5, "stiffness": 1.0, "gap": 0.17, "restitution": 0.8}
    scene = {
        "model": {"name": "impact_oscillator"},
        "parameters": dict(params, force=1.0, omega=2.3),
        "run": {"transient_cycles": 300},
    }
    r = continue_orbit(scene, "omega", stop=1.9)
    assert r.attrs["map_evaluations"] == calls[0] > 0


def test_an_iterate_whose_contact_lifts_off_says_what_its_orbit_does():
    """A corrector iterate whose live discrete states differ from the branch's (the nine-bar's
    lasting contact lifting off and beginning again within the orbit) says so with its events
    and live states, not that a contact changed at the strobe time."""
    from workbench.continuation._newton import live_changed
    from workbench.continuation._strobe import MapValue

    v = MapValue(np.zeros(8), np.zeros(2), np.array([0]), None, 2, {})
    why = live_changed(v, 1, 0)
    assert "(2 events per 1 period(s), live discrete states [0], against 0 where it" in why
    assert "lifts off and begins again within it" in why
