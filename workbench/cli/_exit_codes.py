"""Exit codes of the ``workbench`` command, derived from the one failure vocabulary
(:class:`workbench.Status`) in one function.

====  ==========================  ==============================================================
code  class                       outcomes
====  ==========================  ==============================================================
0     success                     ``ok``; ``terminated`` (an event stopped the run as the model
                                  intends)
1     unexpected error            any other exception (a bug or a broken setup; Python's own);
                                  a campaign point flagged ``error`` (it raised one)
2     invalid input               a scene error, a refused campaign store (another scene, or
                                  in use by another process), a missing, unreadable or altered
                                  file, an output that exists (without ``--overwrite``), is a
                                  device, FIFO or socket, or cannot be written (checked before
                                  the work), a write that failed after it (the result kept
                                  elsewhere, and named), a bad argument, a refused kernel cache;
                                  a campaign point with ``invalid_parameters``
3     solver limit                ``max_steps`` (raise ``solver.max_steps``)
4     integration failure         ``step_underflow``, ``non_finite``
5     model failure               ``model_failure`` (a state outside the model's domain)
130   interrupted                 Ctrl-C (SIGINT)
143   terminated                  SIGTERM (128 + the signal's number, as a shell reports it)
====  ==========================  ==============================================================

A run that fails is still written (records before the failure, its status in ``run_status``);
a campaign, a study or a work-precision study exits with the largest code among its points,
runs or settings, and says how many failed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from workbench._errors import WorkbenchError

if TYPE_CHECKING:
    from workbench.solver import Status

__all__ = ["EXIT_INVALID", "UsageError", "exit_code", "worst_exit_code"]


class UsageError(WorkbenchError, ValueError):
    """A command-line argument that the command refuses before any work: the message names the
    argument, the value and what is allowed."""


EXIT_INVALID = 2
#: by :class:`workbench.Status` label (the classes load with the first command that runs)
_BY_STATUS = {
    "ok": 0,
    "terminated": 0,
    "max_steps": 3,
    "step_underflow": 4,
    "non_finite": 4,
    "model_failure": 5,
}


def exit_code(outcome: Status | BaseException) -> int:
    """The exit code of a run's :class:`~workbench.Status` or of an exception (table in the
    module doc)."""
    from workbench._cache import CacheError
    from workbench.archive import ArchiveError
    from workbench.campaign import CampaignError
    from workbench.scene import SceneError
    from workbench.solver import SolverError, Status

    if isinstance(outcome, Status):
        return _BY_STATUS[outcome.label]
    if isinstance(outcome, SolverError):
        return _BY_STATUS[outcome.status.label]
    if isinstance(outcome, KeyboardInterrupt):  # Ctrl-C, or a Terminated signal
        return 128 + getattr(outcome, "signum", 2)
    if isinstance(outcome, SceneError | CampaignError | ArchiveError | CacheError | UsageError):
        return EXIT_INVALID
    if isinstance(outcome, FileNotFoundError):
        return EXIT_INVALID
    return 1


def worst_exit_code(flags, invalid: int | None = None, raised: int | None = None) -> int:
    """The largest exit code among int status flags (a run's :class:`Status`; ``invalid``, the
    flag of a point that did not run: invalid input; ``raised``, the flag of a point that
    raised an exception: 1, an unexpected error)."""
    from workbench.solver import Status

    extra = {invalid: EXIT_INVALID, raised: 1}
    codes = [
        extra[f] if f in extra else exit_code(Status(f))
        for f in set(int(x) for x in getattr(flags, "flat", flags))
    ]
    return max(codes, default=0)
