"""Progress of a long computation, shown as suits where it is written.

- On a terminal (stderr is a tty): a tqdm bar, redrawn at most every 0.2 s.
- In Jupyter with ipywidgets installed: tqdm's notebook widget.
- Anywhere else (a log file, a pipe, CI, Jupyter without ipywidgets): plain lines, one when
  the work starts, at most one per ``interval`` seconds while it runs, and one at the end,
  so that a 0.3-s run writes two lines to a log instead of a bar per update, and Jupyter
  shows no "IProgress not found" warning.

Simulated time, campaign points, work-precision runs, the points of a branch of orbits and the
runs of a verification all report through :class:`Progress`; a work of unequal parts (a study
whose settings differ in cost by orders of magnitude) estimates its time left with
:class:`TimeLeft`; a wait of unknown length (a first compile) says how long it has lasted with
:func:`elapsed`.
"""

from __future__ import annotations

import contextlib
import importlib.util
import math
import sys
import threading
import time
from collections.abc import Hashable, Iterator, Mapping
from typing import TextIO

__all__ = ["INTERVAL", "Progress", "TimeLeft", "elapsed", "progress_mode"]

#: seconds between two lines in a log (the ``"lines"`` mode), unless a call gives its own
INTERVAL = 30.0


def _in_notebook() -> bool:
    """Whether this process is a Jupyter kernel (an IPython shell speaking ZMQ)."""
    shell = sys.modules.get("IPython")
    if shell is None:
        return False
    try:
        ip = shell.get_ipython()
    except Exception:  # pragma: no cover - any error: a broken IPython; no display stops work
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


class TimeLeft:
    """The time left of a work made of jobs of unequal cost, from the jobs finished so far.

    Each job has a *kind* and an expected *cost* in a unit common to all jobs (e.g. expected
    right-hand-side evaluations times a cost per evaluation): only the ratios of costs matter.
    A finished job gives its kind's rate, seconds per unit of cost (the sum of its kind's
    seconds over the sum of their costs); the time left is the sum, over the jobs left, of
    their cost times their kind's rate, or, for a kind none of whose jobs has finished yet, the
    rate of all finished jobs together. So the expected costs carry the estimate from one kind
    to the next (a method never run yet), and the measured rates correct them as soon as a job
    of the kind has run (a method whose evaluations cost more here than expected). A uniform
    estimate (every job alike) is the special case of one kind and equal costs.

    Parameters
    ----------
    jobs : mapping
        Job -> (kind, expected cost > 0), for the jobs still to do (not those already done,
        e.g. reused from a store).

    Examples
    --------
    >>> left = TimeLeft({"a": ("cheap", 1.0), "b": ("cheap", 1.0), "c": ("dear", 10.0)})
    >>> left.seconds()      # nothing finished: unknown
    nan
    >>> left.finished("a", 2.0)    # 2 s per unit: b 2 s, c (no dear job yet) 20 s
    >>> left.seconds()
    22.0
    >>> left.finished("c", 5.0)    # the dear kind measured: 0.5 s per unit
    >>> left.seconds()
    2.0
    """

    def __init__(self, jobs: Mapping[Hashable, tuple[Hashable, float]]) -> None:
        self.left = dict(jobs)
        self._seconds: dict[Hashable, float] = {}  # by kind, of the finished jobs
        self._cost: dict[Hashable, float] = {}

    def finished(self, job: Hashable, seconds: float) -> None:
        """Job ``job`` took ``seconds``; a job not in the work (or already finished) is
        ignored."""
        if job not in self.left:
            return
        kind, cost = self.left.pop(job)
        self._seconds[kind] = self._seconds.get(kind, 0.0) + float(seconds)
        self._cost[kind] = self._cost.get(kind, 0.0) + float(cost)

    def seconds(self) -> float:
        """The estimated seconds left (0 when no job is left, NaN before any job finished)."""
        if not self.left:
            return 0.0
        cost = sum(self._cost.values())
        if cost <= 0:
            return math.nan
        overall = sum(self._seconds.values()) / cost
        return sum(
            c * (self._seconds[k] / self._cost[k] if self._cost.get(k) else overall)
            for k, c in self.left.values()
        )


