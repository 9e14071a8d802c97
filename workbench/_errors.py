"""The errors scenes and models raise: :class:`SceneError`, and the solver's
:class:`~workbench.solver.SolverError` (re-exported: models raise it for a state outside their
domain); :class:`~workbench._cache.CacheError` (re-exported: a kernel cache that could hold
someone else's code); and :class:`ModelWarning`, for a run that ended well but left its model's
physics."""

from __future__ import annotations

from workbench._cache import CacheError
from workbench.solver import SolverError

__all__ = ["CacheError", "ModelWarning", "SceneError", "SolverError"]


class SceneError(ValueError):
    """A scene is malformed: the message names the key (dotted path), the value and what is allowed.

    Attributes
    ----------
    key : str
        Dotted path of the offending key, e.g. ``"solver.rtol"``.
    """

    def __init__(self, key: str, message: str) -> None:
        self.key = key
        super().__init__(f"{key}: {message}" if key else message)

    def __reduce__(self):  # the same error across processes (raised in a campaign's worker)
        return (type(self), (self.key, str(self)[len(self.key) + 2 :] if self.key else str(self)))


class ModelWarning(UserWarning):
    """A run completed, but its model says a law left the range where it is physical (e.g. a
    LuGre friction coefficient beyond its envelope, :mod:`workbench.models._friction_report`);
    the message says where and the likely cause."""
