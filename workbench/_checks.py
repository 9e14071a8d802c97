"""Checks of the arguments a public function takes, written once.

Examples
--------
>>> from workbench._checks import positive_int
>>> positive_int("workers", 2)
2
>>> positive_int("workers", 0)
Traceback (most recent call last):
...
ValueError: workers must be a positive integer, got 0
"""

from __future__ import annotations

import numbers
from typing import Any

__all__ = ["positive_int"]


def positive_int(name: str, value: Any, *, allow_none: bool = False) -> int | None:
    """``value`` as an ``int`` when it is an integer >= 1 (``None`` passes where
    ``allow_none``), else a ``ValueError`` naming ``name`` and the value; booleans are refused."""
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        allowed = "a positive integer" + (" or None" if allow_none else "")
        raise ValueError(f"{name} must be {allowed}, got {value!r}")
    return int(value)
