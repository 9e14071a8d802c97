"""Progress that suits where it is written: a bar on a terminal, a few lines in a log, no
warning in Jupyter without ipywidgets; and one ``-q`` on every command."""

import argparse
import io
import math
import time
import warnings

import pytest

import workbench
import workbench._progress as progress_module
from workbench._progress import Progress, TimeLeft, elapsed, progress_mode
from workbench.cli import build_parser, main


def test_a_log_gets_a_line_at_the_start_and_one_at_the_end():
    log = io.StringIO()
    with Progress(4.0, desc="simulated time", unit="s", file=log) as p:
        for k in range(1, 1001):
            p.update_to(4.0 * k / 1000)
    lines = log.getvalue().splitlines()
    assert lines[0] == "simulated time: 0 s/4 s ..."
    assert lines[1].startswith("simulated time: 4 s/4 s (100 %) in ") and len(lines) == 2


def test_a_long_computation_adds_a_line_per_interval():
    log = io.StringIO()
    with Progress(10, desc="campaign", unit="pt", file=log, interval=0.0) as p:
        for _ in range(10):
            p.update(1)
    lines = log.getvalue().splitlines()
    # start, one per update before the end (interval 0), the end
    assert len(lines) == 11 and lines[5].startswith("campaign: 5/10 pt (50 %), ")
    assert "s left" in lines[5]


def test_a_run_writes_two_lines_to_a_log_not_a_bar_per_update(capsys):
    workbench.simulate(
        {"model": {"name": "duffing"}, "run": {"cycles": 50}, "record": {"samples_per_period": 4}},
        progress=True,
    )
    err = capsys.readouterr().err
    assert "\r" not in err
    assert len(err.splitlines()) == 2 and "(100 %)" in err.splitlines()[-1]


def test_jupyter_without_ipywidgets_gets_lines_and_no_warning(monkeypatch):
    monkeypatch.setattr(progress_module, "_in_notebook", lambda: True)
    monkeypatch.setattr(progress_module.importlib.util, "find_spec", lambda name: None)
    assert progress_mode(io.StringIO()) == "lines"
    log = io.StringIO()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # tqdm's "IProgress not found" would raise here
        with Progress(3, desc="accuracy", unit="run", file=log) as p:
            p.update(3)
    assert len(log.getvalue().splitlines()) == 2


def test_a_terminal_gets_a_bar():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    out = Tty()
    assert progress_mode(out) == "bar"
    with Progress(2, desc="campaign", unit="pt", file=out) as p:
        p.update(2)
    assert "campaign: 100%" in out.getvalue() and "\r" in out.getvalue()


def _subcommands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(sub.choices)


# 'analyse' is left out here: its options are reworked with its automatic choices (issue 26,
# item 3), which adds its -q
@pytest.mark.parametrize("command", sorted(set(_subcommands()) - {"analyse"}))
def test_every_command_has_the_one_quiet_flag(command):
    options = {
        s for a in _subcommands()[command]._actions for s in a.option_strings if s.startswith("-q")
    }
    assert options == {"-q"}, command


def test_study_no_progress_is_a_deprecated_alias_of_q(capsys):
    assert main(["study", "list", "--no-progress"]) == 0
    captured = capsys.readouterr()
    assert "chaos" in captured.out.split()
    assert "--no-progress is deprecated; use -q" in captured.err
    assert main(["study", "list", "-q"]) == 0
    assert capsys.readouterr().err == ""


# -- the time left (issue 40, item 5) ----------------------------------------------------------


def test_the_time_left_weights_each_job_by_its_cost():
    """Fake costs: a kind's rate (s per unit of cost) comes from its own finished jobs, a kind
    not seen yet borrows the rate of all finished jobs."""
    left = TimeLeft({"a1": ("a", 1.0), "a2": ("a", 3.0), "b1": ("b", 10.0), "b2": ("b", 20.0)})
    assert math.isnan(left.seconds())
    left.finished("a1", 2.0)  # 2 s per unit: a2 6 s, b 60 s
    assert left.seconds() == pytest.approx(66.0)
    left.finished("b1", 5.0)  # b measured: 0.5 s per unit
    assert left.seconds() == pytest.approx(6.0 + 10.0)
    left.finished("unknown", 100.0)  # not a job of the work: ignored
    left.finished("a2", 3.0)
    assert left.seconds() == pytest.approx(10.0)
    left.finished("b2", 9.0)
    assert left.seconds() == 0.0


class _Clock:
    def __init__(self) -> None:
        self.now = 1000.0

    def __call__(self) -> float:
        return self.now


def test_a_log_line_gives_the_time_left_by_the_jobs_costs(monkeypatch):
    clock = _Clock()
    monkeypatch.setattr(progress_module.time, "monotonic", clock)
    log = io.StringIO()
    left = TimeLeft({"cheap": ("x", 1.0), "dear": ("y", 10.0), "cheap2": ("x", 1.0)})
    with Progress(3, desc="accuracy", unit="run", file=log, interval=0.0, time_left=left) as p:
        clock.now += 2.0
        p.update(1, job="cheap")  # 2 s per unit: dear 20 s, cheap2 2 s
        clock.now += 5.0
        p.update(1, job="dear")  # dear measured at 0.5 s per unit; cheap2 at its own 2 s
    lines = log.getvalue().splitlines()
    assert lines[1] == "accuracy: 1/3 run (33 %), 2 s elapsed, ~22 s left"
    assert lines[2] == "accuracy: 2/3 run (67 %), 7 s elapsed, ~2 s left"


def test_the_time_left_counts_only_the_work_done_here(monkeypatch):
    """A resumed work (half of it reused from a store): the rate is that of the work done in
    this process, not of the reused part, which took no time."""
    clock = _Clock()
    monkeypatch.setattr(progress_module.time, "monotonic", clock)
    log = io.StringIO()
    with Progress(10, initial=5, desc="campaign", unit="pt", file=log, interval=0.0) as p:
        clock.now += 10.0
        p.update(1)
    assert log.getvalue().splitlines()[1] == "campaign: 6/10 pt (60 %), 10 s elapsed, ~40 s left"


def test_a_note_says_where_the_work_is():
    log = io.StringIO()
    with Progress(0.02, desc="branch over gamma", unit="", file=log, interval=0.0) as p:
        p.update_to(0.01, note="gamma = 0.26, 12 points")
    lines = log.getvalue().splitlines()
    assert lines[0] == "branch over gamma: 0/0.02 ..."
    assert lines[1].startswith("branch over gamma: 0.01/0.02 (50 %), ")
    assert lines[1].endswith("; gamma = 0.26, 12 points") and "; gamma = 0.26" in lines[2]


def test_a_wait_says_how_long_it_has_lasted_while_it_lasts(monkeypatch):
    log = io.StringIO()
    with elapsed("compiling the duffing kernel", interval=0.05, file=log):
        time.sleep(0.3)
    lines = log.getvalue().splitlines()
    assert len(lines) >= 2 and set(lines) == {"compiling the duffing kernel: 0 s so far"}
    log = io.StringIO()
    with elapsed("quick", interval=10.0, file=log):
        pass
    assert log.getvalue() == ""  # a wait shorter than the interval says nothing
