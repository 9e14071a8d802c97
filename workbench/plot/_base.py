"""What every figure module shares: matplotlib without a display, axis labels from ``long_name``
and ``units``, and the registry of model-specific overview figures."""

from __future__ import annotations

from collections.abc import Callable

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import xarray as xr  # noqa: E402

__all__ = ["axis_label", "overview", "plt", "register_overview", "run_parameters"]

_OVERVIEWS: dict[str, Callable[[xr.Dataset], plt.Figure]] = {}


def register_overview(model: str):
    """Decorator: a function ``f(ds) -> Figure`` drawn by :func:`run_figures` for ``model``."""

    def deco(f):
        _OVERVIEWS[model] = f
        return f

    return deco


def run_parameters(ds: xr.Dataset) -> dict[str, float]:
    """The resolved parameters (model defaults and the scene's values, SI) of a stored run."""
    from workbench.scene import scene_from_toml

    return scene_from_toml(ds.attrs["scene"]).resolved_parameters


def axis_label(da: xr.DataArray) -> str:
    """``long_name [units]`` of a variable or coordinate."""
    name = da.attrs.get("long_name", da.name)
    units = da.attrs.get("units")
    return f"{name} [{units}]" if units else str(name)


def overview(model: str) -> Callable[[xr.Dataset], plt.Figure] | None:
    """The overview figure registered for ``model`` (None if there is none)."""
    return _OVERVIEWS.get(model)
