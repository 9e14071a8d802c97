"""One failure vocabulary: every workbench.Status through simulate, a campaign and the CLI.

The test model ``failing`` (tests/failing_model.py) ends its run with the status it is asked for
at t_fail = 0.5 s of a 1-s run.
"""

import dask
import failing_model  # noqa: F401 (registers the model "failing")
import numpy as np
import pytest
import tomli_w
import xarray as xr

import workbench
from workbench import SolverError, Status
from workbench.campaign import CampaignWarning
from workbench.cli import main
from workbench.cli._campaign import campaign_exit_code

BASE = {
    "model": {"name": "failing"},
    "run": {"duration": 1.0},
    "record": {"dt": 0.01},
    "solver": {"max_steps": 5000},
}
EXIT = {
    Status.OK: 0,
    Status.TERMINATED: 0,
    Status.MAX_STEPS: 3,
    Status.STEP_UNDERFLOW: 4,
    Status.NON_FINITE: 4,
    Status.MODEL_FAILURE: 5,
}


def scene(status: Status) -> dict:
    return {**BASE, "parameters": {"mode": float(status)}}


@pytest.mark.parametrize("status", list(Status), ids=[s.label for s in Status])
def test_simulate_reports_the_status(status):
    ds = workbench.simulate(scene(status), throw=False)
    assert workbench.run.run_status(ds) is status
    y, t = ds.y.values, ds.time.values
    if status is Status.OK:
        assert ds.attrs["run_message"] == "" and np.isfinite(y).all()
    elif status is Status.TERMINATED:
        assert t[-1] == pytest.approx(0.5) and np.isfinite(y).all()  # the records end there
    elif status is Status.MAX_STEPS:
        assert ds.attrs["solver_steps"] == 5000
        assert "solver.max_steps = 5000" in ds.attrs["run_message"]
        assert np.isnan(y[-1])
    else:  # fails at t_fail: records before it hold the solution, those after it are NaN
        assert "t = 0.5 s" in ds.attrs["run_message"]
        assert np.isfinite(y[t < 0.5]).all() and np.isnan(y[t > 0.5]).all()
    if status.failed:
        with pytest.raises(SolverError) as info:
            workbench.simulate(scene(status))
        assert info.value.status is status and str(info.value) == ds.attrs["run_message"]
        assert set(info.value.state) == {"y"}
    else:
        xr.testing.assert_equal(workbench.simulate(scene(status)), ds)


def test_model_failure_names_the_model_and_its_code():
    with pytest.raises(SolverError, match=r"refuses t > t_fail \(code 7\)") as info:
        workbench.simulate(scene(Status.MODEL_FAILURE))
    assert info.value.model_code == 7
    assert info.value.time == pytest.approx(0.5, abs=1e-12)


@pytest.mark.parametrize("status", list(Status), ids=[s.label for s in Status])
def test_cli_exit_code_and_archive(status, tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text(tomli_w.dumps(scene(status)))
    out = tmp_path / "r.nc"
    assert main(["run", str(path), "-o", str(out), "-q"]) == EXIT[status]
    captured = capsys.readouterr()
    assert f"status {status.label}" in captured.out
    assert (status.label in captured.err) == status.failed
    assert workbench.open_run(out).attrs["run_status"] == status.label  # written either way


def test_campaign_flags_every_status(tmp_path):
    """One campaign over the six statuses: each point's flag is its run's status, failed points
    have NaN data and their message, and the campaign's exit code is the largest one."""
    sweep = workbench.load_scene({**BASE, "sweep": {"mode": [float(s) for s in Status]}})
    # fork: the worker inherits the test model's registration (a fork server would not)
    with (
        dask.config.set({"multiprocessing.context": "fork"}),
        pytest.warns(CampaignWarning, match="4 of 6 campaign points failed"),
    ):
        ds = workbench.run_campaign(sweep, tmp_path / "c.nc", workers=1)
    assert ds.status.values.tolist() == [int(s) for s in Status]
    meanings = ds.status.attrs["flag_meanings"].split()
    assert meanings == [s.label for s in Status] + ["invalid_parameters", "error"]
    for s in Status:
        point = ds.sel(mode=float(s))
        assert str(point.failure.values).startswith(s.label if s.failed else ""), s
        assert np.isnan(point.y).all() == s.failed, s
    assert int(ds.solver_steps.sel(mode=float(Status.MAX_STEPS))) == 5000
    assert campaign_exit_code(ds.status.values) == 5
    assert campaign_exit_code(np.array([0, 1])) == 0


def test_the_status_table_of_the_archives_page_is_the_code():
    """docs/archives.md: every row `name` | value | meaning | exit code is the code's."""
    import re
    from pathlib import Path

    from workbench.campaign._block import STATUS
    from workbench.cli._campaign import campaign_exit_code

    page = (Path(__file__).parents[2] / "docs" / "archives.md").read_text()
    row = r"^\| (?:\(campaign point\) )?`(\w+)` \| (\d+) \| .* \| (\d+) \|$"
    rows = re.findall(row, page, re.M)
    assert {name for name, _, _ in rows} == set(STATUS.values())
    for name, value, code in rows:
        assert STATUS[int(value)] == name
        assert campaign_exit_code(np.array([int(value)])) == int(code), name
