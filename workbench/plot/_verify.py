"""The overlay of a verification: the workbench against exudyn at its finest step."""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench.plot._base import axis_label, display_values, plt


def verification_figure(ds: xr.Dataset) -> plt.Figure:
    """Torques, slider acceleration (where the mechanism has a slider) and (with clearances)
    contact forces of both engines.

    With clearance joints a last row zooms on the first impact at each joint.
    """
    finest = str(ds.run.values[-1])
    rows = [("torque", "crank", c) for c in ds.crank.values]
    if "slider_acceleration" in ds:
        rows.append(("slider_acceleration", None, None))
    joints = list(ds.joint.values) if "joint" in ds.dims else []
    rows += [("contact_force", "joint", j) for j in joints]
    n = len(rows) + (1 if joints else 0)
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.9 * n), squeeze=False)
    axes = axes[:, 0]
    for ax, (var, dim, label) in zip(axes, rows, strict=False):
        for run, style in (("workbench", "-"), (finest, "--")):
            da = ds[var].sel(run=run)
            if dim:
                da = da.sel({dim: label})
            ax.plot(ds.time, display_values(da), style, lw=0.9, label=run)
        ax.set_ylabel(axis_label(ds[var]) + (f"\n{dim} {label}" if dim else ""), fontsize=8)
        ax.grid(alpha=0.3)
    if joints:
        ax = axes[-1]
        t_first = np.nanmin(ds.first_impact_time.sel(run="workbench").values)
        window = (ds.time >= t_first - 2e-4) & (ds.time <= t_first + 1.5e-3)
        for j in joints:
            for run, style in (("workbench", "-"), (finest, "--")):
                da = ds.contact_force.sel(run=run, joint=j).where(window, drop=True)
                ax.plot(da.time * 1e3, display_values(da), style, lw=0.9, label=f"{j}: {run}")
        ax.set_xlabel("time [ms]")
        ax.set_ylabel("first impacts\n" + axis_label(ds.contact_force), fontsize=8)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=2)
        axes[-2].set_xlabel(axis_label(ds.time))
    else:
        axes[-1].set_xlabel(axis_label(ds.time))
    axes[0].legend(fontsize=7)
    axes[0].set_title(
        f"workbench (DOP853, rtol {ds.attrs['workbench_rtol']:.0e}) against exudyn "
        f"(generalised-alpha, {finest})",
        fontsize=9,
    )
    fig.tight_layout()
    return fig
