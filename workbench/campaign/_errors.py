"""The campaign's error and warning."""

from __future__ import annotations

from workbench._errors import WorkbenchError
from workbench.archive import StoreWarning

__all__ = ["CampaignError", "CampaignWarning"]


class CampaignError(WorkbenchError, ValueError):
    """A campaign cannot run as asked (e.g. its store holds a different campaign); the message
    says what differs and how to proceed."""


class CampaignWarning(StoreWarning):
    """Something about a campaign deserves attention (failed points, blocks recomputed)."""
