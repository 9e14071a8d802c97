"""Warnings by kind: a campaign of 51 points that each warn alike says so once, with the count.

:func:`warnings_by_kind` catches the warnings raised inside it and, when it ends, hands on one
:class:`WarningKind` per kind: a category and a message that differ from another's only in
their numbers (the values of a point, a time, a size) are one kind, counted, shown by its
first message. By default it re-raises each kind as one warning of the same category whose
message is the first one with the count (:func:`reraise`), through the filters in force
around it; a :func:`warnings_by_kind` around it adds that count to its own. A campaign's
workers send their kinds to the process that runs the campaign
(``workbench.campaign._execute``), which re-raises them; the command line shows each kind as
one line (``workbench.cli._console``).
"""

from __future__ import annotations

import contextlib
import re
import sys
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace

__all__ = ["WarningKind", "reraise", "warnings_by_kind"]

# a number as messages write it: 12, -0.0327, 1.5e-06, 316.2
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


@dataclass(frozen=True)
class WarningKind:
    """Warnings of one kind: their category (named by module and qualified name, so that a
    kind travels between processes as plain data), the first one's message and where it was
    raised, and how many there were."""

    module: str
    name: str
    message: str
    count: int = 1
    filename: str = ""
    lineno: int = 0

    @property
    def key(self) -> tuple[str, str, str]:
        """What makes two warnings one kind: the category and the message without numbers."""
        return self.module, self.name, _NUMBER.sub("#", self.message)

    @property
    def category(self) -> type[Warning]:
        """The warning class, looked up among the modules already imported (nothing is imported
        for it); UserWarning when it is not there."""
        found = sys.modules.get(self.module)
        for part in self.name.split("."):
            found = getattr(found, part, None)
        return found if isinstance(found, type) and issubclass(found, Warning) else UserWarning

    def text(self) -> str:
        """The first message, and the count when there were more than one."""
        if self.count == 1:
            return self.message
        alike = f"{self.count} warnings like this one, numbers aside"
        return f"{self.message} [{alike}; the first shown]"


def _kind(caught: warnings.WarningMessage) -> WarningKind:
    """The kind of one caught warning (a re-raised kind keeps its count)."""
    kind = getattr(caught.message, "workbench_kind", None)
    if isinstance(kind, WarningKind):
        return kind
    category = caught.category
    return WarningKind(
        category.__module__,
        category.__qualname__,
        str(caught.message),
        1,
        str(caught.filename),
        int(caught.lineno or 0),
    )


def reraise(kind: WarningKind) -> None:
    """Raise ``kind`` as one warning of its category: the first message with the count, at the
    place the first was raised (the filters in force apply to it as to any warning)."""
    category = kind.category
    try:
        message = category(kind.text())
    except TypeError:  # a category that takes other arguments
        category = UserWarning
        message = UserWarning(f"{kind.name}: {kind.text()}")
    message.workbench_kind = kind  # an enclosing warnings_by_kind adds the count to its own
    warnings.warn_explicit(message, category, kind.filename or "<unknown>", kind.lineno)


@contextlib.contextmanager
def warnings_by_kind(show: Callable[[WarningKind], None] = reraise) -> Iterator[None]:
    """Catch every warning raised inside (none is shown meanwhile) and, at the end (also when
    the block raises), call ``show`` once per kind, in the order each kind first appeared.

    Parameters
    ----------
    show : callable
        What to do with each :class:`WarningKind`: by default :func:`reraise` (one warning per
        kind, with the count in its message, through the filters in force outside); a worker
        process collects them to send them to its client.
    """
    caught: list[warnings.WarningMessage] = []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")  # count them all; the filters apply to what is shown
            yield
    except BaseException:
        # any error: an error filter (or ``show``) must not hide what is raised
        with contextlib.suppress(Exception):
            _show(caught, show)
        raise
    _show(caught, show)


def _show(caught: list[warnings.WarningMessage], show: Callable[[WarningKind], None]) -> None:
    """``show`` each kind of the caught warnings, with its count, in order of first appearance."""
    kinds: dict[tuple[str, str, str], WarningKind] = {}
    for kind in map(_kind, caught):
        first = kinds.get(kind.key)
        kinds[kind.key] = kind if first is None else replace(first, count=first.count + kind.count)
    for kind in kinds.values():
        show(kind)
