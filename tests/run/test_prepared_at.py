"""A scene at a point (``Prepared.at``): only the changed values are checked and only what
depends on them is built again, with the same numbers as a scene loaded at that point; the one
function that asks a model for its forcing period; campaign blocks and the strobe map prepare
their points without validating the scene again."""

import dataclasses
import math

import numpy as np
import pytest

import workbench
from workbench.campaign._block import BlockTask, run_block
from workbench.continuation import StrobeMap
from workbench.models import get_model
from workbench.run import forcing_period, prepare
from workbench.scene import _scene

DUFFING = {
    "model": {"name": "duffing"},
    "parameters": {"delta": 0.3},
    "run": {"cycles": 3, "transient_cycles": 1, "perturbation": 1e-6},
    "record": {"dt": 0.3},
    "sweep": {"omega": [0.8, 1.4], "realisation": [0, 2]},
}


def _same_problem(a, b) -> None:
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and np.array_equal(x, y), f.name
        elif not callable(x):
            assert x == y, f.name


@pytest.fixture
def validations(monkeypatch):
    """The number of whole-scene validations (every load_scene, scene_from_toml, replace and
    with_parameters goes through one)."""
    calls = []
    validate = _scene._validate

    def counted(*args, **kwargs):
        calls.append(args)
        return validate(*args, **kwargs)

    monkeypatch.setattr(_scene, "_validate", counted)
    return calls


@pytest.mark.parametrize(
    "point",
    [{"omega": 1.4, "realisation": 2}, {"omega": 2.5, "gamma": 0.45}, {"realisation": 3}],
)
def test_a_point_is_the_scene_loaded_at_that_point(point):
    scene = workbench.load_scene(DUFFING)
    new = prepare(scene, points=True).at(**point)
    old = prepare(scene.with_parameters(**point))
    assert new.scene.to_toml() == old.scene.to_toml() and new.scene == old.scene
    assert new.parameters == old.parameters and new.period == old.period
    assert new.record_attrs == old.record_attrs and np.array_equal(new.times, old.times)
    _same_problem(new.problem, old.problem)  # the perturbed initial state included
    assert new.period == 2 * math.pi / point.get("omega", 1.2)


def test_only_the_changed_values_are_checked(validations):
    base = prepare(workbench.load_scene(DUFFING), points=True)
    validations.clear()
    for omega in (0.5, 1.0, 1.5):
        assert base.at(omega=omega).scene.parameters["omega"] == omega
    assert validations == []  # no whole-scene validation, no text round trip
    with pytest.raises(workbench.SceneError) as caught:
        base.at(omega=-2.0)
    message = str(caught.value)  # the line load_scene gives
    assert message == "parameters.omega: got -2.0; must lie in (0, inf] rad s-1"
    assert caught.value.key == "parameters.omega"
    with pytest.raises(workbench.SceneError, match=r"^run\.realisation: .* got -1$"):
        base.at(realisation=-1)
    rejected = prepare({"model": {"name": "slider_crank"}, "run": {"cycles": 1}})
    with pytest.raises(workbench.SceneError, match="rod must be longer than the crank"):
        rejected.at(crank_length=0.2)  # each value in range, the combination is not


def test_the_point_s_records_are_checked_against_the_memory_limit():
    base = prepare(
        {**DUFFING, "run": {"cycles": 1000}, "sweep": {"omega": [0.01, 1.0]}},
        points=True,
        max_memory="1 MiB",
    )
    assert base.at(omega=1.0).times.size == 1000 * round(2 * math.pi / 0.3) + 1
    with pytest.raises(workbench.run.MemoryLimitError):
        base.at(omega=0.01)  # 2094 records per period


def test_a_forcing_period_that_is_not_a_time_is_refused(monkeypatch):
    duffing = get_model("duffing")
    params = duffing.default_parameters()
    assert forcing_period(duffing, params) == 2 * math.pi / params["omega"]
    assert forcing_period(get_model("lorenz"), get_model("lorenz").default_parameters()) is None
    monkeypatch.setattr(type(duffing), "forcing_period", lambda self, p: -p["omega"])
    with pytest.raises(workbench.SceneError, match=r"gives the forcing period -1\.2, not a"):
        forcing_period(duffing, params)


def test_a_block_validates_its_scene_once_whatever_its_points(tmp_path, validations):
    scene = workbench.load_scene(DUFFING)
    counts = []
    for flat in ((0,), (0, 1, 2, 3)):
        validations.clear()
        task = BlockTask(
            scene.to_toml(), ("omega", "realisation"), flat, ((0.8, 1.4), (0.0, 2.0)),
            str(tmp_path / f"block-{len(flat)}.nc"), "id", 0,
        )  # fmt: skip
        out = run_block(task)
        assert out["points"] == len(flat) and out["failures"] == []
        counts.append(len(validations))
    assert counts[0] == counts[1] <= 2  # the task's text, the scene without its sweep


def test_the_strobe_map_prepares_a_value_without_validating_the_scene(validations):
    smap = StrobeMap({"model": {"name": "duffing"}, "run": {"cycles": 1}}, "omega")
    validations.clear()
    prepared = smap.prepared(1.7)
    assert validations == [] and prepared.period == 2 * math.pi / 1.7
    assert prepared.variables == () and smap.prepared(1.7) is prepared  # kept per value
    with pytest.raises(workbench.SceneError, match="parameters.omega"):
        smap.prepared(-1.0)
