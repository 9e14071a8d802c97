"""What an integration returns: the records, the solver's statistics and how the run ended.

:class:`Status` is the one failure vocabulary of workbench: the solver sets it, datasets store it
(``run_status``), campaigns and work-precision studies flag points with its codes, and the
command line derives its exit code from it (:func:`workbench.cli.exit_code`).
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass, field

import numpy as np

from workbench._errors import WorkbenchError

__all__ = ["RunResult", "SolverError", "Status", "solver_stats"]


class Status(enum.IntEnum):
    """How a run ended. The value is the int8 flag stored per point in campaigns and studies.

    ========  ==================  =========================================================
    value     label               meaning
    ========  ==================  =========================================================
    0         ``ok``              every record time was reached
    1         ``terminated``      an event asked to stop (e.g. a ball at rest): the records
                                  end there, which is the model's intended behaviour
    2         ``max_steps``       ``solver.max_steps`` steps were taken before the end
    3         ``step_underflow``  the step size fell below the rounding of t (stiff or
                                  discontinuous right-hand side, or tolerances too tight)
    4         ``non_finite``      the state became NaN or inf and smaller steps did not help
    5         ``model_failure``   the model's hooks or derived outputs rejected the state
                                  (e.g. a penetration beyond the contact law's validity)
    ========  ==================  =========================================================

    ``ok`` and ``terminated`` are successes; the others are failures (:attr:`failed`).
    """

    OK = 0
    TERMINATED = 1
    MAX_STEPS = 2
    STEP_UNDERFLOW = 3
    NON_FINITE = 4
    MODEL_FAILURE = 5

    @property
    def label(self) -> str:
        """The status as stored in datasets and messages, e.g. ``"max_steps"``."""
        return self.name.lower()

    @property
    def failed(self) -> bool:
        """True unless the run reached its end or an event stopped it as the model intends."""
        return self not in (Status.OK, Status.TERMINATED)

    @classmethod
    def from_label(cls, label: str) -> Status:
        """The status of a label (``"max_steps"``) or of a model failure code (``"model_3"``)."""
        if re.fullmatch(r"model_\d+", label):
            return cls.MODEL_FAILURE
        try:
            return cls[label.upper()]
        except KeyError:
            allowed = ", ".join(s.label for s in cls)
            raise ValueError(
                f"unknown run status {label!r}; allowed: {allowed}, or 'model_<code>'"
            ) from None


class SolverError(WorkbenchError, RuntimeError):
    """A run failed: the message names the time, the state and the likely cause.

    Parameters
    ----------
    message : str
        What failed, where and the likely cause, in one line.
    time : float
        Simulated time of the failure, s.
    state : dict[str, float]
        State at the failure (name -> value, in state units).
    cause : Status or str
        The failure: a :class:`Status`, its label, or ``"model_<code>"`` for a model failure
        with that code.

    Attributes
    ----------
    status : Status
    model_code : int
        The model's failure code for :attr:`Status.MODEL_FAILURE` (0 when unknown or another
        status).
    time, state
        As given.
    """

    def __init__(self, message: str, *, time: float, state: dict, cause: Status | str) -> None:
        self.time = time
        self.state = state
        if isinstance(cause, Status):
            self.status, self.model_code = cause, 0
        else:
            self.status = Status.from_label(cause)
            self.model_code = int(cause[6:]) if re.fullmatch(r"model_\d+", cause) else 0
        super().__init__(message)


@dataclass
class RunResult:
    """Raw output of an integration.

    Attributes
    ----------
    t : ndarray
        Record times, s (cut at the last record for :attr:`Status.TERMINATED`).
    Y, AUX : ndarray
        State and discrete state at each record time (NaN after a failure).
    stats : dict
        Solver statistics: ``method``, ``rtol``, ``atol``, ``max_step``, ``steps``,
        ``rejected_steps``, ``rhs_evaluations``, ``events``, ``event_retries``, ``wall_time`` (s).
    status : Status
    message : str
        Empty for :attr:`Status.OK`; else what happened, where, and what to change.
    recorded : int
        Number of leading records that hold the solution (all of them unless the run failed).
    time : float
        Simulated time where the integration stopped, s.
    state : dict[str, float]
        The state there (empty when the run completed).
    model_code : int
        The model's failure code for :attr:`Status.MODEL_FAILURE`, else 0.
    """

    t: np.ndarray
    Y: np.ndarray
    AUX: np.ndarray
    stats: dict
    status: Status = Status.OK
    message: str = ""
    recorded: int = -1
    time: float = float("nan")
    state: dict = field(default_factory=dict)
    model_code: int = 0

    def __post_init__(self) -> None:
        if self.recorded < 0:
            self.recorded = int(np.size(self.t))

    def error(self) -> SolverError:
        """The :class:`SolverError` describing this failed run."""
        cause = f"model_{self.model_code}" if self.model_code else self.status
        return SolverError(self.message, time=self.time, state=self.state, cause=cause)

    def raise_for_status(self) -> None:
        """Raise :meth:`error` if the run failed (:attr:`Status.failed`)."""
        if self.status.failed:
            raise self.error()


def solver_stats(
    method: str,
    rtol: float,
    atol: float,
    max_step: float,
    *,
    steps: int = 0,
    rejected_steps: int = 0,
    rhs_evaluations: int = 0,
    events: int = 0,
    event_retries: int = 0,
    wall_time: float = 0.0,
) -> dict:
    """The statistics every backend reports (see :class:`RunResult`), in one order."""
    return {
        "method": method,
        "rtol": rtol,
        "atol": atol,
        "max_step": max_step,
        "steps": steps,
        "rejected_steps": rejected_steps,
        "rhs_evaluations": rhs_evaluations,
        "events": events,
        "event_retries": event_retries,
        "wall_time": wall_time,
    }
