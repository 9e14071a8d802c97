"""The event hooks of a problem without events (the hook protocol of
:mod:`workbench.solver._templates.integration_loop`): no event functions, no state updates. A
model module without
events re-exports them beside its own ``rhs`` (the compiled loop imports all three from it), as
do the kernel template's placeholder hooks
(:mod:`workbench.solver._templates.placeholder_hooks`)."""

from __future__ import annotations

from numba import njit

__all__ = ["apply_event", "event_values"]


@njit(cache=True)
def event_values(t, y, p, ip, aux, work, g):  # noqa: ARG001
    return None


@njit(cache=True)
def apply_event(k, t, y, p, ip, aux, work):  # noqa: ARG001
    return 0
