"""The layout of an estimator's results over the parameter dims of a record: which variables,
their dims and sizes, which coordinates and attributes are shared and which are per point, read
from a few points' results; filled point by point (see :mod:`workbench.analysis._broadcast`)."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import xarray as xr

from workbench._attributes import flags, variable

__all__ = ["COMPLETE", "ERROR", "ResultLayout", "all_failed"]

ERROR = "analysis_error"
COMPLETE = "evidence_complete"
OTHER = "other_attrs"


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b))
    try:
        return bool(a == b)
    except (TypeError, ValueError):  # pragma: no cover - values without a truth value
        return repr(a) == repr(b)


def _fill_value(dtype: np.dtype):
    if dtype.kind == "f":
        return np.nan
    if dtype.kind in "iu":
        return -1
    if dtype.kind == "b":
        return False
    return ""


class ResultLayout:
    """The variables of the combined result and their sizes, from the probed points' results."""

    def __init__(self, results: list[xr.Dataset], loop: tuple[str, ...], sizes, lazy: bool):
        first = results[0]
        self.loop = loop
        self.lazy = lazy
        names = list(first.data_vars) + [c for c in first.coords if first[c].ndim == 0]
        self.scalars_and_vars = names
        self.sizes: dict[str, int] = {}
        for r in results:
            for d, n in r.sizes.items():
                self.sizes[d] = max(self.sizes.get(d, 0), n)
        self.sizes.update(sizes or {})
        clash = [d for d in self.sizes if d in loop]
        if clash:
            raise ValueError(
                f"the estimator's result has dim(s) {clash!r}, which x also has; rename x's "
                f"dim first, e.g. x.rename({{{clash[0]!r}: {clash[0] + '_param'!r}}})"
            )
        # evidence coordinates: shared (same values on the common prefix) or per point
        self.shared_coords: dict[str, tuple] = {}
        self.point_coords: list[str] = []
        for c, var in first.coords.items():
            if var.ndim == 0:
                continue
            values = [r[c].values for r in results if c in r.coords]
            longest = max(values, key=len)
            if all(_same(v, longest[: len(v)]) for v in values):
                self.shared_coords[c] = (var.dims, longest, dict(var.attrs))
            else:
                self.point_coords.append(c)
        # attributes: shared when equal at every result, else one variable per point
        self.attrs = {
            k: v
            for k, v in first.attrs.items()
            if all(k in r.attrs and _same(r.attrs[k], v) for r in results)
        }
        self.point_attrs = [k for k in first.attrs if k not in self.attrs]
        self.var_attrs: dict[str, dict] = {}
        self.point_var_attrs: list[tuple[str, str]] = []
        for name in names:
            a = first[name].attrs
            shared = {
                k: v
                for k, v in a.items()
                if all(
                    name in r and k in r[name].attrs and _same(r[name].attrs[k], v) for r in results
                )
            }
            self.var_attrs[name] = shared
            self.point_var_attrs += [(name, k) for k in a if k not in shared]
        self.templates = {name: first[name] for name in names}
        outputs = []  # (name, dims, dtype, attrs)
        for name in names:
            v = first[name]
            dtype = np.dtype(v.dtype) if v.dtype.kind in "fiub" else np.dtype(object)
            outputs.append((name, v.dims, dtype, self.var_attrs[name]))
        for c in self.point_coords:
            v = first[c]
            attrs = dict(v.attrs, long_name=f"{v.attrs.get('long_name', c)} of each point")
            outputs.append((f"{c}_value", v.dims, np.dtype(v.dtype), attrs))
        for k in self.point_attrs:
            outputs.append(
                (
                    self._attr_name(k),
                    (),
                    np.dtype(object),
                    variable(f"attribute {k!r} of each point's result"),
                )
            )
        for name, k in self.point_var_attrs:
            outputs.append(
                (
                    f"{name}_{k}",
                    (),
                    np.dtype(object),
                    variable(f"attribute {k!r} of {name!r} at each point"),
                )
            )
        outputs.append(
            (
                ERROR,
                (),
                np.dtype(object),
                variable("why the estimator failed at the point (empty when it did not)"),
            )
        )
        outputs.append(
            (
                COMPLETE,
                (),
                np.dtype(np.int8),
                flags(
                    "every evidence variable of the point fits the result's layout",
                    ["cut_or_missing", "complete"],
                ),
            )
        )
        if lazy:
            outputs.append(
                (
                    OTHER,
                    (),
                    np.dtype(object),
                    variable(
                        "attributes of the point's result that differ from the "
                        "result's own (JSON; empty when none)"
                    ),
                )
            )
        self.outputs = outputs

    def _attr_name(self, k: str) -> str:
        return k if k not in self.templates else f"attr_{k}"

    def allocate(self, lead: tuple[int, ...]) -> dict[str, np.ndarray]:
        out = {}
        for name, dims, dtype, _ in self.outputs:
            shape = tuple(lead) + tuple(self.sizes[d] for d in dims)
            out[name] = np.full(shape, _fill_value(dtype), dtype=dtype)
        out[COMPLETE][...] = 0
        return out

    def fill(self, arrays: dict[str, np.ndarray], i: tuple[int, ...], r) -> None:
        """Write one point's result (a Dataset, or an error message) at index ``i``."""
        if not isinstance(r, xr.Dataset):
            arrays[ERROR][i] = r
            return
        complete = True
        blank: set[str] = set()
        for c in self.shared_coords:
            dims, values, _ = self.shared_coords[c]
            if c in r.coords:
                v = r[c].values
                n = min(len(v), len(values))
                if not _same(v[:n], values[:n]):
                    blank.update(dims)
                    complete = False
        for name, dims, dtype, _ in self.outputs:
            if name in self.templates:
                src = r[name] if name in r.variables else None
            elif name.endswith("_value") and name[:-6] in self.point_coords:
                src = r[name[:-6]] if name[:-6] in r.coords else None
            else:
                continue
            if src is None:
                complete = False
                continue
            values = np.asarray(src.values)
            if any(d in blank for d in dims):
                continue
            cut = tuple(
                slice(0, min(n, self.sizes[d])) for d, n in zip(dims, values.shape, strict=True)
            )
            if any(n > self.sizes[d] for d, n in zip(dims, values.shape, strict=True)):
                complete = False
            target = arrays[name][i]
            if dims:
                target[cut] = values[cut]
            else:
                arrays[name][i] = values if dtype.kind != "O" else values.item()
        for k in self.point_attrs:
            arrays[self._attr_name(k)][i] = str(r.attrs.get(k, ""))
        for name, k in self.point_var_attrs:
            arrays[f"{name}_{k}"][i] = str(r[name].attrs.get(k, "")) if name in r else ""
        if self.lazy:
            other = {
                k: str(v)
                for k, v in r.attrs.items()
                if k in self.attrs and not _same(v, self.attrs[k])
            }
            for name, shared in self.var_attrs.items():
                if name in r:
                    other.update(
                        {
                            f"{name}.{k}": str(v)
                            for k, v in r[name].attrs.items()
                            if k in shared and not _same(v, shared[k])
                        }
                    )
            arrays[OTHER][i] = json.dumps(other) if other else ""
        arrays[COMPLETE][i] = int(complete)
        arrays[ERROR][i] = ""

    def dataset(self, x: xr.DataArray, loop: tuple[str, ...], arrays: dict) -> xr.Dataset:
        coords = {n: c.variable for n, c in x.coords.items() if set(c.dims) <= set(loop)}
        for c, (dims, values, attrs) in self.shared_coords.items():
            if len(dims) == 1 and len(values) == self.sizes[dims[0]]:
                coords[c] = (dims, values, attrs)
            else:  # shared prefix, longer at some point: the dim stays positional
                coords[c] = (
                    dims,
                    np.concatenate(
                        [
                            values,
                            np.full(
                                self.sizes[dims[0]] - len(values),
                                _fill_value(np.asarray(values).dtype),
                            ),
                        ]
                    )
                    if len(dims) == 1
                    else values,
                    attrs,
                )
        data_vars = {}
        for name, dims, _, attrs in self.outputs:
            arr = arrays[name]
            data = arr.data if isinstance(arr, xr.Variable) else arr
            var = xr.Variable(loop + tuple(dims), data, attrs)
            if name.endswith("_value") and name[:-6] in self.point_coords:
                coords[name] = var
            else:
                data_vars[name] = var
        return xr.Dataset(data_vars, coords=coords, attrs=self.attrs)


def all_failed(x, loop, results, shape) -> xr.Dataset:
    errors = np.full(shape, "", dtype=object)
    for i, r in results.items():
        errors[i] = r
    coords = {n: c.variable for n, c in x.coords.items() if set(c.dims) <= set(loop)}
    return xr.Dataset(
        {
            ERROR: (
                loop,
                errors,
                variable("why the estimator failed at the point"),
            )
        },
        coords=coords,
    )
