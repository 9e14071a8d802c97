"""Figures of one run (time series of every stored variable, model-specific overviews) and of a
campaign (every stored variable against the swept parameter)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import xarray as xr

from workbench.archive import SERIES_DIMS, save_figure
from workbench.plot._base import (
    axis_label,
    display_unit,
    display_values,
    overview,
    plain_ticks,
    plt,
    units_label,
    wrap_title,
)
from workbench.plot._failures import failure_note, mark_failed, run_status_note
from workbench.plot._phase import run_phase_figure, run_poincare_figure, strobed

__all__ = [
    "PANELS_PER_FIGURE",
    "campaign_figure",
    "run_figure_names",
    "run_figures",
    "timeseries_figure",
]

# Panels of one time-series or campaign figure: a grid of up to 4 rows x 2 columns; more
# variables go to further figures (``<model>_timeseries-2.png``, ...).
PANELS_PER_FIGURE = 8
_COLUMNS = 2


def _series(ds: xr.Dataset) -> list[str]:
    """The stored variables over time (in dataset order): along ``time``, or along ``record``
    in a campaign whose points have their own record times."""
    return [v for v in ds.data_vars if any(d in SERIES_DIMS for d in ds[v].dims)]


def _pages(names: list[str]) -> list[list[str]]:
    return [names[i : i + PANELS_PER_FIGURE] for i in range(0, len(names), PANELS_PER_FIGURE)]


def run_figure_names(
    model: str | None, n_series: int, *, campaign: bool = False, strobe: bool = False
) -> list[str]:
    """File names :func:`run_figures` writes for a run (or a campaign) of ``model`` with
    ``n_series`` variables over time: known before the run, so that a command can refuse an
    existing file before it simulates anything. A run with two or more series also gets its
    phase portraits (``<model>_phase.png``) and, with stroboscopic samples (``strobe``: a
    forced run), its Poincaré sections (``<model>_poincare.png``)."""
    stem = f"{model or 'run'}_{'campaign' if campaign else 'timeseries'}"
    pages = max(1, math.ceil(n_series / PANELS_PER_FIGURE))
    names = [f"{stem}.png"] + [f"{stem}-{k}.png" for k in range(2, pages + 1)]
    if not campaign and n_series >= 2:
        names.append(f"{model or 'run'}_phase.png")
        if strobe:
            names.append(f"{model or 'run'}_poincare.png")
    if not campaign and model is not None and overview(model) is not None:
        names.append(f"{model}_overview.png")
    return names


def _grid(n: int, title: str, width: float = 11.0) -> tuple[plt.Figure, np.ndarray]:
    """A figure of ``n`` panels in up to two columns, its title wrapped inside the canvas."""
    cols = 1 if n == 1 else _COLUMNS
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(
        rows,
        cols,
        figsize=(width if cols > 1 else 7.5, 2.3 * rows + 0.9),
        squeeze=False,
        layout="constrained",
    )
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    if title:
        fig.suptitle(wrap_title(title, 110 if cols > 1 else 75), fontsize=10)
    return fig, axes


def _panel_title(da: xr.DataArray) -> str:
    return wrap_title(str(da.attrs.get("long_name", da.name)), 60)


def _short_label(da: xr.DataArray) -> str:
    """``name [unit]`` in the display unit (:func:`~workbench.plot.display_unit`)."""
    return f"{da.name}{units_label(display_unit(da.attrs.get('units'))[1])}"


def _last_record(ds: xr.Dataset) -> float:
    """Time (s) of the last record with a finite value (the start when there is none)."""
    finite = np.zeros(ds.sizes["time"], bool)
    for name in _series(ds):
        finite |= np.isfinite(ds[name].values).reshape(ds.sizes["time"], -1).any(axis=1)
    last = np.flatnonzero(finite)
    return float(ds.time[last[-1]] if last.size else ds.time[0])


def _empty_panel(ax, da: xr.DataArray, status: str) -> None:
    """Say why a panel has nothing to draw, instead of leaving it blank."""
    why = f"no finite values: {status}" if status else "no finite values in this record"
    ax.text(
        0.5,
        0.5,
        wrap_title(why, 45),
        ha="center",
        va="center",
        fontsize=8,
        color="tab:red",
        transform=ax.transAxes,
    )


def _proxies(ax) -> list:
    """Legend handles of a scatter panel: the dots' colours at a visible size, the failed
    points' cross as drawn."""
    from matplotlib.lines import Line2D

    out = []
    for h in ax.get_lines():
        if h.get_label().startswith("_"):
            continue
        if h.get_marker() == ".":
            h = Line2D(
                [], [], ls="none", marker="o", ms=4, color=h.get_color(), label=h.get_label()
            )
        out.append(h)
    return out


def _legend_outside(ax, **kw) -> None:
    """A legend to the right of the panel, where it covers no trace."""
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0, **kw)


def _lines(da: xr.DataArray, skip: tuple[str, ...]) -> list[tuple[str, xr.DataArray]]:
    """One (label, 1-D or swept array) per element of the dims other than ``skip``: e.g.
    ``("joint A", ...)``; a single unlabelled line when there are none."""
    others = [d for d in da.dims if d not in skip]
    if not others:
        return [("", da)]
    stacked = da.stack(_line=others)
    out = []
    for i in range(stacked.sizes["_line"]):
        key = stacked["_line"].values[i]
        key = key if isinstance(key, tuple) else (key,)
        label = ", ".join(f"{d} {_fmt(v)}" for d, v in zip(others, key, strict=True))
        out.append((label, stacked.isel(_line=i, drop=True)))
    return out


