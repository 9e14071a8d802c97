"""Figures of analyses: phase portraits, Poincaré maps, delay/dimension evidence, LLE
convergence, 0-1 test and bifurcation diagrams. Axis labels carry the units."""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from workbench.plot._base import axis_label, display_unit, display_values, plain_ticks, plt
from workbench.plot._failures import mark_failed
from workbench.plot._phase import COARSE_JUMP, CoarseSamplingWarning, coarse_sampling

__all__ = [
    "phase_figure",
    "poincare_figure",
    "embedding_figure",
    "lle_figure",
    "zero_one_figure",
    "bifurcation_figure",
]


def phase_figure(portrait: xr.Dataset, section: xr.Dataset | None = None) -> plt.Figure:
    """Phase portrait (from :func:`workbench.analysis.phase_portrait`), with the stroboscopic
    points of ``section`` (a Dataset with the same two variables) on top when given. A series
    too coarse for its fast changes (impacts drawn as straight edges) is said in the title and
    warned about (:class:`workbench.plot.CoarseSamplingWarning`)."""
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    fx, _ = display_unit(portrait.value.attrs.get("units"))
    fy, _ = display_unit(portrait.rate.attrs.get("units"))
    ax.plot(portrait.value * fx, portrait.rate * fy, lw=0.3, color="0.4", label="trajectory")
    if section is not None:
        ax.plot(section["value"] * fx, section["rate"] * fy, "r.", ms=3, label="Poincaré section")
        ax.legend(fontsize=8)
    ax.set_xlabel(axis_label(portrait.value))
    ax.set_ylabel(axis_label(portrait.rate))
    title = f"phase portrait of {portrait.attrs.get('variable', '')}"
    worst, when = coarse_sampling(portrait.value, portrait.rate)
    if worst > COARSE_JUMP:
        warnings.warn(
            CoarseSamplingWarning(
                f"the phase portrait of {portrait.attrs.get('variable', '')!r} is drawn from "
                f"records too coarse for its fastest changes: {100 * worst:.0f} % of the range "
                f"between two records (at t = {when:.4g} s); impacts appear as straight edges: "
                "record more samples per period"
            ),
            stacklevel=2,
        )
        title += "\n(coarse records: straight edges hide what happens within a record step)"
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    plain_ticks(ax)
    fig.tight_layout()
    return fig


def poincare_figure(value: xr.DataArray, rate: xr.DataArray) -> plt.Figure:
    """Stroboscopic Poincaré map: one point per forcing period."""
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    ax.plot(display_values(value), display_values(rate), ".", ms=3)
    ax.set_xlabel(axis_label(value))
    ax.set_ylabel(axis_label(rate))
    ax.set_title(
        f"stroboscopic Poincaré map ({value.sizes.get('strobe', value.size)} periods)", fontsize=9
    )
    ax.grid(alpha=0.3)
    plain_ticks(ax)
    fig.tight_layout()
    return fig


def embedding_figure(
    ami: xr.Dataset, fnn: xr.Dataset | None = None, cao: xr.Dataset | None = None
) -> plt.Figure:
    """The evidence behind the embedding: AMI over lag (chosen delay marked), the fraction of
    false nearest neighbours and Cao's E1, E2 over the dimension (chosen dimension marked).

    ``ami`` may instead be the Dataset of :func:`workbench.analysis.wolf_lle` alone: the
    figure then shows the estimate's own evidence and the delay and dimension it used."""
    if fnn is None:
        ami, fnn, cao = _wolf_evidence(ami)
    n = 3 if cao is not None else 2
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n, 3.8))
    axes[0].plot(ami.lag, ami.ami)
    axes[0].axvline(int(ami.delay), color="r", ls="--", label=f"delay {int(ami.delay)}")
    axes[0].set_xlabel(axis_label(ami.lag))
    axes[0].set_ylabel(axis_label(ami.ami))
    axes[0].set_title("average mutual information (Fraser & Swinney 1986)", fontsize=8)
    axes[1].plot(fnn.dimension, fnn.fnn_fraction, "o-")
    axes[1].axvline(int(fnn.dim), color="r", ls="--", label=f"dim {int(fnn.dim)}")
    axes[1].set_xlabel(axis_label(fnn.dimension))
    axes[1].set_ylabel(axis_label(fnn.fnn_fraction))
    axes[1].set_title("false nearest neighbours (Kennel et al. 1992)", fontsize=8)
    if cao is not None:
        axes[2].plot(cao.dimension, cao.E1, "o-", label="E1")
        axes[2].plot(cao.dimension, cao.E2, "s--", label="E2")
        axes[2].axvline(int(cao.dim), color="r", ls="--", label=f"dim {int(cao.dim)}")
        axes[2].set_xlabel(axis_label(cao.dimension))
        axes[2].set_ylabel("E1, E2")
        axes[2].set_title("Cao (1997)", fontsize=8)
    for ax in axes:
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _wolf_evidence(wolf: xr.Dataset) -> tuple[xr.Dataset, xr.Dataset, xr.Dataset]:
    """The AMI, FNN and Cao Datasets (as :func:`embedding_figure` reads them) of a
    :func:`workbench.analysis.wolf_lle` result, marked at the delay and dimension it used."""
    ami = xr.Dataset({"ami": wolf.ami, "delay": wolf.delay})
    fnn = xr.Dataset({"fnn_fraction": wolf.fnn_fraction, "dim": wolf.dim})
    cao = xr.Dataset({"E1": wolf.cao_E1, "E2": wolf.cao_E2, "dim": wolf.cao_dim})
    return ami, fnn, cao


