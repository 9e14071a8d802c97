"""Phase portraits and Poincaré sections of one run, for ``run --figures`` and
:func:`workbench.plot.run_figures`, and the check that a series is fine enough to draw them.

Pairs: every recorded variable whose attribute ``rate_variable`` names a recorded rate (the
model's declaration, :class:`workbench.models.Quantity`; ``x`` and ``v`` of Duffing, the
clearance coordinates and their rates of the mechanisms, one pair per joint), else the first
three variables against each other (an autonomous system such as Lorenz). The Poincaré section
of a forced run is its stroboscopic samples (every ``samples_per_period``-th record).

A record drawn as a polygon hides what happens between its samples: an impact that reverses a
velocity within one record step becomes a straight edge through the portrait.
:func:`coarse_sampling` finds that (the largest change of a variable between consecutive
records, relative to its range); the figures then say so in their title and warn
(:class:`CoarseSamplingWarning`).
"""

from __future__ import annotations

import itertools
import warnings

import numpy as np
import xarray as xr

from workbench.plot._base import (
    axis_label,
    display_values,
    plain_ticks,
    plt,
    title_width,
    wrap_title,
)
from workbench.plot._failures import run_status_note

__all__ = [
    "COARSE_JUMP",
    "CoarseSamplingWarning",
    "coarse_sampling",
    "phase_pairs",
    "run_phase_figure",
    "run_poincare_figure",
    "strobed",
]

#: a change between consecutive records larger than this share of the variable's range is a
#: visible straight edge in a drawn curve: a sinusoid reaches it below ~pi / 0.25 = 13 samples
#: per period, an impact whenever it lasts less than a record step
COARSE_JUMP = 0.25
_MAX_PAIRS = 6
_FEW_PERIODS = 50


class CoarseSamplingWarning(UserWarning):
    """A series is too coarse for the fast changes (impacts) it draws."""


def _series(ds: xr.Dataset) -> list[str]:
    return [v for v in ds.data_vars if "time" in ds[v].dims]


def _elements(da: xr.DataArray) -> list[tuple[str, dict]]:
    """(label, selection) of each element of the dims other than ``time`` (e.g. a joint)."""
    others = [d for d in da.dims if d != "time"]
    if not others:
        return [("", {})]
    values = [list(da[d].values) for d in others]
    return [
        (
            ", ".join(f"{d} {v}" for d, v in zip(others, combo, strict=True)),
            dict(zip(others, combo, strict=True)),
        )
        for combo in itertools.product(*values)
    ]


def phase_pairs(ds: xr.Dataset) -> list[tuple[str, xr.DataArray, xr.DataArray]]:
    """The (label, value, rate) pairs a run's phase portraits show (module doc), at most six."""
    names = _series(ds)
    pairs = []
    for name in names:
        rate = ds[name].attrs.get("rate_variable")
        if rate in ds.data_vars and ds[rate].dims == ds[name].dims:
            for label, where in _elements(ds[name]):
                pairs.append((label, ds[name].sel(where), ds[rate].sel(where)))
    if not pairs:
        scalar = [n for n in names if ds[n].dims == ("time",)][:3]
        pairs = [("", ds[a], ds[b]) for a, b in itertools.combinations(scalar, 2)]
    return pairs[:_MAX_PAIRS]


def strobed(ds: xr.Dataset) -> bool:
    """Whether a run has stroboscopic samples (a forced run whose records divide the period)."""
    return "forcing_period" in ds.attrs and "samples_per_period" in ds.attrs


def coarse_sampling(*series: xr.DataArray) -> tuple[float, float]:
    """The largest change between consecutive records relative to the series' range, over the
    given series, and the time (s) where it happens (NaN for a constant or empty series)."""
    worst, when = 0.0, float("nan")
    for da in series:
        v = np.asarray(da.values, dtype=float)
        finite = np.isfinite(v)
        if finite.sum() < 3:
            continue
        span = float(np.nanmax(v) - np.nanmin(v))
        if not span > 0:
            continue
        jumps = np.abs(np.diff(v)) / span
        jumps[~np.isfinite(jumps)] = 0.0
        k = int(np.argmax(jumps))
        if jumps[k] > worst:
            worst = float(jumps[k])
            when = float(da["time"].values[k + 1]) if "time" in da.coords else float("nan")
    return worst, when


