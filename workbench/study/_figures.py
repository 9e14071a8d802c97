"""Figures of a study, one per figure (or group of figures) of the paper, titled with its number.

Every case is an ensemble of realisations, and a chaotic run's peak is one sample of a
distribution, so peaks are drawn as distributions:

- ``series``: per case the band between the smallest and largest value over the realisations
  at each time and the unperturbed realisation 0 as a line, over the first two recorded crank
  cycles; beside it a box plot of the realisations' peaks (magnitude) per case with the
  paper's value;
- ``orbit``: journal centre orbits of realisation 0 in units of c, one panel per joint and case;
- ``phase`` (realisation 0), ``poincare`` (all realisations), ``lle`` (running estimate of
  realisation 0 and the band of the realisations' LLEs): the four clearance coordinates x1, y1,
  x2, y2 of the chaos study;
- ``bifurcation``: stroboscopic samples of every realisation against the swept parameter;
- ``contact_vs_friction``: contact fraction and contact-force percentiles (50/90/99 %) against
  the friction coefficient, median and interquartile band over the realisations;
- ``energy_balance``: driver work and dissipated energy per crank cycle against the friction
  coefficient, median and interquartile band.

A figure without a ``paper`` number is one beyond the paper (file ``extra-<kind>.png``).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from workbench.plot import (
    CoarseSamplingWarning,
    coarse_sampling,
    display_unit,
    failure_note,
    mark_failed,
    wrap_title,
)
from workbench.plot._base import display_text, display_values, plain_ticks, units_label
from workbench.plot._phase import COARSE_JUMP
from workbench.plot._runs import axis_label, plt
from workbench.study._claims import _key
from workbench.study._exponents import reference_exponent
from workbench.study._measure import (
    CLEARANCE_COORDINATES,
    PEAK_PERIODS,
    clearance_of,
    select,
    strobe,
)
from workbench.study._spec import Study, parameter_sweep

__all__ = ["study_figures"]


def study_figures(
    study: Study,
    runs: dict,
    members: dict,
    scenes: dict,
    sweeps: dict,
    directory: Path,
    measures: dict,
) -> list[Path]:
    """Draw every ``[[figure]]`` of the study into ``directory``; returns the PNG paths.

    ``runs``: case -> campaign dataset; ``members``: case or view -> ensemble dataset (dims
    ``realisation``, ``time``, ...); ``scenes``: their scenes; ``sweeps``: sweep case ->
    contact statistics (see :func:`workbench.study.run_study`); ``measures``: the study's
    numbers.
    """
    ctx = {
        "study": study,
        "runs": runs,
        "members": members,
        "scenes": scenes,
        "sweeps": sweeps,
        "measures": measures,
    }
    paths = []
    for spec in study.figures:
        kind = spec["kind"]
        fig = _DRAW[kind](spec, ctx)
        label = spec.get("var", kind)
        sel = "".join(f"-{v}" for v in spec.get("select", {}).values())
        name = f"fig{spec['paper']}-{label}{sel}" if "paper" in spec else f"extra-{label}{sel}"
        path = directory / f"{name}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def _title(spec: dict, text: str, width: int = 110) -> str:
    """The figure's title, wrapped between words (never inside "Fig. 28" or "0.1 mm")."""
    if "paper" not in spec:
        return wrap_title(f"Beyond the paper: {text}", width)
    return wrap_title(f"Fig. {spec['paper']} (Chen et al.): {text}", width)


def _failed_in(ctx, case: str) -> str:
    """:func:`workbench.plot.failure_note` of a case's campaign ('' when none failed)."""
    run = ctx["runs"].get(case)
    return failure_note(run) if run is not None else ""


def _first_cycles(ds: xr.Dataset, da: xr.DataArray) -> xr.DataArray:
    t0 = float(ds.time[0])
    period = float(ds.attrs.get("forcing_period", np.inf))
    return da.sel(time=slice(t0, t0 + PEAK_PERIODS * period * (1 + 1e-9)))


def _realisations_note(ctx) -> str:
    n = ctx["study"].realisations
    return f"{n} realisation{'s' if n != 1 else ''}"


