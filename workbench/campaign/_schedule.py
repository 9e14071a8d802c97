"""Which points a campaign's blocks hold, and the order in which they start.

Blocks are dealt by estimated cost: the points ranked by their simulated time (the cost
estimate, :func:`simulated_spans`) are dealt to the B blocks like cards, a tier of B points at a
time, the costliest point of a tier to the block that costs least so far (a snake order: ranks
0 .. B-1 to blocks 0 .. B-1, ranks B .. 2B-1 to blocks B-1 .. 0, ...), so that every block
holds one point of each tier of cost and the blocks cost about the same. A sweep over the
forcing frequency spans 30x in simulated time per point (0.1 pi to 3 pi rad/s); cut into
contiguous blocks, its lowest-frequency block alone could take longer than a worker's share of
the campaign, and every other worker would wait for it at the end. The estimate only needs to
rank the points: its scale does not matter.

Then the blocks start longest first (Graham 1969), so that the campaign does not end waiting
for a long block.

The deal works on arrays: a run of tiers whose points all cost the same adds that cost to
every block, whichever point it gets, so the blocks' running costs over such a run are one
cumulative sum and each tier's seats one sort of it; only a tier that mixes costs is dealt
point by point (at most one per change of cost in the ranking, plus the last).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from workbench.campaign._block import Task
from workbench.campaign._grid import SweepGrid, grid_periods
from workbench.scene import Scene

__all__ = ["block_order", "deal", "longest_first", "partition", "simulated_spans"]


def simulated_spans(scene: Scene, grid: SweepGrid) -> np.ndarray:
    """Simulated time (s) of every point (flat C order): transient and recorded cycles times
    its forcing period, or transient + duration. The cost estimate of a point (the solver's
    work grows with the simulated time; a sweep over the forcing frequency spans 30x between
    0.1 pi and 3 pi). A point whose forcing period cannot be computed is refused in one line
    (:func:`workbench.campaign._grid.grid_periods`), not costed."""
    run = scene.run
    if "cycles" in run:
        periods = grid_periods(scene, grid)
        if periods is not None:
            span = (run["cycles"] + run["transient_cycles"]) * periods
            return np.broadcast_to(span, grid.shape).ravel()
    return np.full(grid.size, run.get("duration", 0.0) + run.get("transient", 0.0))


def deal(cost: np.ndarray, count: int) -> np.ndarray:
    """The block (0 .. ``count`` - 1) of each point of costs ``cost``, dealt a tier of
    ``count`` points at a time by decreasing cost (ties in index order), the costliest point of
    a tier to the block that costs least so far (ties to the lower block; the module
    docstring)."""
    n = len(cost)
    ranked = np.argsort(-cost, kind="stable")
    ranked_cost = cost[ranked]
    rising = -ranked_cost  # ascending, for searchsorted
    block = np.empty(n, np.int64)
    load = [0.0] * count  # cost of each block so far (s), summed in dealing order
    start = 0
    while start < n:
        v = ranked_cost[start]
        same = int(np.searchsorted(rising, -v, side="right")) - start
        tiers = same // count
        if tiers:  # tiers of equal cost: every block gets one point of cost v per tier
            loads = np.empty((tiers + 1, count))
            loads[0] = load
            loads[1:] = v
            np.add.accumulate(loads, axis=0, out=loads)  # each block's running cost
            block[ranked[start : start + tiers * count]] = _seats(loads[:tiers]).ravel()
            load = loads[tiers].tolist()
            start += tiers * count
            continue
        stop = min(start + count, n)  # a tier of mixed costs (or the last): point by point
        seats = sorted(range(count), key=lambda b: (load[b], b))  # cheapest block first
        for i, b in zip(range(start, stop), seats, strict=False):
            block[ranked[i]] = b
            load[b] += float(ranked_cost[i])
        start = stop
    return block


def _seats(loads: np.ndarray) -> np.ndarray:
    """Each row's blocks by increasing cost, ties by block index (a stable argsort of every
    row), for rows that add the same cost to every block: adding it keeps the order of two
    costs or makes them equal, never reverses it, and equal costs stay equal, so the order
    changes only where two costs become equal (at most once per block) and is sorted once
    between such rows."""
    first = np.argsort(loads[0], kind="stable")
    ranked = loads[:, first]  # each row ascending
    ties = ranked[:, 1:] == ranked[:, :-1]
    changes = np.flatnonzero((ties[1:] != ties[:-1]).any(axis=1)) + 1
    seats = np.empty(loads.shape, np.int64)
    for a, b in zip([0, *changes.tolist()], [*changes.tolist(), len(loads)], strict=True):
        seats[a:b] = np.argsort(loads[a], kind="stable")
    return seats


def partition(scene: Scene, grid: SweepGrid, chunk: int) -> list[tuple[int, ...]]:
    """The flat indices of the points of each block: ``ceil(size / chunk)`` blocks of at most
    ``chunk`` points, dealt by estimated cost (:func:`deal`); each block's indices ascending.
    Points of equal cost are dealt in grid order: a sweep of equal spans gives block ``i`` the
    points ``i, i + B, i + 2 B, ...``."""
    count = math.ceil(grid.size / chunk)
    block = deal(simulated_spans(scene, grid), count)
    # by block, ascending flat index within each (a radix sort for a small block index)
    order = np.argsort(block.astype(np.min_scalar_type(count)), kind="stable")
    ends = np.cumsum(np.bincount(block, minlength=count)).tolist()
    return [tuple(order[a:b].tolist()) for a, b in zip([0, *ends[:-1]], ends, strict=True)]


def block_order(scene: Scene, grid: SweepGrid, blocks: Sequence[Sequence[int]]) -> list[int]:
    """Indices of ``blocks`` (sequences of flat indices) by decreasing estimated cost; ties keep
    block order."""
    cost = simulated_spans(scene, grid)
    totals = [sum(cost[np.asarray(b, np.int64)].tolist()) for b in blocks]
    return sorted(range(len(blocks)), key=lambda i: (-totals[i], i))


def longest_first(scene: Scene, grid: SweepGrid, tasks: list[Task]) -> list[Task]:
    """The tasks ordered by decreasing estimated cost (their points' simulated time), so that
    the longest blocks start first and no worker is left with one at the end: Graham's (1969)
    longest-processing-time rule, within 4/3 of the best schedule. Ties keep block order."""
    order = block_order(scene, grid, [t.flat for t in tasks])
    return [tasks[i] for i in order]
