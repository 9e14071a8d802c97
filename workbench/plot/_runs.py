"""Figures of one run: time series of every stored variable and model-specific overviews."""

from __future__ import annotations

from pathlib import Path

import xarray as xr

from workbench.plot import _ninebar, _slider_crank  # noqa: F401 (they register their overviews)
from workbench.plot._base import axis_label, overview, plt

__all__ = ["run_figures", "timeseries_figure"]


def timeseries_figure(ds: xr.Dataset, variables: list[str] | None = None) -> plt.Figure:
    """One panel per variable against time; extra dims (e.g. ``joint``) become labelled lines."""
    names = variables or [v for v in ds.data_vars if "time" in ds[v].dims]
    fig, axes = plt.subplots(
        len(names), 1, figsize=(8, 1.9 * len(names) + 0.8), sharex=True, squeeze=False
    )
    for ax, name in zip(axes[:, 0], names, strict=True):
        da = ds[name]
        others = [d for d in da.dims if d != "time"]
        if others:
            stacked = da.stack(line=others) if len(others) > 1 else da.rename({others[0]: "line"})
            for i in range(stacked.sizes["line"]):
                label = str(stacked["line"].values[i])
                ax.plot(ds.time, stacked.isel(line=i), lw=0.8, label=f"{others[0]} {label}")
            ax.legend(fontsize=7, loc="upper right")
        else:
            ax.plot(ds.time, da, lw=0.8)
        ax.set_ylabel(axis_label(da), fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel(axis_label(ds.time))
    fig.suptitle(ds.attrs.get("title", ""), fontsize=10)
    fig.tight_layout()
    return fig


def run_figures(ds: xr.Dataset, directory: Path) -> list[Path]:
    """Write the standard figures of a run (PNG) into ``directory``; return their paths."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    figures = {"timeseries": timeseries_figure(ds)}
    model = ds.attrs.get("model")
    draw = overview(model)
    if draw is not None:
        figures["overview"] = draw(ds)
    for name, fig in figures.items():
        path = directory / f"{model or 'run'}_{name}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        written.append(path)
    return written
