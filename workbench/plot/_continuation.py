"""Figures of continuation results: a branch of periodic orbits over an orbit diagram, maps of
chaos indicators over two parameters, and curves of bifurcations in two parameters drawn over
either."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr

from workbench._attributes import flag_meaning, flag_names
from workbench.plot._base import axis_label, display_unit, display_values, plt, units_label

__all__ = [
    "CURVE_COLOURS",
    "CURVE_MARKS",
    "LABEL_MARKS",
    "branch_figure",
    "chaos_map_figure",
    "curve_figure",
    "curve_overlay",
]

#: marker, short text and colour of each labelled point of a branch
LABEL_MARKS = {
    "fold": ("s", "LP", "tab:red"),
    "branch_point": ("D", "BP", "tab:purple"),
    "period_doubling": ("o", "PD", "tab:green"),
    "neimark_sacker": ("^", "NS", "tab:orange"),
    "grazing": ("v", "G", "tab:brown"),
    "nonsmooth_fold": ("X", "NF", "tab:pink"),
    "unresolved": ("x", "?", "tab:gray"),
}
#: colour and short name of each kind of curve point
CURVE_COLOURS = {
    "fold": ("tab:red", "LP"),
    "period_doubling": ("tab:green", "PD"),
    "neimark_sacker": ("tab:orange", "NS"),
    "grazing": ("tab:brown", "G"),
    "neutral_saddle": ("0.55", "neutral saddle"),
}
#: marker and short text of each codimension-two point of a curve (the curves' turning points
#: in either parameter are not marked)
CURVE_MARKS = {
    "cusp": ("P", "CP"),
    "resonance_1_1": ("s", "R1"),
    "resonance_1_2": ("D", "R2"),
    "resonance_1_3": ("^", "R3"),
    "resonance_1_4": ("v", "R4"),
    "fold_flip": ("X", "LPPD"),
    "fold_neimark_sacker": ("h", "LPNS"),
    "flip_neimark_sacker": ("H", "PDNS"),
    "grazing_fold": ("<", "G-LP"),
    "grazing_period_doubling": (">", "G-PD"),
    "degenerate_grazing": ("*", "DG"),
}
#: the mark of an exponent that is only an upper bound on a chaos map
BOUND_MARK = r"$\leq$"
_DIRECTION_COLOURS = {"up": "tab:blue", "down": "tab:orange"}


def _label_names(ds: xr.Dataset, var: str = "label") -> list[str]:
    return flag_names(ds[var])


def _diagram(ax, diagram: xr.Dataset, param: str, scale: float) -> None:
    """Strobe samples of a (continued) sweep: one colour per direction."""
    var = diagram.attrs["diagram_variable"]
    samples = diagram[var]
    groups = (
        [(str(d), samples.sel(direction=d)) for d in samples.direction.values]
        if "direction" in samples.dims
        else [("", samples)]
    )
    for name, da in groups:
        other = [d for d in da.dims if d != param]
        da = da.transpose(param, *other)
        x = np.broadcast_to(da[param].values.reshape((-1,) + (1,) * len(other)), da.shape)
        keep = np.isfinite(da.values)
        colour = _DIRECTION_COLOURS.get(name, "0.3")
        label = f"strobe samples ({'sweep ' + name if name else 'sweep'})"
        y = display_values(da)
        ax.plot(x[keep] * scale, y[keep], ".", ms=2, color=colour, alpha=0.45, label=label)


def branch_figure(
    branch: xr.Dataset,
    state: str,
    *,
    diagram: xr.Dataset | None = None,
    scale: float | None = None,
    xlabel: str | None = None,
    ylabel: str | None = None,
):
    """A branch of periodic orbits (from :func:`workbench.continuation.continue_orbit`) over an
    orbit diagram: each orbit's strobe samples of ``state`` against the parameter, solid where
    the orbit is stable and dashed where not, its labelled points marked as in
    :data:`LABEL_MARKS` (LP fold, BP branch point, PD period doubling, NS Neimark-Sacker, G
    grazing, NF nonsmooth fold, ? unresolved: bracketed but not confirmed); under it, when
    given, the strobe samples of a sweep (:func:`workbench.analysis.bifurcation_diagram` of a
    campaign or a continued sweep, one colour per direction).

    Both axes are in their display units (:func:`~workbench.plot.display_unit`) unless
    ``scale`` multiplies the parameter on the x axis (e.g. ``1 / pi``, with ``xlabel``).
    """
    param = branch.attrs["continuation_parameter"]
    values = branch[f"strobe_{state}"]
    if scale is None:
        scale, _ = display_unit(branch[param].attrs.get("units"))
    shown_values = display_values(values)
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    if diagram is not None:
        _diagram(ax, diagram, diagram.attrs["diagram_parameter"], scale)
    names = _label_names(branch)
    p = branch[param].values * scale
    for b in np.unique(branch.branch.values):
        on = np.flatnonzero(branch.branch.values == b)
        k = int(branch.periods.values[on[0]])
        stable = branch.stable.values[on]
        for s in range(k):
            y = shown_values[on, s]
            # runs of equal stability, each drawn to the next point so that the line is whole
            start = 0
            for i in range(1, on.size + 1):
                if i == on.size or stable[i] != stable[start]:
                    seg = slice(start, min(i + 1, on.size))
                    ax.plot(
                        p[on][seg],
                        y[seg],
                        "-" if stable[start] else "--",
                        color="k",
                        lw=1.2 if stable[start] else 0.9,
                    )
                    start = i
    shown = set()
    for i in np.flatnonzero(branch.label.values >= 3):
        kind = names[int(branch.label.values[i])]
        marker, text, colour = LABEL_MARKS[kind]
        k = int(branch.periods.values[i])
        for s in range(k):
            ax.plot(
                p[i],
                shown_values[i, s],
                marker,
                ms=6,
                mfc="none",
                mec=colour,
                mew=1.5,
                label=None if kind in shown else f"{text}: {kind.replace('_', ' ')}",
            )
            shown.add(kind)
        ax.annotate(
            text,
            (p[i], shown_values[i, 0]),
            textcoords="offset points",
            xytext=(4, 4),
            fontsize=7,
            color=colour,
        )
    ax.plot([], [], "-", color="k", label="periodic orbit, stable")
    ax.plot([], [], "--", color="k", lw=0.9, label="periodic orbit, unstable")
    ax.set_xlabel(xlabel or axis_label(branch[param]))
    ax.set_ylabel(ylabel or axis_label(values))
    ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3)
    ax.set_title(f"periodic orbits over {param} (strobe samples of {state})", fontsize=9)
    fig.tight_layout()
    return fig


def chaos_map_figure(
    maps: xr.Dataset,
    *,
    indicators: tuple[str, ...] = ("strobe_period", "zero_one_K", "lle"),
    scales: Mapping[str, float] | None = None,
    labels: Mapping[str, str] | None = None,
    curves: Sequence[xr.Dataset] = (),
    ends: xr.Dataset | None = None,
):
    """Maps of chaos indicators over the two parameter dims of a campaign (from
    :func:`workbench.continuation.chaos_map`): one panel per indicator, the first dim on the
    x axis. ``scales`` multiplies a dim's values (e.g. ``{"omega": 1 / pi}``), ``labels``
    names its axis; a dim without a scale is shown in its display unit (a clearance in mm,
    :func:`~workbench.plot.display_unit`). On the exponent's map, hatched cells hold an
    exponent that did not converge (``lle_converged`` 0; ``lle_unmet`` says why), a "less or
    equal" sign marks an upper bound (``lle_status`` 2) and "x" a failed exponent; a legend
    below the panel says so
    where any cell is marked. ``curves`` (of :func:`workbench.continuation.continue_curve` in
    the map's two parameters, either way round) are drawn over every panel
    (:func:`curve_overlay`), within the map's extent, with a legend on the first panel; so is
    where the period-1 motion of a continued sweep over the same two parameters ends
    (``ends``, :func:`periodic_end_overlay`)."""
    scales = dict(scales or {})
    labels = dict(labels or {})
    dims = maps.attrs["campaign_dims"].split()
    if len(dims) != 2:
        raise ValueError(f"a chaos map needs two parameter dims; this campaign has {dims!r}")
    xd, yd = dims
    for c in curves:
        pair = {c.attrs.get("continuation_parameter"), c.attrs.get("curve_parameter")}
        if pair != {xd, yd}:
            raise ValueError(
                f"curves: a curve in {sorted(p for p in pair if p)!r} cannot be drawn on a map "
                f"over {[xd, yd]!r}; continue the bifurcation in the map's two parameters"
            )
    shown = [v for v in indicators if v in maps]
    fig, axes = plt.subplots(1, len(shown), figsize=(4.2 * len(shown), 3.8), squeeze=False)
    for d in (xd, yd):
        if d not in scales:
            scales[d], _ = display_unit(maps[d].attrs.get("units"))
            labels.setdefault(d, axis_label(maps[d]))
    x = maps[xd].values * scales[xd]
    y = maps[yd].values * scales[yd]
    for ax, name in zip(axes[0], shown, strict=True):
        da = maps[name].transpose(yd, xd)
        if name == "strobe_period":
            vals = da.values.astype(float)
            cmap = plt.get_cmap("viridis", 9)
            im = ax.pcolormesh(
                x,
                y,
                np.where(vals > 0, np.minimum(vals, 8), 9),
                cmap=cmap,
                vmin=0.5,
                vmax=9.5,
                shading="nearest",
            )
            bar = fig.colorbar(im, ax=ax, ticks=range(1, 10))
            bar.ax.set_yticklabels([*map(str, range(1, 8)), "8+", "none"])
        else:
            cmap = "magma" if name != "lle" else "coolwarm"
            kw = {}
            if name == "lle":
                lim = float(np.nanmax(np.abs(da.values))) or 1.0
                kw = {"vmin": -lim, "vmax": lim}
            im = ax.pcolormesh(x, y, da.values, cmap=cmap, shading="nearest", **kw)
            fig.colorbar(im, ax=ax)
            if name == "lle":
                _mark_exponents(ax, maps, xd, yd, x, y)
        ax.set_xlabel(labels.get(xd, axis_label(maps[xd])))
        ax.set_ylabel(labels.get(yd, axis_label(maps[yd])))
        ax.set_title(f"{name}{units_label(maps[name].attrs.get('units'))}", fontsize=9)
        if curves or ends is not None:
            limits = ax.get_xlim(), ax.get_ylim()
            first = ax is axes[0][0]
            for c in curves:
                curve_overlay(ax, c, x=xd, y=yd, scales=scales, marks=first)
            if ends is not None:
                periodic_end_overlay(ax, ends, x=xd, y=yd, scales=scales, marks=first)
            ax.set_xlim(*limits[0])
            ax.set_ylim(*limits[1])
            if first:
                ax.legend(fontsize=7, loc="upper left", framealpha=0.8)
    fig.tight_layout()
    return fig


def curve_overlay(
    ax,
    curve: xr.Dataset,
    *,
    x: str | None = None,
    y: str | None = None,
    scales: Mapping[str, float] | None = None,
    marks: bool = True,
) -> list:
    """Draw a curve of bifurcations (from :func:`workbench.continuation.continue_curve`) on
    given axes, e.g. a chaos map's panel or an orbit diagram's: ``x`` and ``y`` name variables
    along the curve (default its first and second parameter; ``y="orbit_x"`` over a branch of
    orbits in the first parameter draws where the bifurcation's orbit lies as the second
    parameter changes). Each run of points of one kind is a line in its colour
    (:data:`CURVE_COLOURS`, on a white halo that keeps it visible on any map; a
    Neimark-Sacker curve's neutral saddles dotted grey), its
    codimension-two points marked as in :data:`CURVE_MARKS` with their short names; with
    ``marks`` the kinds and marks get legend entries. ``scales`` multiplies a variable's values
    (e.g. ``{"omega": 1 / pi}``); a variable without one is drawn in its display unit
    (:func:`~workbench.plot.display_unit`), as the other figures draw it. Returns the artists
    drawn."""
    from matplotlib.patheffects import Normal, Stroke

    x = x or curve.attrs["continuation_parameter"]
    y = y or curve.attrs["curve_parameter"]
    scales = dict(scales or {})
    xs = curve[x].values * scales.get(x, display_unit(curve[x].attrs.get("units"))[0])
    ys = curve[y].values * scales.get(y, display_unit(curve[y].attrs.get("units"))[0])
    codes = curve.kind.values
    q = curve.attrs["curve_parameter"]
    over = (
        "" if q in (x, y) else f", {q} {curve[q].values.min():.4g} .. {curve[q].values.max():.4g}"
    )
    drawn, named = [], set()
    start = 0
    for i in range(1, codes.size + 1):
        if i == codes.size or codes[i] != codes[start]:
            name = _flag(curve.kind, int(codes[start]))
            colour, short = CURVE_COLOURS[name]
            seg = slice(start, min(i + 1, codes.size))
            (line,) = ax.plot(
                xs[seg],
                ys[seg],
                ":" if name == "neutral_saddle" else "-",
                color=colour,
                lw=1.6,
                path_effects=[Stroke(linewidth=3.2, foreground="white", alpha=0.7), Normal()],
                label=f"{short} curve{over}" if marks and name not in named else None,
            )
            named.add(name)
            drawn.append(line)
            start = i
    shown = set()
    for i in range(curve.label.size):
        name = _flag(curve.label, int(curve.label.values[i]))
        if name not in CURVE_MARKS:
            continue
        marker, text = CURVE_MARKS[name]
        drawn += ax.plot(
            xs[i], ys[i], marker, ms=7, mfc="none", mec="k", mew=1.3,
            label=f"{text}: {name.replace('_', ' ')}" if marks and name not in shown else None,
        )  # fmt: skip
        shown.add(name)
        drawn.append(
            ax.annotate(text, (xs[i], ys[i]), textcoords="offset points", xytext=(4, 4),
                        fontsize=7)
        )  # fmt: skip
    return drawn


#: marker and name of each direction of a continued sweep's periodic end (periodic_end_overlay)
END_MARKS = {"up": (">", "sweep up"), "down": ("<", "sweep down")}


def periodic_end_overlay(
    ax,
    ends: xr.Dataset,
    *,
    x: str = "omega",
    y: str | None = None,
    scales: Mapping[str, float] | None = None,
    marks: bool = True,
) -> list:
    """Draw where the period-1 motion of a continued sweep ends (``ends``: ``strobe_period``
    over ``x``, ``y`` and ``direction``, e.g. ``data/periodic_end.nc``) on given axes, e.g. a
    chaos map's panel: per direction and value of ``y`` (default the other dim), a marker at
    the last value of the run of period-1 values from the bottom of ``x``
    (:func:`workbench.analysis.periodic_run_end`: going up, where the periodic motion
    ends; coming down, where it has set in again) and a bar to the next value of ``x``, the
    bracket the end lies in. ``scales`` as in :func:`curve_overlay`; with ``marks`` legend
    entries. Returns the artists drawn."""
    from workbench.analysis import periodic_run_end

    period = ends["strobe_period"]
    if y is None:
        others = [d for d in period.dims if d not in (x, "direction")]
        if len(others) != 1:
            raise ValueError(
                f"ends: strobe_period over {list(period.dims)!r}; give y, the dim other than "
                f"{x!r} and 'direction'"
            )
        y = others[0]
    scales = dict(scales or {})
    sx = scales.get(x, display_unit(ends[x].attrs.get("units"))[0])
    sy = scales.get(y, display_unit(ends[y].attrs.get("units"))[0])
    xs = ends[x].values
    drawn = []
    for direction in ends["direction"].values:
        marker, name = END_MARKS.get(str(direction), ("o", str(direction)))
        line_x, line_y = [], []
        for yv in ends[y].values:
            runs = period.sel({"direction": direction, y: yv}).transpose(x).values
            last = periodic_run_end(list(xs), [int(k) for k in runs])
            if last is None:
                continue
            i = int(np.flatnonzero(xs == last)[0])
            bar = [last, xs[min(i + 1, xs.size - 1)]]
            drawn += ax.plot(np.array(bar) * sx, [yv * sy] * 2, "-", color="k", lw=1.0)
            line_x.append(last * sx)
            line_y.append(yv * sy)
        drawn += ax.plot(
            line_x, line_y, "--" + marker, color="k", lw=0.8, ms=6, mfc="white", mew=1.2,
            label=f"period 1 ends ({name})" if marks else None,
        )  # fmt: skip
    return drawn


def _flag(da: xr.DataArray, code: int) -> str:
    """The flag meaning of ``code`` in a CF-flagged variable."""
    return flag_meaning(da, code)


def curve_figure(
    curves: Sequence[xr.Dataset],
    *,
    scales: Mapping[str, float] | None = None,
    labels: Mapping[str, str] | None = None,
):
    """Curves of bifurcations (from :func:`workbench.continuation.continue_curve`, all in the
    same two parameters) in the plane of their parameters, the first parameter of the first
    curve on the x axis (:func:`curve_overlay`); ``scales`` as there, ``labels`` names an
    axis (default the parameter's long name and display unit)."""
    if not curves:
        raise ValueError("curves: give at least one curve")
    first = curves[0]
    x, y = first.attrs["continuation_parameter"], first.attrs["curve_parameter"]
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    for c in curves:
        pair = (c.attrs["continuation_parameter"], c.attrs["curve_parameter"])
        if set(pair) != {x, y}:
            raise ValueError(f"curves: a curve in {list(pair)!r} among curves in {[x, y]!r}")
        curve_overlay(ax, c, x=x, y=y, scales=scales)
    labels = dict(labels or {})
    ax.set_xlabel(labels.get(x, axis_label(first[x])))
    ax.set_ylabel(labels.get(y, axis_label(first[y])))
    ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3)
    ax.set_title(f"bifurcation curves in ({x}, {y})", fontsize=9)
    fig.tight_layout()
    return fig


def _edges(centres: np.ndarray) -> np.ndarray:
    """Cell edges around ``centres`` (midpoints; the outer cells as wide as their neighbour),
    as ``pcolormesh(shading="nearest")`` draws them."""
    c = np.asarray(centres, dtype=float)
    if c.size == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = (c[1:] + c[:-1]) / 2
    return np.concatenate([[2 * c[0] - mid[0]], mid, [2 * c[-1] - mid[-1]]])


def _mark_exponents(ax, maps: xr.Dataset, xd: str, yd: str, x, y) -> None:
    """Hatch the exponent map's unconverged cells, mark bounds "<=" and failures "x", and say
    so in a legend below the panel (only the marks that occur)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    handles = []
    if "lle_converged" in maps:
        conv = maps["lle_converged"].transpose(yd, xd).values
        xe, ye = _edges(x), _edges(y)
        cells = [(i, j) for (i, j), c in np.ndenumerate(conv) if c == 0]
        for i, j in cells:
            ax.add_patch(
                Rectangle(
                    (xe[j], ye[i]), xe[j + 1] - xe[j], ye[i + 1] - ye[i],
                    fill=False, hatch="///", edgecolor="0.3", linewidth=0,
                )
            )  # fmt: skip
        if cells:
            handles.append(
                Patch(facecolor="none", edgecolor="0.3", hatch="///", label="not converged")
            )
    if "lle_status" in maps:
        status = maps["lle_status"].transpose(yd, xd).values
        for (i, j), st in np.ndenumerate(status):
            if st in (1, 2):
                mark = BOUND_MARK if st == 2 else "x"
                ax.text(x[j], y[i], mark, ha="center", va="center", fontsize=12)
        for code, mark, text in ((2, BOUND_MARK, "upper bound"), (1, "x", "failed")):
            if (status == code).any():
                handles.append(Line2D([], [], ls="", marker=mark, color="k", label=text))
    if handles:
        ax.legend(
            handles=handles,
            loc="upper center",
            bbox_to_anchor=(0.5, -0.16),
            ncol=len(handles),
            fontsize=8,
            frameon=False,
        )
