"""Attributes of a stored variable: its name, units and flags, written one way everywhere.

Every data variable and coordinate the workbench stores carries ``long_name`` and ``units``
(CF-1.11; ``"1"`` for a dimensionless number); a variable of categories carries the CF pair
``flag_values`` / ``flag_meanings``. These helpers build those dictionaries and read them back,
so that no module spells them out by hand.

Examples
--------
>>> from workbench._attributes import flag_names, flags, variable
>>> variable("crank angle", "rad")
{'long_name': 'crank angle', 'units': 'rad'}
>>> a = flags("side of the stop", ["free", "in contact"])
>>> a["flag_values"], a["flag_meanings"]
(array([0, 1], dtype=int8), 'free in_contact')
>>> import xarray as xr
>>> flag_names(xr.DataArray(0, attrs=a))
['free', 'in_contact']
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np
import xarray as xr

__all__ = ["flag_meaning", "flag_names", "flags", "named", "variable"]


def variable(long_name: str, units: str = "1", /, **extra: object) -> dict:
    """The attributes of a stored variable: ``long_name``, ``units`` (UDUNITS; ``"1"`` for a
    dimensionless number), then ``extra`` in the order given."""
    if not isinstance(units, str) or not units:
        raise ValueError(
            f'units of {long_name!r} must be a non-empty UDUNITS string ("1" for a '
            f"dimensionless number), got {units!r}"
        )
    return {"long_name": long_name, "units": units, **extra}


def named(long_name: str, /, **extra: object) -> dict:
    """The attributes of a text variable (a message, a note, a name), which CF gives no
    ``units``: ``long_name``, then ``extra``. A number, a flag or a boolean takes
    :func:`variable` (units ``"1"`` when dimensionless)."""
    return {"long_name": long_name, **extra}


def flags(
    long_name: str,
    meanings: Iterable[str] | Mapping[int, str],
    /,
    *,
    dtype: type = np.int8,
    **extra: object,
) -> dict:
    """The attributes of a variable of categories: CF ``flag_values`` (``dtype``) and
    ``flag_meanings`` (blanks in a meaning become underscores, as CF requires).

    ``meanings`` is a sequence (values 0, 1, ...) or a mapping value -> meaning.
    """
    pairs = dict(meanings) if isinstance(meanings, Mapping) else dict(enumerate(meanings))
    words = [str(m).replace(" ", "_") for m in pairs.values()]
    if len(set(words)) != len(words) or not all(words):
        raise ValueError(f"flag meanings of {long_name!r} must be distinct and non-empty: {words}")
    return variable(
        long_name,
        "1",
        flag_values=np.array(list(pairs), dtype=dtype),
        flag_meanings=" ".join(words),
        **extra,
    )


def flag_names(da: xr.DataArray) -> list[str]:
    """The meanings of a flag variable's values, in the order of its ``flag_values``."""
    return str(da.attrs.get("flag_meanings", "")).split()


def flag_meaning(da: xr.DataArray, value: int) -> str:
    """The meaning of one value of a flag variable (``KeyError`` naming the allowed values when
    the variable has no such flag)."""
    values = [int(v) for v in np.atleast_1d(da.attrs.get("flag_values", []))]
    table = dict(zip(values, flag_names(da), strict=True))
    if int(value) not in table:
        raise KeyError(f"{da.name!r} has no flag {int(value)}; its flags are {table}")
    return table[int(value)]
