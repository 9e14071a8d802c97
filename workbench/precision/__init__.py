"""What accuracy costs in time: work-precision studies of a scene (:func:`accuracy`) and the
cheapest setting under a target error (:func:`recommend`). Above the run layer: every run here
is a :func:`workbench.simulate` of a variant of the scene."""

from workbench.precision._measures import LIMIT_FACTOR, REFERENCE_FLOOR, short_horizon
from workbench.precision._recommend import Recommendation, recommend
from workbench.precision._study import (
    DEFAULT_METHODS,
    DEFAULT_TOLERANCES,
    REFERENCE_MIN_TOL,
    accuracy,
)

__all__ = [
    "DEFAULT_METHODS",
    "DEFAULT_TOLERANCES",
    "LIMIT_FACTOR",
    "REFERENCE_FLOOR",
    "REFERENCE_MIN_TOL",
    "Recommendation",
    "accuracy",
    "recommend",
    "short_horizon",
]
