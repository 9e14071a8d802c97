"""The nine-bar mechanism: spec kinematics, energy balance, clearance limit, backends, effects."""

import math

import numpy as np
import pytest
from helpers import ENERGY, IDEAL_SLIDER_PEAKS, energy_residual

import workbench
from workbench.models import get_model
from workbench.models._mechanism_layouts import JOINT
from workbench.models.ninebar import _dynamics as dyn
from workbench.models.ninebar._geometry import geometry_array
from workbench.models.ninebar._kinematics import N_POINTS, PT_E, kinematics

SCENE = "studies/ninebar.toml"


def kin(q, qd=None):
    qd = np.zeros(6) if qd is None else qd
    out = (
        np.empty((8, 3)),
        np.empty((N_POINTS, 2)),
        np.empty((8, 3, 6)),
        np.empty((N_POINTS, 2, 6)),
        np.empty((8, 3)),
        np.empty((N_POINTS, 2)),
        np.empty((8, 3)),
        np.empty((N_POINTS, 2)),
    )
    code = kinematics(np.asarray(q, float), np.asarray(qd, float), geometry_array(), *out)
    return code, out


def test_initial_configuration_matches_spec():
    code, (pos, pts, *_) = kin(np.zeros(6))
    assert code == 0
    angles = np.degrees(pos[:, 2])
    np.testing.assert_allclose(
        angles[[1, 2, 4, 5, 6]], [73.351, 141.065, -44.914, 22.206, -157.529], atol=0.01
    )
    np.testing.assert_allclose(
        pts[[0, 2, 4, 5, 6, 7]],
        [
            [0.0450, 0],
            [0.5250, 0],
            [0.1384, 0.3123],
            [-0.1671, 0.1876],
            [-0.3231, 0.4784],
            [-0.6336, 0.3500],
        ],
        atol=1e-4,
    )
    geo = geometry_array()
    assert geo[12] - (pts[PT_E, 0] - geo[10]) == pytest.approx(0.1066, abs=1e-4)


@pytest.mark.parametrize(("omega", "vmax", "amax"), IDEAL_SLIDER_PEAKS)
def test_ideal_slider_peaks_and_stroke(omega, vmax, amax):
    ds = workbench.simulate(
        {
            "model": {"name": "ninebar"},
            "effects": {"clearance": []},
            "parameters": {"omega": omega},
            "run": {"cycles": 1},
            "record": {"samples_per_period": 3600},
        }
    )
    assert ds.attrs["solver_steps"] == 0  # inverse dynamics only, nothing integrated
    assert float(abs(ds.slider_velocity).max()) == pytest.approx(vmax, rel=0.01)
    assert float(abs(ds.slider_acceleration).max()) == pytest.approx(amax, rel=0.01)
    s = ds.slider_position
    assert float(s.max() - s.min()) == pytest.approx(0.3722, abs=0.5e-3)
    phase = np.degrees(omega * ds.time.values)
    assert phase[int(np.argmin(s.values))] == pytest.approx(304.9, abs=0.2)
    assert phase[int(np.argmax(s.values))] == pytest.approx(147.0, abs=0.2)


def test_closure_and_derivatives_against_finite_differences():
    rng = np.random.default_rng(1)
    for _ in range(20):
        q = np.concatenate([rng.uniform(-np.pi, np.pi, 2), rng.uniform(-3e-4, 3e-4, 4)])
        qd = rng.normal(size=6) * np.array([8, 8, 0.05, 0.05, 0.05, 0.05])
        code, (pos, pts, J, Jp, gam, _, vel, _) = kin(q, qd)
        assert code == 0
        # the loop P closes from both sides to round-off: |P - B'| = L3
        geo = geometry_array()
        assert abs(np.hypot(*(pts[4] - pts[3])) - geo[2]) < 1e-12
        np.testing.assert_allclose(vel, J @ qd, rtol=0, atol=1e-13)  # the stored velocity pass
        h = 1e-7
        for col in range(6):
            e = np.zeros(6)
            e[col] = h
            _, (pp, *_r) = kin(q + e)
            _, (pm, *_r) = kin(q - e)
            fd = (pp - pm) / (2 * h)
            np.testing.assert_allclose(J[:, :, col], fd, rtol=1e-6, atol=1e-8)
        # bias acceleration: d/dt (J qd) along q(t) = q + qd t, with qdd = 0
        tau = 1e-5
        _, (_, _, Jf, *_r) = kin(q + qd * tau, qd)
        _, (_, _, Jb, *_r) = kin(q - qd * tau, qd)
        fd = ((Jf - Jb) @ qd) / (2 * tau)
        np.testing.assert_allclose(gam, fd, rtol=1e-5, atol=1e-6)


def test_absurd_clearance_fails_cleanly():
    code, _ = kin([0, 0, 1.0, 0, 0, 0])
    assert code != 0


