"""Shared fixtures. Numba compiles once per model into the on-disk cache (see workbench._cache)."""

import signal

import matplotlib
import pytest

matplotlib.use("Agg")

# The Ctrl-C tests send SIGINT as a terminal does to its foreground job. A suite started as a
# background job of a non-interactive shell (`make test &`, `nohup ... &`) inherits SIGINT
# ignored, and so would every command it starts: Python then never raises KeyboardInterrupt and
# those tests saw a run finish with exit code 0. Restore Python's own handler (the children then
# inherit the default action), so the tests mean the same however the suite was started.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture(autouse=True)
def _close_figures():
    """Close the figures a test left open: pyplot keeps every figure until it is closed, and
    warns once more than 20 are open, into the output of whatever command runs next."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")
