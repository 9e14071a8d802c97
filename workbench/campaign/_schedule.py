"""The order in which a campaign's blocks start: longest first (Graham 1969)."""

from __future__ import annotations

from workbench.campaign._block import BlockTask
from workbench.campaign._grid import SweepGrid, forcing_period
from workbench.scene import Scene

__all__ = ["longest_first", "simulated_span"]


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


def longest_first(scene: Scene, grid: SweepGrid, tasks: list[BlockTask]) -> list[BlockTask]:
    """The tasks ordered by decreasing estimated cost (their points' simulated time), so that
    the longest blocks start first and no worker is left with one at the end: Graham's (1969)
    longest-processing-time rule, within 4/3 of the best schedule. Ties keep block order."""
    cost = {t.block: sum(simulated_span(scene, grid, f) for f in t.flat) for t in tasks}
    return sorted(tasks, key=lambda t: (-cost[t.block], t.block))
