"""A torque-driven crank of a declared linkage (issue 42, item 1's option): its keys, checked in
one line naming the key; the motor's linear characteristic; its TOML round trip; the tables of
constant-speed cranks unchanged (so are their models' names); what is refused (a motor among
several cranks, a run in cycles, two clearances besides the motor); and its dynamics: the
crank's angle and speed as states, the energy balance of the four-bar with ideal joints and
with the clearance at B, and a motor-driven pendulum against scipy's solution of its ODE."""

import copy
import importlib
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from scipy.integrate import simpson, solve_ivp

import workbench
from workbench import load_scene
from workbench._errors import SceneError
from workbench.models._declaration import Crank, from_table, to_table
from workbench.models._declare import parse_mechanism
from workbench.run import prepare

MECHANISMS = Path(__file__).resolve().parents[2] / "studies" / "mechanisms"
#: a DC motor on the four-bar's crank: 2 N m at stall, 40 rad s-1 without load
MOTOR = {"drive": "torque", "stall_torque": 2.0, "no_load_speed": 40.0}


def fourbar(**crank) -> dict:
    """The [mechanism] table of studies/mechanisms/fourbar.toml, its crank's table updated."""
    with open(MECHANISMS / "fourbar.toml", "rb") as f:
        table = tomllib.load(f)["mechanism"]
    table["cranks"][0].update(crank)
    return table


def test_a_motor_follows_its_linear_characteristic():
    crank = parse_mechanism(fourbar(**MOTOR)).cranks[0]
    assert crank.torque_driven
    # tau = T_s (1 - w / w_0): T_s at rest, T_s / 2 at half the no-load speed, 0 at it
    assert crank.motor_torque(0.0) == 2.0
    assert crank.motor_torque(20.0) == pytest.approx(1.0, rel=1e-15)
    assert crank.motor_torque(40.0) == 0.0
    assert crank.motor_torque(-40.0) == pytest.approx(4.0, rel=1e-15)  # driven backwards
    constant = parse_mechanism(fourbar(drive="torque", stall_torque=1.5)).cranks[0]
    assert constant.no_load_speed == math.inf
    assert parse_mechanism(fourbar(drive="torque", stall_torque=1.5, no_load_speed=math.inf))
    assert constant.motor_torque(0.0) == constant.motor_torque(1e3) == 1.5


def test_the_default_drive_is_the_constant_speed_and_its_table_is_unchanged():
    linkage = parse_mechanism(fourbar())
    assert not linkage.cranks[0].torque_driven
    assert linkage.cranks[0].drive == "speed"
    # the table a constant-speed crank writes is the one it wrote before the drive existed: the
    # model's name (the digest of the table) and the scenes' digests stay what they were
    assert set(to_table(linkage)["cranks"][0]) == {"link", "pivot", "omega", "angle0"}
    assert parse_mechanism(fourbar(drive="speed")) == linkage


@pytest.mark.parametrize("motor", [MOTOR, {"drive": "torque", "stall_torque": -0.5}])
def test_a_torque_driven_crank_round_trips_through_toml(motor):
    linkage = parse_mechanism(fourbar(**motor))
    text = tomli_w.dumps({"mechanism": to_table(linkage)})
    assert from_table(tomllib.loads(text)["mechanism"]) == linkage


ERRORS = {
    "unknown_drive": (
        {"drive": "current"},
        "drive",
        "got 'current'; a crank's drive is one of 'speed', 'torque'",
    ),
    "torque_without_stall_torque": (
        {"drive": "torque"},
        "stall_torque",
        'missing; a crank with drive = "torque" declares its motor\'s stall torque (N m)',
    ),
    "stall_torque_not_a_number": (
        {**MOTOR, "stall_torque": "2 N m"},
        "stall_torque",
        "got '2 N m'; must be a finite number (N m)",
    ),
    "zero_no_load_speed": (
        {**MOTOR, "no_load_speed": 0.0},
        "no_load_speed",
        "got 0.0; a motor's no-load speed is positive (rad s-1), or inf for a constant torque",
    ),
    "no_load_speed_not_a_number": (
        {**MOTOR, "no_load_speed": "fast"},
        "no_load_speed",
        "got 'fast'; a motor's no-load speed is positive (rad s-1), or inf for a constant torque",
    ),
    "negative_no_load_speed": (
        {**MOTOR, "no_load_speed": -40.0},
        "no_load_speed",
        "got -40.0; a motor's no-load speed is positive (rad s-1), or inf for a constant torque",
    ),
    "nan_no_load_speed": (
        {**MOTOR, "no_load_speed": math.nan},
        "no_load_speed",
        "got nan; a motor's no-load speed is positive (rad s-1), or inf for a constant torque",
    ),
    "stall_torque_on_a_constant_speed_crank": (
        {"stall_torque": 2.0},
        "stall_torque",
        'got 2.0; only a torque-driven crank has it (set drive = "torque", or remove it)',
    ),
    "no_load_speed_on_a_constant_speed_crank": (
        {"drive": "speed", "no_load_speed": 40.0},
        "no_load_speed",
        'got 40.0; only a torque-driven crank has it (set drive = "torque", or remove it)',
    ),
}


