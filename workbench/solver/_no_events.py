"""The event hooks of a problem without events (the hook protocol of
:mod:`workbench.solver._templates.integration_loop`): no event functions, no state updates. A
model module without
events re-exports them beside its own ``rhs`` (the compiled loop imports all three from it), as
do the kernel template's placeholder hooks
(:mod:`workbench.solver._templates.placeholder_hooks`). Also the no-op ``step_end`` the loop
imports for hooks that do not define that optional hook (and then compiles out)."""

from __future__ import annotations

from numba import njit

__all__ = ["apply_event", "event_values", "step_end"]


@njit(cache=True, nogil=True)
def event_values(t, y, p, ip, aux, work, g):  # noqa: ARG001
    return None


@njit(cache=True, nogil=True)
def apply_event(k, t, y, p, ip, aux, work):  # noqa: ARG001
    return 0


@njit(cache=True, nogil=True)
def step_end(t, y, p, ip, aux, work, dydt):  # noqa: ARG001
    """The optional ``step_end`` hook: nothing to do (0: nothing changed)."""
    return 0
