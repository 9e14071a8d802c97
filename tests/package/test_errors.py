"""One error base (issue 41 item 5): every error workbench raises on purpose is a
``workbench.WorkbenchError`` and keeps its former built-in base; no handler turns an error it
does not mean into a number or into another error's message."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
from pathlib import Path

import numpy as np
import pytest

import workbench
from workbench import WorkbenchError
from workbench.models import get_model

DOCS = Path(__file__).parents[2] / "docs"

#: exception classes of the package that are not errors workbench raises to its caller: the
#: scipy backend's signal to stop solve_ivp (caught where it is raised), and a signal that
#: the command line honours like Ctrl-C (a KeyboardInterrupt)
NOT_ERRORS = {"workbench.solver._scipy_backend._TooMany", "workbench.cli._signals.Terminated"}

#: the built-in (or workbench) base each error had before it became a WorkbenchError
FORMER_BASES = {
    "SceneError": ValueError,
    "MemoryLimitError": ValueError,
    "CampaignError": ValueError,
    "ArchiveError": ValueError,
    "StoreLocked": ValueError,
    "OutputExists": ValueError,
    "WriteFailed": ValueError,
    "DiskFull": ValueError,
    "CacheError": ValueError,
    "UsageError": ValueError,
    "SolverError": RuntimeError,
    "NewtonFailure": RuntimeError,
}


def _exception_classes() -> dict[str, type]:
    """Every exception class (not a warning) defined in a module of the package."""
    found = {}
    for info in pkgutil.walk_packages(workbench.__path__, "workbench."):
        if info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        for _, cls in inspect.getmembers(module, inspect.isclass):
            if (
                cls.__module__ == info.name
                and issubclass(cls, BaseException)
                and not issubclass(cls, Warning)
            ):
                found[f"{cls.__module__}.{cls.__qualname__}"] = cls
    return found


def test_every_error_of_the_package_is_a_workbench_error_and_keeps_its_former_base():
    classes = _exception_classes()
    errors = {k: c for k, c in classes.items() if k not in NOT_ERRORS}
    assert set(classes) >= NOT_ERRORS  # the exceptions named above still exist
    assert {c.__name__ for c in errors.values()} >= set(FORMER_BASES)
    for name, cls in errors.items():
        assert issubclass(cls, WorkbenchError), name
        if cls.__name__ in FORMER_BASES:
            assert issubclass(cls, FORMER_BASES[cls.__name__]), name
    for name in NOT_ERRORS:
        assert not issubclass(classes[name], WorkbenchError)


def test_raised_errors_are_instances_of_both_bases():
    from workbench.campaign import CampaignError
    from workbench.continuation._newton import NewtonFailure
    from workbench.solver import SolverError, Status

    with pytest.raises(WorkbenchError) as caught:
        workbench.load_scene({"model": {"name": "duffing"}, "solver": {"rtol": -1.0}})
    assert isinstance(caught.value, workbench.SceneError) and isinstance(caught.value, ValueError)
    assert caught.value.key == "solver.rtol"
    failed = SolverError("x", time=1.0, state={"x": 1.0}, cause=Status.NON_FINITE)
    assert isinstance(failed, WorkbenchError) and isinstance(failed, RuntimeError)
    for error in (CampaignError("c"), NewtonFailure("n")):
        assert isinstance(error, WorkbenchError)
    assert isinstance(CampaignError("c"), ValueError)
    assert isinstance(NewtonFailure("n"), RuntimeError)


def test_workbench_error_is_exported_and_documented():
    assert "WorkbenchError" in workbench.__all__
    assert workbench.WorkbenchError is importlib.import_module("workbench._errors").WorkbenchError
    reference = (DOCS / "reference" / "workbench.md").read_text()
    assert re.search(r"^ +- WorkbenchError$", reference, re.M)
    assert "WorkbenchError" in (DOCS / "robustness.md").read_text()


def test_a_scene_with_a_sweep_is_refused_by_prepare_as_a_scene_error():
    scene = {"model": {"name": "duffing"}, "sweep": {"gamma": [0.3, 0.4]}}
    with pytest.raises(workbench.SceneError) as caught:
        workbench.prepare(scene)
    assert caught.value.key == "sweep" and "workbench.run_campaign" in str(caught.value)


def test_a_forcing_period_that_raises_is_refused_not_costed_as_zero(monkeypatch):
    """The cost estimate caught every exception of the model's forcing period and costed the
    point 0 s; now the plan stops at a WorkbenchError naming the point and the error."""
    from workbench.campaign import CampaignError, expand_sweep
    from workbench.campaign._schedule import partition

    def period(self, params):
        if params["omega"] == 2.0:
            raise ZeroDivisionError("float division by zero")
        return 2 * np.pi / params["omega"]

    monkeypatch.setattr(type(get_model("duffing")), "forcing_period", period)
    scene = workbench.load_scene(
        {
            "model": {"name": "duffing"},
            "run": {"cycles": 2, "transient_cycles": 1},
            "sweep": {"omega": [1.0, 2.0, 3.0]},
        }
    )
    with pytest.raises(WorkbenchError) as caught:
        partition(scene, expand_sweep(scene), 1)
    assert isinstance(caught.value, CampaignError)
    assert "omega=2" in str(caught.value) and "ZeroDivisionError" in str(caught.value)


def test_an_error_that_is_not_about_the_file_is_not_called_an_unreadable_file(
    monkeypatch, tmp_path
):
    """Reading back a campaign's archive catches the errors of an unreadable file only: a bug
    on the way is raised as it is, not reported as 'not a readable netCDF file'."""
    from workbench.campaign import _run
    from workbench.campaign._store import Store

    class Bug(Exception):
        pass

    def broken(path):
        raise Bug("not a file problem")

    path = tmp_path / "c.nc"
    path.write_bytes(b"not netCDF")
    scene = workbench.load_scene({"model": {"name": "duffing"}, "sweep": {"gamma": [0.3]}})
    with pytest.raises(workbench.CampaignError, match="not a readable netCDF file"):
        _run._complete_archive(Store(path), scene, None)
    monkeypatch.setattr(_run, "open_run", broken)
    with pytest.raises(Bug):
        _run._complete_archive(Store(path), scene, None)


def test_the_command_line_says_any_workbench_error_in_one_line_and_keeps_its_exit_codes(
    monkeypatch, tmp_path, capsys
):
    from workbench.cli import _run, main
    from workbench.cli._exit_codes import exit_code
    from workbench.continuation._newton import NewtonFailure

    scene = tmp_path / "s.toml"
    scene.write_text(workbench.load_scene({"model": {"name": "duffing"}}).to_toml())

    def fails(args):
        raise NewtonFailure("Newton's method did not converge in 3 iterations")

    monkeypatch.setattr(_run, "_cmd_run", fails)
    assert main(["run", str(scene), "-o", str(tmp_path / "r.nc")]) == 1
    err = capsys.readouterr().err
    assert err == "workbench run: error: Newton's method did not converge in 3 iterations\n"
    # the exit codes users rely on: invalid input 2, a failed run by its status
    from workbench.solver import SolverError, Status

    assert exit_code(workbench.SceneError("run.cycles", "bad")) == 2
    assert exit_code(workbench.CampaignError("bad")) == 2
    failed = SolverError("x", time=0.0, state={}, cause=Status.MAX_STEPS)
    assert exit_code(failed) == 3
    assert exit_code(NewtonFailure("n")) == 1
