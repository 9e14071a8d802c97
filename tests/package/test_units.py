"""Units (issue 40 item 7): a non-dimensional model stores "1", a dimensional one SI, a pure
number's range error names no unit, and every figure shows a variable in one display unit
(:func:`workbench.plot.display_unit`), whatever values the figure draws."""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import workbench
from workbench.analysis import bifurcation_diagram
from workbench.models import get_model
from workbench.plot import (
    CoarseSamplingWarning,
    bifurcation_figure,
    campaign_figure,
    chaos_map_figure,
    display_unit,
    run_phase_figure,
    run_poincare_figure,
    timeseries_figure,
)
from workbench.plot._base import plt

DATA = Path(__file__).resolve().parents[2] / "data"


def _unit(label: str) -> str | None:
    """The unit in a label's trailing brackets (None: a label without a unit)."""
    m = re.search(r"\[([^\]]*)\]$", label)
    return m.group(1) if m else None


def _labels(fig, long_name: str, name: str) -> list[str]:
    """Every axis label of ``fig`` that names the variable (by long name or by name)."""
    out = []
    for ax in fig.axes:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            text = label.split(": ")[-1]
            if text.startswith((f"{long_name} [", f"{name} [")) or text in (long_name, name):
                out.append(text)
    return out


def test_the_duffing_oscillator_stores_pure_numbers():
    ds = workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 2}})
    for name in ("x", "v"):
        assert ds[name].attrs["units"] == "1", name
    for name in ("delta", "alpha", "beta", "gamma", "x0", "v0"):
        assert ds[name].attrs["units"] == "1", name
    # the time axis (and with it the forcing frequency) is in the solver's unit of time
    assert ds.omega.attrs["units"] == "rad s-1" and ds.time.attrs["units"] == "s"
    # what the analysis derives from a state keeps its units
    section = workbench.analysis.poincare_section(ds, "x")
    assert section.x.attrs["units"] == "1"


def test_a_pure_number_out_of_range_is_named_without_a_unit():
    with pytest.raises(workbench.SceneError) as bad:
        workbench.load_scene({"model": {"name": "duffing"}, "parameters": {"delta": -1.0}})
    assert str(bad.value).endswith("parameters.delta: got -1.0; must lie in [0, inf]")
    with pytest.raises(workbench.SceneError, match=r"must lie in \(0, inf\] m$"):
        workbench.load_scene({"model": {"name": "bouncing_ball"}, "parameters": {"h0": 0.0}})


@pytest.mark.parametrize(
    ("model", "variable", "units"),
    [
        ("ninebar", "clearance_x", "m"),
        ("ninebar", "contact_force", "N"),
        ("ninebar", "slider_acceleration", "m s-2"),
        ("slider_crank", "slider_acceleration", "m s-2"),
        ("stop_oscillator", "x", "m"),
        ("impact_oscillator", "x", "m"),
        ("bouncing_ball", "h", "m"),
        ("lorenz", "x", "1"),
    ],
)
def test_a_dimensional_model_keeps_si_and_a_dimensionless_one_carries_1(model, variable, units):
    m = get_model(model)
    assert m.variables(m.default_effects())[variable].units == units


def test_the_stop_and_impact_oscillators_are_dimensional():
    for name in ("stop_oscillator", "impact_oscillator"):
        m = get_model(name)
        assert m.parameter("mass").units == "kg" and m.parameter("stiffness").units == "N m-1"
        assert m.parameter("force").units == "N" and m.parameter("gap").units == "m"


def test_the_display_unit_depends_on_the_units_alone():
    assert display_unit("m") == (1e3, "mm")
    for units in ("1", "m s-1", "m s-2", "N", "rad s-1", "s", None):
        assert display_unit(units) == (1.0, units)


