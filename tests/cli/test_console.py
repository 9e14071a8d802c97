"""What a person sees (issue 18, item 6): figures that fit their canvas, campaign figures over
the swept parameter, the notice before a first compile, the self-check in the run's summary
line, and verify's tables with one explaining header each."""

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import workbench
from workbench.cli import main
from workbench.plot import PANELS_PER_FIGURE, campaign_figure, run_figure_names, run_figures
from workbench.plot._base import plt

TITLE = (
    "Nine-bar mechanism, clearances at A and B (0.5 mm), omega = 2.5 pi, modified Coulomb "
    "(Chen et al. 2019, Sec. 4.2)"
)


def _run_like(n_vars: int) -> xr.Dataset:
    """A run-shaped dataset with ``n_vars`` variables over time, every other one per joint,
    with long names as long as the nine-bar's."""
    t = np.linspace(0.0, 1.0, 200)
    data = {}
    for k in range(n_vars):
        attrs = {"units": "m s-1", "long_name": f"rate of the clearance vector number {k}, x"}
        if k % 2:
            data[f"v{k}"] = (("time", "joint"), np.c_[np.sin(t * k), np.cos(t * k)] * 1e-4, attrs)
        else:
            data[f"v{k}"] = ("time", np.sin(t * k) * 1e3, attrs)
    return xr.Dataset(
        data,
        coords={
            "time": ("time", t, {"units": "s", "long_name": "time"}),
            "joint": ("joint", ["A", "B"], {"units": "1", "long_name": "joint"}),
        },
        attrs={"title": TITLE, "model": "duffing"},
    )


