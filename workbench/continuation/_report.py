"""Progress of a continuation over a parameter's range (:class:`workbench._progress.Progress`):
how much of the range from the start to the end the branch or curve has covered, and where it
is, so that a continuation of minutes says what it does while it runs."""

from __future__ import annotations

from workbench._progress import Progress

__all__ = ["RangeProgress"]


class RangeProgress:
    """Progress from ``start`` to ``stop`` of ``name``: the distance covered so far (it goes
    back where a fold turns the branch) and a note with the current value and the points.

    Parameters
    ----------
    enabled : bool
        False: every call does nothing.
    name : str
        The parameter continued in.
    start, stop : float
        The range followed (parameter units).
    what : str
        What is continued (``"branch"``, ``"curve"``).
    """

    def __init__(self, enabled: bool, name: str, start: float, stop: float, what: str) -> None:
        self.name, self.start = name, float(start)
        self.span = abs(float(stop) - self.start)
        self.bar = Progress(self.span, desc=f"{what} over {name}", unit="") if enabled else None

    def __call__(self, value: float, points: int) -> None:
        """The continuation is at ``name`` = ``value`` with ``points`` points."""
        if self.bar is not None:
            covered = min(abs(float(value) - self.start), self.span)
            self.bar.update_to(covered, note=f"{self.name} = {value:.8g}, {points} points")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
