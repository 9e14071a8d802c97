"""The nine-bar's hooks with the reference right-hand side: ``rhs`` is the model's
``rhs_reference`` (the full record-time evaluation, :mod:`workbench.models._record`: the
formulation the lean ``rhs`` replaced), for the "reference rhs" rows of
``benchmarks/ninebar_speed.py``.

A module with a source file, not one made in memory: the compiled loop of a hooks module is
cached under the digest of its code and of what it imports
(:func:`workbench._sources.source_digest`), which follows this file's imports into the model, so
an edit of the model or of ``_record`` compiles the loop anew. A module made in memory has no
file to follow: its loop was keyed by the loop's templates alone and ran stale machine code
after such an edit (2026-11-26).
"""

from workbench.models.ninebar._dynamics import apply_event, event_values
from workbench.models.ninebar._dynamics import rhs_reference as rhs

__all__ = ["apply_event", "event_values", "rhs"]
