"""The slider-crank with a revolute clearance joint (Flores et al. 2006): kinematics, energy."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import ENERGY, energy_residual
from test_ninebar_lean import lean_against_reference, same_run_as_reference

import workbench
from workbench.run import prepare
from workbench.solver import integrate

BASE = {"model": {"name": "slider_crank"}, "solver": {"rtol": 1e-9, "atol": 1e-9}}


def _run(effects, *, cycles=1, samples=4000, variables=None, **parameters):
    record = {"samples_per_period": samples}
    if variables:
        record["variables"] = variables
    scene = {
        **BASE,
        "effects": effects,
        "parameters": parameters,
        "run": {"cycles": cycles},
        "record": record,
    }
    return workbench.simulate(scene)


def test_ideal_kinematics_closed_form_and_rates():
    ds = _run({"clearance": []})
    w = 5000 * 2 * np.pi / 60
    th = w * ds.time.values
    l1, l2 = 0.05, 0.12
    s = l1 * np.cos(th) + np.sqrt(l2**2 - (l1 * np.sin(th)) ** 2)
    np.testing.assert_allclose(ds.slider_position, s, rtol=0, atol=1e-14)
    t = ds.time.values
    v = ds.slider_velocity.values
    a = ds.slider_acceleration.values
    inner = slice(5, -5)
    fd_v = np.gradient(ds.slider_position.values, t)[inner]
    fd_a = np.gradient(v, t)[inner]
    assert np.abs(fd_v - v[inner]).max() < 1e-5 * np.abs(v).max()
    assert np.abs(fd_a - a[inner]).max() < 1e-5 * np.abs(a).max()
    # the classic peak at the crank's dead centre: w^2 l1 (1 + l1 / l2)
    assert a.min() == pytest.approx(-(w**2) * l1 * (1 + l1 / l2), rel=1e-6)


def test_ideal_torque_is_the_rate_of_mechanical_energy():
    ds = _run({"clearance": []})
    w = 5000 * 2 * np.pi / 60
    energy = (ds.kinetic_energy + ds.potential_energy).values
    power = ds.torque.sel(crank="1").values * w
    fd = np.gradient(energy, ds.time.values)[5:-5]
    assert np.abs(fd - power[5:-5]).max() < 1e-4 * np.abs(power).max()


@pytest.mark.parametrize(("friction", "n_states"), [("none", 4), ("coulomb", 4), ("lugre", 5)])
def test_states_and_energy_balance(friction, n_states):
    effects = {"clearance": ["B"], "friction": friction}
    scene = workbench.load_scene({**BASE, "effects": effects})
    model = workbench.models.get_model("slider_crank")
    assert len(model.states(scene.effects)) == n_states
    ds = _run(
        effects,
        friction_coefficient=0.05,
        variables=ENERGY,
    )
    residual = energy_residual(ds)
    scale = float(abs(ds.driver_work).max())
    assert float(abs(residual).max()) < 1e-4 * scale
    assert float(ds.dissipated_energy[-1]) > 0  # the impacts dissipate (c_e = 0.9)


def test_impacts_raise_the_slider_acceleration_far_above_ideal():
    # Flores et al. (2006): with a 0.5 mm clearance at 5000 rpm the slider acceleration shows
    # impact peaks many times the ideal one and free-flight stretches where it vanishes
    ds = _run({"clearance": ["B"], "friction": "none"}, cycles=2)
    ideal = 5000 * 2 * np.pi / 60
    ideal_peak = ideal**2 * 0.05 * (1 + 0.05 / 0.12)
    peak = float(abs(ds.slider_acceleration).max())
    assert peak > 3 * ideal_peak
    free = (ds.contact_force.sel(joint="B") == 0).values
    assert free.mean() > 0.1
    np.testing.assert_allclose(ds.slider_acceleration.values[free], 0.0, atol=1e-6 * peak)


def test_bad_geometry_is_refused():
    with pytest.raises(workbench.SceneError, match="parameters.rod_length"):
        workbench.load_scene({**BASE, "parameters": {"rod_length": 0.04}})


@pytest.mark.parametrize("gravity", [True, False], ids=["gravity", "no_gravity"])
@pytest.mark.parametrize("friction", ["none", "coulomb", "lugre"])
def test_lean_rhs_equals_the_reference(friction, gravity):
    """The lean hook against the record-time evaluation at 401 records of 2 cycles (each also
    with the onset unlocated and as an implicit stage), energy quadratures on (see
    test_ninebar_lean). Measured: at most 4e-16 of each rate's range."""
    scene = workbench.load_scene(
        {
            **BASE,
            "effects": {"clearance": ["B"], "friction": friction, "gravity": gravity},
            "parameters": {"friction_coefficient": 0.05},
            "run": {"cycles": 2},
            "record": {"samples_per_period": 200, "variables": ["clearance_x", "driver_work"]},
        }
    )
    assert lean_against_reference(scene) < 1e-12


@pytest.mark.chaotic
def test_same_events_as_the_reference(monkeypatch):
    """Integrated by the same solver (scipy's DOP853, rtol 1e-10) over 3 cycles, the lean and
    the reference right-hand sides give the same 65 events, and their records differ by less
    than the solver's own tolerance makes a run differ (the reference at rtol 1e-10 against
    1e-11): two correct right-hand sides, rounded differently, are two correct integrations.
    (One processor measured 3.7e-7 of each state's range against the tolerance's 1.1e-5,
    another 2.6e-5: the 65 impacts amplify rounding differently per instruction set.)"""
    scene = workbench.load_scene(
        {
            **BASE,
            "effects": {"friction": "coulomb"},
            "parameters": {"friction_coefficient": 0.05},
            "run": {"cycles": 3},
            "record": {"samples_per_period": 400, "variables": ["clearance_x"]},
        }
    )
    _, whole = same_run_as_reference(monkeypatch, scene, rtol=1e-10, early=0.0)
    prepared = prepare(scene)
    problem, t = prepared.problem, prepared.times
    loose, tight = (
        integrate(problem, t, method="scipy:DOP853", rtol=rtol, atol=rtol)
        for rtol in (1e-10, 1e-11)
    )
    assert loose.stats["events"] == tight.stats["events"] == 65
    tolerance = float((np.abs(loose.Y - tight.Y) / np.ptp(tight.Y, axis=0)).max())
    assert whole < 10 * tolerance, (whole, tolerance)
