"""Declared mechanisms run through the built-in mechanisms' solver path (issue 42, items 2 and 4):
the declared nine-bar and slider-crank of studies/mechanisms/ against the built-in models (ideal
joints over one cycle, clearances over the first part of a cycle, the right-hand side at states
in and out of contact), a scene with a [mechanism] table that round-trips through TOML and an
archive, and a campaign over a declared joint's clearance."""

import importlib
import tomllib
from pathlib import Path

import numpy as np
import pytest

import workbench
from workbench._errors import SceneError
from workbench.models import get_model
from workbench.run import prepare
from workbench.scene import load_scene, scene_from_toml

ROOT = Path(__file__).resolve().parents[2]
MECHANISMS = ROOT / "studies" / "mechanisms"
C = 0.5e-3  # m, the clearance of every joint of the three declarations


def declaration(name: str) -> dict:
    """The [mechanism] table of studies/mechanisms/NAME.toml."""
    with open(MECHANISMS / f"{name}.toml", "rb") as f:
        return tomllib.load(f)["mechanism"]


def ninebar_study() -> dict:
    with open(ROOT / "studies" / "ninebar.toml", "rb") as f:
        return tomllib.load(f)


def pair(name: str, effects: dict, run: dict, variables: list, solver=None, builtin_params=None):
    """The built-in model ``name`` and its declared twin run on the same scene but the model."""
    study = ninebar_study()
    common = {
        "effects": effects,
        "run": run,
        "record": {"samples_per_period": 2000, "variables": variables},
    }
    if solver is not None:
        common["solver"] = solver
    builtin = {"model": {"name": name}, "parameters": builtin_params or {}, **common}
    params = {}
    if name == "ninebar":
        p = study["parameters"]
        params = {
            "omega": p["omega"],
            "clearance_A": p["clearance"],
            "clearance_B": p["clearance"],
            "friction_coefficient": p["friction_coefficient"],
        }
    declared = {
        "model": {"name": "declared"},
        "mechanism": declaration(name),
        "parameters": params,
        **common,
    }
    return workbench.simulate(load_scene(builtin)), workbench.simulate(load_scene(declared))


# ================================================================================================
# item 4: the declared nine-bar and slider-crank reproduce the built-in models
# ================================================================================================
@pytest.mark.parametrize("name", ["ninebar", "slider_crank"])
def test_ideal_joints_crank_torque_over_a_cycle(name):
    """With ideal joints the driving torques over one cycle agree within 1e-8 of their range."""
    study = ninebar_study()
    params = dict(study["parameters"]) if name == "ninebar" else {}
    effects = {"clearance": [], "friction": "none"}
    a, b = pair(name, effects, {"cycles": 1}, ["torque"], builtin_params=params)
    assert a.torque.shape == b.torque.shape and a.time.size == 2001
    span = np.ptp(a.torque.values, axis=0)
    assert np.all(span > 1.0)  # N m: the comparison is of a torque that varies
    assert np.all(np.abs(a.torque.values - b.torque.values).max(axis=0) <= 1e-8 * span)


def test_slider_crank_clearance_states_over_a_fifth_of_a_cycle():
    """With the clearance joint B the clearance vector over the first 0.2 cycle agrees within
    1e-6 of c (contacts included: the journal reaches the bearing's wall)."""
    effects = {"clearance": ["B"], "friction": "none"}
    solver = {"method": "dop853", "rtol": 1e-9, "atol": 1e-9}
    variables = ["clearance_x", "clearance_y", "penetration"]
    a, b = pair("slider_crank", effects, {"cycles": 1}, variables, solver)
    window = slice(0, 401)  # the first 0.2 cycle: 400 of the cycle's 2000 samples
    assert a.penetration[window].max() > 0  # in contact within the window
    for v in ("clearance_x", "clearance_y"):
        assert np.abs(a[v].values[window] - b[v].values[window]).max() <= 1e-6 * C


