"""The compiled hooks every mechanism shares, written once and compiled per mechanism.

A mechanism's module (``workbench.models.<name>._dynamics``) defines what is its own: the
layouts of its arrays (a :class:`~workbench.models._record_types.MechanismLayout`), the
record-time evaluation ``evaluate(t, y, p, ip, aux, work)`` and the lean right-hand side
``rhs``. The other hooks are the same for every mechanism, given those two:

``evaluate_many(t, Y, p, ip, AUX, ws)``
    ``evaluate`` at every record (rows of ``Y`` and ``AUX``) into ``ws[i, :RECORD.size]``;
    returns the failure code per record (the model's ``derive`` reads the records from it).
``rhs_reference(t, y, p, ip, aux, work, dydt)``
    The right-hand side that ``evaluate`` gives (hook protocol of ``rhs``): the reference the
    lean ``rhs`` is tested against.
``event_values(t, y, p, ip, aux, work, g)``, ``apply_event(k, t, y, p, ip, aux, work)``
    The contact events of the clearance joints (:mod:`workbench.models._contact_events`).

Numba freezes a compiled function's module globals into constants (the layouts ``P``, ``IP``,
``RECORD``, the sizes) and calls other compiled functions (``evaluate``) as globals; a function
that took ``evaluate`` as an argument or closed over it could not be cached. So
:func:`mechanism_hooks` compiles the plain functions below once per mechanism with globals of
their own: this module's names, the mechanism's ``evaluate`` and layouts, and the mechanism
module's ``__name__``, so that numba names, caches and keys each compiled hook as a function of
that module (its cache follows the module's code and what it imports, this module included).

>>> from workbench.models.ninebar import _dynamics as dyn
>>> dyn.event_values.py_func.__module__
'workbench.models.ninebar._dynamics'
"""

from __future__ import annotations

import types
from collections.abc import Callable

import numpy as np
from numba import njit

from workbench.models._contact_events import contact_event, contact_event_values
from workbench.models._record import rates_from_record
from workbench.models._record_types import MechanismLayout

__all__ = ["mechanism_hooks"]

# The globals the functions below read, bound per mechanism by mechanism_hooks (these stand-ins
# only make this module importable and lintable; the functions are never compiled with them).
evaluate = MECHANISM = RECORD = P = IP = None
WORK_SIZE = N_JOINTS = 0


def evaluate_many(t, Y, p, ip, AUX, ws):
    """`evaluate` at every record (rows of Y and AUX) into ws[i, :RECORD.size]; returns the
    failure code per record."""
    codes = np.zeros(t.size, np.int64)
    work = np.zeros(WORK_SIZE)
    for i in range(t.size):
        codes[i] = evaluate(t[i], Y[i], p, ip, AUX[i], work)
        ws[i, :] = work[: RECORD.size]
    return codes


def rhs_reference(t, y, p, ip, aux, work, dydt):
    """The right-hand side that `evaluate` gives (the hook protocol of `rhs`): the reference of
    the tests and of the benchmark's "before"."""
    code = evaluate(t, y, p, ip, aux, work)
    if code != 0:
        return code
    return rates_from_record(y, ip, aux, work, dydt, MECHANISM)


def event_values(t, y, p, ip, aux, work, g):
    """Penetration e - c (m) of each joint with a clearance, twice: its contact onset (rising
    zero) and end (falling zero); see
    :func:`workbench.models._contact_events.contact_event_values`."""
    contact_event_values(y, p, ip, g, P, IP, N_JOINTS)


def apply_event(k, t, y, p, ip, aux, work):
    """Contact onset: hold the normal velocity (LN) and reset the LuGre bristles; end: clear it."""
    return contact_event(k, y, ip, aux, IP, N_JOINTS)


_SHARED = (evaluate_many, rhs_reference, event_values, apply_event)


def mechanism_hooks(
    module: str, evaluate: Callable, mechanism: MechanismLayout
) -> tuple[Callable, ...]:
    """The shared hooks of one mechanism, compiled (``numba.njit(cache=True)``) as functions of
    its module: ``(evaluate_many, rhs_reference, event_values, apply_event)``.

    Parameters
    ----------
    module : str
        The mechanism module's ``__name__`` (the solver imports the hooks from it by name).
    evaluate : numba dispatcher
        The mechanism's record-time evaluation, ``evaluate(t, y, p, ip, aux, work) -> int``.
    mechanism : MechanismLayout
        Its layouts and joints: ``P``, ``IP``, ``W``, ``RECORD``, one journal body per joint.

    Examples
    --------
    At the end of a mechanism's ``_dynamics`` module::

        evaluate_many, rhs_reference, event_values, apply_event = mechanism_hooks(
            __name__, evaluate, MECHANISM
        )
    """
    namespace = dict(globals())
    namespace.update(
        __name__=module,
        evaluate=evaluate,
        MECHANISM=mechanism,
        RECORD=mechanism.RECORD,
        P=mechanism.P,
        IP=mechanism.IP,
        WORK_SIZE=mechanism.W.size,
        N_JOINTS=len(mechanism.journal),
    )
    return tuple(
        njit(cache=True)(types.FunctionType(f.__code__, namespace, f.__name__)) for f in _SHARED
    )