def _coarse_note(ds: xr.Dataset, pairs) -> str:
    """The title's note (and a warning) when the records are too coarse for the portrait."""
    worst, when = coarse_sampling(*(r for _, _, r in pairs), *(v for _, v, _ in pairs))
    if worst <= COARSE_JUMP:
        return ""
    spp = ds.attrs.get("samples_per_period")
    per = (
        f"{spp} samples per period" if spp else f"records {ds.attrs.get('record_dt', '?')} s apart"
    )
    text = (
        f"the records ({per}) are too coarse for the fastest changes they draw: a variable "
        f"changes by {100 * worst:.0f} % of its range between two records (at t = {when:.4g} s), "
        "so fast changes such as impacts appear as straight edges; record more samples per "
        "period to resolve them"
    )
    warnings.warn(CoarseSamplingWarning(text), stacklevel=3)
    return f"coarse records: straight edges hide what happens within a record step ({per})"


def _grid(n: int) -> tuple[plt.Figure, np.ndarray]:
    cols = 1 if n == 1 else (2 if n in (2, 4) else 3)
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(
        rows, cols, figsize=(4.4 * cols, 3.9 * rows + 0.9), squeeze=False, layout="constrained"
    )
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    return fig, axes


def _scaled(da: xr.DataArray) -> tuple[np.ndarray, str]:
    return display_values(da), axis_label(da)


def _panel_title(label: str, value: xr.DataArray, rate: xr.DataArray) -> str:
    """``clearance_vx against clearance_x, joint A``."""
    return f"{rate.name} against {value.name}" + (f", {label}" if label else "")


def _title(fig, ds: xr.Dataset, what: str, notes: list[str]) -> str:
    width = title_width(fig, 9)
    lines = [wrap_title(f"{what}: {ds.attrs.get('title', '')}".rstrip(": "), width)]
    lines += [wrap_title(n, width) for n in notes if n]
    return "\n".join(lines)


def run_phase_figure(ds: xr.Dataset) -> plt.Figure:
    """Phase portraits of a run (:func:`phase_pairs`): the trajectory as a thin line, the
    stroboscopic samples of a forced run as red dots; the title names a failed run's status and
    records too coarse for their impacts."""
    pairs = phase_pairs(ds)
    if not pairs:
        raise ValueError("the run records fewer than two variables over time: no phase portrait")
    fig, axes = _grid(len(pairs))
    strobe = ds.attrs["samples_per_period"] if strobed(ds) else None
    for ax, (label, value, rate) in zip(axes.flat, pairs, strict=False):
        x, xl = _scaled(value)
        y, yl = _scaled(rate)
        ax.plot(x, y, lw=0.3, color="0.35", label="trajectory")
        if strobe:
            ax.plot(x[::strobe], y[::strobe], ".", color="tab:red", ms=3, label="once per period")
        ax.set_xlabel(xl, fontsize=8)
        ax.set_ylabel(yl, fontsize=8)
        ax.set_title(_panel_title(label, value, rate), fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
        plain_ticks(ax)
    if strobe:
        handles, labels = axes.flat[0].get_legend_handles_labels()
        fig.legend(handles, labels, fontsize=7, loc="outside lower center", ncol=2)
    notes = [run_status_note(ds), _coarse_note(ds, pairs)]
    fig.suptitle(_title(fig, ds, "phase portraits", notes), fontsize=9)
    return fig


def run_poincare_figure(ds: xr.Dataset) -> plt.Figure:
    """Stroboscopic Poincaré sections of a forced run: one point per forcing period (the
    records at t0 + k T), one panel per pair of :func:`phase_pairs`."""
    if not strobed(ds):
        raise ValueError(
            "the run has no stroboscopic samples (an autonomous model, or records "
            "that do not divide the forcing period)"
        )
    pairs = phase_pairs(ds)
    strobe = int(ds.attrs["samples_per_period"])
    fig, axes = _grid(len(pairs))
    n = 0
    for ax, (label, value, rate) in zip(axes.flat, pairs, strict=False):
        x, xl = _scaled(value)
        y, yl = _scaled(rate)
        x, y = x[::strobe], y[::strobe]
        n = int(np.isfinite(x).sum())
        ax.plot(x, y, ".", color="k", ms=3)
        ax.set_xlabel(xl, fontsize=8)
        ax.set_ylabel(yl, fontsize=8)
        ax.set_title(_panel_title(label, value, rate), fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
        plain_ticks(ax)
    what = f"stroboscopic Poincaré sections ({n} periods, one point each)"
    if n < _FEW_PERIODS:
        what += f"; with fewer than {_FEW_PERIODS} points a section shows no structure yet"
    fig.suptitle(_title(fig, ds, what, [run_status_note(ds)]), fontsize=9)
    return fig
