"""Progress of a long computation, shown as suits where it is written.

- On a terminal (stderr is a tty): a tqdm bar, redrawn at most every 0.2 s.
- In Jupyter with ipywidgets installed: tqdm's notebook widget.
- Anywhere else (a log file, a pipe, CI, Jupyter without ipywidgets): plain lines, one when
  the work starts, at most one per ``interval`` seconds while it runs, and one at the end,
  so that a 0.3-s run writes two lines to a log instead of a bar per update, and Jupyter
  shows no "IProgress not found" warning.

Simulated time, campaign points and work-precision runs all report through :class:`Progress`.
"""

from __future__ import annotations

import importlib.util
import sys
import time
from typing import TextIO

__all__ = ["Progress", "progress_mode"]


def _in_notebook() -> bool:
    """Whether this process is a Jupyter kernel (an IPython shell speaking ZMQ)."""
    shell = sys.modules.get("IPython")
    if shell is None:
        return False
    try:
        ip = shell.get_ipython()
    except Exception:  # pragma: no cover - a broken IPython
        return False
    return ip is not None and type(ip).__name__ == "ZMQInteractiveShell"


def progress_mode(file: TextIO | None = None) -> str:
    """``"bar"`` (a terminal), ``"widget"`` (Jupyter with ipywidgets) or ``"lines"``."""
    file = sys.stderr if file is None else file
    if _in_notebook():
        return "widget" if importlib.util.find_spec("ipywidgets") is not None else "lines"
    isatty = getattr(file, "isatty", None)
    try:
        return "bar" if isatty is not None and isatty() else "lines"
    except ValueError:  # a closed stream
        return "lines"


def _fmt(value: float, unit: str) -> str:
    if unit == "s":
        return f"{value:.3g} s"
    return f"{value:g} {unit}"


class Progress:
    """Progress towards ``total`` (in ``unit``): a bar, a widget or a few lines (module doc).

    Parameters
    ----------
    total : float
        The amount of work (simulated seconds, points, runs).
    desc : str
        What progresses (e.g. ``"simulated time"``, ``"campaign"``).
    unit : str
        Unit of ``total`` (``"s"`` shows values with 3 significant digits).
    initial : float
        Work already done (e.g. blocks of a campaign reused from its store).
    interval : float
        Seconds between two lines in the ``"lines"`` mode.
    file : text stream, optional
        Default ``sys.stderr``.
    mode : str, optional
        Force ``"bar"``, ``"widget"`` or ``"lines"`` (default: :func:`progress_mode`).

    Examples
    --------
    >>> import io
    >>> log = io.StringIO()
    >>> with Progress(10, desc="campaign", unit="pt", file=log) as p:
    ...     for _ in range(10):
    ...         p.update(1)
    >>> lines = log.getvalue().splitlines()
    >>> len(lines), lines[0], lines[-1].startswith("campaign: 10/10 pt (100 %) in ")
    (2, 'campaign: 0/10 pt ...', True)
    """

    def __init__(
        self,
        total: float,
        *,
        desc: str,
        unit: str,
        initial: float = 0.0,
        interval: float = 30.0,
        file: TextIO | None = None,
        mode: str | None = None,
    ) -> None:
        self.total, self.desc, self.unit = float(total), desc, unit
        self.n = float(initial)
        self.file = sys.stderr if file is None else file
        self.mode = mode or progress_mode(self.file)
        self.interval = float(interval)
        self._start = self._last = time.monotonic()
        self._closed = False
        self._bar = None
        if self.mode in ("bar", "widget"):
            if self.mode == "widget":
                from tqdm.notebook import tqdm
            else:
                from tqdm.std import tqdm
            fmt = (
                "{l_bar}{bar}| {n:.3g}/{total:.3g} s [{elapsed}<{remaining}]"
                if unit == "s"
                else None
            )
            self._bar = tqdm(
                total=self.total,
                initial=self.n,
                desc=desc,
                unit=unit,
                file=self.file if self.mode == "bar" else None,
                mininterval=0.2,
                smoothing=0.1,
                bar_format=fmt,
            )
        else:
            self._line(f"{self._amount()} ...")

    # -- reporting ----------------------------------------------------------------------------
    def _amount(self) -> str:
        if self.unit == "s":
            return f"{self.desc}: {_fmt(self.n, 's')}/{_fmt(self.total, 's')}"
        return f"{self.desc}: {self.n:g}/{self.total:g} {self.unit}"

    def _line(self, text: str) -> None:
        print(text, file=self.file, flush=True)

    def update_to(self, n: float) -> None:
        """Set the work done to ``n``."""
        self.update(n - self.n)

    def update(self, k: float = 1.0) -> None:
        """Add ``k`` to the work done."""
        self.n += k
        if self._bar is not None:
            self._bar.update(k)
            return
        now = time.monotonic()
        if now - self._last >= self.interval and self.n < self.total:
            self._last = now
            share = 100.0 * self.n / self.total if self.total else 100.0
            elapsed = now - self._start
            left = elapsed * (self.total - self.n) / self.n if self.n > 0 else float("nan")
            self._line(
                f"{self._amount()} ({share:.0f} %), {elapsed:.0f} s elapsed, ~{left:.0f} s left"
            )

    def write(self, text: str) -> None:
        """A line of text that does not break the bar."""
        if self._bar is not None:
            self._bar.write(text, file=self.file if self.mode == "bar" else None)
        else:
            self._line(text)

    def close(self) -> None:
        """End the display (the last line in the ``"lines"`` mode)."""
        if self._closed:
            return
        self._closed = True
        if self._bar is not None:
            self._bar.close()
            return
        share = 100.0 * self.n / self.total if self.total else 100.0
        elapsed = time.monotonic() - self._start
        self._line(f"{self._amount()} ({share:.0f} %) in {elapsed:.3g} s")

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
