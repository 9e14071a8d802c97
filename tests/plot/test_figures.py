"""What the figures show (issue 26 item 6, issue 23 item 7, issue 40 item 7): titles that wrap
between words, values in their display units (lengths in mm) without offsets, no "[1]",
legends beside the traces, empty panels that say why, phase portraits and Poincaré sections of
a run, a warning where records are too coarse for the impacts they draw, work-precision
diagrams without empty legend entries, failed campaign points marked and counted, a failed
run's status in its titles."""

import re
import warnings

import numpy as np
import pytest
import xarray as xr

import workbench
from workbench.analysis import bifurcation_diagram
from workbench.plot import (
    CoarseSamplingWarning,
    bifurcation_figure,
    campaign_figure,
    chaos_map_figure,
    run_figures,
    timeseries_figure,
    work_precision_figure,
    wrap_title,
)
from workbench.plot._base import plt
from workbench.solver import Status

TITLE = (
    "Nine-bar mechanism, clearances at A and B (0.5 mm), omega = 2.5 pi, modified Coulomb "
    "(Chen et al. 2019, Sec. 4.2)"
)


def _run(values: dict, status: str = "ok") -> xr.Dataset:
    t = np.linspace(1.6, 4.0, 1201)
    data = {name: (dims, f(t), attrs) for name, (dims, f, attrs) in values.items()}
    return xr.Dataset(
        data,
        coords={
            "time": ("time", t, {"units": "s", "long_name": "time"}),
            "joint": ("joint", ["A", "B"], {"units": "1", "long_name": "joint"}),
        },
        attrs={"title": TITLE, "model": "test", "run_status": status, "run_message": ""},
    )


PENETRATION = (
    ("time", "joint"),
    lambda t: np.c_[np.abs(np.sin(40 * t)), np.abs(np.cos(40 * t))] * 1.6e-5,
    {"units": "m", "long_name": "penetration depth max(e - c, 0)"},
)
RATIO = ("time", lambda t: 0.5 + 0.1 * np.sin(t), {"units": "1", "long_name": "a ratio"})


@pytest.mark.parametrize("width", range(40, 130, 3))
def test_titles_never_break_inside_a_reference_or_a_quantity(width):
    lines = wrap_title(TITLE, width).splitlines()
    assert " ".join(lines) == TITLE
    for line in lines:
        assert not re.search(r"(Sec\.|et al\.|0\.5|2\.5|omega =|=)$", line), (width, line)
        assert not line.startswith(("4.2", "2019", "mm", "pi", "=")), (width, line)


def test_small_lengths_are_shown_in_millimetres_without_an_offset():
    ds = _run({"penetration": PENETRATION, "ratio": RATIO})
    fig = timeseries_figure(ds)
    fig.canvas.draw()
    pen, ratio = fig.axes[0], fig.axes[1]
    assert pen.get_ylabel() == "penetration [mm]"
    assert max(max(line.get_ydata()) for line in pen.get_lines()) == pytest.approx(0.016, rel=0.01)
    assert pen.yaxis.get_offset_text().get_text() == ""
    assert ratio.get_ylabel() == "ratio"  # dimensionless: no "[1]"
    # the legend lies beside the panel, where it covers no trace
    renderer = fig.canvas.get_renderer()
    legend = pen.get_legend().get_window_extent(renderer)
    assert legend.x0 >= pen.get_window_extent(renderer).x1
    assert "(Chen et al. 2019, Sec. 4.2)" in fig._suptitle.get_text().splitlines()[-1]
    plt.close(fig)


def test_a_chaos_map_shows_the_clearance_in_millimetres_and_keeps_a_given_scale():
    c = np.array([2e-5, 6e-5, 1e-4])
    omega = np.pi * np.array([0.5, 1.0])
    maps = xr.Dataset(
        {"zero_one_K": (("omega", "clearance"), [[0.1, 0.2, 0.9], [0.95, 1.0, 0.99]])},
        coords={
            "omega": ("omega", omega, {"units": "rad s-1"}),
            "clearance": ("clearance", c, {"units": "m", "long_name": "radial clearance"}),
        },
        attrs={"campaign_dims": "omega clearance"},
    )
    fig = chaos_map_figure(maps, scales={"omega": 1 / np.pi}, labels={"omega": "omega / pi"})
    fig.canvas.draw()
    ax = fig.axes[0]
    assert ax.get_xlabel() == "omega / pi"
    assert ax.get_ylabel() == "radial clearance [mm]"
    assert ax.get_ylim() == pytest.approx((0.0, 0.12))  # cells around 0.02, 0.06, 0.1 mm
    assert ax.get_xlim() == pytest.approx((0.25, 1.25))
    assert ax.yaxis.get_offset_text().get_text() == ""
    plt.close(fig)


def test_an_empty_panel_says_why_and_a_failed_run_names_its_status():
    nan = ("time", lambda t: np.full(t.size, np.nan), {"units": "m", "long_name": "nothing"})
    cut = ("time", lambda t: np.where(t < 3.0, np.sin(t), np.nan), {"units": "m", "long_name": "x"})
    fig = timeseries_figure(_run({"x": cut, "gone": nan}, status="max_steps"))
    title = fig._suptitle.get_text()
    assert "run failed: max_steps (records end at t = 2.998 s)" in title
    texts = [t.get_text() for t in fig.axes[1].texts]
    assert texts and texts[0].startswith("no finite values: run failed: max_steps")
    assert fig.axes[0].get_xlim() == (1.6, 4.0)  # the whole span, the failure marked
    assert any(line.get_linestyle() == ":" for line in fig.axes[0].get_lines())
    plt.close(fig)