def test_ninebar_clearance_states_until_the_first_impacts():
    """With clearances at A and B (studies/ninebar.toml: Coulomb friction; DOP853 at rtol = atol
    = 1e-10, so that the integration's error is far below the comparison's) the clearance
    vectors agree within 1e-6 of c while the journals fly, up to the first contact. (Beyond,
    the impacts multiply every difference: a change of the initial normal velocity by
    1e-12 m s-1 moves the built-in's own clearance vectors by 1e-9 m within 0.05 s; the
    right-hand sides are compared in every state below.)"""
    study = ninebar_study()
    variables = ["clearance_x", "clearance_y", "penetration"]
    a, b = pair(
        "ninebar",
        dict(study["effects"]),
        {"cycles": 1},
        variables,
        {"method": "dop853", "rtol": 1e-10, "atol": 1e-10},
        dict(study["parameters"]),
    )
    first = int(np.argmax((a.penetration.values > 0).any(axis=1)))
    assert 10 < first < 400  # the journals fly, then reach their bearings in the first 0.2 cycle
    for v in ("clearance_x", "clearance_y"):
        assert np.abs(a[v].values[:first] - b[v].values[:first]).max() <= 1e-6 * C


@pytest.mark.chaotic
def test_ninebar_clearance_states_over_a_fifth_of_a_cycle_within_the_builtins_own_spread():
    """Over the first 0.2 cycle, through the impacts, the declared nine-bar differs from the
    built-in no more than the built-in differs from itself when its tolerance is tightened
    tenfold. Within 1e-6 of c, as issue 42 item 4 words it, is below what double precision
    resolves here: the impacts multiply every difference, and the built-in's own clearance
    vectors at rtol 1e-11 and 1e-12 differ by about 8e-3 c, no less than at 1e-10 and 1e-11
    once the integration's error is below the rounding's (measured on one processor: declared
    against built-in 7.4e-3 c at rtol 1e-11; the built-in against itself 7.9e-3 c). Rounding
    sets these figures, so another processor gets others of the same size: the test allows 3x."""
    study = ninebar_study()
    variables = ["clearance_x", "clearance_y"]
    runs = {}
    for rtol in (1e-11, 1e-12):
        solver = {"method": "dop853", "rtol": rtol, "atol": rtol}
        runs[rtol] = pair(
            "ninebar", dict(study["effects"]), {"cycles": 1}, [*variables, "penetration"], solver,
            dict(study["parameters"]),
        )  # fmt: skip
    window = slice(0, 401)  # the first 0.2 cycle: 400 of the cycle's 2000 samples

    def spread(a, b):
        return max(np.abs(a[v].values[window] - b[v].values[window]).max() for v in variables)

    builtin, declared = runs[1e-11]
    first = int(np.argmax((builtin.penetration.values > 0).any(axis=1)))
    assert first < 300  # the window holds the impacts, not only the free flight
    own = spread(builtin, runs[1e-12][0])
    twin = spread(builtin, declared)
    assert 0 < own < 0.1 * C  # the built-in's own spread: the rounding's, far below c
    assert twin <= 3.0 * own, (twin / C, own / C)


def _problems(name: str, friction: str, energy: bool):
    """The built-in's and the declared twin's problems; ``energy``: with the driver-work and
    dissipation quadratures (and, under LuGre, the friction-law ones), else the clearance states
    alone."""
    study = ninebar_study()
    joints = ["A", "B"] if name == "ninebar" else ["B"]
    scene = {
        "effects": {"clearance": joints, "friction": friction},
        "parameters": {"omega": study["parameters"]["omega"]} if name == "ninebar" else {},
    }
    if not energy:
        scene["record"] = {"variables": ["clearance_x"]}
    builtin = prepare(load_scene({"model": {"name": name}, **scene})).problem
    declared = prepare(
        load_scene({"model": {"name": "declared"}, "mechanism": declaration(name), **scene})
    ).problem
    return builtin, declared, len(joints)


