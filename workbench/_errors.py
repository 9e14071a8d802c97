"""The errors scenes and models raise: :class:`SceneError`, and the solver's
:class:`~workbench.solver.SolverError` (re-exported: models raise it for a state outside their
domain)."""

from __future__ import annotations

from workbench.solver import SolverError

__all__ = ["SceneError", "SolverError"]


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