@pytest.mark.parametrize("case", ERRORS)
def test_each_error_is_one_line_naming_the_key(case):
    crank, field, says = ERRORS[case]
    key = f"mechanism.cranks[crank].{field}"
    with pytest.raises(SceneError) as info:
        parse_mechanism(fourbar(**crank))
    assert info.value.key == key
    assert str(info.value) == f"{key}: {says}"


def test_python_declares_the_same_torque_driven_crank():
    crank = Crank(link="crank", pivot="O2", omega=31.41592653589793, **MOTOR)
    assert parse_mechanism(fourbar(**MOTOR)).cranks[0] == crank


def test_a_motor_drives_a_linkage_of_one_crank():
    with open(MECHANISMS / "ninebar.toml", "rb") as f:
        table = tomllib.load(f)["mechanism"]
    table["cranks"][0].update(MOTOR)
    name = table["cranks"][0]["link"]
    with pytest.raises(SceneError) as info:
        workbench.load_scene({"mechanism": table})
    assert str(info.value) == (
        f"mechanism.cranks[{name}].drive: got 'torque' with 2 cranks; a motor drives a linkage "
        "of one crank (declare the others' speeds, or drive this one at its speed: "
        'drive = "speed")'
    )


def test_a_motor_driven_linkage_has_no_forcing_period():
    """The crank's speed is a state: no period 2 pi / omega to count cycles, strobe or skip
    transients in; the run's length is a duration (s), and a scene in cycles is refused."""
    with pytest.raises(SceneError) as info:
        workbench.load_scene({"mechanism": fourbar(**MOTOR), "run": {"cycles": 2}})
    assert str(info.value) == (
        "run.cycles: this model has no forcing period; use run.duration (s) instead"
    )


def test_a_motor_and_two_clearance_joints_are_refused():
    table = fourbar(**MOTOR)
    table["clearances"].append(
        {"joint": "A", "journal": "crank", "bearing": "coupler", "clearance": 0.2e-3}
    )
    with pytest.raises(SceneError) as info:
        workbench.load_scene({"mechanism": table, "run": {"duration": 0.1}})
    assert str(info.value) == (
        "effects.clearance: got ['B', 'A']; with a motor-driven crank (a free coordinate too) "
        "at most 1 joint has a clearance at once"
    )
    assert workbench.load_scene(
        {"mechanism": table, "run": {"duration": 0.1}, "effects": {"clearance": ["A"]}}
    )


def test_verify_refuses_a_motor_driven_crank():
    from workbench.verification._mechanisms import declared_mechanism

    scene = load_scene({"mechanism": fourbar(**MOTOR), "run": {"duration": 0.1}})
    with pytest.raises(SceneError) as info:
        declared_mechanism(scene)
    assert str(info.value) == (
        "mechanism.cranks[crank].drive: got 'torque'; the exudyn model drives its cranks at "
        'constant speeds: verify the linkage with drive = "speed"'
    )


# ================================================================================================
# the dynamics
# ================================================================================================
TIGHT = {"method": "dop853", "rtol": 1e-11, "atol": 1e-11}


def run(table, effects, duration=0.5, solver=TIGHT):
    return workbench.simulate(
        {
            "mechanism": table,
            "effects": effects,
            "run": {"duration": duration},
            "record": {"dt": 1e-3},
            "solver": solver,
        }
    )


def energy_residual(ds):
    """Largest |change of kinetic + potential energy - (driver work - dissipation)| (J)."""
    energy = ds.kinetic_energy + ds.potential_energy
    return float(abs((energy - energy[0]) - (ds.driver_work - ds.dissipated_energy)).max())


@pytest.fixture(scope="module")
def ideal():
    return run(fourbar(**MOTOR), {"clearance": []})


def test_the_crank_angle_and_speed_are_states_with_their_units(ideal):
    assert ideal.attrs["run_status"] == "ok"
    assert ideal.crank_angle_crank.attrs["units"] == "rad"
    assert ideal.crank_speed_crank.attrs["units"] == "rad s-1"
    assert float(ideal.crank_angle_crank[0]) == 0.0
    assert float(ideal.crank_speed_crank[0]) == pytest.approx(31.41592653589793, rel=1e-15)
    # the recorded torque is the motor's at the recorded speed
    law = 2.0 * (1.0 - ideal.crank_speed_crank / 40.0)
    assert float(abs(ideal.torque.sel(crank="crank") - law).max()) <= 1e-12


def test_ideal_joints_driver_work_is_the_energy_change(ideal):
    work = float(abs(ideal.driver_work).max())
    assert work > 0.5  # J: the motor speeds the linkage up from 31.4 rad s-1 towards 40
    assert float(ideal.crank_speed_crank[-1]) > 33.0
    assert energy_residual(ideal) <= 1e-8 * work
    # the work is the integral of tau theta_dot: Simpson's rule on the 1 ms records (the power's
    # harmonics of the turn, 31 rad s-1 and above, leave it ~1e-7 of the work off)
    power = (ideal.torque.sel(crank="crank") * ideal.crank_speed_crank).values
    assert simpson(power, dx=1e-3) == pytest.approx(float(ideal.driver_work[-1]), rel=1e-6)


