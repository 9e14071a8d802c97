"""Figures of linear stability: the Jacobian's eigenvalues along a run, and Floquet multipliers
over a parameter. Axis labels carry the units."""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench.plot._base import axis_label, display_unit, plt

__all__ = ["floquet_figure", "jacobian_spectrum_figure"]


def jacobian_spectrum_figure(spec: xr.Dataset) -> plt.Figure:
    """Left: the largest real part of the Jacobian's eigenvalues over the run, coloured by mode
    (:func:`workbench.analysis.jacobian_spectrum`). Right: every eigenvalue in the complex
    plane (real part against frequency), coloured by mode."""
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [3, 2]})
    modes = list(spec.modes.values)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    t = spec.time.values
    for k, name in enumerate(modes):
        sel = spec["mode"].values == k
        if not sel.any():
            continue
        c = colors[k % len(colors)]
        ax0.plot(t[sel], spec.largest_real.values[sel], ".", ms=2, color=c, label=name)
        re = spec.eigenvalue_real.values[sel].ravel()
        hz = spec.eigenvalue_imag.values[sel].ravel() / (2 * np.pi)
        ax1.plot(re, hz, ".", ms=1.5, color=c, alpha=0.5)
    ax0.axhline(0.0, color="k", lw=0.6)
    ax0.set_yscale("symlog", linthresh=10.0)
    ax0.set_xlabel(axis_label(spec.time))
    ax0.set_ylabel("largest real part of an eigenvalue [1/s]")
    ax0.legend(fontsize=7, markerscale=4, title="mode", title_fontsize=7)
    ax0.grid(alpha=0.3)
    ax1.axvline(0.0, color="k", lw=0.6)
    ax1.set_xscale("symlog", linthresh=10.0)
    ax1.set_xlabel("real part [1/s]")
    ax1.set_ylabel("imaginary part / 2 pi [Hz]")
    ax1.grid(alpha=0.3)
    fig.suptitle("eigenvalues of the Jacobian along the run (" + spec.attrs.get("method", "") + ")",
                 fontsize=9)  # fmt: skip
    fig.tight_layout()
    return fig


def floquet_figure(sweep: xr.Dataset) -> plt.Figure:
    """Moduli of the Floquet multipliers of a continued periodic orbit against the parameter
    in its display unit (:func:`workbench.analysis.floquet_sweep`), the unit circle's radius
    and the first loss of stability marked."""
    (param,) = [d for d in sweep.modulus.dims if d != "multiplier"]
    x = sweep[param]
    scale, _ = display_unit(x.attrs.get("units"))
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for m in sweep.multiplier.values:
        ax.plot(
            x * scale, sweep.modulus.sel(multiplier=m), "o-", ms=3, lw=0.8, label=f"multiplier {m}"
        )
    ax.axhline(1.0, color="k", lw=0.8, ls="--", label="|mu| = 1")
    value = sweep.attrs.get("first_loss_value", np.nan) * scale
    if np.isfinite(value):
        ax.axvline(value, color="C3", lw=0.8)
        ax.text(value, ax.get_ylim()[1], f" {sweep.attrs['first_loss_kind']} at {value:.4g}",
                color="C3", va="top", fontsize=8)  # fmt: skip
    ax.set_xlabel(axis_label(x))
    ax.set_ylabel("|Floquet multiplier|")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig
