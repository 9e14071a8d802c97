"""What every figure module shares: matplotlib without a display, the one display unit of each
stored unit (:func:`display_unit`: lengths in mm, every other unit as stored), axis labels from
``long_name`` and that unit (none for a dimensionless ``1``), tick labels without an offset,
titles that wrap between words but never inside "Sec. 4.2" or "0.5 mm", and the overview
figure a model declares."""

from __future__ import annotations

import re
import textwrap
from collections.abc import Callable

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

__all__ = [
    "DISPLAY_UNITS",
    "axis_label",
    "display_text",
    "display_unit",
    "display_values",
    "overview",
    "plain_ticks",
    "plt",
    "run_parameters",
    "title_width",
    "units_label",
    "wrap_title",
]

_NBSP = "\u00a0"
# spaces that must not become line breaks: "Sec. 4.2", "Figs. 28-30", "Eq. 17", "et al. 2019",
# "0.5 mm", "2.5 pi", "c = 0.1", "c_f = 0.01", and a short parenthesis
_KEEP_TOGETHER = (
    re.compile(r"\b(?:Sec|Secs|Fig|Figs|Eq|Eqs|Table|No|Ch)\.\s+(?=\S)"),
    re.compile(r"\bet al\.\s+(?=\d)"),
    re.compile(r"(?<=\d)\s+(?=(?:mm|µm|um|nm|m|ms|s|pi|rad|Hz|N|kN|J|%|1/s|rad/s)\b)"),
    re.compile(r"\s+=\s+"),
    re.compile(r"\([^()\n]{1,40}\)"),  # a short parenthesis: "(Chen et al. 2019, Sec. 4.2)"
)


def run_parameters(ds: xr.Dataset) -> dict[str, float]:
    """The resolved parameters (model defaults and the scene's values, SI) of a stored run."""
    from workbench.scene import scene_from_toml

    return scene_from_toml(ds.attrs["scene"]).resolved_parameters


def wrap_title(text: str, width: int = 90) -> str:
    """``text`` on lines of at most ``width`` characters, broken between words only where a
    reader expects it: never inside "Sec. 4.2", "Fig. 28", "et al. 2019", "0.5 mm" or
    "omega = 2.5".

    >>> print(wrap_title("Nine-bar, clearances at A and B (0.5 mm), Coulomb (Chen et al. 2019, "
    ...                  "Sec. 4.2)", 50))
    Nine-bar, clearances at A and B (0.5 mm), Coulomb
    (Chen et al. 2019, Sec. 4.2)
    """
    for pattern in _KEEP_TOGETHER:
        text = pattern.sub(lambda m: re.sub(r"\s", _NBSP, m.group(0)), text)
    lines = []
    for paragraph in text.split("\n"):
        lines.extend(
            textwrap.wrap(paragraph, width, break_long_words=False, break_on_hyphens=False) or [""]
        )
    return "\n".join(lines).replace(_NBSP, " ")


def title_width(fig, fontsize: float = 9.0) -> int:
    """How many characters of a title at ``fontsize`` (pt) fit across ``fig`` (about 0.6 em
    per character)."""
    return max(30, int(fig.get_figwidth() * 72 / (0.6 * fontsize)))


#: stored unit -> (factor from the stored value to the shown one, shown unit): lengths in mm, the
#: unit the field quotes clearances in (a journal's eccentricity, a clearance, a slider's
#: position alike). A unit not listed is shown as stored (a velocity in m s-1, a force in N).
DISPLAY_UNITS: dict[str, tuple[float, str]] = {"m": (1e3, "mm")}


def display_unit(units: str | None) -> tuple[float, str | None]:
    """The factor and the unit every figure shows a quantity stored in ``units`` with
    (:data:`DISPLAY_UNITS`; else ``(1, units)``).

    The choice depends on the units alone, never on the values drawn, so that a variable has
    the same unit in every figure: a displacement in mm in the time series, the phase portrait
    and the Poincaré section of a run, and a parameter in the same unit on every axis. A
    dimensionless quantity (units ``"1"``) keeps ``"1"``, which a label shows as no unit at all
    (:func:`units_label`).

    >>> display_unit("m")
    (1000.0, 'mm')
    >>> display_unit("m s-1")
    (1.0, 'm s-1')
    >>> display_unit("1")
    (1.0, '1')
    """
    if units in DISPLAY_UNITS:
        return DISPLAY_UNITS[units]
    return 1.0, units


def display_values(da: xr.DataArray) -> np.ndarray:
    """The values of ``da`` (float) in its display unit (:func:`display_unit`)."""
    factor, _ = display_unit(da.attrs.get("units"))
    return np.asarray(da.values, dtype=float) * factor


def display_text(value: float, units: str | None) -> str:
    """``value`` (in ``units``) as text in its display unit, for a title: ``"0.1 mm"``.

    >>> display_text(1e-4, "m")
    '0.1 mm'
    """
    factor, shown = display_unit(units)
    return f"{value * factor:g}" + (f" {shown}" if shown and shown != "1" else "")


def units_label(units: str | None) -> str:
    """`` [units]`` for a label, or nothing for a dimensionless quantity (``"1"``): a figure
    names a pure number by its name alone, never "[1]" or "[-]"."""
    return f" [{units}]" if units and units != "1" else ""


def axis_label(da: xr.DataArray) -> str:
    """``long_name [unit]`` of a variable or coordinate in its display unit
    (:func:`display_unit`; no brackets for units ``1``): the label of values drawn as
    :func:`display_values` gives them."""
    name = da.attrs.get("long_name", da.name)
    return f"{name}{units_label(display_unit(da.attrs.get('units'))[1])}"


def plain_ticks(ax) -> None:
    """Tick labels without an offset ("+1e-5") or a common factor on linear axes."""
    for axis, scale in (("x", ax.get_xscale()), ("y", ax.get_yscale())):
        if scale == "linear":
            try:
                ax.ticklabel_format(axis=axis, useOffset=False, style="plain")
            except AttributeError:  # a categorical or date axis
                pass


def overview(model: str | None) -> Callable[[xr.Dataset], plt.Figure] | None:
    """The overview figure of ``model``: the function its ``overview_figure`` names
    (:attr:`workbench.models.Model.overview_figure`); None for a model without one, or one
    that this process does not know (a stored run of a model not imported)."""
    from workbench.models import get_model

    try:
        return get_model(model).plugin("overview_figure")
    except KeyError:
        return None
