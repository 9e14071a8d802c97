"""A torque-driven crank in a declaration (issue 42, item 1's option): its keys, checked in one
line naming the key; the motor's linear characteristic; its TOML round trip; the tables of
constant-speed cranks unchanged (so are their models' names); and the refusal, in one line, of a
scene that would integrate one (its dynamics are not generated yet)."""

import copy
import math
import tomllib
from pathlib import Path

import pytest
import tomli_w

import workbench
from workbench._errors import SceneError
from workbench.models._declaration import Crank, from_table, to_table
from workbench.models._declare import parse_mechanism

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


def test_a_scene_with_a_torque_driven_crank_is_refused_in_one_line():
    with pytest.raises(SceneError) as info:
        workbench.load_scene({"mechanism": fourbar(**MOTOR)})
    assert str(info.value) == (
        "mechanism.cranks[crank].drive: got 'torque'; the dynamics of a torque-driven crank are "
        'not available yet (only declared): drive it at its constant speed (drive = "speed")'
    )


def test_an_unknown_body_is_named_with_the_kinds_in_the_plural():
    table = copy.deepcopy(fourbar())
    table["clearances"][0]["bearing"] = "rocket"
    with pytest.raises(SceneError) as info:
        parse_mechanism(table)
    assert str(info.value) == (
        "mechanism.clearances[B].bearing: got 'rocket', no link or slider of that name; the "
        "links and sliders: crank, coupler, rocker"
    )
