"""The work-precision diagram of an accuracy study."""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench.plot._base import plt


def work_precision_figure(wp: xr.Dataset, error: str = "short_error") -> plt.Figure:
    """Error against wall time (log-log), one line per method, tolerances annotated."""
    fig, ax = plt.subplots(figsize=(6.5, 4.8))
    for method in wp.solver_method.values:
        sel = wp.sel(solver_method=method)
        ok = np.isfinite(sel[error].values) & np.isfinite(sel.wall_time.values)
        ok &= sel[error].values > 0
        x, y = sel.wall_time.values[ok], sel[error].values[ok]
        ax.loglog(x, y, "o-", label=str(method))
        for xi, yi, tol in zip(x, y, sel.rtol.values[ok], strict=True):
            ax.annotate(
                f"{tol:.0e}",
                (xi, yi),
                fontsize=6,
                alpha=0.7,
                xytext=(3, 3),
                textcoords="offset points",
            )
    ax.set_xlabel(f"{wp.wall_time.attrs['long_name']} [s]")
    ax.set_ylabel(f"{wp[error].attrs['long_name']} [1]", fontsize=8)
    ax.set_title(
        f"work-precision: reference {wp.attrs.get('reference_method')} at "
        f"{wp.attrs.get('reference_tolerance'):.0e}",
        fontsize=9,
    )
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