@contextlib.contextmanager
def elapsed(
    desc: str,
    *,
    interval: float | None = None,
    file: TextIO | None = None,
    mode: str | None = None,
) -> Iterator[None]:
    """Say how long the work inside has lasted while it runs, from a thread: a line
    ``DESC: N s so far`` every ``interval`` seconds (default :data:`INTERVAL`) in a log
    (nothing when it ends sooner), a running clock on a terminal. For a wait of unknown length,
    e.g. a first compile, which holds no loop to report from."""
    interval = INTERVAL if interval is None else float(interval)
    file = sys.stderr if file is None else file
    mode = mode or progress_mode(file)
    stop = threading.Event()
    start = time.monotonic()
    bar = None
    if mode in ("bar", "widget"):
        if mode == "widget":
            from tqdm.notebook import tqdm
        else:
            from tqdm.std import tqdm
        bar = tqdm(
            desc=desc,
            total=None,
            bar_format="{desc}: {elapsed}",
            file=file if mode == "bar" else None,
            leave=False,
        )

    def tick() -> None:
        wait = 1.0 if bar is not None else interval
        while not stop.wait(wait):
            if bar is not None:
                bar.refresh()
            else:
                print(f"{desc}: {time.monotonic() - start:.0f} s so far", file=file, flush=True)

    thread = threading.Thread(target=tick, name="workbench-elapsed", daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        if bar is not None:
            bar.close()


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
    interval : float, optional
        Seconds between two lines in the ``"lines"`` mode (default :data:`INTERVAL`).
    file : text stream, optional
        Default ``sys.stderr``.
    mode : str, optional
        Force ``"bar"``, ``"widget"`` or ``"lines"`` (default: :func:`progress_mode`).
    time_left : TimeLeft, optional
        The time left weighted by each job's cost (:meth:`update` names the job finished);
        default: the work left at the rate of the work done since the start.

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
        interval: float | None = None,
        file: TextIO | None = None,
        mode: str | None = None,
        time_left: TimeLeft | None = None,
    ) -> None:
        self.total, self.desc, self.unit = float(total), desc, unit
        self.n = self.initial = float(initial)
        self.time_left = time_left
        self._note = ""
        self.file = sys.stderr if file is None else file
        self.mode = mode or progress_mode(self.file)
        self.interval = INTERVAL if interval is None else float(interval)
        self._start = self._last = self._mark = time.monotonic()
        self._closed = False
        self._bar = None
        if self.mode in ("bar", "widget"):
            if self.mode == "widget":
                from tqdm.notebook import tqdm
            else:
                from tqdm.std import tqdm
            amount = ("{n:.3g}/{total:.3g}" if unit == "s" else "{n:g}/{total:g}") + (
                f" {unit}" if unit else ""
            )
            # tqdm's own estimate (the rate of the last updates) unless the jobs' costs give one
            left = "{postfix}" if time_left is not None else "<{remaining}{postfix}"
            fmt = f"{{l_bar}}{{bar}}| {amount} [{{elapsed}}{left}]"
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
        return f"{self.desc}: {self.n:g}/{self.total:g}" + (f" {self.unit}" if self.unit else "")

    def _line(self, text: str) -> None:
        print(text, file=self.file, flush=True)

    def update_to(self, n: float, *, note: str | None = None) -> None:
        """Set the work done to ``n`` (``note``: see :meth:`update`)."""
        self.update(n - self.n, note=note)

    def seconds_left(self) -> float:
        """The estimated seconds left: the :class:`TimeLeft` given, else the work left at the
        rate of the work done here (not counting ``initial``); NaN while unknown."""
        if self.time_left is not None:
            return self.time_left.seconds()
        done = self.n - self.initial
        if done <= 0:
            return math.nan
        return (time.monotonic() - self._start) * max(self.total - self.n, 0.0) / done

    def update(self, k: float = 1.0, *, job: Hashable = None, note: str | None = None) -> None:
        """Add ``k`` to the work done. ``job``: the job of :class:`TimeLeft` that this update
        finishes (it took the time since the previous update). ``note``: where the work is
        (e.g. ``"gamma = 0.2613, 14 points"``), shown from now on."""
        now = time.monotonic()
        if self.time_left is not None and job is not None:
            self.time_left.finished(job, now - self._mark)
        self._mark = now
        self.n += k
        if note is not None:
            self._note = note
        if self._bar is not None:
            left = self.seconds_left() if self.time_left is not None else math.nan
            parts = [f"~{self._bar.format_interval(left)} left"] if math.isfinite(left) else []
            parts += [self._note] if self._note else []
            self._bar.set_postfix_str(", ".join(parts), refresh=False)
            self._bar.update(k)
            return
        if now - self._last >= self.interval and self.n < self.total:
            self._last = now
            share = 100.0 * self.n / self.total if self.total else 100.0
            left = self.seconds_left()
            text = f"{self._amount()} ({share:.0f} %), {now - self._start:.0f} s elapsed"
            text += f", ~{left:.0f} s left" if math.isfinite(left) else ""
            self._line(text + (f"; {self._note}" if self._note else ""))

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
        seconds = time.monotonic() - self._start
        note = f"; {self._note}" if self._note else ""
        self._line(f"{self._amount()} ({share:.0f} %) in {seconds:.3g} s{note}")

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
