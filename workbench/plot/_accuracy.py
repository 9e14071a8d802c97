"""The work-precision diagram of an accuracy study."""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench.plot._base import axis_label, plt, wrap_title
from workbench.solver import Status


def work_precision_figure(wp: xr.Dataset, error: str = "short_error") -> plt.Figure:
    """Error against wall time (log-log), one line per method: the legend gives each method's
    tolerances (loosest to tightest), the two ends of each line are labelled with theirs, and
    the settings without a point (a failed run, or no error to show) are listed in the panel
    with their status instead of a legend entry without a point."""
    fig, ax = plt.subplots(figsize=(7.0, 5.0), layout="constrained")
    missing = []
    for k, method in enumerate(wp.solver_method.values):
        sel = wp.sel(solver_method=method)
        ok = np.isfinite(sel[error].values) & np.isfinite(sel.wall_time.values)
        ok &= sel[error].values > 0
        tols = sel.rtol.values
        for tol in tols[~ok]:
            flag = int(sel.status.sel(rtol=tol)) if "status" in sel else 0
            why = Status(flag).label if 0 < flag < len(Status) else "no error to show"
            missing.append((str(method), float(tol), why))
        if not ok.any():
            continue
        x, y, t = sel.wall_time.values[ok], sel[error].values[ok], tols[ok]
        label = (
            f"{method} (rtol {t[0]:.0e} .. {t[-1]:.0e})" if len(t) > 1 else f"{method} ({t[0]:.0e})"
        )
        (line,) = ax.loglog(x, y, "o-", ms=4, label=label)
        for i, dy in ((0, 4), (len(t) - 1, -10)):  # the loose end above, the tight end below
            ax.annotate(
                f"{t[i]:.0e}",
                (x[i], y[i]),
                fontsize=6,
                color=line.get_color(),
                xytext=(4, dy + 2 * (k % 3)),
                textcoords="offset points",
            )
    if missing:
        by_method: dict[str, list[str]] = {}
        for method, tol, why in missing:
            by_method.setdefault(method, []).append(f"{tol:.0e} {why}")
        text = "no point: " + "; ".join(f"{m} ({', '.join(v)})" for m, v in by_method.items())
        ax.text(
            0.01,
            0.01,
            wrap_title(text, 80),
            transform=ax.transAxes,
            fontsize=6,
            va="bottom",
            ha="left",
            color="tab:red",
            bbox={"facecolor": "white", "alpha": 0.8, "lw": 0},
        )
    ax.set_xlabel(f"{wp.wall_time.attrs['long_name']} [s]")
    ax.set_ylabel(axis_label(wp[error]), fontsize=8)
    ax.set_title(
        f"work-precision: reference {wp.attrs.get('reference_method')} at "
        f"{wp.attrs.get('reference_tolerance'):.0e}",
        fontsize=9,
    )
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    return fig
