"""``workbench orbit`` and ``workbench chaos-map`` from scene files: what they write, what they
print, and their one-line errors (the continued sweep's ``workbench campaign`` is in
``tests/continuation/test_continuation.py``)."""

import re

import pytest

import workbench
import workbench.continuation._branch as branch_module
from workbench.archive import open_run
from workbench.cli import main
from workbench.continuation._newton import NewtonFailure

DUFFING = {
    "model": {"name": "duffing"},
    "parameters": {"gamma": 0.25},
    "run": {"transient_cycles": 100},
}


def _scene_file(tmp_path, data, name="scene.toml"):
    path = tmp_path / name
    path.write_text(workbench.load_scene(data).to_toml())
    return str(path)


def test_orbit_writes_the_branch_and_names_its_period_doubling(tmp_path, capsys):
    """The default Duffing oscillator's first period doubling (gamma = 0.2655818, see
    test_continuation.py) from a scene file whose [sweep] gives the range, drawn over the
    strobe samples of a continued sweep of the same scene."""
    sweep = dict(
        DUFFING,
        record={"samples_per_period": 1},
        run={"transient_cycles": 100, "cycles": 20},
        sweep={"gamma": {"start": 0.25, "stop": 0.27, "num": 5}, "continuation": "up"},
    )
    path = _scene_file(tmp_path, sweep)
    diagram = tmp_path / "sweep.nc"
    assert main(["campaign", path, "-o", str(diagram), "-q", "--workers", "1"]) == 0
    out, fig = tmp_path / "branch.nc", tmp_path / "branch.png"
    code = main(
        ["orbit", path, "-o", str(out), "--param", "gamma", "--figure", str(fig), "--state", "x"]
        + ["--diagram", str(diagram), "--var", "x"]
    )
    assert code == 0
    printed = capsys.readouterr().out
    assert "period_doubling at gamma = 0.26558" in printed and "multiplier -1.0000" in printed
    branch = open_run(out)
    assert float(branch.gamma.min()) == 0.25 and 0.2656 < float(branch.gamma.max()) <= 0.27
    assert fig.stat().st_size > 10_000
    # an existing output is refused without --overwrite
    assert main(["orbit", path, "-o", str(out), "--param", "gamma"]) == 2
    assert "exists" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--param", "gamma"], "--stop: the scene does not sweep 'gamma'"),
        (["--param", "gamma", "--stop", "0.26", "--figure", "f.png"], "--figure needs --state"),
        (["--param", "gamma", "--stop", "0.26", "--diagram", "s.nc"], "--diagram needs"),
        (["--param", "nope", "--stop", "0.26"], "nope"),
        # Newton fails at the branch's start (emulated below): one line, no traceback
        (
            ["--param", "gamma", "--stop", "0.26", "-q", "--fail-start"],
            "no first orbit for the branch in 'gamma': Newton's method did not converge at "
            "p = 0.25",
        ),
    ],
)
def test_orbit_errors_are_one_line(tmp_path, capsys, monkeypatch, extra, message):
    monkeypatch.chdir(tmp_path)
    path = _scene_file(tmp_path, DUFFING)
    if "--fail-start" in extra:  # a failure that is not the map's noise: it is not papered over
        extra = [e for e in extra if e != "--fail-start"]

        def failing(*args, **kwargs):
            raise NewtonFailure("Newton's method did not converge at p = 0.25 (emulated)")

        monkeypatch.setattr(branch_module, "orbit_at", failing)
    assert main(["orbit", path, "-o", "b.nc", *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "b.nc").exists()


def test_a_tolerance_below_the_maps_noise_is_raised_at_the_start(tmp_path, capsys):
    """``--tolerance 1e-20`` lies far below the map's noise: Newton stagnates at the branch's
    start, the tolerance is raised to ten times the noise there, and the branch is continued
    (before, the command ended with "no first orbit for the branch"); the archive says where,
    from what and to what."""
    path = _scene_file(tmp_path, DUFFING)
    out = tmp_path / "b.nc"
    args = ["orbit", path, "-o", str(out), "--param", "gamma", "--stop", "0.26", "-q"]
    assert main([*args, "--tolerance", "1e-20"]) == 0
    raised = open_run(out).attrs["tolerance_raised"]
    assert raised.startswith("at 0.25: from 1e-20 to "), raised


def test_orbit_curve_holds_both_parameters_along_the_curve(tmp_path, capsys):
    """``--curve omega`` continues the branch's period doubling (gamma = 0.2655818 at omega =
    1.2) in omega from 1.15 to 1.25: the archive holds gamma and omega along the curve, the
    figure draws it alone, over an orbit diagram (--state) or over a chaos map (--map)."""
    import numpy as np
    import xarray as xr

    from workbench.archive import save_run

    path = _scene_file(tmp_path, DUFFING)
    out, fig = tmp_path / "curve.nc", tmp_path / "curve.png"
    args = ["orbit", path, "-o", str(out), "--param", "gamma", "--stop", "0.27"]
    args += ["--curve", "omega", "--curve-start", "1.15", "--curve-stop", "1.25"]
    assert main([*args, "--figure", str(fig)]) == 0
    printed = capsys.readouterr().out
    assert "period_doubling curve from the period_doubling at gamma = 0.26558" in printed
    curve = open_run(out)
    assert curve.gamma.dims == ("curve_point",) and curve.omega.dims == ("curve_point",)
    assert curve.gamma.attrs["units"] == "1" and curve.omega.attrs["units"] == "rad s-1"
    assert (float(curve.omega[0]), float(curve.omega[-1])) == (1.15, 1.25)
    assert (
        curve.attrs["curve_kind"] == "period_doubling" and "omega" in curve.attrs["curve_parameter"]
    )
    assert 0.2656 < float(curve.gamma.max()) and float(curve.gamma.min()) < 0.2655
    assert fig.stat().st_size > 10_000
    # over the orbit diagram of the branch, and over a chaos map of (gamma, omega)
    assert main([*args, "--overwrite", "--figure", str(fig), "--state", "x"]) == 0
    maps = xr.Dataset(
        {"strobe_period": (("gamma", "omega"), np.ones((3, 3), np.int8), {"units": "1"})},
        coords={
            "gamma": ("gamma", [0.25, 0.26, 0.27], {"units": "1", "long_name": "gamma"}),
            "omega": ("omega", [1.15, 1.2, 1.25], {"units": "rad s-1", "long_name": "omega"}),
        },
        attrs={"campaign_dims": "gamma omega"},
    )
    mapfile = save_run(maps, tmp_path / "map.nc")
    map_fig = tmp_path / "map.png"
    assert main([*args, "--overwrite", "--figure", str(map_fig), "--map", str(mapfile)]) == 0
    assert map_fig.stat().st_size > 10_000
    # and drawn by the chaos map's own command over the map it computes (--curve, repeatable)
    sweep = {"gamma": [0.25, 0.27], "omega": [1.15, 1.25]}
    mapped = {"record": {"samples_per_period": 1}, "run": {"cycles": 100, "transient_cycles": 100}}
    scene = _scene_file(tmp_path, dict(DUFFING, sweep=sweep, **mapped), name="map.toml")
    drawn = tmp_path / "drawn.png"
    cmd = ["chaos-map", scene, "-o", str(tmp_path / "cm.nc"), "--workers", "1", "-q"]
    assert main([*cmd, "--figure", str(drawn), "--curve", str(out), "--curve", str(out)]) == 0
    assert drawn.stat().st_size > 10_000


def test_chaos_map_curve_errors_are_one_line_before_the_map_runs(tmp_path, capsys):
    """``--curve`` needs ``--figure``, an existing file, and a curve in the map's two
    parameters; each refused in one line before any point runs."""
    import xarray as xr

    from workbench.archive import save_run

    sweep = {"gamma": [0.25, 0.27], "delta": [0.3, 0.25]}
    mapped = {"record": {"samples_per_period": 1}, "run": {"cycles": 100, "transient_cycles": 100}}
    scene = _scene_file(tmp_path, dict(DUFFING, sweep=sweep, **mapped))
    other = xr.Dataset(
        {"gamma": ("curve_point", [0.26, 0.27], {"units": "1"})},
        attrs={"continuation_parameter": "gamma", "curve_parameter": "omega"},
    )
    curve = str(save_run(other, tmp_path / "curve.nc"))
    out = tmp_path / "m.nc"
    cases = [
        (["--curve", curve], "--curve draws on the map's figure: give --figure PNG too"),
        (["--figure", str(tmp_path / "m.png"), "--curve", "none.nc"], "--curve 'none.nc': no such"),
        (
            ["--figure", str(tmp_path / "m.png"), "--curve", curve],
            "a curve in ['gamma', 'omega'], the map is over ['delta', 'gamma']",
        ),
    ]
    for extra, message in cases:
        assert main(["chaos-map", scene, "-o", str(out), "-q", *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0], err
        assert not out.exists()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--stop", "0.26", "--curve", "omega", "--curve-stop", "1.3"], "--curve-start: the scene"),
        (
            ["--stop", "0.26", "--curve", "omega", "--curve-start", "1.1", "--curve-stop", "1.3"],
            "--curve: no labelled fold, period_doubling, neimark_sacker or grazing point found "
            "along gamma between 0.25 and 0.26 (found: none)",
        ),
        (
            ["--stop", "0.27", "--curve", "omega", "--curve-start", "1.1", "--curve-stop", "1.3"]
            + ["--curve-kind", "fold"],
            "--curve-kind: no labelled fold point found along gamma between 0.25 and 0.27 "
            "(found: period_doubling at 0.26558179)",
        ),
        (["--stop", "0.27", "--curve-kind", "fold"], "--curve-kind needs --curve"),
        (["--stop", "0.27", "--curve-start", "1.0"], "--curve-start needs --curve"),
        (["--stop", "0.27", "--curve", "nope", "--curve-stop", "1.3"], "--curve 'nope': not a"),
        (["--stop", "0.27", "--curve", "gamma", "--curve-stop", "1.3"], "the same as --param"),
        (
            ["--stop", "0.27", "--curve", "omega", "--curve-start", "1.3", "--curve-stop", "1.4"],
            "must contain the scene's value 1.2",
        ),
        (
            ["--stop", "0.27", "--curve", "omega", "--curve-stop", "1.3", "--curve-kind", "hopf"],
            "--curve-kind 'hopf': allowed: fold, period_doubling",
        ),
        (
            ["--stop", "0.27", "--curve", "omega", "--curve-stop", "1.3", "--map", "m.nc"],
            "--map needs --figure",
        ),
    ],
)
def test_orbit_curve_errors_are_one_line(tmp_path, capsys, monkeypatch, extra, message):
    monkeypatch.chdir(tmp_path)
    path = _scene_file(tmp_path, DUFFING)
    assert main(["orbit", path, "-o", "c.nc", "--param", "gamma", *extra]) == 2
    # an error found on the branch follows the branch's progress lines (issue 40 item 5)
    err = [line for line in capsys.readouterr().err.splitlines() if "branch over" not in line]
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "c.nc").exists()


