"""Exceptions raised by workbench."""

from __future__ import annotations

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


class SolverError(RuntimeError):
    """An integration failed: the message names the time, the state and the likely cause.

    Attributes
    ----------
    time : float
        Simulated time of the failure, s.
    state : dict[str, float]
        State at the failure (name -> value, in state units).
    cause : str
        Short machine-readable cause, e.g. ``"step_underflow"``, ``"non_finite"``,
        ``"max_steps"`` or a model-specific code name.
    """

    def __init__(self, message: str, *, time: float, state: dict, cause: str) -> None:
        self.time = time
        self.state = state
        self.cause = cause
        super().__init__(message)
