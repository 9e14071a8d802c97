"""The work-precision diagram of an accuracy study."""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from workbench.plot._base import axis_label, plt, wrap_title
from workbench.solver import Status


def _missing_note(missing: list[tuple[str, float, str]], n_tolerances: int) -> str:
    """``"scipy:LSODA: model_failure at every tolerance; scipy:Radau: no error to show at
    1e-05, 1e-06"``: the settings without a point, by method and reason."""
    parts = []
    for method in dict.fromkeys(m for m, _, _ in missing):
        rows = [(t, why) for m, t, why in missing if m == method]
        for why in dict.fromkeys(w for _, w in rows):
            tols = [t for t, w in rows if w == why]
            where = (
                "at every tolerance"
                if len(rows) == len(tols) == n_tolerances
                else "at " + ", ".join(f"{t:.0e}" for t in tols)
            )
            parts.append(f"{method}: {why} {where}")
    return "; ".join(parts)


def work_precision_figure(wp: xr.Dataset, error: str = "short_error") -> plt.Figure:
    """Error against wall time (log-log), one line per method: the legend gives each method's
    tolerances (loosest to tightest), the two ends of each line are labelled with theirs, and
    the settings without a point (a failed run, or no error to show) are listed in the panel
    with their status instead of a legend entry without a point."""
    fig, ax = plt.subplots(figsize=(7.0, 5.0), layout="constrained")
    missing, labelled = [], []
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
            at = (np.log10(x[i]), np.log10(y[i]))
            if any(abs(at[0] - a) < 0.06 and abs(at[1] - b) < 0.25 for a, b in labelled):
                continue  # another line's end label is there already (the legend has both)
            labelled.append(at)
            ax.annotate(
                f"{t[i]:.0e}",
                (x[i], y[i]),
                fontsize=6,
                color=line.get_color(),
                xytext=(4, dy + 2 * (k % 3)),
                textcoords="offset points",
            )
    if missing:
        ax.text(
            0.0,
            -0.13,
            wrap_title("no point: " + _missing_note(missing, len(wp.rtol)), 110),
            transform=ax.transAxes,
            fontsize=7,
            va="top",
            ha="left",
            color="tab:red",
        )
    for axis in (ax.xaxis, ax.yaxis):  # decades and their 2 and 5, as plain numbers
        axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(NullFormatter())
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
