"""Processes that die with their campaign, whatever ends it (``kill -9`` included).

The local pool's processes form a chain: the campaign starts a fork server, the fork server
forks the workers. Each link asks the Linux kernel to kill it when its parent dies
(``prctl(PR_SET_PDEATHSIG, SIGKILL)`` through ctypes), so the death of the campaign takes the
fork server down at once and the fork server's takes the workers; this works while a worker is
inside compiled code that holds the GIL. Each worker also runs a watchdog thread on the
campaign's process (a pidfd on Linux, else polling every 0.5 s), which covers systems without
``prctl`` and a fork server that was started by someone else. multiprocessing's resource tracker
exits by itself once the last of them has closed its pipe.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import select
import signal
import sys
import threading
import time

__all__ = ["PARENT_ENV", "die_with_parent", "watch_process"]

# pid of the campaign process, for the fork server it starts (read by ``_preload``)
PARENT_ENV = "WORKBENCH_CAMPAIGN_PID"
_PR_SET_PDEATHSIG = 1
_POLL = 0.5  # s, the watchdog's polling interval where there is no pidfd


def _prctl_pdeathsig() -> bool:
    """Ask for SIGKILL when the parent (thread) dies; False where prctl is unavailable."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    except (OSError, AttributeError):  # pragma: no cover - no libc prctl
        return False


def die_with_parent(parent: int) -> bool:
    """Make this process die with its parent ``parent`` (a pid): the kernel sends SIGKILL when
    the parent dies (Linux); if the parent is already gone, exit now.

    Returns whether the kernel took the request (False off Linux).
    """
    armed = _prctl_pdeathsig()
    if os.getppid() != parent:  # the parent died before the request: we were re-parented
        os._exit(1)
    return armed


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # pragma: no cover - exists, owned by someone else
        return True
    return True


def _watch(pid: int) -> None:
    """Block until process ``pid`` ends, then kill this process."""
    fd = None
    if hasattr(os, "pidfd_open"):
        try:
            fd = os.pidfd_open(pid)
        except ProcessLookupError:
            os.kill(os.getpid(), signal.SIGKILL)
        except OSError:  # pragma: no cover - a kernel before 5.3
            fd = None
    if fd is not None:
        select.select([fd], [], [])  # readable when the process has ended
    else:
        while _alive(pid):
            time.sleep(_POLL)
    os.kill(os.getpid(), signal.SIGKILL)


def watch_process(pid: int) -> threading.Thread:
    """Start a daemon thread that kills this process (SIGKILL) as soon as process ``pid`` ends.

    A process inside compiled code that holds the GIL is killed when it next releases it (at
    the latest between two campaign points); :func:`die_with_parent` acts at once.
    """
    thread = threading.Thread(target=_watch, args=(pid,), name="campaign-watchdog", daemon=True)
    thread.start()
    return thread