def test_a_forced_run_gets_phase_portraits_and_poincare_sections(tmp_path):
    ds = workbench.simulate(
        {"model": {"name": "duffing"}, "run": {"cycles": 60}, "record": {"samples_per_period": 100}}
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", CoarseSamplingWarning)  # 100 samples: fine enough
        names = [p.name for p in run_figures(ds, tmp_path)]
    assert names == ["duffing_timeseries.png", "duffing_phase.png", "duffing_poincare.png"]
    lorenz = workbench.simulate({"model": {"name": "lorenz"}, "run": {"duration": 5.0}})
    assert [p.name for p in run_figures(lorenz, tmp_path)] == [
        "lorenz_timeseries.png",
        "lorenz_phase.png",  # autonomous: no stroboscopic section
    ]


def test_records_too_coarse_for_their_impacts_are_warned_about(tmp_path):
    """A velocity reversed within one record step (an impact) is a straight edge in the
    portrait: the figure says so and warns; the same motion finely recorded does not."""

    def bouncing(samples: int) -> xr.Dataset:
        t = np.linspace(0.0, 4.0, 4 * samples + 1)
        phase = (t % 1.0) - 0.5  # a sawtooth position: the rate jumps at every impact
        x = np.abs(phase) * 1e-3
        v = np.sign(phase) * 1e-3
        v[np.abs(phase) < 0.5 / samples] = 0.0
        ds = xr.Dataset(
            {
                "x": ("time", x, {"units": "m", "long_name": "x", "rate_variable": "v"}),
                "v": ("time", v, {"units": "m s-1", "long_name": "v"}),
            },
            coords={"time": ("time", t, {"units": "s", "long_name": "time"})},
            attrs={"samples_per_period": samples, "forcing_period": 1.0, "model": "test"},
        )
        return ds

    with pytest.warns(CoarseSamplingWarning, match=r"too coarse .* changes by 100 % of its range"):
        paths = run_figures(bouncing(200), tmp_path)
    assert [p.name for p in paths][1:] == ["test_phase.png", "test_poincare.png"]
    smooth = bouncing(200).assign(v=lambda d: d.v.copy(data=np.cos(2 * np.pi * d.time.values)))
    with warnings.catch_warnings():
        warnings.simplefilter("error", CoarseSamplingWarning)
        run_figures(smooth, tmp_path / "smooth")


def test_work_precision_lists_failed_settings_instead_of_empty_legend_entries():
    methods, tols = ["dop853", "dopri5", "scipy:LSODA"], [1e-4, 1e-6, 1e-8]
    error = np.array([[1e-2, 1e-4, 1e-6], [2e-2, 3e-4, 4e-6], [np.nan, np.nan, np.nan]])
    wall = np.array([[0.1, 0.2, 0.4], [0.1, 0.3, 0.6], [np.nan, np.nan, np.nan]])
    status = np.zeros((3, 3), np.int8)
    status[2] = int(Status.MODEL_FAILURE)
    wp = xr.Dataset(
        {
            "short_error": (("solver_method", "rtol"), error, {"long_name": "error", "units": "1"}),
            "wall_time": (("solver_method", "rtol"), wall, {"long_name": "wall time"}),
            "status": (("solver_method", "rtol"), status),
        },
        coords={"solver_method": methods, "rtol": tols},
        attrs={"reference_method": "dop853", "reference_tolerance": 1e-10},
    )
    fig = work_precision_figure(wp)
    ax = fig.axes[0]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend == ["dop853 (rtol 1e-04 .. 1e-08)", "dopri5 (rtol 1e-04 .. 1e-08)"]
    assert ax.get_ylabel() == "error"
    notes = [t.get_text() for t in ax.texts]
    assert any("no point: scipy:LSODA: model_failure at every tolerance" in n for n in notes)
    assert sorted(a.get_text() for a in ax.texts if a.get_text().startswith("1e")) == sorted(
        ["1e-04", "1e-08"] * 2
    )  # each line labelled at its two ends only
    plt.close(fig)


@pytest.mark.filterwarnings("ignore::workbench.campaign.CampaignWarning")
def test_failed_campaign_points_are_marked_and_counted(tmp_path):
    scene = {
        "model": {"name": "duffing"},
        "run": {"cycles": 30, "transient_cycles": 20},
        "record": {"samples_per_period": 1},
        "solver": {"max_steps": 850},
        "sweep": {"gamma": {"start": 0.2, "stop": 0.6, "num": 9}},
    }
    runs = workbench.run_campaign(scene, tmp_path / "c.nc", workers=1)
    failed = runs.gamma.values[runs.status.values > 1]
    assert 0 < failed.size < 9  # the tolerance makes some points exceed max_steps
    note = f"{failed.size} of 9 points failed ({failed.size} max_steps)"
    fig = campaign_figure(runs)
    assert note in fig._suptitle.get_text()
    for ax in fig.axes:
        (cross,) = [line for line in ax.get_lines() if line.get_label().startswith("failed")]
        np.testing.assert_array_equal(cross.get_xdata(), failed)
    plt.close(fig)
    fig = bifurcation_figure(bifurcation_diagram(runs, "x"))
    ax = fig.axes[0]
    assert note in ax.get_title()
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [
        f"failed ({failed.size} max_steps)"
    ]
    plt.close(fig)