@pytest.mark.parametrize(
    ("name", "friction", "energy"),
    [
        ("ninebar", "coulomb", False),
        ("ninebar", "coulomb", True),
        ("ninebar", "lugre", True),
        ("ninebar", "none", False),
        ("slider_crank", "coulomb", False),
        ("slider_crank", "none", True),
    ],
)
def test_right_hand_side_equals_the_builtin(name, friction, energy):
    """At random states, out of contact and in it (penetrations up to 10 um, onset velocities
    held or not, LuGre bristles within their bound), the declared right-hand side equals the
    built-in's lean one to rounding, and its own record-time evaluation's; with and without the
    energy (and friction-law) quadratures."""
    pa, pb, nj = _problems(name, friction, energy)
    ha, hb = importlib.import_module(pa.hooks), importlib.import_module(pb.hooks)
    rng = np.random.default_rng(42)
    n, nf = pa.y0.size, 2 * nj
    assert pb.y0.size == n and (n > 2 * nf) == (energy or friction == "lugre")
    contacts = 0
    for _ in range(200):
        y = np.zeros(n)
        for j in range(nj):
            angle, e = rng.uniform(0, 2 * np.pi), C * rng.uniform(0.9, 1.02)
            contacts += e > C
            y[2 * j : 2 * j + 2] = e * np.cos(angle), e * np.sin(angle)
            y[nf + 2 * j : nf + 2 * j + 2] = rng.normal(size=2) * 8 * C
        if friction == "lugre":
            y[2 * nf : 2 * nf + nj] = rng.uniform(-1.5e-6, 1.5e-6, nj)  # m, |z| <= mu_s / sigma0
        t = rng.uniform(0, 0.8)
        aux = rng.uniform(0, 0.01, pa.aux0.size) * (rng.uniform() > 0.2)
        da, db, dr = np.zeros(n), np.zeros(n), np.zeros(n)
        ca = ha.rhs(t, y.copy(), pa.p, pa.ip, aux, np.zeros(pa.work_size), da)
        cb = hb.rhs(t, y.copy(), pb.p, pb.ip, aux, np.zeros(pb.work_size), db)
        cr = hb.rhs_reference(t, y.copy(), pb.p, pb.ip, aux, np.zeros(pb.work_size), dr)
        assert ca == cb == cr
        scale = np.abs(da).max()
        assert np.abs(da - db).max() <= 1e-12 * scale
        assert np.abs(dr - db).max() <= 1e-12 * scale  # lean = record-time
    assert contacts > 30


# ================================================================================================
# the scene: a [mechanism] table, its TOML, an archive and a campaign
# ================================================================================================
def test_scene_with_a_mechanism_table_round_trips():
    scene = load_scene({"mechanism": declaration("fourbar"), "parameters": {"clearance_B": 0.3e-3}})
    model = get_model(scene.model)
    assert scene.model.startswith("declared_fourbar_")
    assert model.joints == ("B",) and model.cranks == ("crank",)
    assert {"clearance_B", "restitution_B", "mass_coupler", "omega"} <= set(
        model.default_parameters()
    )
    assert "slider_position" not in scene.variables  # a four-bar has no slider
    text = scene.to_toml()
    assert 'name = "declared"' in text and "[mechanism]" in text
    again = scene_from_toml(text)
    assert again == scene and again.model == scene.model


def test_scene_errors_name_the_key():
    with pytest.raises(SceneError, match=r"^model\.name: .*without a \[mechanism\] table"):
        load_scene({"model": {"name": "declared"}})
    with pytest.raises(SceneError, match=r"^model\.name: got 'ninebar' with a \[mechanism\]"):
        load_scene({"model": {"name": "ninebar"}, "mechanism": declaration("fourbar")})
    table = declaration("ninebar")
    table["clearances"][1]["friction_coefficient"] = 0.1
    with pytest.raises(SceneError, match=r"clearances\[B\]\.friction_coefficient: got 0\.1"):
        load_scene({"mechanism": table})


def test_declared_run_archives_and_campaigns(tmp_path):
    """A declared four-bar's run goes to an archive and back; a campaign sweeps a declared
    joint's clearance (its points run in workers that rebuild the model from the scene's
    TOML)."""
    scene = {
        "mechanism": declaration("fourbar"),
        "run": {"cycles": 1},
        "record": {"samples_per_period": 200},
    }
    ds = workbench.simulate(load_scene(scene))
    path = workbench.save_run(ds, tmp_path / "fourbar.nc")
    back = workbench.open_run(path)
    np.testing.assert_array_equal(back.torque.values, ds.torque.values)
    assert scene_from_toml(back.attrs["scene"]).model == load_scene(scene).model
    swept = scene | {"sweep": {"clearance_B": [0.2e-3, 0.5e-3]}}
    out = workbench.run_campaign(swept, tmp_path / "sweep.nc", workers=1)
    assert out.sizes["clearance_B"] == 2
    assert np.isfinite(out.torque.values).all()
