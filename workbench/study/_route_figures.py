"""Figures of a study's route to chaos (:mod:`workbench.study._route`): the sweep continued both
ways with the periodic branch over it, and the indicators against the parameter."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from workbench._attributes import flag_names
from workbench.archive import open_run
from workbench.plot import LABEL_MARKS, display_unit
from workbench.plot._base import plt, units_label
from workbench.study._measure import CLEARANCE_COORDINATES, clearance_of, select
from workbench.study._spec import Study

__all__ = ["route_figures"]

_COLOURS = {"up": "tab:blue", "down": "tab:orange"}
_STATES = {"x1": "x_A", "y1": "y_A", "x2": "x_B", "y2": "y_B"}


def _axis(param: str) -> tuple[float, str]:
    """The factor and the label of the parameter's axis: omega / pi, a clearance in its display
    unit (:func:`~workbench.plot.display_unit`), else the parameter as stored."""
    if param == "omega":
        return 1 / math.pi, "crank speed omega / pi"
    if param == "clearance":
        factor, unit = display_unit("m")
        return factor, f"clearance{units_label(unit)}"
    return 1.0, param.replace("_", " ")


def route_figures(study: Study, r: dict, directory: Path) -> list[Path]:
    """``fig<N>-route.png`` and ``fig<N>-route-indicators.png`` (N: the study's paper figure)."""
    param = r["parameter"]
    scale, xlabel = _axis(param)
    scene = study.cases[r["case"]]
    ds = open_run(r["archive"])
    branch = open_run(r["branch"]["archive"]) if r.get("branch") else None
    tag = f"fig{study.paper_figures}" if study.paper_figures else study.name
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5))
    for ax, (label, (var, where)) in zip(axes.ravel(), CLEARANCE_COORDINATES.items(), strict=True):
        _samples(ax, ds, param, var, where, scene, scale)
        if branch is not None:
            _branch(ax, branch, param, scale, _STATES[label], scene, where["joint"])
        ax.set_xlabel(xlabel, fontsize=8)
        ax.set_ylabel(f"{label}: strobe samples of {var} at {where['joint']} / c", fontsize=8)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(
        f"{study.title}: continued both ways (each point from its neighbour's settled state, "
        f"{r['cycles'][1]} + {r['cycles'][0]} cycles)"
        + ("; periodic orbit: solid stable, dashed unstable" if branch is not None else ""),
        fontsize=9,
    )
    fig.tight_layout()
    first = directory / f"{tag}-route.png"
    fig.savefig(first, dpi=130)
    plt.close(fig)
    paths = [first, _indicators(r, directory / f"{tag}-route-indicators.png", param, scale, xlabel)]
    if r.get("end", {}).get("status") == "computed":
        end = directory / f"{tag}-route-end.png"
        paths.append(_end(study, scene, r["end"], end, param, scale, xlabel))
    return paths


def _samples(ax, ds, param: str, var: str, where: dict, scene, scale: float) -> None:
    """A continued sweep's strobe samples of ``var`` at ``where``, both ways, in units of the
    clearance, against the parameter."""
    for d in ("up", "down"):
        da = select(ds.sel(direction=d), var, where).transpose(param, ...)
        c = np.array(
            [
                v if param == "clearance" else clearance_of(scene, where["joint"])
                for v in da[param].values
            ]
        )
        y = da.values.reshape(da.shape[0], -1) / c[:, None]
        x = np.broadcast_to(da[param].values[:, None] * scale, y.shape)
        ax.plot(
            x.ravel(), y.ravel(), ".", ms=2.5, color=_COLOURS[d], alpha=0.5, label=f"continued {d}"
        )


