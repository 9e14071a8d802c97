"""Progress that suits where it is written: a bar on a terminal, a few lines in a log, no
warning in Jupyter without ipywidgets; and one ``-q`` on every command."""

import argparse
import io
import warnings

import pytest

import workbench
import workbench._progress as progress_module
from workbench._progress import Progress, progress_mode
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
