"""The event hooks of a system without events, for a model module to import beside its ``rhs``.

The compiled integration loop imports three hooks from a model's module by name: ``rhs``,
``event_values`` and ``apply_event`` (the protocol: :mod:`workbench.models`, and the guide
``docs/own-models.md``). A system without events imports these two::

    from workbench.models.no_events import apply_event, event_values  # noqa: F401
"""

from __future__ import annotations

from workbench.solver._no_events import apply_event, event_values

__all__ = ["apply_event", "event_values"]