def lle_figure(
    wolf: xr.Dataset,
    rosenstein: float | None = None,
    label: str = "",
    *,
    equations: float | None = None,
) -> plt.Figure:
    """Running Wolf estimate of the LLE over the time followed, with its reliability flag and
    reasons, and lines for the Rosenstein estimate (nolds) and the LLE from the equations when
    given (each named for what it is, in the units of the Wolf estimate)."""
    import textwrap

    fig, ax = plt.subplots(figsize=(6, 4))
    reliable = bool(int(wolf.reliable))
    flag = "reliable" if reliable else "FLAGGED"
    ax.plot(
        wolf.elapsed,
        wolf.running,
        lw=0.8,
        label=f"Wolf et al. 1985: {float(wolf.lle):.4g} ({flag})",
    )
    if rosenstein is not None:
        ax.axhline(
            rosenstein, color="k", ls="--", lw=0.8, label=f"Rosenstein (nolds): {rosenstein:.4g}"
        )
    if equations is not None:
        ax.axhline(
            equations, color="C3", ls=":", lw=1.0, label=f"from the equations: {equations:.4g}"
        )
    ax.set_xlabel(axis_label(wolf.elapsed))
    ax.set_ylabel(axis_label(wolf.running))
    ax.set_title(
        f"largest Lyapunov exponent {label}\n(Wolf et al. 1985; dim {int(wolf.dim)}, delay "
        f"{int(wolf.delay)}, {int(wolf.replacements)} replacements)",
        fontsize=8,
    )
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    if not reliable:  # the reasons under the axes, one paragraph each
        attrs = wolf.reliable.attrs
        reasons = attrs.get("reasons", attrs.get("message", "")).splitlines()
        text = "\n".join(textwrap.fill(f"- {r}", 120) for r in ["flagged:"] + reasons)
        lines = text.count("\n") + 1
        height = 4 + 0.1 * lines  # inches: 6-point lines
        fig.set_figheight(height)
        fig.text(0.01, 0.01, text, fontsize=6, va="bottom", ha="left", color="C3")
        fig.tight_layout(rect=(0, (0.1 * lines + 0.1) / height, 1, 1))
    else:
        fig.tight_layout()
    return fig


def zero_one_figure(result: xr.Dataset) -> plt.Figure:
    """K_c over c of the 0-1 test, with the median K."""
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.plot(result.c, result.K_c, ".")
    ax.axhline(float(result.K), color="r", ls="--", label=f"K = {float(result.K):.3f}")
    ax.set_ylim(-0.1, 1.1)
    ax.set_xlabel(axis_label(result.c))
    ax.set_ylabel(axis_label(result.K_c))
    ax.set_title("0-1 test for chaos (Gottwald & Melbourne 2004)", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def bifurcation_figure(
    diagram: xr.Dataset, *, scale: float | None = None, xlabel: str | None = None
):
    """The familiar scatter of a bifurcation diagram (from
    :func:`workbench.analysis.bifurcation_diagram`): strobe samples over the parameter, both in
    their display units (:func:`~workbench.plot.display_unit`) unless ``scale`` multiplies the
    parameter (e.g. ``1 / pi``, with ``xlabel``). Failed points (the diagram's ``status``) are
    marked by red crosses on the bottom edge at their parameter values, counted in the legend
    and named in the title."""
    param = diagram.attrs["diagram_parameter"]
    samples = diagram[diagram.attrs["diagram_variable"]]
    other = [d for d in samples.dims if d != param]
    da = samples.transpose(param, *other)
    if scale is None:
        scale, _ = display_unit(da[param].attrs.get("units"))
    x = np.broadcast_to(da[param].values.reshape((-1,) + (1,) * len(other)), da.shape)
    y = display_values(da)
    keep = np.isfinite(y)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(x[keep] * scale, y[keep], ".", ms=1.5, color="k", alpha=0.6)
    note = mark_failed(ax, diagram, param, scale=scale)
    if note:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0, -0.14))
    ax.set_xlabel(xlabel or axis_label(da[param]))
    ax.set_ylabel(axis_label(da))
    title = f"bifurcation diagram of {da.name} over {param}"
    ax.set_title(f"{title}\n{note}" if note else title, fontsize=9)
    ax.grid(alpha=0.3)
    plain_ticks(ax)
    fig.tight_layout()
    return fig
