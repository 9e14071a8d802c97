"""How the motion changes with a parameter: continued sweeps (each point from its neighbour's
settled state, up, down or both ways), periodic orbits of the stroboscopic map by shooting
with their Floquet multipliers, pseudo-arclength branches with labelled bifurcations,
chaos indicators per campaign point, and curves of fold, period-doubling, Neimark-Sacker and
grazing points in two parameters.

Its own layer, directly above campaign (whose store, executors and block files it uses for its
parallel parts) and below verification and study (:data:`workbench._layers.LAYERS`).
"""

from workbench.continuation._curve import CURVE_KINDS, CURVE_LABELS, continue_curve
from workbench.continuation._exponent import PointExponent, exponent_method, point_exponent
from workbench.continuation._indicators import (
    chaos_indicators,
    chaos_map,
    lle_cycles,
    strobe_period,
    strobe_zero_one,
)
from workbench.continuation._orbits import branch_bifurcations, continue_orbit, periodic_orbit
from workbench.continuation._seams import attractor_distance
from workbench.continuation._strobe import StrobeMap
from workbench.continuation._sweep import continued_sweep

__all__ = [
    "CURVE_KINDS",
    "CURVE_LABELS",
    "PointExponent",
    "StrobeMap",
    "attractor_distance",
    "branch_bifurcations",
    "chaos_indicators",
    "chaos_map",
    "continue_curve",
    "continue_orbit",
    "continued_sweep",
    "exponent_method",
    "lle_cycles",
    "periodic_orbit",
    "point_exponent",
    "strobe_period",
    "strobe_zero_one",
]
