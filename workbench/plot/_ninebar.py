"""Overview figure of a nine-bar run: journal orbits (in units of c), contact forces, driving
torques and slider acceleration."""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench.plot._base import (
    axis_label,
    display_text,
    display_unit,
    plain_ticks,
    plt,
    run_parameters,
    wrap_title,
)
from workbench.plot._failures import run_status_note


def _clearances(ds: xr.Dataset) -> dict[str, float]:
    from workbench.models import get_model

    return get_model("ninebar").clearances(run_parameters(ds))


def ninebar_overview(ds: xr.Dataset) -> plt.Figure:
    """Journal orbits in units of c beside the time series of forces, torques and slider
    (legends beside the panels, values in readable units, a failed run's status in the
    title)."""
    joints = list(ds.joint.values) if "joint" in ds.coords and ds.sizes.get("joint") else []
    series = [v for v in ("contact_force", "torque", "slider_acceleration") if v in ds]
    ncol = max(len(joints), 1)
    fig = plt.figure(figsize=(4.2 * ncol + 7, 7.5), layout="constrained")
    grid = fig.add_gridspec(max(len(series), 1), 2, width_ratios=[4.2 * ncol, 7])
    if joints and "clearance_x" in ds:
        sub = grid[:, 0].subgridspec(1, ncol)
        c = _clearances(ds)
        theta = np.linspace(0, 2 * np.pi, 200)
        for i, j in enumerate(joints):
            ax = fig.add_subplot(sub[0, i])
            x = ds.clearance_x.sel(joint=j) / c[j]
            y = ds.clearance_y.sel(joint=j) / c[j]
            ax.plot(np.cos(theta), np.sin(theta), "k--", lw=0.8)
            ax.plot(x, y, lw=0.5)
            ax.set_aspect("equal")
            ax.set_xlabel("x / c")
            ax.set_ylabel("y / c")
            ax.set_title(
                f"journal centre, joint {j}\n(c = {display_text(c[j], 'm')}; dashed: e = c)",
                fontsize=9,
            )
    for r, name in enumerate(series):
        ax = fig.add_subplot(grid[r, 1])
        da = ds[name]
        factor, _ = display_unit(da.attrs.get("units"))
        extra = [d for d in da.dims if d != "time"]
        if extra:
            for label in da[extra[0]].values:
                ax.plot(
                    ds.time, da.sel({extra[0]: label}) * factor, lw=0.7, label=f"{extra[0]} {label}"
                )
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
        else:
            ax.plot(ds.time, da * factor, lw=0.7)
        ax.set_ylabel(wrap_title(axis_label(da), 30), fontsize=8)
        ax.grid(alpha=0.3)
        plain_ticks(ax)
        if r == len(series) - 1:
            ax.set_xlabel(axis_label(ds.time))
    status = run_status_note(ds)
    title = wrap_title(ds.attrs.get("title", "nine-bar run"), 120)
    fig.suptitle(f"{title}\n{status}" if status else title, fontsize=10)
    return fig