def _end(study: Study, scene, e: dict, path: Path, param: str, scale: float, xlabel: str) -> Path:
    """Where the periodic motion ends: the refined continued sweep's strobe samples of x1 with
    the orbit continued from its last periodic value, the orbit's smallest penetration and its
    largest |multiplier|."""
    var, where = CLEARANCE_COORDINATES["x1"]
    ds = open_run(e["archive"])
    b = e.get("branch")
    fig, axes = plt.subplots(3 if b else 1, 1, figsize=(8, 8.4 if b else 3.2), sharex=True)
    axes = np.atleast_1d(axes)
    _samples(axes[0], ds, param, var, where, scene, scale)
    axes[0].set_ylabel(f"x1: strobe samples of {var} at {where['joint']} / c", fontsize=8)
    if b:
        branch = open_run(b["archive"])
        _branch(axes[0], branch, param, scale, _STATES["x1"], scene, where["joint"])
        p = np.array(b["values"]) * scale
        factor, unit = display_unit("m")  # the mechanisms' event functions are lengths
        axes[1].semilogy(p, factor * np.maximum(b["smallest_event"], 1e-12), "k.-", lw=1, ms=3)
        axes[1].set_ylabel(f"smallest penetration along the orbit{units_label(unit)}", fontsize=8)
        axes[2].semilogy(p, b["largest_modulus"], "k.-", lw=1, ms=3)
        axes[2].axhline(1.0, color="0.5", lw=0.6)
        axes[2].set_ylabel("largest |Floquet multiplier|", fontsize=8)
    axes[0].legend(fontsize=7)
    axes[-1].set_xlabel(xlabel, fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.suptitle(
        f"{study.title}: where the periodic motion ends\nrefined continued sweep; period-1 "
        "orbit continued from the bracket's lower end (solid stable, dashed unstable)",
        fontsize=8,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def _branch(ax, branch, param: str, scale: float, state: str, scene, joint: str) -> None:
    c = clearance_of(scene, joint)
    p = branch[param].values * scale
    y = branch[f"strobe_{state}"].values[:, 0] / c
    stable = branch.stable.values
    start = 0
    for i in range(1, p.size + 1):
        if i == p.size or stable[i] != stable[start]:
            seg = slice(start, min(i + 1, p.size))
            ax.plot(p[seg], y[seg], "-" if stable[start] else "--", color="k", lw=1.1)
            start = i
    names = flag_names(branch.label)
    for i in np.flatnonzero(branch.label.values >= 3):
        marker, text, colour = LABEL_MARKS[names[int(branch.label.values[i])]]
        ax.plot(p[i], y[i], marker, mfc="none", mec=colour, ms=7, mew=1.5)
        ax.annotate(
            text, (p[i], y[i]), textcoords="offset points", xytext=(4, 4), fontsize=7, color=colour
        )


def _indicators(r: dict, path: Path, param: str, scale: float, xlabel: str) -> Path:
    x = np.array(r["values"]) * scale
    panels = 3 if r.get("branch") or r.get("exponents") else 2
    fig, axes = plt.subplots(panels, 1, figsize=(8, 2.6 * panels), sharex=True)
    for d in ("up", "down"):
        rows = r["directions"][d]
        axes[0].plot(x, rows["spread"], ".-", color=_COLOURS[d], label=f"continued {d}")
        axes[1].plot(x, rows["K"], ".-", color=_COLOURS[d], label=f"continued {d}")
    hx = [v * scale for v in r["hysteresis"]["values"]]
    for ax in axes[:2]:
        for v in hx:
            ax.axvline(v, color="0.6", lw=0.6, ls=":")
    axes[0].set_ylabel("strobe spread / c", fontsize=8)
    axes[0].set_yscale("symlog", linthresh=1e-6)
    axes[1].set_ylabel("0-1 test K", fontsize=8)
    axes[0].legend(fontsize=7)
    if panels == 3:
        ax = axes[2]
        if r.get("branch"):
            b = r["branch"]
            ax.plot(
                np.array(b["values"]) * scale,
                b["largest_modulus"],
                "k-",
                lw=1,
                label="periodic orbit: largest |Floquet multiplier|",
            )
            ax.axhline(1.0, color="0.5", lw=0.6)
        if r.get("exponents"):
            ok = [e for e in r["exponents"] if "lle" in e and not e.get("bound")]
            bounds = [e for e in r["exponents"] if e.get("bound")]
            twin = ax.twinx()
            if bounds:
                twin.plot(
                    [e["value"] * scale for e in bounds],
                    [e["lle"] for e in bounds],
                    "v",
                    color="tab:red",
                    ms=5,
                    label="upper bound (Floquet, below the differences' noise)",
                )
            twin.errorbar(
                [e["value"] * scale for e in ok],
                [e["lle"] for e in ok],
                yerr=[e["stderr"] for e in ok],
                fmt="o",
                color="tab:red",
                ms=4,
                capsize=2,
                label="largest Lyapunov exponent",
            )
            twin.axhline(0.0, color="tab:red", lw=0.5, ls=":")
            twin.set_ylabel("largest Lyapunov exponent [s-1]", fontsize=8, color="tab:red")
        ax.set_ylabel("largest |multiplier|", fontsize=8)
        ax.legend(fontsize=7, loc="upper left")
    axes[-1].set_xlabel(xlabel, fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path
