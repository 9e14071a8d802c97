"""Signals a command honours like Ctrl-C: SIGTERM and SIGHUP raise :class:`Terminated` (a
``KeyboardInterrupt``) in the main thread, so that the same clean-up runs as for Ctrl-C (a
campaign stops its workers and keeps its finished blocks, an atomic write removes its temporary
file) instead of the process vanishing mid-write.

The compiled integration loop returns to Python about every 0.1 s
(:data:`workbench.solver.PAUSE_SECONDS`), where Python runs its signal handlers: a run stops
within that time, with or without a progress bar.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator

__all__ = ["Terminated", "signals_as_interrupts"]

_SIGNALS = tuple(getattr(signal, n) for n in ("SIGTERM", "SIGHUP") if hasattr(signal, n))


class Terminated(KeyboardInterrupt):
    """A termination signal arrived (``signum``, e.g. SIGTERM); the command stops as on Ctrl-C
    and exits with 128 + ``signum``."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum

    @property
    def name(self) -> str:
        return signal.Signals(self.signum).name


@contextlib.contextmanager
def signals_as_interrupts() -> Iterator[None]:
    """Within the block, SIGTERM and SIGHUP raise :class:`Terminated` in the main thread (the
    first one; later ones are ignored while the clean-up runs). Outside the main thread (where
    Python cannot install handlers) nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    raised: list[int] = []

    def handler(signum, frame) -> None:
        if raised:
            return
        raised.append(signum)
        raise Terminated(signum)

    previous = {s: signal.signal(s, handler) for s in _SIGNALS}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
