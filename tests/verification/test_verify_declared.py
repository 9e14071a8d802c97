"""A declared mechanism against exudyn (issue 42, items 3 and 4): exudyn rebuilds it from its
declaration, so that ``verify`` and ``workbench verify`` take the four-bar of
studies/mechanisms/fourbar.toml (and the declared nine-bar) as they take the built-ins, and any
linkage the declaration allows (RPR and RRP groups, tilted guides, several sliders, a bearing in
the ground).

Skipped, with the reason, where the ``verify`` extra (exudyn) is not installed.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import workbench

exudyn = pytest.importorskip("exudyn", reason="the 'verify' extra (exudyn) is not installed")

from workbench.models import get_model  # noqa: E402
from workbench.models._declared_kinematics import kinematics  # noqa: E402
from workbench.verification import run_exudyn, verify  # noqa: E402

pytestmark = pytest.mark.verify

ROOT = Path(__file__).resolve().parents[2]
FOURBAR = ROOT / "studies" / "mechanisms" / "fourbar.toml"


def fourbar(**effects):
    scene = workbench.load_scene(FOURBAR)
    # verify rebuilds the record table; drop the default one, which names the clearance
    # outputs that an ideal scene does not have
    return scene.replace(effects={**scene.effects, **effects}, record={"dt": 1e-3})


def test_fourbar_ideal_crank_torque_agrees_and_improves_with_the_step():
    # prescribed motion: record by record, exudyn's error second order in its step (after the
    # start-up transient of its multipliers); the four-bar has no slider, so none is compared
    ds = verify(fourbar(clearance=[]), steps=(2.5e-4, 1e-4))
    assert list(ds.series.values) == ["torque"]
    err = ds.max_relative_error.sel(series="torque")
    fine, coarse = float(err.sel(run="exudyn h=0.0001")), float(err.sel(run="exudyn h=0.00025"))
    assert fine < 1e-3
    assert fine < coarse / 4


def test_fourbar_first_impact_at_b_agrees_under_step_refinement():
    # the journal starts centred at B, flies free and hits the rocker's bearing: before any
    # chaotic divergence, the same event on both sides
    ds = verify(fourbar(), horizon=0.02, steps=(4e-6, 2e-6))
    ours = ds.sel(run="workbench", joint="B")
    finest = ds.sel(run="exudyn h=2e-06", joint="B")
    coarse = ds.sel(run="exudyn h=4e-06", joint="B")
    assert 0.001 < float(ours.first_impact_time) < 0.02
    np.testing.assert_allclose(finest.first_impact_time, ours.first_impact_time, rtol=0.01)
    np.testing.assert_allclose(finest.first_impact_force, ours.first_impact_force, rtol=0.05)
    d_fine = abs(float(finest.first_impact_force - ours.first_impact_force))
    d_coarse = abs(float(coarse.first_impact_force - ours.first_impact_force))
    assert d_fine <= d_coarse + 1e-3 * float(ours.first_impact_force)


def test_fourbar_clearance_statistics_agree_over_a_cycle():
    # the bounds of the built-ins' statistics test (test_verify.py): equally valid runs of a
    # chaotic motion differ by < 0.05 in contact fraction, < 6 % in mean eccentricity, < 50 %
    # in the force's 95th percentile and peak
    ds = verify(fourbar(), horizon=0.2, steps=(4e-6,), record_dt=2e-5)
    ours = ds.sel(run="workbench", joint="B")
    other = ds.sel(run="exudyn h=4e-06", joint="B")
    assert float(ours.contact_fraction) > 0.1  # the journal does sit in contact
    np.testing.assert_allclose(other.contact_fraction, ours.contact_fraction, atol=0.05)
    np.testing.assert_allclose(other.mean_eccentricity, ours.mean_eccentricity, rtol=0.06)
    np.testing.assert_allclose(other.force_p95, ours.force_p95, rtol=0.5)
    np.testing.assert_allclose(other.peak_force, ours.peak_force, rtol=0.5)


def test_declared_ninebar_agrees_with_exudyn():
    """The nine-bar of studies/mechanisms/ninebar.toml (two cranks turning opposite ways, a
    slider, clearances at A and B) with the parameters of studies/ninebar.toml: ideal joints
    record by record over a cycle as the built-in's test demands, then the first impact at each
    joint."""
    table = tomllib.loads((ROOT / "studies" / "mechanisms" / "ninebar.toml").read_text())
    study = tomllib.loads((ROOT / "studies" / "ninebar.toml").read_text())["parameters"]
    params = {
        "omega": study["omega"],
        "clearance_A": study["clearance"],
        "clearance_B": study["clearance"],
    }
    base = {"mechanism": table["mechanism"], "parameters": params, "record": {"dt": 1e-3}}
    ideal = workbench.load_scene({**base, "effects": {"clearance": []}})
    ds = verify(ideal, steps=(2.5e-4, 1e-4))
    fine = ds.max_relative_error.sel(run="exudyn h=0.0001")
    coarse = ds.max_relative_error.sel(run="exudyn h=0.00025")
    assert float(fine.sel(series="torque")) < 1e-3
    assert float(fine.sel(series="slider_acceleration")) < 1e-3
    assert float(fine.sel(series="slider_position")) < 1e-9
    assert float(fine.sel(series="torque")) < float(coarse.sel(series="torque")) / 4
    scene = workbench.load_scene({**base, "effects": {"friction": "none"}})
    ds = verify(scene, horizon=0.02, steps=(2e-6,))
    ours, finest = ds.sel(run="workbench"), ds.sel(run="exudyn h=2e-06")
    assert list(ds.joint.values) == ["A", "B"]
    assert np.all((ours.first_impact_time > 0.005) & (ours.first_impact_time < 0.02))
    np.testing.assert_allclose(finest.first_impact_time, ours.first_impact_time, rtol=0.01)
    np.testing.assert_allclose(finest.first_impact_force, ours.first_impact_force, rtol=0.05)


def test_workbench_verify_takes_the_fourbar_file(tmp_path):
    from workbench.cli import main

    out = tmp_path / "v.nc"
    args = ["verify", str(FOURBAR), "--horizon", "0.01", "--steps", "1e-5", "--record-dt", "1e-5"]
    assert main([*args, "-o", str(out), "-q"]) == 0
    ds = xr.load_dataset(out)
    assert list(ds.joint.values) == ["B"]
    assert np.isfinite(ds.first_impact_time.values).all()


# ------------------------------------------------------------------------------------------------
# any declared linkage: exudyn's ideal run against the declaration's closed-form kinematics
# ------------------------------------------------------------------------------------------------
def _bar(name, points, mass, length, com):
    """A uniform bar's link table (kg, m; inertia m L^2 / 12 about its centre of mass)."""
    return {
        "name": name,
        "points": points,
        "mass": mass,
        "inertia": mass * length**2 / 12,
        "centre_of_mass": com,
    }