def test_a_length_has_one_display_unit_in_every_figure_of_a_run():
    """A displacement reaching 2 m over the record whose stroboscopic samples stay within
    0.02 m: the time series, the phase portrait and the Poincaré section all show it in mm."""
    t = np.linspace(0.0, 40.0, 4001)
    x = 2.0 * np.sin(2 * np.pi * t) + 0.01 * np.cos(0.1 * t)
    v = 4 * np.pi * np.cos(2 * np.pi * t) - 0.001 * np.sin(0.1 * t)
    ds = xr.Dataset(
        {
            "x": ("time", x, {"units": "m", "long_name": "displacement", "rate_variable": "v"}),
            "v": ("time", v, {"units": "m s-1", "long_name": "velocity"}),
        },
        coords={"time": ("time", t, {"units": "s", "long_name": "time"})},
        attrs={"samples_per_period": 100, "forcing_period": 1.0, "model": "test"},
    )
    figures = [timeseries_figure(ds), run_phase_figure(ds), run_poincare_figure(ds)]
    labels = [label for fig in figures for label in _labels(fig, "displacement", "x")]
    assert len(labels) == 3 and {_unit(label) for label in labels} == {"mm"}, labels
    # the values drawn are in that unit
    top = max(np.nanmax(np.abs(line.get_ydata())) for line in figures[0].axes[0].get_lines())
    assert top == pytest.approx(1e3 * np.abs(x).max(), rel=1e-12)
    for fig in figures:
        plt.close(fig)


@pytest.mark.filterwarnings("ignore::workbench.campaign.CampaignWarning")
def test_every_figure_of_a_duffing_campaign_labels_gamma_and_x_alike(tmp_path):
    scene = {
        "model": {"name": "duffing"},
        "run": {"cycles": 8, "transient_cycles": 4},
        "record": {"samples_per_period": 20},
        "sweep": {"gamma": {"start": 0.1, "stop": 0.5, "num": 3}, "delta": [0.2, 0.3]},
    }
    runs = workbench.run_campaign(scene, tmp_path / "c.nc", workers=1)
    one = workbench.simulate(
        {"model": {"name": "duffing"}, "run": {"cycles": 60}, "record": {"samples_per_period": 50}}
    )
    peak = np.abs(runs.x).max("time").assign_attrs(runs.x.attrs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CoarseSamplingWarning)
        figures = [
            campaign_figure(runs, ["x"]),
            bifurcation_figure(bifurcation_diagram(runs.sel(delta=0.3), "x")),
            chaos_map_figure(runs.assign(peak=peak), indicators=("peak",)),
            timeseries_figure(one),
            run_phase_figure(one),
            run_poincare_figure(one),
        ]
    gamma = [label for fig in figures for label in _labels(fig, "forcing amplitude", "gamma")]
    x = [label for fig in figures for label in _labels(fig, "displacement", "x")]
    assert len(gamma) == 3 and len(x) == 5, (gamma, x)
    # pure numbers: the label names the quantity without a unit, in every figure
    assert set(gamma) == {"forcing amplitude"}
    assert {_unit(label) for label in x} == {None}, x
    for fig in figures:
        plt.close(fig)


def test_a_ninebar_length_keeps_its_si_unit_and_shows_in_mm():
    ds = workbench.open_run(DATA / "ninebar_default.nc")
    assert ds.clearance_x.attrs["units"] == "m" and ds.contact_force.attrs["units"] == "N"
    name = ds.clearance_x.attrs["long_name"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", CoarseSamplingWarning)  # the archive's impacts
        figures = [timeseries_figure(ds, ["clearance_x", "contact_force"]), run_phase_figure(ds)]
    labels = [label for fig in figures for label in _labels(fig, name, "clearance_x")]
    assert labels and {_unit(label) for label in labels} == {"mm"}, labels
    force = figures[0].axes[1]
    assert _unit(force.get_ylabel()) == "N"
    top = max(np.nanmax(np.abs(line.get_ydata())) for line in figures[0].axes[0].get_lines())
    assert top == pytest.approx(1e3 * float(np.abs(ds.clearance_x).max()), rel=1e-9)
    for fig in figures:
        plt.close(fig)
