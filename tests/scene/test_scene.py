"""Scenes: validation messages name the key, TOML round trip, record variables."""

import pytest

import workbench
from workbench import SceneError, load_scene, scene_from_toml

GOOD = {"model": {"name": "duffing"}, "run": {"cycles": 2}}

MALFORMED = [
    ({"run": {"cycles": 2}}, "model.name"),
    ({"model": {"name": "nope"}}, "model.name"),
    ({**GOOD, "colour": "red"}, "colour"),
    ({**GOOD, "parameters": {"gama": 0.3}}, "parameters.gama"),
    ({**GOOD, "parameters": {"gamma": "big"}}, "parameters.gamma"),
    ({**GOOD, "parameters": {"omega": -1.0}}, "parameters.omega"),
    ({**GOOD, "solver": {"method": "euler"}}, "solver.method"),
    ({**GOOD, "solver": {"rtol": 0.0}}, "solver.rtol"),
    ({**GOOD, "solver": {"rtol": 1e-20}}, "solver.rtol"),
    ({**GOOD, "solver": {"atol": -1}}, "solver.atol"),
    ({**GOOD, "solver": {"max_steps": 1.5}}, "solver.max_steps"),
    ({"model": {"name": "duffing"}, "run": {"cycles": 0}}, "run.cycles"),
    ({"model": {"name": "duffing"}, "run": {"cycles": 2, "duration": 3.0}}, "run"),
    ({"model": {"name": "lorenz"}, "run": {"cycles": 2}}, "run.cycles"),
    ({"model": {"name": "lorenz"}}, "run.duration"),
    ({**GOOD, "record": {"samples_per_period": 0}}, "record.samples_per_period"),
    ({**GOOD, "record": {"variables": ["x", "q"]}}, "record.variables"),
    ({**GOOD, "record": {"variables": []}}, "record.variables"),
    ({**GOOD, "initial": {"z": 1.0}}, "initial.z"),
    ({**GOOD, "sweep": {"gamma": []}}, "sweep.gamma"),
    ({**GOOD, "sweep": {"gamma": {"start": 0.1, "stop": 0.5}}}, "sweep.gamma.num"),
    ({**GOOD, "sweep": {"omega": [1.0, -1.0]}}, "sweep.omega[1]"),
    ({**GOOD, "sweep": {"nothing": [1.0]}}, "sweep.nothing"),
    ({**GOOD, "effects": {"friction": "lugre"}}, "effects.friction"),
    ({**GOOD, "solver": "fast"}, "solver"),
]


@pytest.mark.parametrize(
    ("data", "key"), MALFORMED, ids=[f"{i}-{k}" for i, (_, k) in enumerate(MALFORMED)]
)
def test_malformed_scene_names_the_key(data, key):
    with pytest.raises(SceneError) as info:
        load_scene(data)
    assert info.value.key == key
    assert str(info.value).startswith(key)


def test_error_message_shows_value_and_allowed():
    with pytest.raises(SceneError, match=r"solver\.method: got 'euler'; allowed: dop853, dopri5"):
        load_scene({**GOOD, "solver": {"method": "euler"}})


def test_toml_round_trip(tmp_path):
    scene = load_scene(
        {
            "title": "round trip",
            "model": {"name": "duffing"},
            "parameters": {"gamma": 0.28},
            "initial": {"x": 0.5},
            "solver": {"method": "dopri5", "rtol": 1e-7, "max_step": 0.1},
            "run": {"cycles": 3, "transient_cycles": 1},
            "record": {"samples_per_period": 7, "variables": ["x"]},
            "sweep": {"gamma": {"start": 0.2, "stop": 0.3, "num": 3}, "omega": [1.1, 1.2]},
        }
    )
    path = tmp_path / "s.toml"
    path.write_text(scene.to_toml())
    again = load_scene(path)
    assert again == scene
    assert again.sweep["gamma"] == (0.2, 0.25, 0.3)
    assert again.to_toml() == scene.to_toml()


def test_load_scene_takes_a_scene_a_path_or_a_mapping_and_text_only_explicitly(tmp_path):
    scene = load_scene(GOOD)
    assert load_scene(scene) is scene
    path = tmp_path / "omega=2.toml"  # a path with "=" is a path, not TOML text
    path.write_text(scene.to_toml())
    assert load_scene(path) == scene and load_scene(str(path)) == scene
    assert scene_from_toml(scene.to_toml()) == scene
    with pytest.raises(SceneError, match="looks like TOML text: read it with .*scene_from_toml"):
        load_scene(scene.to_toml())
    with pytest.raises(SceneError, match="a TOML file path or a mapping; got int"):
        load_scene(3)


def test_missing_file_and_bad_toml(tmp_path):
    with pytest.raises(SceneError, match="does not exist"):
        load_scene(tmp_path / "none.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[model\nname=1")
    with pytest.raises(SceneError, match="not valid TOML"):
        load_scene(bad)


def test_record_variables_limits_what_is_stored():
    ds = workbench.simulate({**GOOD, "record": {"variables": ["x"]}})
    assert list(ds.data_vars) == ["x"]


def test_every_variable_and_coordinate_has_units():
    ds = workbench.simulate(GOOD)
    for name, var in ds.variables.items():
        assert var.attrs.get("units"), name
        assert var.attrs.get("long_name"), name


def test_simulate_refuses_a_sweep():
    with pytest.raises(ValueError, match="run_campaign"):
        workbench.simulate({**GOOD, "sweep": {"gamma": [0.2, 0.3]}})


@pytest.mark.parametrize("friction", ["none", "coulomb", "lugre"])
@pytest.mark.parametrize("model", ["ninebar", "slider_crank"])
def test_no_recorded_variable_is_named_like_a_parameter(model, friction):
    """A variable named like a parameter hides one of the two once the parameters are stored as
    coordinates: LuGre's |F_t|/F_n was recorded as ``friction_coefficient``, the name of the
    Coulomb coefficient, and the friction study read c_f for it."""
    from workbench.models import get_model

    m = get_model(model)
    clearance = ["A", "B"] if model == "ninebar" else ["B"]
    scene = load_scene(
        {"model": {"name": model}, "effects": {"clearance": clearance, "friction": friction}}
    )
    clash = set(m.variables(scene.effects)) & {p.name for p in m.parameters}
    assert not clash, f"{model} with {friction} friction records {sorted(clash)}"
