"""What every figure module shares: matplotlib without a display, axis labels from ``long_name``
and ``units`` (none for a dimensionless ``1``), values shown in a readable SI prefix (µm, not a
"1e-5" offset), titles that wrap between words but never inside "Sec. 4.2" or "0.5 mm", and the
registry of model-specific overview figures."""

from __future__ import annotations

import math
import re
import textwrap
from collections.abc import Callable

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

__all__ = [
    "axis_label",
    "display_scale",
    "overview",
    "plain_ticks",
    "plt",
    "register_overview",
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

_OVERVIEWS: dict[str, Callable[[xr.Dataset], plt.Figure]] = {}


def register_overview(model: str):
    """Decorator: a function ``f(ds) -> Figure`` drawn by :func:`run_figures` for ``model``."""

    def deco(f):
        _OVERVIEWS[model] = f
        return f

    return deco


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


def units_label(units: str | None) -> str:
    """`` [units]`` for a label, or nothing for a dimensionless quantity (``"1"``)."""
    return f" [{units}]" if units and units != "1" else ""


def axis_label(da: xr.DataArray, units: str | None = None) -> str:
    """``long_name [units]`` of a variable or coordinate (no brackets for units ``1``);
    ``units`` replaces the variable's own (e.g. a prefixed unit of :func:`display_scale`)."""
    name = da.attrs.get("long_name", da.name)
    return f"{name}{units_label(units or da.attrs.get('units'))}"


# units whose values are shown with an SI prefix, and the prefixes allowed for each
_PREFIXES = {"m": ("", "m", "µ", "n"), "N": ("k", "", "m"), "J": ("k", "", "m", "µ")}
_FACTORS = {"k": 1e-3, "": 1.0, "m": 1e3, "µ": 1e6, "n": 1e9}


def display_scale(values, units: str | None) -> tuple[float, str | None]:
    """The factor and the unit to show ``values`` (SI, in ``units``) with: an SI prefix on the
    leading unit so that the largest magnitude lies in [1, 1000) where one allows it (m -> mm,
    µm; N -> kN; "m s-1" -> "mm s-1"), else (1, units). Values are never shown as an offset.

    >>> display_scale([2e-6, 4e-5], "m")
    (1000000.0, 'µm')
    >>> display_scale([1500.0], "N m")
    (0.001, 'kN m')
    >>> display_scale([0.3], "rad")
    (1.0, 'rad')
    """
    if not units:
        return 1.0, units
    head, _, tail = units.partition(" ")
    allowed = _PREFIXES.get(head)
    finite = np.abs(np.asarray(values, dtype=float))
    finite = finite[np.isfinite(finite) & (finite > 0)]
    if allowed is None or finite.size == 0:
        return 1.0, units
    top = float(finite.max())
    best = ""
    for prefix in allowed:  # largest unit first: the first that keeps the values >= 1
        best = prefix
        if top * _FACTORS[prefix] >= 1.0:
            break
    factor = _FACTORS[best]
    if best == "" or not math.isfinite(top * factor):
        return 1.0, units
    return factor, f"{best}{head}" + (f" {tail}" if tail else "")


def plain_ticks(ax) -> None:
    """Tick labels without an offset ("+1e-5") or a common factor on linear axes."""
    for axis, scale in (("x", ax.get_xscale()), ("y", ax.get_yscale())):
        if scale == "linear":
            try:
                ax.ticklabel_format(axis=axis, useOffset=False, style="plain")
            except AttributeError:  # a categorical or date axis
                pass


def overview(model: str) -> Callable[[xr.Dataset], plt.Figure] | None:
    """The overview figure registered for ``model`` (None if there is none)."""
    return _OVERVIEWS.get(model)
