"""The workbench against exudyn, an independent multibody engine (issue: independent verification).

Skipped, with the reason, where the ``verify`` extra (exudyn) is not installed; ``make test``
installs it, so CI runs these.
"""

from __future__ import annotations

import numpy as np
import pytest

import workbench

exudyn = pytest.importorskip("exudyn", reason="the 'verify' extra (exudyn) is not installed")

from workbench.verification import verify  # noqa: E402

pytestmark = pytest.mark.verify

DEFAULT = "studies/ninebar.toml"


def _scene(**effects):
    scene = workbench.load_scene(DEFAULT)
    # the record table is rebuilt by verify; drop the default scene's variable list, which
    # names clearance outputs that an ideal scene does not have
    return scene.replace(effects={**scene.effects, **effects}, record={"dt": 1e-3})


def test_ideal_torques_and_slider_agree_over_a_cycle():
    # prescribed motion: both sides must agree record by record; exudyn's error is second order
    # in its step (after a start-up transient of its multipliers), so it shrinks with the step
    ds = verify(_scene(clearance=[]), steps=(2.5e-4, 1e-4))
    err = ds.max_relative_error
    fine = err.sel(run="exudyn h=0.0001")
    assert float(fine.sel(series="torque")) < 1e-3
    assert float(fine.sel(series="slider_acceleration")) < 1e-3
    assert float(fine.sel(series="slider_position")) < 1e-9
    coarse = err.sel(run="exudyn h=0.00025")
    assert float(fine.sel(series="torque")) < float(coarse.sel(series="torque")) / 4


def test_first_impacts_agree_under_step_refinement():
    # journals start centred: both joints fly free, then hit their bearings; before any chaotic
    # divergence the first impact must be the same event on both sides
    ds = verify(_scene(friction="none"), horizon=0.02, steps=(4e-6, 2e-6))
    ours = ds.sel(run="workbench")
    finest = ds.sel(run="exudyn h=2e-06")
    coarse = ds.sel(run="exudyn h=4e-06")
    t_ours = ours.first_impact_time.values
    assert np.all((t_ours > 0.005) & (t_ours < 0.02))  # both joints do hit
    np.testing.assert_allclose(finest.first_impact_time, t_ours, rtol=0.01)
    np.testing.assert_allclose(finest.first_impact_force, ours.first_impact_force, rtol=0.05)
    # refinement brings exudyn's peak towards the workbench's
    d_fine = np.abs(finest.first_impact_force - ours.first_impact_force)
    d_coarse = np.abs(coarse.first_impact_force - ours.first_impact_force)
    assert np.all(d_fine <= d_coarse + 1e-3 * ours.first_impact_force)


def test_chaos_robust_statistics_agree_over_a_cycle():
    # after a few impacts the two solutions part (chaos): compare distributions, not histories.
    # Bounds, from this case run at exudyn steps 4e-6 and 2e-6 s (README, verification): the
    # contact fraction and the mean eccentricity of equally valid runs differ by < 0.03 and
    # < 4 %; the 95th percentile and the peak of the contact force, set by the few hardest
    # impacts of one cycle, by up to 35 % even between exudyn's own two steps.
    ds = verify(_scene(friction="none"), horizon=0.8, steps=(4e-6,), record_dt=2e-5)
    ours = ds.sel(run="workbench")
    other = ds.sel(run="exudyn h=4e-06")
    np.testing.assert_allclose(other.contact_fraction, ours.contact_fraction, atol=0.05)
    np.testing.assert_allclose(other.mean_eccentricity, ours.mean_eccentricity, rtol=0.06)
    np.testing.assert_allclose(other.force_p95, ours.force_p95, rtol=0.5)
    np.testing.assert_allclose(other.peak_force, ours.peak_force, rtol=0.5)


SLIDER_CRANK = "studies/verification/slider_crank.toml"


def test_slider_crank_ideal_and_first_impact_agree():
    # the community benchmark (Flores et al. 2006): ideal torques record by record, then the
    # first impact of the journal in the slider's bearing (at 0.23 ms, ~46 kN)
    scene = workbench.load_scene(SLIDER_CRANK)
    ideal = scene.replace(effects={**scene.effects, "clearance": []}, record={"dt": 1e-5})
    ds = verify(ideal, steps=(5e-6, 2e-6), record_dt=1e-5)
    assert float(ds.max_relative_error.sel(run="exudyn h=2e-06", series="torque")) < 1e-3
    assert (
        float(ds.max_relative_error.sel(run="exudyn h=2e-06", series="slider_acceleration")) < 1e-4
    )
    ds = verify(scene, horizon=1e-3, steps=(1e-6, 5e-7), record_dt=1e-6)
    ours = ds.sel(run="workbench", joint="B")
    finest = ds.sel(run="exudyn h=5e-07", joint="B")
    assert 1e-4 < float(ours.first_impact_time) < 1e-3
    np.testing.assert_allclose(finest.first_impact_time, ours.first_impact_time, rtol=0.01)
    np.testing.assert_allclose(finest.first_impact_force, ours.first_impact_force, rtol=0.05)


def test_refusals_name_the_problem(tmp_path):
    from workbench.verification import run_exudyn

    lugre = _scene(friction="lugre")
    with pytest.raises(workbench.SceneError, match="^effects.friction: 'lugre' has no"):
        run_exudyn(lugre, t_end=1e-3, step=1e-4, record_dt=1e-4)
    duffing = workbench.load_scene({"model": {"name": "duffing"}})
    with pytest.raises(workbench.SceneError, match="^model.name: .* knows the models"):
        run_exudyn(duffing, t_end=1e-3, step=1e-4, record_dt=1e-4)
    with pytest.raises(ValueError, match="whole multiple"):
        verify(_scene(), horizon=1e-3, steps=(3e-6,), record_dt=1e-5)
    # the command line prints the rule instead of a traceback
    path = tmp_path / "lugre.toml"
    path.write_text(lugre.to_toml())
    from workbench.cli import main

    assert main(["verify", str(path), "-o", str(tmp_path / "v.nc")]) == 2


def test_verify_shows_its_runs_as_they_end(tmp_path, capsys):
    """Issue 40 item 5: a line at the start, one per run as it ends, and the end (exudyn's
    runs weighted by their steps in the time left); none with -q."""
    from workbench.cli import main

    args = ["verify", SLIDER_CRANK, "--horizon", "1e-3", "--steps", "1e-5,5e-6"]
    args += ["--record-dt", "1e-5"]
    assert main([*args, "-o", str(tmp_path / "q.nc"), "-q"]) == 0
    assert "verify:" not in capsys.readouterr().err
    assert main([*args, "-o", str(tmp_path / "v.nc")]) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if "so far" not in line]
    assert lines[0] == "verify: 0/3 run ..."
    assert lines[1].startswith("workbench (dop853, rtol 1e-10): ")
    assert lines[2].startswith("exudyn h=1e-05 (100 steps): ")
    assert lines[3].startswith("exudyn h=5e-06 (200 steps): ")
    assert lines[4].startswith("verify: 3/3 run (100 %) in ")