def _envelope(da: xr.DataArray, samples_per_period: int) -> tuple[xr.DataArray, xr.DataArray]:
    """Smallest and largest value over the realisations within windows of 1/100 crank cycle:
    contact spikes last a few records, too thin to see as a band at the records' resolution."""
    w = max(1, samples_per_period // 100)
    low = da.min("realisation").rolling(time=w, center=True, min_periods=1).min()
    high = da.max("realisation").rolling(time=w, center=True, min_periods=1).max()
    return low, high


def _series(spec, ctx):
    fig, (ax, box) = plt.subplots(
        1,
        2,
        figsize=(10, 4.8),
        gridspec_kw={"width_ratios": [3, 1.1]},
        squeeze=True,
        layout="constrained",
    )
    where = spec.get("select", {})
    key = _key(spec)
    da = None
    labels, peaks, records = [], [], []
    paper = {
        p["case"]: abs(float(p["value"]))
        for p in ctx["study"].paper_values
        if _key(p) == key and p.get("statistic", "peak") == "peak"
    }
    for i, (name, ds) in enumerate(ctx["members"].items()):
        if spec["var"] not in ds:  # e.g. contact force of the ideal-joint reference
            continue
        whole = select(ds, spec["var"], where)
        da = _first_cycles(ds, whole)
        if not np.isfinite(da.values).any():
            continue
        t = da.time - float(ds.time[0])
        color = f"C{i}"
        low, high = _envelope(da, int(ds.attrs.get("samples_per_period", 100)))
        factor, _ = display_unit(da.attrs.get("units"))
        ax.fill_between(t, low * factor, high * factor, color=color, alpha=0.3, lw=0)
        ax.plot(t, da.isel(realisation=0) * factor, lw=0.7, color=color, label=f"{name}")
        labels.append(name)
        peaks.append(np.abs(da).max("time").values)
        records.append(np.abs(whole).max("time").values)
    name = axis_label(da) if da is not None else spec["var"]
    where_text = ", ".join(f"{k} {v}" for k, v in where.items())
    ax.set_xlabel("time from the end of the transient [s]")
    ax.set_ylabel(name)
    ax.grid(alpha=0.3)
    ax.legend(  # below the panel: inside it would cover the traces
        fontsize=8,
        title="line: realisation 0; band: range of the realisations (in 1/100-cycle windows)",
        title_fontsize=7,
        loc="upper left",
        bbox_to_anchor=(0.0, -0.16),
        ncol=max(1, len(labels)),
    )
    if peaks:
        _peak_boxes(box, labels, peaks, records, paper, da.attrs.get("units"))
    failed = "; ".join(f"{c}: {n}" for c in ctx["runs"] if (n := _failed_in(ctx, c)))
    fig.suptitle(
        _title(
            spec,
            f"{name}{', ' + where_text if where_text else ''}; {_realisations_note(ctx)}"
            + (f"; {failed}" if failed else ""),
        ),
        fontsize=9,
    )
    return fig


def _peak_boxes(box, labels, peaks, records, paper, units) -> None:
    """Box plots of the realisations' peak magnitudes per case: over the first cycles (as the
    paper's values) and over the whole record (as the claims), with the paper's value; all
    stored in ``units``, drawn in their display unit."""
    factor, shown = display_unit(units)
    peaks = [v * factor for v in peaks]
    records = [v * factor for v in records]
    paper = {c: v * factor for c, v in paper.items()}
    x = np.arange(1, len(labels) + 1)
    for values, dx, color, what in (
        (peaks, -0.18, "tab:gray", f"first {PEAK_PERIODS} cycles"),
        (records, 0.18, "tab:green", "whole record (claims)"),
    ):
        b = box.boxplot(
            [v[np.isfinite(v)] for v in values],
            positions=x + dx,
            widths=0.3,
            patch_artist=True,
            manage_ticks=False,
        )
        for patch in b["boxes"]:
            patch.set(facecolor=color, alpha=0.45)
        box.plot([], [], "s", color=color, alpha=0.6, label=what)
    marked = [(i, paper[c]) for i, c in zip(x, labels, strict=True) if c in paper]
    if marked:
        box.plot(*zip(*marked, strict=True), "rx", ms=9, mew=2, label="paper (|value|)")
    box.set_xticks(x, labels, rotation=20, fontsize=8)
    box.set_ylabel(f"|peak| of the realisations{units_label(shown)}")
    box.legend(fontsize=7)
    box.grid(alpha=0.3)


def _orbit(spec, ctx):
    joints_wanted = spec.get("select", {}).get("joint")
    members = ctx["members"]
    panels = [
        (case, j)
        for case, ds in members.items()
        if "joint" in ds.dims
        for j in ds.joint.values
        if joints_wanted in (None, j)
    ]
    fig, axes = plt.subplots(1, len(panels), figsize=(3.6 * len(panels), 4.1), squeeze=False)
    theta = np.linspace(0, 2 * np.pi, 200)
    for ax, (case, j) in zip(axes[0], panels, strict=True):
        ds = members[case].isel(realisation=0)
        c = clearance_of(ctx["scenes"][case], str(j))
        ax.plot(np.cos(theta), np.sin(theta), "k--", lw=0.7)
        ax.plot(ds.clearance_x.sel(joint=j) / c, ds.clearance_y.sel(joint=j) / c, lw=0.4)
        ax.set_aspect("equal")
        ax.set_xlabel("x / c")
        ax.set_ylabel("y / c")
        ax.set_title(f"{case}: joint {j}", fontsize=8)
    fig.suptitle(_title(spec, "journal centre orbits of realisation 0 (dashed: e = c)"), fontsize=9)
    fig.tight_layout()
    return fig


def _grid4(spec, text):
    fig, axes = plt.subplots(2, 2, figsize=(9, 7.5), layout="constrained")
    fig.suptitle(_title(spec, text, 100), fontsize=9)
    return fig, axes.ravel()


def _first_member(ctx) -> xr.Dataset:
    return next(iter(ctx["members"].values()))


def _phase_planes(spec, title: str, ds: xr.Dataset, samples, *fmt, check=False, **style):
    """One panel per clearance coordinate: its rate against it (in their display units), at the
    points ``samples`` picks from a variable (every record, or the stroboscopic samples).
    ``check``: say in the title (and warn) when the records are too coarse for the impacts the
    curves draw."""
    pairs = []
    for label, (var, where) in CLEARANCE_COORDINATES.items():
        x = samples(select(ds, var, where))
        v = samples(select(ds, var.replace("clearance_", "clearance_v"), where))
        pairs.append((label, x, v))
    if check:
        worst, when = coarse_sampling(*(v for _, _, v in pairs), *(x for _, x, _ in pairs))
        if worst > COARSE_JUMP:
            spp = ds.attrs.get("samples_per_period")
            warnings.warn(
                CoarseSamplingWarning(
                    f"{_title(spec, 'phase portraits', 1000)}: the records ({spp} per crank "
                    f"period) are too coarse for the impacts: a clearance rate changes by "
                    f"{100 * worst:.0f} % of its range between two records (t = {when:.4g} s), "
                    "drawn as straight edges; record more samples per period to resolve them"
                ),
                stacklevel=2,
            )
            title += f" - coarse: {spp} samples per crank period draw impacts as straight edges"
    fig, axes = _grid4(spec, title)
    for ax, (label, x, v) in zip(axes, pairs, strict=True):
        ax.plot(display_values(x).ravel(), display_values(v).ravel(), *fmt, **style)
        ax.set_xlabel(f"{label}: {axis_label(x)}", fontsize=8)
        ax.set_ylabel(axis_label(v), fontsize=8)
        ax.grid(alpha=0.3)
        plain_ticks(ax)
    return fig


def _phase(spec, ctx):
    ds = _first_member(ctx).isel(realisation=0)
    title = "phase portraits of the clearance coordinates (realisation 0)"
    return _phase_planes(spec, title, ds, lambda da: da, lw=0.2, check=True)


def _poincare(spec, ctx):
    ds = _first_member(ctx)
    title = f"stroboscopic Poincaré maps (one point per crank period; {_realisations_note(ctx)})"
    return _phase_planes(spec, title, ds, lambda da: strobe(ds, da), ".", ms=2)


def _lle(spec, ctx):
    from workbench import analysis

    ds = _first_member(ctx)
    m = ctx["measures"]
    fig, axes = _grid4(
        spec,
        "largest Lyapunov exponent, Wolf et al. (1985): running estimate of realisation 0;\n"
        f"band: interquartile range of the final values over {len(ds.realisation)} realisations",
    )
    ref = reference_exponent(m.get("exponents", {}))
    bench = ref["lle"] if ref else None
    period = ds.attrs.get("forcing_period")
    for ax, (label, (var, where)) in zip(axes, CLEARANCE_COORDINATES.items(), strict=True):
        w = analysis.wolf_lle(select(ds, var, where).isel(realisation=0), period=period)
        run = w["running"]
        x = run[run.dims[0]]
        flagged = "" if bool(w["reliable"]) else " (flagged: see the exponent table)"
        ax.plot(x, run, lw=0.8, label=f"realisation 0: {float(w['lle']):.3g} 1/s{flagged}")
        shown = list(run.values[x.values >= 0.05 * float(x.max())])
        values = np.asarray(m.get("wolf_lle", {}).get(label, []), float)
        if np.isfinite(values).any():
            q25, med, q75 = np.nanpercentile(values, [25, 50, 75])
            ax.axhspan(q25, q75, color="C1", alpha=0.3, lw=0, label=f"median {med:.3g} 1/s")
            shown += [q25, q75]
        low, high = np.nanmin(shown + [0.0]), np.nanmax(shown + [0.0])
        pad = 0.1 * (high - low) or 1.0
        ax.set_ylim(low - pad, high + pad)
        if bench is not None:  # the converged exponent of the equations, noted if off scale
            off = not low - pad <= bench <= high + pad
            ax.axhline(bench, color="k", ls="--", lw=0.8)
            ax.plot(
                [], [], "k--", lw=0.8, label=f"equations: {bench:.3g} 1/s" + off * " (off scale)"
            )
        ax.set_xlabel(axis_label(x), fontsize=8)
        ax.set_ylabel(f"{label}: LLE [1/s]", fontsize=8)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    return fig


def _bifurcation(spec, ctx):
    ds = next(iter(ctx["runs"].values()))
    scene = next(iter(ctx["study"].cases.values()))
    (param,) = list(parameter_sweep(scene))
    note = failure_note(ds)
    fig, axes = _grid4(
        spec,
        f"bifurcation diagram over {axis_label(ds[param])}; {_realisations_note(ctx)}"
        + (f"; {note} (red crosses)" if note else ""),
    )
    scale = 1 / np.pi if param == "omega" else display_unit(ds[param].attrs.get("units"))[0]
    xlabel = "omega / pi (crank 4)" if param == "omega" else axis_label(ds[param])
    for ax, (label, (var, where)) in zip(axes, CLEARANCE_COORDINATES.items(), strict=True):
        da = select(ds, var, where).transpose(param, ...)
        y = display_values(da).reshape(da.shape[0], -1)
        x = np.broadcast_to(ds[param].values[:, None] * scale, y.shape)
        ax.plot(x.ravel(), y.ravel(), ".", ms=1.5, color="k", alpha=0.4)
        if mark_failed(ax, ds, param, scale=scale):
            ax.legend(fontsize=6, loc="upper right")
        ax.set_xlabel(xlabel, fontsize=8)
        ax.set_ylabel(f"{label}: {axis_label(da)}", fontsize=8)
        ax.grid(alpha=0.3)
        plain_ticks(ax)
    return fig


def _band(ax, x, da: xr.DataArray, color: str, label: str, ls: str = "-") -> None:
    """Median line and interquartile band over ``realisation`` of ``da`` (dim: the swept
    parameter) against ``x``."""
    q = da.quantile([0.25, 0.5, 0.75], dim="realisation", skipna=True)
    ax.fill_between(x, q.sel(quantile=0.25), q.sel(quantile=0.75), color=color, alpha=0.2, lw=0)
    ax.plot(x, q.sel(quantile=0.5), ls, color=color, marker="o", ms=3, lw=1.1, label=label)


def _sweep_parameter(d: xr.Dataset) -> str:
    (param,) = [k for k in d.dims if k not in ("realisation", "joint", "percentile")]
    return param


def _case_label(d: xr.Dataset) -> str:
    return f"c = {display_text(d.attrs['clearance'], 'm')}"


def _mark_sweep_failures(ax, ctx) -> None:
    """Red crosses at the parameter values where a point of a swept case failed."""
    for case in ctx["sweeps"]:
        run = ctx["runs"].get(case)
        if run is not None:
            mark_failed(ax, run, _sweep_parameter(ctx["sweeps"][case]))


def _sweep_failures(ctx) -> str:
    """'; failed points (red crosses): c_0.1mm: 2 of 112 points failed (...)' or ''."""
    notes = [f"{case}: {n}" for case in ctx["sweeps"] if (n := _failed_in(ctx, case))]
    return f"; failed points (red crosses): {'; '.join(notes)}" if notes else ""


def _contact_vs_friction(spec, ctx):
    sweeps = ctx["sweeps"]
    joints = sorted({str(j) for d in sweeps.values() for j in d["joint"].values})
    fig, axes = plt.subplots(len(joints), 2, figsize=(10, 3.4 * len(joints) + 0.6), squeeze=False)
    styles = {50.0: ":", 90.0: "--", 99.0: "-"}
    for row, joint in zip(axes, joints, strict=True):
        for i, d in enumerate(sweeps.values()):
            param = _sweep_parameter(d)
            x = d[param].values
            color = f"C{i}"
            _band(row[0], x, d["contact_fraction"].sel(joint=joint), color, _case_label(d))
            for q in d["percentile"].values:
                _band(
                    row[1],
                    x,
                    d["contact_force_percentile"].sel(joint=joint, percentile=q),
                    color,
                    f"{_case_label(d)}, {q:g} %",
                    styles.get(float(q), "-"),
                )
        row[0].set_ylabel(f"joint {joint}: fraction of time in contact")
        row[0].set_ylim(0, 1.05)
        row[1].set_ylabel(f"joint {joint}: contact force percentile [N]")
        row[1].set_yscale("log")
        row[1].text(
            0.99,
            0.02,
            "a percentile of 0 N (out of contact that share of the time) is off the log axis",
            transform=row[1].transAxes,
            ha="right",
            fontsize=6,
        )
        for ax in row:
            ax.set_xlabel(axis_label(d[param]))
            ax.grid(alpha=0.3, which="both")
        for ax in row:
            _mark_sweep_failures(ax, ctx)
        row[0].legend(fontsize=7)
        row[1].legend(fontsize=6, ncol=2)
    fig.suptitle(
        _title(
            spec,
            "contact against the friction coefficient (median and interquartile band over "
            f"{_realisations_note(ctx)}){_sweep_failures(ctx)}",
        ),
        fontsize=9,
    )
    fig.tight_layout()
    return fig


def _energy_balance(spec, ctx):
    sweeps = ctx["sweeps"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    for i, d in enumerate(sweeps.values()):
        param = _sweep_parameter(d)
        x = d[param].values
        w, e = d["driver_work_per_cycle"], d["dissipated_energy_per_cycle"]
        _band(axes[0], x, w, f"C{i}", f"{_case_label(d)}: driver work")
        _band(axes[0], x, e, f"C{i}", f"{_case_label(d)}: dissipated", "--")
        _band(axes[1], x, e / w, f"C{i}", _case_label(d))
    axes[0].set_ylabel("energy per crank cycle [J]")
    axes[1].set_ylabel("dissipated energy / driver work")
    axes[1].axhline(1.0, color="k", lw=0.6)
    for ax in axes:
        ax.set_xlabel(axis_label(d[param]))
        ax.grid(alpha=0.3)
        _mark_sweep_failures(ax, ctx)
        ax.legend(fontsize=7)
    fig.suptitle(
        _title(
            spec,
            "energy balance per crank cycle (median and interquartile band over "
            f"{_realisations_note(ctx)}){_sweep_failures(ctx)}",
        ),
        fontsize=9,
    )
    fig.tight_layout()
    return fig


_DRAW = {
    "series": _series,
    "orbit": _orbit,
    "phase": _phase,
    "poincare": _poincare,
    "lle": _lle,
    "bifurcation": _bifurcation,
    "contact_vs_friction": _contact_vs_friction,
    "energy_balance": _energy_balance,
}
