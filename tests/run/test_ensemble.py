"""Ensembles: perturbed initial states (run.realisation / run.perturbation), reproducible and
sweepable as a campaign dimension."""

import numpy as np
import pytest

import workbench
from workbench import SceneError, load_scene, scene_from_toml
from workbench.models import get_model
from workbench.run import DEFAULT_PERTURBATION, perturb_initial_state

C = 1e-4  # m, the clearance of the nine-bar scene below


def _ninebar(**run) -> dict:
    return {
        "model": {"name": "ninebar"},
        "effects": {"clearance": ["A", "B"], "friction": "coulomb"},
        "parameters": {"omega": 2 * np.pi, "clearance": C, "friction_coefficient": 0.01},
        "solver": {"rtol": 1e-6, "atol": 1e-6},
        "run": {"cycles": 1, "transient_cycles": 0, **run},
        "record": {"samples_per_period": 50, "variables": ["clearance_x", "clearance_y"]},
    }


def _duffing(**extra) -> dict:
    return {
        "model": {"name": "duffing"},
        "run": {"cycles": 3, "transient_cycles": 0},
        "record": {"samples_per_period": 20},
        **extra,
    }


@pytest.mark.parametrize(
    ("run", "key"),
    [
        ({"realisation": -1}, "run.realisation"),
        ({"realisation": 1.5}, "run.realisation"),
        ({"realisation": True}, "run.realisation"),
        ({"realisation": "3"}, "run.realisation"),
        ({"perturbation": 0.0}, "run.perturbation"),
        ({"perturbation": -1e-9}, "run.perturbation"),
        ({"perturbation": 0.5}, "run.perturbation"),
        ({"perturbation": "1e-9"}, "run.perturbation"),
    ],
)
def test_bad_ensemble_keys_name_the_key(run, key):
    scene = _duffing()
    scene["run"] = {**scene["run"], **run}
    with pytest.raises(SceneError) as info:
        load_scene(scene)
    assert info.value.key == key
    assert repr(next(iter(run.values()))) in str(info.value)


@pytest.mark.parametrize(
    ("values", "key"),
    [
        ([0, 1.5], "sweep.realisation[1]"),
        ([0, -2], "sweep.realisation[1]"),
        ({"start": 0, "stop": 3, "num": 3}, "sweep.realisation[1]"),  # 0, 1.5, 3
        ([1, 1], "sweep.realisation"),
    ],
)
def test_bad_realisation_sweep_names_the_key(values, key):
    with pytest.raises(SceneError) as info:
        load_scene(_duffing(sweep={"realisation": values}))
    assert info.value.key == key


def test_ensemble_keys_round_trip_and_unknown_run_key_lists_them():
    scene = load_scene(_duffing(run={"cycles": 3, "realisation": 4, "perturbation": 1e-7}))
    assert (scene.run["realisation"], scene.run["perturbation"]) == (4, 1e-7)
    assert scene_from_toml(scene.to_toml()) == scene
    point = load_scene(_duffing(sweep={"realisation": [0, 2]})).with_parameters(
        realisation=2.0, gamma=0.4
    )
    assert point.run["realisation"] == 2 and point.parameters["gamma"] == 0.4 and not point.sweep
    with pytest.raises(SceneError, match="allowed: .*perturbation, realisation"):
        load_scene(_duffing(run={"cycles": 3, "realization": 1}))


def test_perturbation_is_seeded_scaled_and_spares_realisation_zero():
    scene = load_scene(_ninebar())
    model = get_model(scene.model)
    problem = model.problem(scene.resolved_parameters, scene.effects, {}, ())
    assert perturb_initial_state(problem, 0) is problem
    a = perturb_initial_state(problem, 3)
    z = np.random.default_rng(3).standard_normal(problem.y0.size)
    np.testing.assert_array_equal(a.y0 - problem.y0, DEFAULT_PERTURBATION * problem.atol_scale * z)
    # positions by 1e-9 c, rates by 1e-9 c omega
    assert problem.atol_scale[0] == C and problem.atol_scale[-1] == pytest.approx(C * 2 * np.pi)
    b = perturb_initial_state(problem, 3, 1e-6)
    np.testing.assert_allclose(b.y0 - problem.y0, 1e3 * (a.y0 - problem.y0), rtol=1e-12)


def test_same_realisation_is_bit_identical_and_realisations_differ_at_1e_9_c():
    runs = {k: workbench.simulate(_ninebar(realisation=k)) for k in (0, 1, 2)}
    again = workbench.simulate(_ninebar(realisation=1))
    for var in ("clearance_x", "clearance_y"):
        np.testing.assert_array_equal(runs[1][var].values, again[var].values)
    t0 = {
        k: np.concatenate([r.clearance_x[0].values, r.clearance_y[0].values])
        for k, r in runs.items()
    }
    # the state is x_A, y_A, x_B, y_B, ...: the recorded offsets at t0 are the drawn ones
    z = np.random.default_rng(1).standard_normal(8)
    np.testing.assert_allclose(t0[1] - t0[0], 1e-9 * C * z[[0, 2, 1, 3]], rtol=1e-6, atol=0)
    gap = np.abs(t0[2] - t0[1]) / C
    assert 1e-11 < gap.max() < 1e-8  # the 1e-9 c level
    # chaos: within one crank cycle the realisations separate by a sizeable part of c
    late = abs(runs[2].clearance_x.isel(time=-1) - runs[1].clearance_x.isel(time=-1)).max()
    assert float(late) / C > 1e-3


def test_realisation_is_a_campaign_dimension(tmp_path):
    scene = load_scene(_duffing(sweep={"gamma": [0.3, 0.5], "realisation": [0, 1, 2]}))
    ds = workbench.run_campaign(scene, tmp_path / "ens.nc", workers=1)
    assert ds.x.dims[:3] == ("gamma", "realisation", "time")
    assert ds.realisation.attrs["units"] == "1" and "perturbed" in ds.realisation.attrs["long_name"]
    single = workbench.simulate(_duffing(parameters={"gamma": 0.5}))
    np.testing.assert_array_equal(ds.x.sel(gamma=0.5, realisation=0).values, single.x.values)
    first = ds.x.isel(time=0).sel(gamma=0.5)
    # Duffing's x has the characteristic size 1 (atol_scale 1): offsets of order 1e-9
    assert 1e-11 < float(abs(first.sel(realisation=1) - first.sel(realisation=0))) < 1e-8
    assert float(abs(first.sel(realisation=2) - first.sel(realisation=1))) > 0
