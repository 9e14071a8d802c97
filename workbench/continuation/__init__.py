"""How the motion changes with a parameter: continued sweeps (each point from its neighbour's
settled state, up, down or both ways), periodic orbits of the stroboscopic map by shooting
with their Floquet multipliers, pseudo-arclength branches with labelled bifurcations, and
chaos indicators per campaign point.

Above the run and analysis layers, beside campaign (whose store, executors and block files it
uses for its parallel parts).
"""

from workbench.continuation._orbits import continue_orbit, periodic_orbit
from workbench.continuation._strobe import StrobeMap
from workbench.continuation._sweep import continued_sweep

__all__ = ["StrobeMap", "continue_orbit", "continued_sweep", "periodic_orbit"]