def test_chaos_map_from_a_scene_file(tmp_path, capfd):
    data = {
        "model": {"name": "duffing"},
        "run": {"cycles": 100, "transient_cycles": 100},
        "record": {"samples_per_period": 1},
        "sweep": {"gamma": [0.25, 0.3], "delta": [0.3, 0.25]},
    }
    path = _scene_file(tmp_path, data)
    out, fig = tmp_path / "map.nc", tmp_path / "map.png"
    code = main(["chaos-map", path, "-o", str(out), "--workers", "2", "-q", "--figure", str(fig)])
    assert code == 0
    assert main(["chaos-map", path, "-o", str(out), "--workers", "2", "-q"]) == 0  # resumed
    maps = open_run(out)
    assert maps.strobe_period.values.tolist() == [[1, 2], [0, 0]]
    assert maps.lle.attrs["units"] == "s-1" and (maps.lle.values[1] > 0).all()
    assert fig.stat().st_size > 10_000
    out, err = capfd.readouterr()  # the workers' output too (file descriptors, not sys.stderr)
    assert "4 points" in out
    # what the workers warned about (exponents not converged over 100 cycles) is one line per
    # kind in the command's form, not Python's file:line lines from each worker (issue 40)
    assert "Warning: " not in err and "_indicators.py" not in err, err
    shown = [line for line in err.splitlines() if line.startswith("workbench chaos-map: warning:")]
    assert len(shown) == len(err.splitlines()), err


