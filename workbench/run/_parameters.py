"""A run's resolved parameters in its dataset: one scalar coordinate per model parameter.

Every parameter of the model (its default, or the scene's value) is stored with its units and
long name as a 0-d coordinate named after the parameter, so that a reader without workbench
sees what produced the numbers and xarray can combine and select runs by them, e.g. five stored
runs over ``gamma``::

    runs = xarray.open_mfdataset(paths, combine="nested", concat_dim="gamma")
    runs.x.sel(gamma=0.28)

In a campaign the swept parameters are its dims already (coordinates with the same names,
units and long names) and every other parameter is such a scalar coordinate. The global
attribute ``model_parameters`` lists their names (``ds[ds.attrs["model_parameters"].split()]``
selects them all).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from workbench._attributes import variable
from workbench.models import Model

__all__ = ["PARAMETERS_ATTR", "parameter_coords"]

#: the global attribute that lists the names of the parameter coordinates
PARAMETERS_ATTR = "model_parameters"
_COMMENT = "model parameter: the model's default or the scene's value"


def parameter_coords(
    model: Model,
    parameters: Mapping[str, float],
    *,
    skip: Iterable[str] = (),
    taken: Iterable[str] = (),
) -> dict[str, tuple[tuple, np.float64, dict]]:
    """The scalar coordinates of the resolved ``parameters`` of ``model``.

    Parameters
    ----------
    model : Model
        Declares each parameter's units and long name (in its declared order).
    parameters : mapping
        Name -> value in SI units (the model's defaults overridden by the scene).
    skip : iterable of str
        Parameters left out (a campaign's swept ones, which are its dims).
    taken : iterable of str
        Names of the dataset's variables, dims and coordinates: a parameter with such a name
        is stored as ``parameter_<name>`` instead (the attribute ``parameter`` names it).

    Returns
    -------
    dict
        Coordinate name -> ``((), value, attrs)`` for :class:`xarray.Dataset`'s ``coords``.

    Examples
    --------
    >>> from workbench.models import get_model
    >>> coords = parameter_coords(get_model("duffing"), {"delta": 0.3, "alpha": -1.0,
    ...     "beta": 1.0, "gamma": 0.5, "omega": 1.2, "x0": 1.0, "v0": 0.0}, skip=["gamma"])
    >>> list(coords)[:3], coords["omega"][2]["units"]
    (['delta', 'alpha', 'beta'], 'rad s-1')
    """
    skip, taken = set(skip), set(taken)
    out = {}
    for p in model.parameters:
        if p.name in skip or p.name not in parameters:
            continue
        attrs = variable(p.long_name, p.units, comment=_COMMENT)
        name = p.name
        if name in taken:
            name = f"parameter_{p.name}"
            attrs["parameter"] = p.name
        out[name] = ((), np.float64(parameters[p.name]), attrs)
    return out
