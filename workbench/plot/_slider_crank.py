"""Overview figure of a slider-crank run, drawn as Flores et al. (2006) draw theirs: slider
acceleration and crank moment against the crank angle, and the journal orbit in units of c."""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench.plot._base import (
    axis_label,
    display_text,
    display_values,
    plain_ticks,
    plt,
    run_parameters,
    wrap_title,
)
from workbench.plot._failures import run_status_note


def crank_angle_deg(ds: xr.Dataset, params: dict[str, float]) -> np.ndarray:
    """Crank angle (deg) at the records: theta10 + omega t."""
    return np.degrees(params["theta10"] + params["omega"] * ds.time.values)


def slider_crank_overview(ds: xr.Dataset) -> plt.Figure:
    """Slider acceleration and crank moment against crank angle; the journal orbit (x/c, y/c)."""
    params = run_parameters(ds)
    angle = crank_angle_deg(ds, params)
    has_joint = "clearance_x" in ds
    fig, axes = plt.subplots(
        1, 3 if has_joint else 2, figsize=(15 if has_joint else 10, 4.4), layout="constrained"
    )
    axes[0].plot(angle, display_values(ds.slider_acceleration), lw=0.7)
    axes[0].set_ylabel(axis_label(ds.slider_acceleration))
    axes[1].plot(angle, ds.torque.sel(crank="1"), lw=0.7)
    axes[1].set_ylabel("crank moment [N m]")
    for ax in axes[:2]:
        ax.set_xlabel("crank angle [deg]")
        ax.grid(alpha=0.3)
    if has_joint:
        c = params["clearance"]
        theta = np.linspace(0, 2 * np.pi, 200)
        ax = axes[2]
        ax.plot(np.cos(theta), np.sin(theta), "k--", lw=0.8)
        ax.plot(ds.clearance_x.sel(joint="B") / c, ds.clearance_y.sel(joint="B") / c, lw=0.5)
        ax.set_aspect("equal")
        ax.set_xlabel("x / c")
        ax.set_ylabel("y / c")
        ax.set_title(
            f"journal centre in the slider's bearing\n(c = {display_text(c, 'm')}; dashed: e = c)",
            fontsize=9,
        )
    for ax in axes:
        plain_ticks(ax)
    status = run_status_note(ds)
    title = wrap_title(ds.attrs.get("title", "slider-crank run"), 140)
    fig.suptitle(f"{title}\n{status}" if status else title, fontsize=10)
    return fig
