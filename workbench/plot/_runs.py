"""Figures of one run: time series of every stored variable and model-specific overviews."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import xarray as xr  # noqa: E402

__all__ = ["axis_label", "run_figures", "timeseries_figure", "register_overview"]

_OVERVIEWS: dict[str, Callable[[xr.Dataset], plt.Figure]] = {}


def register_overview(model: str):
    """Decorator: a function ``f(ds) -> Figure`` drawn by :func:`run_figures` for ``model``."""

    def deco(f):
        _OVERVIEWS[model] = f
        return f

    return deco


def run_parameters(ds: xr.Dataset) -> dict[str, float]:
    """The resolved parameters (model defaults and the scene's values, SI) of a stored run."""
    import tomllib

    from workbench import load_scene

    return load_scene(tomllib.loads(ds.attrs["scene"])).resolved_parameters


def axis_label(da: xr.DataArray) -> str:
    """``long_name [units]`` of a variable or coordinate."""
    name = da.attrs.get("long_name", da.name)
    units = da.attrs.get("units")
    return f"{name} [{units}]" if units else str(name)


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
    if model == "ninebar":
        import workbench.plot._ninebar  # noqa: F401  (registers the overview)
    elif model == "slider_crank":
        import workbench.plot._slider_crank  # noqa: F401  (registers the overview)
    if model in _OVERVIEWS:
        figures["overview"] = _OVERVIEWS[model](ds)
    for name, fig in figures.items():
        path = directory / f"{model or 'run'}_{name}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        written.append(path)
    return written