@pytest.mark.parametrize("joints", [["A"], ["B"], ["A", "B"]], ids=["A", "B", "AB"])
@pytest.mark.parametrize("friction", ["none", "coulomb", "lugre"])
def test_energy_balance(joints, friction):
    """W_driver - dissipated - dKE - dPE (gravity and contact elastic) over 5 cycles.

    The net driver work over whole cycles is small (it equals the dissipation), while the work
    swings by about 20 J within each cycle; the residual is held below 1e-4 of that swing and
    below 1e-4 of the net work whenever the net work exceeds 0.5 J."""
    base = workbench.load_scene(SCENE)
    ds = workbench.simulate(
        base.replace(
            effects={"clearance": joints, "friction": friction},
            run={"cycles": 5, "transient_cycles": 0},
            record={
                "samples_per_period": 100,
                "variables": ENERGY,
            },
        )
    )
    residual = energy_residual(ds)
    worst = float(abs(residual).max())
    swing = float(abs(ds.driver_work).max())
    net = abs(float(ds.driver_work[-1]))
    assert worst < 1e-4 * swing
    if net > 0.5:
        assert worst < 1e-4 * net
    assert float(ds.dissipated_energy[-1]) >= 0


def test_torques_converge_to_ideal_as_clearance_vanishes():
    """rtol 1e-6, 1 recorded cycle after 1, omega 2.5 pi, no friction: the rms difference from
    the ideal torques falls with the clearance, below 1 % of the ideal peak at 1 um (the
    measured rms at 100, 10, 1 um, with their spread over chaotic realisations: README, "The
    nine-bar model")."""
    base = workbench.load_scene(SCENE)
    common = {
        "run": {"cycles": 1, "transient_cycles": 1},
        "record": {"samples_per_period": 200, "variables": ["torque"]},
    }
    ideal = workbench.simulate(
        base.replace(effects={"clearance": [], "friction": "none"}, **common)
    )
    rms = []
    for c in (100e-6, 10e-6, 1e-6):
        ds = workbench.simulate(
            base.replace(
                effects={"clearance": ["A", "B"], "friction": "none"},
                parameters={**base.parameters, "clearance": c},
                **common,
            )
        )
        rms.append(float(np.sqrt(((ds.torque - ideal.torque) ** 2).mean())))
    assert rms[0] > 2 * rms[1] and rms[1] > 4 * rms[2]
    assert rms[2] < 0.01 * float(abs(ideal.torque).max())


def test_compiled_and_scipy_agree_over_one_cycle():
    """At omega = pi the motion stays regular over a cycle, so two backends at rtol 1e-10 agree
    to 1e-3 c (README, "The nine-bar model"). At the default omega = 2.5 pi they separate
    exponentially (chaos) and part within a tenth of a second, as any two correct solvers do."""
    base = workbench.load_scene(SCENE)
    runs = [
        workbench.simulate(
            base.replace(
                parameters={**base.parameters, "omega": math.pi},
                solver={"method": m, "rtol": 1e-10, "atol": 1e-10},
                run={"cycles": 1, "transient_cycles": 0},
                record={"samples_per_period": 400, "variables": ["clearance_x", "clearance_y"]},
            )
        )
        for m in ("dop853", "scipy:DOP853")
    ]
    c = 0.5e-3
    for var in ("clearance_x", "clearance_y"):
        assert float(abs(runs[0][var] - runs[1][var]).max()) < 1e-3 * c
    assert runs[0].attrs["solver_events"] == runs[1].attrs["solver_events"]


def test_effects_decide_the_state():
    m = get_model("ninebar")
    params = m.default_parameters()

    def n_states(joints, friction, variables=("torque",)):
        effects = {"clearance": tuple(joints), "friction": friction, "gravity": True}
        return m.problem(params, effects, {}, variables).y0.size

    assert n_states(["A"], "coulomb") == 4
    assert n_states(["A"], "lugre") == 5
    assert n_states(["A", "B"], "lugre") == 10
    assert n_states(["B"], "none") == 4
    assert n_states([], "none") == 0
    assert n_states(["A"], "coulomb", ("driver_work",)) == 6  # energy quadratures on request


def test_dataset_holds_only_requested_variables_with_units():
    base = workbench.load_scene(SCENE)
    ds = workbench.simulate(
        base.replace(
            effects={"clearance": ["B"], "friction": "coulomb"},
            run={"cycles": 1},
            record={"samples_per_period": 50, "variables": ["contact_force", "torque"]},
        )
    )
    assert set(ds.data_vars) == {"contact_force", "torque"}
    assert list(ds.joint.values) == ["B"]
    assert list(ds.crank.values) == ["1", "4"]
    for v in ds.variables.values():
        assert v.attrs["units"] and v.attrs["long_name"]
    with pytest.raises(workbench.SceneError, match="lugre_z"):
        base.replace(record={"variables": ["lugre_z"]})


def test_clearance_larger_than_bearing_is_rejected():
    with pytest.raises(workbench.SceneError, match="parameters.clearance"):
        workbench.load_scene({"model": {"name": "ninebar"}, "parameters": {"clearance": 0.02}})


def test_stiffness_from_eq4_matches_spec_table():
    m = get_model("ninebar")
    for c, k in [
        (0.5e-3, 6.61e10),
        (0.1e-3, 1.509e11),
        (0.08e-3, 1.689e11),
        (0.02e-3, 3.388e11),
        (0.01e-3, 4.793e11),
    ]:
        params = {**m.default_parameters(), "clearance": c}
        prob = m.problem(
            params, {"clearance": ("A",), "friction": "none", "gravity": True}, {}, ("torque",)
        )
        assert prob.p[dyn.P.joint + JOINT.k] == pytest.approx(k, rel=2e-3)
