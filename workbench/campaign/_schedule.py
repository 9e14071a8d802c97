"""Which points a campaign's blocks hold, and the order in which they start.

Blocks are dealt by estimated cost: the points ranked by their simulated time (the cost
estimate, :func:`simulated_span`) are dealt to the B blocks like cards, a tier of B points at a
time, the costliest point of a tier to the block that costs least so far (a snake order: ranks
0 .. B-1 to blocks 0 .. B-1, ranks B .. 2B-1 to blocks B-1 .. 0, ...), so that every block
holds one point of each tier of cost and the blocks cost about the same. A sweep over the
forcing frequency spans 30x in simulated time per point (0.1 pi to 3 pi rad/s); cut into
contiguous blocks, its lowest-frequency block alone could take longer than a worker's share of
the campaign, and every other worker would wait for it at the end. The estimate only needs to
rank the points: its scale does not matter.

Then the blocks start longest first (Graham 1969), so that the campaign does not end waiting
for a long block.
"""

from __future__ import annotations

import math

from workbench.campaign._block import BlockTask
from workbench.campaign._grid import SweepGrid, forcing_period
from workbench.scene import Scene

__all__ = ["block_order", "longest_first", "partition", "simulated_span"]


def simulated_span(scene: Scene, grid: SweepGrid, flat: int) -> float:
    """Simulated time (s) of one point: transient and recorded cycles times its forcing period,
    or transient + duration. The cost estimate of a point (the solver's work grows with the
    simulated time; a sweep over the forcing frequency spans 30x between 0.1 pi and 3 pi)."""
    try:
        period = forcing_period(scene, grid, flat)
    except Exception:  # the point is invalid: it costs nothing (it fails at validation)
        return 0.0
    run = scene.run
    if period is not None and "cycles" in run:
        return (run["cycles"] + run["transient_cycles"]) * period
    return run.get("duration", 0.0) + run.get("transient", 0.0)


def partition(scene: Scene, grid: SweepGrid, chunk: int) -> list[tuple[int, ...]]:
    """The flat indices of the points of each block: ``ceil(size / chunk)`` blocks of at most
    ``chunk`` points, dealt by estimated cost (see the module docstring); each block's indices
    ascending. Points of equal cost are dealt in grid order: a sweep of equal spans gives block
    ``i`` the points ``i, i + B, i + 2 B, ...``."""
    n = grid.size
    count = math.ceil(n / chunk)
    cost = [simulated_span(scene, grid, f) for f in range(n)]
    ranked = sorted(range(n), key=lambda f: (-cost[f], f))
    blocks: list[list[int]] = [[] for _ in range(count)]
    load = [0.0] * count
    for start in range(0, n, count):
        seats = sorted(range(count), key=lambda b: (load[b], b))  # cheapest block first
        for flat, b in zip(ranked[start : start + count], seats, strict=False):
            blocks[b].append(flat)
            load[b] += cost[flat]
    return [tuple(sorted(b)) for b in blocks]


def block_order(scene: Scene, grid: SweepGrid, blocks: list) -> list[int]:
    """Indices of ``blocks`` (sequences of flat indices) by decreasing estimated cost; ties keep
    block order."""
    cost = [sum(simulated_span(scene, grid, f) for f in b) for b in blocks]
    return sorted(range(len(blocks)), key=lambda i: (-cost[i], i))


def longest_first(scene: Scene, grid: SweepGrid, tasks: list[BlockTask]) -> list[BlockTask]:
    """The tasks ordered by decreasing estimated cost (their points' simulated time), so that
    the longest blocks start first and no worker is left with one at the end: Graham's (1969)
    longest-processing-time rule, within 4/3 of the best schedule. Ties keep block order."""
    order = block_order(scene, grid, [t.flat for t in tasks])
    return [tasks[i] for i in order]
