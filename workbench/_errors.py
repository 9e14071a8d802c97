"""The root of workbench's errors, :class:`WorkbenchError`, and the errors of the lowest layers:
:class:`SceneError` (scenes and models raise it) and :class:`ModelWarning` (a run that ended well
but left its model's physics).

Every error workbench raises on purpose derives from :class:`WorkbenchError` and keeps the
built-in base it had before, so that ``except ValueError`` and ``except RuntimeError`` still
catch what they caught:

- refused input, a ``ValueError`` too: :class:`SceneError` (and ``workbench.run.MemoryLimitError``),
  ``workbench.campaign.CampaignError``, ``workbench.archive.ArchiveError`` (and its
  ``OutputExists``, ``WriteFailed``, ``DiskFull``, ``StoreLocked``), the kernel cache's
  ``CacheError``, the command line's ``UsageError``;
- a computation that failed, a ``RuntimeError`` too: ``workbench.solver.SolverError`` (a run),
  the continuation's ``NewtonFailure`` (a periodic orbit not found).

Other exceptions (``TypeError`` from a wrong call, an ``OSError`` from the system, a model's own
error) pass through unchanged.
"""

from __future__ import annotations

__all__ = ["ModelWarning", "SceneError", "WorkbenchError"]


class WorkbenchError(Exception):
    """The base of every error workbench raises on purpose: an input it refuses (also a
    ``ValueError``) or a computation that failed (also a ``RuntimeError``). The message is one
    line that names what is wrong and how to fix it.

    Examples
    --------
    >>> import workbench
    >>> try:
    ...     workbench.load_scene({"model": {"name": "duffing"}, "solver": {"rtol": -1}})
    ... except workbench.WorkbenchError as exc:
    ...     print(type(exc).__name__, isinstance(exc, ValueError))
    SceneError True
    """


class SceneError(WorkbenchError, ValueError):
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
