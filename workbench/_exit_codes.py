"""Exit codes of the ``workbench`` command, derived from the one failure vocabulary
(:class:`workbench.Status`) in one function.

====  ==========================  ==============================================================
code  class                       outcomes
====  ==========================  ==============================================================
0     success                     ``ok``; ``terminated`` (an event stopped the run as the model
                                  intends)
1     unexpected error            any other exception (a bug or a broken setup; Python's own)
2     invalid input               a scene error, a refused campaign store, a missing file, a
                                  bad argument; a campaign point with ``invalid_parameters``
3     solver limit                ``max_steps`` (raise ``solver.max_steps``)
4     integration failure         ``step_underflow``, ``non_finite``
5     model failure               ``model_failure`` (a state outside the model's domain)
130   interrupted                 Ctrl-C
====  ==========================  ==============================================================

A run that fails is still written (records before the failure, its status in ``run_status``);
a campaign exits with the largest code among its points.
"""

from __future__ import annotations

from workbench.campaign import CampaignError
from workbench.scene import SceneError
from workbench.solver import SolverError, Status

__all__ = ["EXIT_INVALID", "exit_code"]

EXIT_INVALID = 2
_BY_STATUS = {
    Status.OK: 0,
    Status.TERMINATED: 0,
    Status.MAX_STEPS: 3,
    Status.STEP_UNDERFLOW: 4,
    Status.NON_FINITE: 4,
    Status.MODEL_FAILURE: 5,
}


def exit_code(outcome: Status | BaseException) -> int:
    """The exit code of a run's :class:`Status` or of an exception (table in the module doc)."""
    if isinstance(outcome, Status):
        return _BY_STATUS[outcome]
    if isinstance(outcome, SolverError):
        return _BY_STATUS[outcome.status]
    if isinstance(outcome, KeyboardInterrupt):
        return 130
    if isinstance(outcome, SceneError | CampaignError | FileNotFoundError):
        return EXIT_INVALID
    return 1