# A shaper-like linkage: the crank's pin A drives a block along the guide link pivoted at O3
# (RPR); the guide's end C drives a rod to slider1 on a guide tilted 0.2 rad, with an offset and
# an off-pin centre of mass (RRP); a second rod from A drives slider2 on a near-vertical guide.
SHAPER = {
    "name": "shaper",
    "ground": {"O2": [0.0, 0.0], "O3": [0.0, -0.15], "O4": [0.0, 0.25], "O5": [-0.1, 0.0]},
    "links": [
        _bar("crank", {"O2": [0.0, 0.0], "A": [0.05, 0.0]}, 0.3, 0.05, [0.025, 0.0]),
        _bar("block", {"A": [0.0, 0.0]}, 0.1, 0.03, [0.0, 0.0]),
        _bar("guide", {"O3": [0.0, 0.0], "C": [0.3, 0.0]}, 0.6, 0.3, [0.15, 0.0]),
        _bar("rod", {"C": [0.0, 0.0], "D": [0.25, 0.0]}, 0.25, 0.25, [0.125, 0.0]),
        _bar("rod2", {"A": [0.0, 0.0], "E": [0.2, 0.0]}, 0.2, 0.2, [0.1, 0.0]),
    ],
    "sliders": [
        {
            "name": "slider1",
            "pin": "D",
            "guide": "O4",
            "angle": 0.2,
            "mass": 0.4,
            "offset": 0.1,
            "centre_of_mass": [0.01, 0.005],
        },
        {"name": "slider2", "pin": "E", "guide": "O5", "angle": 1.4, "mass": 0.2},
    ],
    "cranks": [{"link": "crank", "pivot": "O2", "omega": 10.0, "angle0": 0.3}],
    "groups": [
        {
            "kind": "RPR",
            "name": "guide_block",
            "guide": "guide",
            "block": "block",
            "pivot": "O3",
            "pin": "A",
            "line": ["O3", "C"],
            "branch": 1,
        },
        {
            "kind": "RRP",
            "name": "rod_s1",
            "link": "rod",
            "point": "C",
            "slider": "slider1",
            "branch": 1,
        },
        {
            "kind": "RRP",
            "name": "rod2_s2",
            "link": "rod2",
            "point": "A",
            "slider": "slider2",
            "branch": 1,
        },
    ],  # fmt: skip
    "clearances": [{"joint": "D", "journal": "rod", "bearing": "slider1", "clearance": 0.5e-3}],
}


