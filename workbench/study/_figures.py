"""Figures of a study, one per figure (or group of figures) of the paper, titled with its number.

``series``: the cases overlaid over the first two recorded crank cycles; ``orbit``: journal
centre orbits in units of c, one panel per joint and case; ``phase``, ``poincare``, ``lle``: the
four clearance coordinates x1, y1, x2, y2 of the chaos study; ``bifurcation``: stroboscopic
samples against the swept parameter.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from workbench.plot._runs import axis_label, plt
from workbench.study._measure import clearance_of, select, strobe
from workbench.study._run import CLEARANCE_COORDINATES, PEAK_PERIODS
from workbench.study._spec import Study

__all__ = ["study_figures"]


def study_figures(
    study: Study, runs: dict, scenes: dict, directory: Path, measures: dict
) -> list[Path]:
    """Draw every ``[[figure]]`` of the study into ``directory``; returns the PNG paths."""
    paths = []
    for fig_spec in study.figures:
        kind = fig_spec["kind"]
        draw = _DRAW[kind]
        fig = draw(fig_spec, runs, scenes, measures)
        label = fig_spec.get("var", kind)
        sel = "".join(f"-{v}" for v in fig_spec.get("select", {}).values())
        path = directory / f"fig{fig_spec['paper']}-{label}{sel}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def _title(spec: dict, text: str) -> str:
    return f"Fig. {spec['paper']} (Chen et al.): {text}"


def _first_cycles(ds: xr.Dataset, da: xr.DataArray) -> xr.DataArray:
    t0 = float(ds.time[0])
    period = float(ds.attrs.get("forcing_period", np.inf))
    return da.sel(time=slice(t0, t0 + PEAK_PERIODS * period * (1 + 1e-9)))


def _series(spec, runs, scenes, measures):
    fig, ax = plt.subplots(figsize=(8, 4.2))
    where = spec.get("select", {})
    da = None
    for case, ds in runs.items():
        if spec["var"] not in ds:  # e.g. contact force of the ideal-joint reference
            continue
        da = _first_cycles(ds, select(ds, spec["var"], where))
        if not np.isfinite(da.values).any():
            continue
        ax.plot(da.time - float(ds.time[0]), da, lw=0.8, label=case)
    name = axis_label(da) if da is not None else spec["var"]
    where_text = ", ".join(f"{k} {v}" for k, v in where.items())
    ax.set_xlabel("time from the end of the transient [s]")
    ax.set_ylabel(name)
    ax.set_title(_title(spec, f"{name}{', ' + where_text if where_text else ''}"), fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def _orbit(spec, runs, scenes, measures):
    joints_wanted = spec.get("select", {}).get("joint")
    panels = [
        (case, j)
        for case, ds in runs.items()
        if "joint" in ds.dims
        for j in ds.joint.values
        if joints_wanted in (None, j)
    ]
    fig, axes = plt.subplots(1, len(panels), figsize=(3.6 * len(panels), 3.9), squeeze=False)
    theta = np.linspace(0, 2 * np.pi, 200)
    for ax, (case, j) in zip(axes[0], panels, strict=True):
        ds = runs[case]
        c = clearance_of(scenes[case], str(j))
        ax.plot(np.cos(theta), np.sin(theta), "k--", lw=0.7)
        ax.plot(ds.clearance_x.sel(joint=j) / c, ds.clearance_y.sel(joint=j) / c, lw=0.4)
        ax.set_aspect("equal")
        ax.set_xlabel("x / c [1]")
        ax.set_ylabel("y / c [1]")
        ax.set_title(f"{case}: joint {j}", fontsize=8)
    fig.suptitle(_title(spec, "journal centre orbits (dashed: e = c)"), fontsize=9)
    fig.tight_layout()
    return fig


def _grid4(spec, text):
    fig, axes = plt.subplots(2, 2, figsize=(9, 7.5))
    fig.suptitle(_title(spec, text), fontsize=9)
    return fig, axes.ravel()


def _phase(spec, runs, scenes, measures):
    ds = next(iter(runs.values()))
    fig, axes = _grid4(spec, "phase portraits of the clearance coordinates")
    for ax, (label, (var, where)) in zip(axes, CLEARANCE_COORDINATES.items(), strict=True):
        x = select(ds, var, where)
        v = select(ds, var.replace("clearance_", "clearance_v"), where)
        ax.plot(x * 1e3, v, lw=0.2)
        ax.set_xlabel(f"{label}: {axis_label(x).replace('[m]', '[mm]')}", fontsize=8)
        ax.set_ylabel(axis_label(v), fontsize=8)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _poincare(spec, runs, scenes, measures):
    ds = next(iter(runs.values()))
    fig, axes = _grid4(spec, "stroboscopic Poincaré maps (one point per crank period)")
    for ax, (label, (var, where)) in zip(axes, CLEARANCE_COORDINATES.items(), strict=True):
        x = strobe(ds, select(ds, var, where))
        v = strobe(ds, select(ds, var.replace("clearance_", "clearance_v"), where))
        ax.plot(x * 1e3, v, ".", ms=3)
        ax.set_xlabel(f"{label}: {axis_label(x).replace('[m]', '[mm]')}", fontsize=8)
        ax.set_ylabel(axis_label(v), fontsize=8)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _lle(spec, runs, scenes, measures):
    from workbench import analysis

    ds = next(iter(runs.values()))
    fig, axes = _grid4(spec, "largest Lyapunov exponent, Wolf et al. (1985): running estimate")
    bench = measures.get("lle_from_equations")
    for ax, (label, (var, where)) in zip(axes, CLEARANCE_COORDINATES.items(), strict=True):
        w = analysis.wolf_lle(select(ds, var, where))
        run = w["running"]
        ax.plot(run[run.dims[0]], run, lw=0.8, label=f"Wolf: {float(w['lle']):.3g} 1/s")
        if bench is not None:
            ax.axhline(bench, color="k", ls="--", lw=0.8, label=f"equations: {bench:.3g} 1/s")
        ax.set_xlabel(axis_label(run[run.dims[0]]), fontsize=8)
        ax.set_ylabel(f"{label}: LLE [1/s]", fontsize=8)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _bifurcation(spec, runs, scenes, measures):
    ds = next(iter(runs.values()))
    scene = next(iter(scenes.values()))
    (param,) = list(scene.sweep)
    fig, axes = _grid4(spec, f"bifurcation diagram over {axis_label(ds[param])}")
    scale = 1e3 if param == "clearance" else (1 / np.pi if param == "omega" else 1.0)
    xlabel = {"clearance": "clearance [mm]", "omega": "omega / pi [1] (crank 4)"}.get(
        param, axis_label(ds[param])
    )
    for ax, (label, (var, where)) in zip(axes, CLEARANCE_COORDINATES.items(), strict=True):
        da = select(ds, var, where)
        x = np.broadcast_to(ds[param].values[:, None] * scale, da.shape)
        ax.plot(x.ravel(), da.values.ravel() * 1e3, ",", color="k", alpha=0.6)
        ax.plot(x.ravel(), da.values.ravel() * 1e3, ".", ms=1.5, color="k", alpha=0.4)
        ax.set_xlabel(xlabel, fontsize=8)
        ax.set_ylabel(f"{label}: {axis_label(da).replace('[m]', '[mm]')}", fontsize=8)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


_DRAW = {
    "series": _series,
    "orbit": _orbit,
    "phase": _phase,
    "poincare": _poincare,
    "lle": _lle,
    "bifurcation": _bifurcation,
}
