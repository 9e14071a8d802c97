"""The plan of a continued sweep: which points each task runs, in which order, from what.

A continued sweep runs along one swept parameter (``along``) per *line* (each combination of
the other swept values) and *direction* (``up``: increasing values, ``down``: decreasing). Each
line and direction is cut into ``segments`` runs of consecutive points (in traversal order) that
are continued side by side, one task each:

* a **brute-force segment** starts ``overlap`` points before its own first point (or at the
  line's first point), from the scene's initial state with the scene's transient, and continues
  from there; the points before its own range are *seam points*, computed only to compare with
  what the previous segment found there;
* a **chained segment** is the same range run again from the state the previous segment left at
  its last point (what a single sequential continuation would do there); the sweep runs it
  only where the seam comparison failed (:mod:`workbench.continuation._sweep`).

Block indices (files ``block-NNNNN.nc`` of the store) are fixed by the plan:
``((kind * directions + d) * lines + line) * segments + j`` with kind 0 brute force, 1 chained.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from workbench.campaign import SweepGrid

__all__ = ["BRUTE", "CHAINED", "Plan", "SegmentSpec"]

BRUTE, CHAINED = 0, 1


@dataclass(frozen=True)
class SegmentSpec:
    """One segment of one line and direction: the flat grid indices it runs, in order."""

    direction: int
    line: int
    index: int
    flat: tuple[int, ...]  # seam points first, then its own points
    own_from: int  # position in ``flat`` of its first own point


class Plan:
    """Lines, directions and segments of a continued sweep over ``grid``.

    Parameters
    ----------
    grid : SweepGrid
    settings : Mapping
        The scene's normalised ``continuation`` settings (``direction``, ``along``,
        ``segments``, ``overlap``).
    """

    def __init__(self, grid: SweepGrid, settings: Mapping) -> None:
        self.grid = grid
        self.along = settings["along"]
        self.axis = grid.dims.index(self.along)
        d = settings["direction"]
        self.directions: tuple[str, ...] = ("up", "down") if d == "both" else (d,)
        self.segments = int(settings["segments"])
        self.overlap = int(settings["overlap"])
        shape = grid.shape
        self.other_dims = tuple(x for i, x in enumerate(grid.dims) if i != self.axis)
        self.other_shape = tuple(n for i, n in enumerate(shape) if i != self.axis)
        self.lines = math.prod(self.other_shape)
        values = np.array(grid.values[self.axis])
        self._ascending = np.argsort(values, kind="stable")
        n = shape[self.axis]
        edges = np.linspace(0, n, self.segments + 1).round().astype(int)
        self.ranges = [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True)]

    @property
    def n_blocks(self) -> int:
        """Block indices the plan can use (brute-force and chained segments)."""
        return 2 * len(self.directions) * self.lines * self.segments

    def block(self, kind: int, seg: SegmentSpec) -> int:
        nd = len(self.directions)
        return ((kind * nd + seg.direction) * self.lines + seg.line) * self.segments + seg.index

    def order(self, direction: int, line: int) -> list[int]:
        """Flat grid indices of a line in traversal order (``up``: increasing values)."""
        other = np.unravel_index(line, self.other_shape) if self.other_shape else ()
        steps = self._ascending if self.directions[direction] == "up" else self._ascending[::-1]
        out = []
        for k in steps:
            idx = list(other)
            idx.insert(self.axis, int(k))
            out.append(int(np.ravel_multi_index(idx, self.grid.shape)))
        return out

    def segment(self, direction: int, line: int, j: int, kind: int = BRUTE) -> SegmentSpec:
        order = self.order(direction, line)
        a, b = self.ranges[j]
        start = a if kind == CHAINED else max(0, a - self.overlap)
        return SegmentSpec(direction, line, j, tuple(order[start:b]), a - start)

    def all_segments(self) -> list[SegmentSpec]:
        return [
            self.segment(d, line, j)
            for d in range(len(self.directions))
            for line in range(self.lines)
            for j in range(self.segments)
        ]

    def line_index(self, flat: int) -> tuple[int, ...]:
        """Index over the other (non-continued) dims of a flat grid index."""
        idx = np.unravel_index(flat, self.grid.shape)
        return tuple(int(i) for k, i in enumerate(idx) if k != self.axis)