def test_the_nine_bar_chaos_map_scenes_are_valid():
    """``make chaos-maps`` runs these: two swept dims, strobe records, 100 cycles for the 0-1
    test (tests/continuation/test_continuation.py checks the indicators themselves)."""
    from pathlib import Path

    found = sorted((Path(__file__).parents[2] / "studies" / "chaos_maps").glob("*.toml"))
    assert [p.stem for p in found] == ["clearance_friction", "omega_clearance"]
    for path in found:
        scene = workbench.load_scene(path)
        assert scene.model == "ninebar" and len(scene.sweep) == 2, path
        assert scene.record["samples_per_period"] == 1 and scene.run["cycles"] >= 100, path
        assert not scene.continuation, path


def test_orbit_shows_its_progress_while_it_runs(tmp_path, capsys, monkeypatch):
    """Issue 40 item 5: a line at the start, where the branch is while it runs (a line per
    point here, the interval set to 0), and the end; none with -q."""
    import workbench._progress as progress_module

    path = _scene_file(tmp_path, DUFFING)
    args = ["orbit", path, "-o", str(tmp_path / "b.nc"), "--param", "gamma", "--stop", "0.27"]
    assert main([*args, "-q"]) == 0
    assert "branch over" not in capsys.readouterr().err
    monkeypatch.setattr(progress_module, "INTERVAL", 0.0)
    assert main([*args, "--overwrite"]) == 0
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "branch over gamma: 0/0.02 ..."
    during = [line for line in lines[1:-1] if line.startswith("branch over gamma: ")]
    assert len(during) >= 10 and all(" s elapsed" in line for line in during)
    assert "points" in during[-1].split("; gamma = ")[1]
    assert lines[-1].startswith("branch over gamma: 0.02/0.02 (100 %) in ")
    assert re.search(r"; gamma = 0\.27, \d+ points$", lines[-1]), lines[-1]