def _fmt(value) -> str:
    return f"{value:.4g}" if isinstance(value, float | np.floating) else str(value)


def timeseries_figure(
    ds: xr.Dataset, variables: list[str] | None = None, *, title: str | None = None
) -> plt.Figure:
    """Variables against time in a grid of panels (up to two columns), each titled with its
    ``long_name`` and labelled with its name and display unit (:func:`display_unit`: a
    length in mm);
    extra dims (e.g. ``joint``) become lines named in a legend beside the panel. A panel
    without a finite value says so; a failed run's status is in the title, and a dotted red
    line marks its last record on the whole span asked for. Give at most
    :data:`PANELS_PER_FIGURE` variables for a readable figure (:func:`run_figures` pages
    them)."""
    names = variables or _series(ds)
    status = run_status_note(ds)
    text = ds.attrs.get("title", "") if title is None else title
    fig, axes = _grid(len(names), f"{text}\n{status}" if status else text)
    for k, (ax, name) in enumerate(zip(axes.flat, names, strict=False)):
        da = ds[name]
        factor, _ = display_unit(da.attrs.get("units"))
        if not np.isfinite(da.values).any():
            _empty_panel(ax, da, status)
        for label, line in _lines(da, ("time",)):
            ax.plot(ds.time, line * factor, lw=0.7, label=label or None)
        if status and ds.sizes["time"] > 1:  # the whole span asked for, and where it ended
            ax.set_xlim(float(ds.time[0]), float(ds.time[-1]))
            ax.axvline(_last_record(ds), color="tab:red", ls=":", lw=1.0)
        if len(da.dims) > 1:
            _legend_outside(ax)
        ax.set_title(_panel_title(da), fontsize=8)
        ax.set_ylabel(_short_label(da), fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
        plain_ticks(ax)
        if k >= len(names) - axes.shape[1]:  # the bottom panel of each column
            ax.set_xlabel(axis_label(ds.time), fontsize=8)
    return fig


def _campaign_axis(ds: xr.Dataset) -> str:
    """The swept dim on the x axis: the one with the most values."""
    dims = ds.attrs["campaign_dims"].split()
    return max(dims, key=lambda d: ds.sizes[d])


def campaign_figure(
    ds: xr.Dataset, variables: list[str] | None = None, *, title: str | None = None
) -> plt.Figure:
    """Every record of each point against the swept parameter (the dim with the most values,
    axis labelled with its ``long_name`` and display unit), one panel per variable: a bifurcation
    diagram when the campaign records one sample per forcing period. The other dims (the
    model's, e.g. ``joint``, and other swept ones) are lines named in a legend beside the
    panel. Failed points have no data: each is marked by a red cross on the panel's bottom
    edge at its parameter value, counted in the legend and named in the title."""
    names = variables or _series(ds)
    param = _campaign_axis(ds)
    text = ds.attrs.get("title", "") if title is None else title
    note = failure_note(ds)
    fig, axes = _grid(len(names), f"{text}\n{note}" if note else text)
    ok = ds["status"] <= 1 if "status" in ds else True  # ok or terminated
    for k, (ax, name) in enumerate(zip(axes.flat, names, strict=False)):
        da = ds[name].where(ok)
        factor, _ = display_unit(da.attrs.get("units"))
        if not np.isfinite(da.values).any():
            _empty_panel(ax, da, note or "")
        rdim = next(d for d in da.dims if d in SERIES_DIMS)  # time, or record
        for label, line in _lines(da, (param, rdim)):
            y = line.transpose(param, rdim).values * factor
            x = np.broadcast_to(display_values(ds[param])[:, None], y.shape)
            ax.plot(x.ravel(), y.ravel(), ".", ms=1.5, alpha=0.6, label=label or None)
        mark_failed(ax, ds, param)  # counted in the title
        if any(d not in (param, rdim) for d in da.dims):
            _legend_outside(ax, handles=_proxies(ax))
        ax.set_title(_panel_title(da), fontsize=8)
        ax.set_ylabel(_short_label(da), fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
        plain_ticks(ax)
        if k >= len(names) - axes.shape[1]:
            ax.set_xlabel(axis_label(ds[param]), fontsize=8)
    return fig


def run_figures(ds: xr.Dataset, directory: Path) -> list[Path]:
    """Write the standard figures of a run or a campaign (PNG) into ``directory``; return their
    paths (named as :func:`run_figure_names` says).

    A run: its time series, :data:`PANELS_PER_FIGURE` variables per figure, its phase portraits
    and, when forced, its stroboscopic Poincaré sections (:mod:`workbench.plot._phase`), and
    the model's overview when it has one. A campaign archive (from
    :func:`workbench.run_campaign`): every variable against the swept parameter, failed points
    marked.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    model = ds.attrs.get("model")
    campaign = "campaign_dims" in ds.attrs
    series = _series(ds)
    pages = _pages(series)
    names = run_figure_names(model, len(series), campaign=campaign, strobe=strobed(ds))
    draw = campaign_figure if campaign else timeseries_figure
    title = ds.attrs.get("title", "")
    figures = []
    for k, page in enumerate(pages):
        suffix = f" ({k + 1}/{len(pages)})" if len(pages) > 1 else ""
        figures.append(draw(ds, page, title=title + suffix))
    if not campaign and len(series) >= 2:
        figures.append(run_phase_figure(ds))
        if strobed(ds):
            figures.append(run_poincare_figure(ds))
    if not campaign and overview(model) is not None:
        figures.append(overview(model)(ds))
    written = []
    for name, fig in zip(names, figures, strict=True):
        path = directory / name
        save_figure(fig, path, dpi=120, close=True)
        written.append(path)
    return written
