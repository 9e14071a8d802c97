"""Named layouts of the flat arrays that compiled hooks take (parameters, indices, workspaces).

A compiled model receives its parameters as one float64 array ``p``, its integer settings as one
int64 array ``ip`` and a scratch array ``work``. Their layouts are declared once, as an ordered
list of named fields with their sizes; the offsets follow. A layout is a named tuple of integer
offsets (plus the total ``size``), so compiled code reads ``p[P.omega]`` with ``P`` a module
global that numba freezes to constants, and Python code packs the array by field name:

>>> JOINT = layout("Joint", [("radius", 1), ("stiffness", 1)])
>>> P = layout("P", [("omega", 1), ("joint", 2 * JOINT.size)])
>>> P.joint, P.size
(1, 5)
>>> P.pack({"omega": 3.0, "joint": [1.0, 2.0, 1.5, 4.0]})
array([3. , 1. , 2. , 1.5, 4. ])
>>> P.block("joint")
slice(1, 5, None)

Blocks that several models share (a clearance joint's parameters, the friction parameters) are
layouts of their own, placed as fields of ``n * BLOCK.size`` and addressed as
``P.joint + j * JOINT.size + JOINT.stiffness``.
"""

from __future__ import annotations

from collections import namedtuple
from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["Layout", "layout", "named_values"]


class Layout:
    """Mixin of the layout named tuples (see :func:`layout`); fields are offsets, ``size`` the
    total length."""

    __slots__ = ()

    @property
    def fields(self) -> tuple[tuple[str, int, int], ...]:
        """(name, offset, size) of every field, in order."""
        names = self._fields[:-1]
        offsets = [*self[:-1], self.size]
        return tuple((n, offsets[i], offsets[i + 1] - offsets[i]) for i, n in enumerate(names))

    def block(self, name: str) -> slice:
        """The slice of field ``name``."""
        for n, offset, size in self.fields:
            if n == name:
                return slice(offset, offset + size)
        raise KeyError(f"{type(self).__name__} has no field {name!r}")

    def pack(
        self,
        values: Mapping[str, float | Sequence[float] | np.ndarray],
        *,
        fill: float = 0.0,
        dtype: type = np.float64,
    ) -> np.ndarray:
        """A new array of ``size`` with the fields in ``values`` set (the rest ``fill``).

        Parameters
        ----------
        values : mapping of str to scalar or sequence
            Field name -> its value(s); a sequence must have the field's size.
        fill : float
            Value of the fields not given.
        dtype : numpy dtype
            float64 for parameters and workspaces, int64 for index arrays.

        Raises
        ------
        KeyError
            For a name that is not a field.
        ValueError
            For a value whose size differs from the field's.
        """
        out = np.full(self.size, fill, dtype=dtype)
        for name, value in values.items():
            sl = self.block(name)
            arr = np.asarray(value, dtype=dtype).ravel()
            if arr.size != sl.stop - sl.start:
                raise ValueError(
                    f"{type(self).__name__}.{name} has {sl.stop - sl.start} entries, got {arr.size}"
                )
            out[sl] = arr
        return out


def layout(name: str, fields: Sequence[tuple[str, int]]) -> Layout:
    """A layout of consecutive fields, offsets derived from the sizes.

    Parameters
    ----------
    name : str
        Name of the layout (a valid identifier; shown in errors).
    fields : sequence of (str, int)
        Field names (identifiers, not ``size``) and their sizes (>= 0), in array order.

    Returns
    -------
    Layout
        A named tuple of the fields' offsets and ``size``, usable as a global in numba-compiled
        code, with the methods of :class:`Layout`.
    """
    names = [n for n, _ in fields]
    if len(set(names)) != len(names) or "size" in names:
        raise ValueError(f"layout {name}: field names must be distinct and not 'size': {names}")
    offsets = []
    total = 0
    for n, size in fields:
        if size < 0:
            raise ValueError(f"layout {name}: field {n!r} has negative size {size}")
        offsets.append(total)
        total += int(size)
    base = namedtuple(name, [*names, "size"])
    cls = type(name, (Layout, base), {"__slots__": ()})
    return cls(*offsets, total)


def named_values(
    fields: Sequence[str],
    defaults: Mapping[str, float],
    values: Mapping[str, float] | None = None,
    what: str = "field",
) -> np.ndarray:
    """float64 array of ``defaults`` overridden by ``values``, in the order of ``fields``.

    Raises
    ------
    KeyError
        For a name in ``values`` that is not in ``fields`` (``what`` names the kind of field).
    """
    merged = dict(defaults)
    for name, value in (values or {}).items():
        if name not in fields:
            raise KeyError(f"unknown {what} {name!r}; known: {tuple(fields)}")
        merged[name] = value
    return np.array([merged[f] for f in fields], dtype=np.float64)