def test_through_impacts_at_b_the_energy_balances():
    ds = run(fourbar(**MOTOR), {"clearance": ["B"]})
    assert ds.attrs["run_status"] == "ok"
    assert float(ds.penetration.max()) > 0  # the journal hits the bearing's wall
    onsets = np.sum(np.diff((ds.penetration.sel(joint="B").values > 0).astype(int)) == 1)
    assert onsets >= 3
    work = float(abs(ds.driver_work).max())
    assert energy_residual(ds) <= 1e-6 * work


# a crank alone, pivoted at O by a joint that may have a clearance: with an ideal joint a
# pendulum driven by its motor, I_O theta'' = tau(theta') - m g r cos(theta) (gravity along -Y)
PENDULUM = {
    "name": "driven_pendulum",
    "ground": {"O": [0.0, 0.0]},
    "links": [
        {
            "name": "arm",
            "points": {"O": [0.0, 0.0]},
            "mass": 0.3,
            "inertia": 2.0e-4,
            "centre_of_mass": [0.05, 0.0],
        }
    ],
    "cranks": [{"link": "arm", "pivot": "O", "omega": 2.0, **MOTOR, "stall_torque": 0.2}],
    "clearances": [{"joint": "O", "journal": "arm", "bearing": "ground", "clearance": 0.2e-3}],
}


def test_a_motor_driven_pendulum_follows_its_ode():
    ds = run(copy.deepcopy(PENDULUM), {"clearance": []}, duration=1.0)
    m, r, inertia, g = 0.3, 0.05, 2.0e-4 + 0.3 * 0.05**2, 9.81  # I about O (kg m2)

    def f(t, y):
        tau = 0.2 * (1.0 - y[1] / 40.0)
        return [y[1], (tau - m * g * r * math.cos(y[0])) / inertia]

    ref = solve_ivp(f, (0, 1.0), [0.0, 2.0], t_eval=ds.time.values, rtol=1e-12, atol=1e-12)
    angle = ds.crank_angle_arm.values
    assert np.ptp(angle) > 2 * math.pi  # it turns over the top, not only swings
    assert np.abs(angle - ref.y[0]).max() <= 1e-8
    assert np.abs(ds.crank_speed_arm.values - ref.y[1]).max() <= 1e-7


def test_an_unknown_body_is_named_with_the_kinds_in_the_plural():
    table = copy.deepcopy(fourbar())
    table["clearances"][0]["bearing"] = "rocket"
    with pytest.raises(SceneError) as info:
        parse_mechanism(table)
    assert str(info.value) == (
        "mechanism.clearances[B].bearing: got 'rocket', no link or slider of that name; the "
        "links and sliders: crank, coupler, rocker"
    )


@pytest.mark.parametrize(
    ("effects", "energy"),
    [
        ({"clearance": []}, True),
        ({"clearance": ["B"], "friction": "none"}, True),
        ({"clearance": ["B"], "friction": "coulomb"}, False),
        ({"clearance": ["B"], "friction": "lugre"}, True),
    ],
)
def test_the_lean_right_hand_side_equals_the_record_time_one(effects, energy):
    """At random states (crank angle and speed, clearance vectors in and out of contact), the
    lean right-hand side equals the record-time evaluation's (the motor's torque in both)."""
    table = fourbar(**MOTOR)
    table["clearances"][0]["friction_coefficient"] = 0.1
    scene = load_scene(
        {
            "mechanism": table,
            "effects": effects,
            "run": {"duration": 0.1},
            "record": {"dt": 1e-3, "variables": ["driver_work"] if energy else ["torque"]},
        }
    )
    problem = prepare(scene).problem
    hooks = importlib.import_module(problem.hooks)
    nj = len(effects["clearance"])
    nf = 2 * nj + 1
    c = 0.5e-3  # m
    rng = np.random.default_rng(7)
    n = problem.y0.size
    assert n >= 2 * nf
    for _ in range(100):
        y = np.zeros(n)
        y[2 * nj], y[nf + 2 * nj] = rng.uniform(0, 2 * np.pi), rng.uniform(-40, 40)
        if nj:
            angle, e = rng.uniform(0, 2 * np.pi), c * rng.uniform(0.9, 1.02)
            y[0:2] = e * np.cos(angle), e * np.sin(angle)
            y[nf : nf + 2] = rng.normal(size=2) * 8 * c
        aux = rng.uniform(0, 0.01, problem.aux0.size) * (rng.uniform() > 0.2)
        lean, record = np.zeros(n), np.zeros(n)
        work = np.zeros(problem.work_size)
        code = hooks.rhs(0.0, y.copy(), problem.p, problem.ip, aux, work, lean)
        ref = hooks.rhs_reference(
            0.0, y.copy(), problem.p, problem.ip, aux, np.zeros(problem.work_size), record
        )
        assert code == ref
        assert np.abs(lean - record).max() <= 1e-12 * np.abs(record).max()