def _inside(fig: plt.Figure) -> None:
    """Every title and axis label lies inside the canvas, and no two y-labels overlap."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    width, height = fig.bbox.width, fig.bbox.height
    texts = [fig._suptitle] if fig._suptitle is not None else []
    ylabels = []
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        texts += [ax.title, ax.xaxis.label, ax.yaxis.label]
        ylabels.append(ax.yaxis.label.get_window_extent(renderer))
    for text in texts:
        if not text.get_text():
            continue
        bb = text.get_window_extent(renderer)
        assert bb.x0 >= -0.5 and bb.x1 <= width + 0.5, (text.get_text(), bb, width)
        assert bb.y0 >= -0.5 and bb.y1 <= height + 0.5, (text.get_text(), bb, height)
    for i, a in enumerate(ylabels):
        for b in ylabels[i + 1 :]:
            assert not a.overlaps(b), (a, b)


def test_time_series_are_paged_and_fit_their_canvas(tmp_path):
    ds = _run_like(16)
    paths = run_figures(ds, tmp_path)
    names = [p.name for p in paths]
    assert (
        names
        == run_figure_names("duffing", 16)
        == [
            "duffing_timeseries.png",
            "duffing_timeseries-2.png",
            "duffing_phase.png",  # no rate declared: the first three variables, pairwise
        ]
    )
    from workbench.plot import timeseries_figure

    fig = timeseries_figure(ds, list(ds.data_vars)[:PANELS_PER_FIGURE], title=TITLE + " (1/2)")
    assert sum(ax.get_visible() for ax in fig.axes) == PANELS_PER_FIGURE
    _inside(fig)
    legend = [t.get_text() for t in fig.axes[1].get_legend().get_texts()]
    assert legend == ["joint A", "joint B"]
    plt.close(fig)


def test_campaign_figures_put_the_swept_parameter_on_the_axis(tmp_path):
    omega = np.array([1.0, 1.5, 2.0, 2.5])
    x = np.random.default_rng(0).normal(size=(4, 6, 2))
    ds = xr.Dataset(
        {
            "clearance_x": (("omega", "time", "joint"), x, {"units": "m", "long_name": "x"}),
            "status": ("omega", np.array([0, 0, 2, 0], np.int8), {"units": "1"}),
        },
        coords={
            "omega": ("omega", omega, {"units": "rad s-1", "long_name": "crank speed"}),
            "joint": ("joint", ["A", "B"]),
        },
        attrs={"campaign_dims": "omega", "model": "ninebar", "title": "omega sweep"},
    )
    fig = campaign_figure(ds)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "crank speed [rad s-1]"
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend == ["joint A", "joint B", "failed (1 max_steps)"]
    data = [line for line in ax.get_lines() if not line.get_label().startswith("failed")]
    xs = np.concatenate([line.get_xdata() for line in data])
    ys = np.concatenate([line.get_ydata() for line in data])
    assert set(xs[np.isfinite(ys)]) == {1.0, 1.5, 2.5}  # the failed point has no data ...
    (cross,) = [line for line in ax.get_lines() if line.get_label().startswith("failed")]
    assert list(cross.get_xdata()) == [2.0] and cross.get_label() == "failed (1 max_steps)"
    assert "1 of 4 points failed (1 max_steps)" in fig._suptitle.get_text()  # ... but is marked
    _inside(fig)
    plt.close(fig)
    assert [p.name for p in run_figures(ds, tmp_path)] == ["ninebar_campaign.png"]


def test_plot_of_a_campaign_archive(tmp_path, capsys):
    spec = {
        "model": {"name": "duffing"},
        "run": {"cycles": 10, "transient_cycles": 10},
        "record": {"samples_per_period": 1},
        "sweep": {"gamma": [0.3, 0.4, 0.5]},
    }
    store = tmp_path / "c.nc"
    workbench.run_campaign(spec, store, workers=1)
    assert main(["plot", str(store), "-o", str(tmp_path / "figs")]) == 0
    assert (tmp_path / "figs" / "duffing_campaign.png").stat().st_size > 10_000
    assert main(["plot", str(store), "-o", str(tmp_path / "figs")]) == 2  # exists
    assert "pass --overwrite" in capsys.readouterr().err


def test_the_first_compile_is_announced_timed_and_named_in_the_summary(tmp_path, capsys):
    """A cold cache: the notice says what the compile takes and on what it depends, the time
    it took follows, and the run's summary names it apart from the integration's wall time. A
    warm cache: not a word."""
    from workbench.campaign._warm import kernel_cached
    from workbench.cli._console import compile_kernel

    scene = workbench.load_scene({"model": {"name": "duffing"}, "run": {"cycles": 1}})
    workbench.simulate(scene)
    assert kernel_cached(scene) is True
    assert compile_kernel(scene) is None
    assert capsys.readouterr().err == ""
    assert kernel_cached(scene.replace(solver={"method": "scipy:RK45"})) is None
    import workbench.campaign._warm as warm

    with pytest.MonkeyPatch.context() as mp:  # as if the cache were cold
        mp.setattr(warm, "kernel_cached", lambda scene: False)
        assert compile_kernel(scene, quiet=True) >= 0 and capsys.readouterr().err == ""
        assert compile_kernel(scene) >= 0
        assert capsys.readouterr().err.count("\n") == 2  # the notice, the time it took
    (tmp_path / "s.toml").write_text('[model]\nname = "duffing"\n[run]\ncycles = 2\n')
    with tempfile.TemporaryDirectory() as cold:  # an empty cache: nothing compiled yet
        env = dict(os.environ, WORKBENCH_CACHE_DIR=cold)
        out = subprocess.run(
            [sys.executable, "-m", "workbench.cli", "run", "s.toml", "-o", "r.nc"],
            capture_output=True,
            text=True,
            env=env,
            timeout=900,
            cwd=tmp_path,
        )
    assert out.returncode == 0, out.stderr
    notice = "compiling the duffing kernel (first run only; measured on a "
    assert notice in out.stderr and "the wall time growing with the machine's load" in out.stderr
    assert re.search(r"compiled the duffing kernel in \d+ s \(\d+ s of CPU\)", out.stderr)
    assert re.search(r"s of integration \(after compiling the kernel in \d+ s\)", out.stdout)


def test_the_run_summary_line_shows_the_self_check(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(
        '[model]\nname = "duffing"\n[solver]\ncheck = true\n[run]\ncycles = 3\n'
        "[record]\nsamples_per_period = 10\n"
    )
    assert main(["run", str(scene), "-o", str(tmp_path / "r.nc"), "-q"]) == 0
    line = capsys.readouterr().out.strip()
    assert "; self-check (solver.check): error " in line and "against rtol 1e-10" in line


def test_verify_tables_have_a_header_each_and_none_is_empty(capsys):
    from workbench.cli._verify import _print_tables

    runs = ["workbench", "exudyn h=1e-06"]
    ds = xr.Dataset(
        {
            "max_relative_error": (("run", "series"), [[0.0, 0.0], [0.01, 0.02]]),
            "first_impact_time": (("run", "joint"), np.zeros((2, 0))),
            "first_impact_force": (("run", "joint"), np.zeros((2, 0))),
            "peak_force": (("run", "joint"), np.zeros((2, 0))),
        },
        coords={"run": runs, "series": ["torque", "slider_acceleration"], "joint": []},
    )
    _print_tables(ds)
    out = capsys.readouterr().out
    assert "largest difference from the workbench" in out and "exudyn h=1e-06" in out
    assert "first contact" not in out and "peak_force" not in out and "Empty" not in out


def test_the_generated_kernel_of_a_model_is_printed(capsys):
    assert main(["kernel", "duffing", "--part", "jacobian", "--path"]) == 0
    path = Path(capsys.readouterr().out.strip())
    assert path.is_file() and path.name.startswith("jacobian_workbench_models_duffing_")
    assert main(["kernel", "duffing", "--part", "jacobian"]) == 0
    out = capsys.readouterr().out
    assert "from workbench.models.duffing import" in out and out.endswith(path.read_text())
    assert main(["kernel", "no_such_model"]) == 2
    assert "MODEL: got 'no_such_model'; allowed: a scene file or one of" in capsys.readouterr().err


def test_every_command_takes_quiet():
    """Getting started promises ``-q`` on every command."""
    from workbench.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    for name, parser in sub.choices.items():
        assert "-q" in parser._option_string_actions, name


def test_a_long_compile_says_how_long_it_has_lasted(capsys, monkeypatch):
    """Issue 40 item 5: between the notice and the time it took, a line per interval (set to
    0.05 s here, 30 s in use) while the compile lasts; nothing more with -q."""
    import time

    import workbench._progress as progress_module
    import workbench.campaign._warm as warm
    from workbench.cli._console import compile_kernel

    scene = workbench.load_scene({"model": {"name": "duffing"}, "run": {"cycles": 1}})
    monkeypatch.setattr(warm, "kernel_cached", lambda scene: False)
    monkeypatch.setattr(warm, "load_kernel", lambda toml: time.sleep(0.4))
    monkeypatch.setattr(progress_module, "INTERVAL", 0.05)
    assert compile_kernel(scene) >= 0.4
    lines = capsys.readouterr().err.splitlines()
    assert lines[0].startswith("compiling the duffing kernel (")
    assert lines[-1].startswith("compiled the duffing kernel in ")
    assert len(lines) >= 4 and set(lines[1:-1]) == {"compiling the duffing kernel: 0 s so far"}
    assert compile_kernel(scene, quiet=True) >= 0.4
    assert capsys.readouterr().err == ""
