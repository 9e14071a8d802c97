"""Declaring a linkage: its declaration checked whole, the parts and how they refer to each other
(:mod:`workbench.models._declaration`), then the closure of every loop over a cycle of the cranks
(:mod:`workbench.models._declared_kinematics`), so that a declaration that is accepted moves."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from workbench.models._declaration import Linkage, from_table
from workbench.models._declared_kinematics import closure_failure

__all__ = ["declare", "parse_mechanism"]


def declare(linkage: Linkage, samples_per_turn: int = 3600) -> Linkage:
    """The linkage, once every loop closes over a cycle (a turn of the slowest crank), sampled
    every 1/``samples_per_turn`` of a turn of the fastest crank.

    Parameters
    ----------
    linkage : Linkage
        A declaration (its parts already checked when it was built).
    samples_per_turn : int, optional
        Crank angles checked per turn (3600: every 0.1 deg).

    Returns
    -------
    Linkage
        The same declaration.

    Raises
    ------
    SceneError
        Naming the group whose loop does not close, at which crank angle and why.
    """
    error = closure_failure(linkage, samples_per_turn)
    if error is not None:
        raise error
    return linkage


def parse_mechanism(table: Mapping[str, Any]) -> Linkage:
    """The linkage of a ``[mechanism]`` table (the dict :mod:`tomllib` reads), checked whole.

    Parameters
    ----------
    table : mapping
        The table (see :func:`workbench.models._declaration.from_table`).

    Returns
    -------
    Linkage
        The declaration, whose loops close over a cycle.

    Raises
    ------
    SceneError
        One line naming the link, slider, group or joint that is wrong and how.
    """
    return declare(from_table(table))
