"""Warnings once per kind (issue 40, item 4): warnings alike but for their numbers (one per point
of a campaign, a realisation of a study) are one line with their count on the command line, and
one warning with the count from a campaign, however many worker processes raised them."""

import warnings

import dask
import pytest
import xarray as xr

import workbench
from workbench._warnings import WarningKind, warnings_by_kind
from workbench.campaign import CampaignWarning
from workbench.cli._console import one_line_warnings

LUGRE = "LuGre friction at joint A left its law's range for {:.3g} s (largest {:.3g})"


def test_warnings_alike_but_for_their_numbers_are_one_line_with_their_count(capsys):
    with one_line_warnings("study"):
        for i in range(51):  # as a study of 51 runs raised them
            warnings.warn(workbench.ModelWarning(LUGRE.format(0.01 * i, 12.5 + i)), stacklevel=1)
        with warnings_by_kind():  # a campaign's count adds to the command's
            for i in range(3):
                warnings.warn(workbench.ModelWarning(LUGRE.format(i, -i)), stacklevel=1)
        warnings.warn(CampaignWarning("2 of 4 campaign points failed\nsee 'status'"), stacklevel=1)
    err = capsys.readouterr().err.splitlines()
    assert err == [
        f"workbench study: warning: {LUGRE.format(0, 12.5)} [54 warnings like this one, numbers "
        "aside; the first shown]",
        "workbench study: warning: 2 of 4 campaign points failed see 'status'",
    ]


def test_the_filters_in_force_decide_what_is_shown(capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", workbench.ModelWarning)
        with one_line_warnings("run"):
            for i in range(3):
                warnings.warn(workbench.ModelWarning(LUGRE.format(i, 2)), stacklevel=1)
    assert capsys.readouterr().err == ""
    with warnings.catch_warnings():  # an error filter inside still raises where it is raised
        warnings.simplefilter("error", CampaignWarning)
        with pytest.raises(CampaignWarning), warnings_by_kind():
            warnings.warn(CampaignWarning("stop"), stacklevel=1)


def test_a_kind_names_its_category_by_name_and_imports_nothing():
    kind = WarningKind("workbench._errors", "ModelWarning", "x = 1", count=2)
    assert kind.category is workbench.ModelWarning
    assert kind.key == WarningKind("workbench._errors", "ModelWarning", "x = -2.5e-06").key
    assert WarningKind("no_such_module_xyz", "Oops", "a").category is UserWarning


def measure_and_warn(scene, run):
    """A campaign's per-point measurement that warns, with the point's value, in the worker."""
    gamma = scene.resolved_parameters["gamma"]
    warnings.warn(workbench.ModelWarning(f"a test warning at gamma = {gamma:g}"), stacklevel=1)
    return xr.Dataset({"x_end": ((), float(run.x[-1]), {"units": run.x.attrs["units"]})})


def test_a_campaign_raises_its_workers_warnings_once_per_kind_with_the_count(tmp_path):
    scene = workbench.load_scene(
        {
            "model": {"name": "duffing"},
            "run": {"cycles": 2},
            "record": {"samples_per_period": 2},
            "sweep": {"gamma": [0.3, 0.4, 0.5]},
        }
    )
    with (
        dask.config.set({"multiprocessing.context": "fork"}),  # the workers know this module
        warnings.catch_warnings(record=True) as caught,
    ):
        warnings.simplefilter("always")
        ds = workbench.run_campaign(
            scene, tmp_path / "c.nc", workers=2, chunk=1, per_point=measure_and_warn
        )
    assert ds.attrs["computed_blocks"] == 3  # one point per block: three worker tasks
    mine = [w for w in caught if "a test warning" in str(w.message)]
    assert len(mine) == 1 and mine[0].category is workbench.ModelWarning
    text = str(mine[0].message)
    assert text.endswith("[3 warnings like this one, numbers aside; the first shown]")