def test_exudyn_moves_a_declared_shaper_as_its_kinematics():
    """Ideal joints, 3 s-1 of crank turn: exudyn's slider1 (the recorded slider) on its tilted
    guide where the declaration's closed-form kinematics put it, and its driving torque the
    power balance of the closed-form motion, tau omega = sum of m a.v + I w al - m g.v.
    Measured at h = 5e-5 s: position 4e-16, velocity 4e-8, acceleration 2e-7, torque 9e-7 of
    their ranges; a guide along the wrong direction or a joint left out is off by order 1."""
    scene = workbench.load_scene({"mechanism": SHAPER, "effects": {"clearance": []}})
    ex = run_exudyn(scene, t_end=0.3, step=5e-5, record_dt=1e-3)
    linkage = get_model(scene.model).linkage
    motion = kinematics(linkage, ex.time.values)
    track = motion.sliders["slider1"]
    for name, expected, tol in (
        ("slider_position", track.position, 1e-12),
        ("slider_velocity", track.velocity, 1e-6),
        ("slider_acceleration", track.acceleration, 1e-5),
    ):
        err = np.abs(ex[name].values - expected).max() / np.abs(expected).max()
        assert err < tol, name
    g = np.array([0.0, -scene.resolved_parameters["gravity"]])
    power = 0.0
    for body in (*linkage.links, *linkage.sliders):
        c, a = motion.centres[body.name], motion.angles[body.name]
        power = power + body.mass * ((c.acceleration - g) * c.velocity).sum(axis=1)
        power = power + getattr(body, "inertia", 0.0) * a.velocity * a.acceleration
    tau = power / linkage.cranks[0].omega
    err = np.abs(ex.torque.values[:, 0] - tau).max() / np.abs(tau).max()
    assert err < 1e-5


def test_exudyn_rebuilds_a_bearing_in_the_ground_and_orders_the_joints():
    """The four-bar with a second clearance, O4 (the rocker's journal in a bearing in the
    ground, 0.3 mm): both joints' records under their own names; the journal at O4 hits its
    bearing (eccentricity up to c plus a penetration) and B's up to its 0.5 mm."""
    table = tomllib.loads(FOURBAR.read_text())["mechanism"]
    table["clearances"].append(
        {"joint": "O4", "journal": "rocker", "bearing": "ground", "clearance": 0.3e-3}
    )
    scene = workbench.load_scene({"mechanism": table})
    assert scene.effects["clearance"] == ("B", "O4")
    ex = run_exudyn(scene, t_end=0.02, step=4e-6, record_dt=4e-5)
    e = np.hypot(ex.clearance_x, ex.clearance_y).max("time")
    assert list(ex.joint.values) == ["B", "O4"]
    np.testing.assert_allclose(e.values, [0.5e-3, 0.3e-3], rtol=0.05)
    assert float(ex.contact_force.sel(joint="O4").max()) > 0


@pytest.mark.parametrize(
    ("source", "change", "key"),
    [
        ("fourbar", {"effects": {"friction": "lugre"}}, "effects.friction"),
        ("fourbar", {"effects": {"contact": "hunt_crossley"}}, "effects.contact"),
        ("fourbar", {"initial": {"x_B": 1e-4}}, "initial.x_B"),
        # the built-ins too: exudyn's damping scales with the onset velocity, and its journals
        # start centred
        ("ninebar", {"effects": {"contact": "hunt_crossley"}}, "effects.contact"),
        ("ninebar", {"initial": {"vy_A": 1e-3}}, "initial.vy_A"),
    ],
)
def test_what_exudyn_cannot_rebuild_is_refused_naming_the_key(source, change, key):
    if source == "fourbar":
        model = {"mechanism": tomllib.loads(FOURBAR.read_text())["mechanism"]}
    else:
        model = {"model": {"name": source}}
    scene = workbench.load_scene({**model, **change})
    with pytest.raises(workbench.SceneError, match=f"^{key}: "):
        run_exudyn(scene, t_end=1e-3, step=1e-4, record_dt=1e-4)
