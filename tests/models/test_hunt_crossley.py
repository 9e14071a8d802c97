"""The Hunt-Crossley contact law (``[effects] contact = "hunt_crossley"``): a dissipative law
without memory beside the default Lankarani-Nikravesh one.

F_n = K delta^n (1 + 1.5 alpha delta_dot) (Hunt & Crossley 1975, J. Appl. Mech. 42:440; the form
of Marhefka & Orin 1999). A free impact rebounds with the exact e(alpha v) of
:func:`workbench.models.contact.hunt_crossley_restitution`, which is Hunt & Crossley's
e = 1 - alpha v to first order in alpha v and 1 - alpha v + (alpha v)^2 to second (the series of
the phase-plane integral; the derivation is in :mod:`workbench.models.contact`).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import ENERGY, energy_residual, flow_map_copies, flow_map_tangent
from test_ninebar_lean import lean_against_reference

import workbench
from workbench.cli import main
from workbench.models.contact import (
    hertz_internal_stiffness,
    hunt_crossley_damping,
    hunt_crossley_restitution,
)

NINEBAR = "studies/ninebar.toml"


def free_impact(speed: float, contact: str = "hunt_crossley", **parameters) -> float:
    """The effective restitution of the free journal launched radially 1e-3 * speed s from
    the wall (m s-1), recorded after its one contact."""
    gap = min(0.5e-3, speed * 1e-3)
    duration = gap / speed + 5e-4 * (0.5 / speed) ** 0.2  # reach the wall, one contact
    ds = workbench.simulate(
        {
            "model": {"name": "free_journal"},
            "effects": {"contact": contact},
            "parameters": {"speed": speed, **parameters},
            "initial": {"x": 0.5e-3 - gap},
            "run": {"duration": duration},
            "record": {"dt": duration / 300},
            # positions to 1e-14 c: the penetration of a 2 mm/s impact is ~4e-7 m
            "solver": {"rtol": 1e-12, "atol": 1e-14},
        }
    )
    assert ds.attrs["solver_events"] == 2  # one contact: onset and end, located as under LN
    assert float(ds.onset_velocity[-1]) == pytest.approx(speed, rel=1e-3)
    return -float(ds.vx[-1]) / speed


@pytest.mark.parametrize(
    ("alpha", "speed", "exponent"),
    [(47.5, 2e-3, 1.5), (47.5, 5e-3, 1.5), (0.111, 1.0, 1.5), (2.0, 0.1, 1.0)],
)
def test_free_impact_rebounds_with_the_exact_restitution(alpha, speed, exponent):
    """The rebound of a radial impact against the closed form, which holds for any mass,
    stiffness and exponent (here also n = 1), to 1e-8: the first-order 1 - alpha v is off by
    (alpha v)^2 ~ 1e-2 at these impacts."""
    e = free_impact(speed, hunt_crossley_damping=alpha, contact_exponent=exponent)
    assert e == pytest.approx(hunt_crossley_restitution(alpha, speed), rel=1e-8)


@pytest.mark.parametrize("alpha_v", [2e-3, 1e-2])
def test_restitution_at_low_impact_velocity_is_one_minus_alpha_v(alpha_v):
    """Hunt & Crossley's e = 1 - alpha v for small alpha v (the slope of e(v) at v -> 0 is
    alpha; Simbody's HuntCrossleyForce reads its dissipation constant so): the simulated
    rebound departs from it by (alpha v)^2, the series' next term, within 5 % (its third-order
    term is ~alpha v of it; measured 0.998 and 0.989)."""
    alpha, speed = 1.0, alpha_v
    e = free_impact(speed, hunt_crossley_damping=alpha)
    assert (e - (1.0 - alpha_v)) / alpha_v**2 == pytest.approx(1.0, abs=0.05)


def test_the_default_damping_gives_steel_restitution_at_one_metre_per_second():
    """The default alpha = 0.111 s/m is the constant whose impact at 1 m/s rebounds with the
    LN default c_e = 0.9 (the exact inverse gives 0.11099)."""
    model = workbench.models.get_model("ninebar")
    alpha = model.default_parameters()["hunt_crossley_damping"]
    assert alpha == pytest.approx(hunt_crossley_damping(0.9, 1.0), rel=1e-3)
    assert free_impact(1.0, hunt_crossley_damping=alpha) == pytest.approx(0.9, abs=1e-4)


def _short(contact: str, **parameters) -> workbench.Scene:
    base = workbench.load_scene(NINEBAR)
    return base.replace(
        effects={**base.effects, "contact": contact},
        parameters={**base.parameters, **parameters},
        run={"cycles": 1, "transient_cycles": 0},
        record={
            "samples_per_period": 400,
            "variables": [
                "clearance_x", "clearance_y", "clearance_vx", "clearance_vy", "penetration",
                "contact_force", *ENERGY,
            ],
        },
    )  # fmt: skip


def test_the_force_depends_on_penetration_and_rate_only():
    """At every record of a nine-bar run (impacts with many onset velocities) the contact force
    is K delta^n (1 + 1.5 alpha delta_dot) of that record's penetration and rate: the same
    penetration and rate give the same force whatever the contact's onset velocity. The run
    has no discrete state at all (the LN run holds one onset velocity per joint), and the same
    check fails under LN, whose damping scales with the onset velocity."""
    alpha = 0.5
    runs = {
        c: _short(c, hunt_crossley_damping=alpha) for c in ("hunt_crossley", "lankarani_nikravesh")
    }
    assert workbench.prepare(runs["hunt_crossley"]).problem.aux0.size == 0
    assert workbench.prepare(runs["lankarani_nikravesh"]).problem.aux0.size == 2
    worst = {}
    for contact, scene in runs.items():
        ds = workbench.simulate(scene)
        delta = ds.penetration.values
        inside = delta > 0
        assert inside[:, 0].sum() > 50 and inside[:, 1].sum() > 50  # records in contact
        x, y = ds.clearance_x.values[inside], ds.clearance_y.values[inside]
        rate = (x * ds.clearance_vx.values[inside] + y * ds.clearance_vy.values[inside]) / (
            np.hypot(x, y)
        )
        K = hertz_internal_stiffness(10e-3, 0.5e-3, 207e9, 0.3)
        law = np.maximum(K * delta[inside] ** 1.5 * (1.0 + 1.5 * alpha * rate), 0.0)
        force = ds.contact_force.values[inside]
        worst[contact] = float(np.abs(force - law).max() / np.abs(force).max())
    assert worst["hunt_crossley"] < 1e-12
    assert worst["lankarani_nikravesh"] > 1e-2


def test_a_run_is_bit_identical_run_to_run_and_differs_from_ln():
    scene = _short("hunt_crossley")
    first, second = workbench.simulate(scene), workbench.simulate(scene)
    for name in first.data_vars:
        np.testing.assert_array_equal(first[name].values, second[name].values)
    assert first.attrs["solver_events"] == second.attrs["solver_events"] > 0
    ln = workbench.simulate(_short("lankarani_nikravesh"))
    assert not np.array_equal(first.contact_force.values, ln.contact_force.values)
    # the default is the Lankarani-Nikravesh law
    default = workbench.load_scene(NINEBAR)
    assert default.effects["contact"] == "lankarani_nikravesh"
    assert workbench.prepare(default).problem.aux0.size == 2


@pytest.mark.parametrize(
    ("friction", "alpha", "rtol"),
    [
        ("none", 47.5, 1e-6),
        ("coulomb", 47.5, 1e-6),
        ("lugre", 47.5, 1e-6),
        ("coulomb", 0.111, 1e-8),
    ],
)
def test_energy_balance(friction, alpha, rtol):
    """As test_ninebar's balance under LN, with the same tolerance: W_driver - dissipated -
    dKE - dPE over 5 cycles within 1e-4 of the driver work's swing (and of the net work where
    it exceeds 0.5 J), at the route's alpha = 47.5 s/m and the scene's rtol, and at the default
    0.111 s/m. With the default the journals bounce 5 000-7 000 times in the 5 cycles (LN:
    1 100-1 700): at rtol 1e-6 the residual was 8e-5 to 1.7e-4 J, above 1e-4 of the net work,
    and it falls with rtol (2.6e-5 and 1.5e-5 J at 1e-7, 9e-6 and 1e-6 J at 1e-8, no friction
    and Coulomb): the integration's error, not the balance's, so the default is held at 1e-8."""
    base = workbench.load_scene(NINEBAR)
    ds = workbench.simulate(
        base.replace(
            effects={"clearance": ["A", "B"], "friction": friction, "contact": "hunt_crossley"},
            parameters={**base.parameters, "hunt_crossley_damping": alpha},
            solver={**base.solver, "rtol": rtol, "atol": rtol},
            run={"cycles": 5, "transient_cycles": 0},
            record={"samples_per_period": 100, "variables": ENERGY},
        )
    )
    residual = energy_residual(ds)
    worst = float(abs(residual).max())
    net = abs(float(ds.driver_work[-1]))
    assert worst < 1e-4 * float(abs(ds.driver_work).max())
    if net > 0.5:
        assert worst < 1e-4 * net
    assert float(ds.dissipated_energy[-1]) > 0


def test_slider_crank_energy_balance():
    ds = workbench.simulate(
        {
            "model": {"name": "slider_crank"},
            "effects": {"friction": "coulomb", "contact": "hunt_crossley"},
            "parameters": {"friction_coefficient": 0.05},
            "solver": {"rtol": 1e-9, "atol": 1e-9},
            "run": {"cycles": 1},
            "record": {"samples_per_period": 4000, "variables": ENERGY},
        }
    )
    residual = energy_residual(ds)
    assert float(abs(residual).max()) < 1e-4 * float(abs(ds.driver_work).max())
    assert float(ds.dissipated_energy[-1]) > 0


@pytest.mark.parametrize("friction", ["coulomb", "lugre"])
def test_lean_rhs_equals_the_reference(friction):
    """The nine-bar's lean hook against its record-time evaluation under Hunt-Crossley (see
    test_ninebar_lean), at the route's damping so that the damping part is large."""
    base = workbench.load_scene(NINEBAR)
    scene = base.replace(
        effects={**base.effects, "friction": friction, "contact": "hunt_crossley"},
        parameters={**base.parameters, "hunt_crossley_damping": 47.5},
        run={"duration": 0.2, "transient": 0.0},
        record={"dt": 1e-3, "variables": ["clearance_x", "driver_work"]},
    )
    assert lean_against_reference(scene) < 1e-12


def test_tangent_map_through_impacts_without_memory_matches_copies():
    """A free journal launched obliquely under Hunt-Crossley: impacts with no discrete state
    (the problem has none; the force is continuous at onset and end, so the saltation is the
    identity). The tangent map equals the shared-step finite differences of the flow map, as
    under LN (test_lyapunov)."""
    scene = workbench.load_scene(
        {
            "model": {"name": "free_journal"},
            "effects": {"contact": "hunt_crossley"},
            "parameters": {"hunt_crossley_damping": 1.0},
            "initial": {"vy": 0.2},
            "run": {"duration": 0.01},
        }
    )
    pb = workbench.prepare(scene).problem
    assert pb.aux0.size == 1 and pb.aux_scale[0] == np.inf  # the last onset's record only
    M, _, events = flow_map_tangent(pb, 0.006, 1e-11)
    assert events >= 4
    F = flow_map_copies(pb, 0.006, 1e-11)
    assert np.abs(M - F).max() < 1e-4 * np.abs(F).max()


def test_an_unknown_contact_law_is_one_line(tmp_path, capsys):
    with pytest.raises(workbench.SceneError) as err:
        workbench.load_scene({"model": {"name": "ninebar"}, "effects": {"contact": "hertz"}})
    message = str(err.value)
    assert message == (
        "effects.contact: got 'hertz'; allowed: 'lankarani_nikravesh', 'hunt_crossley'"
    )
    scene = tmp_path / "s.toml"
    scene.write_text('[model]\nname = "slider_crank"\n[effects]\ncontact = "hertz"\n')
    assert main(["run", str(scene), "-o", str(tmp_path / "r.nc"), "-q"]) == 2
    err_text = capsys.readouterr().err.strip()
    assert len(err_text.splitlines()) == 1 and "effects.contact" in err_text


def test_the_closed_form_and_its_inverse():
    """hunt_crossley_restitution against its series 1 - alpha v + (alpha v)^2 for small alpha
    v, its large-damping limit e -> 1 / (1.5 alpha v) (the rebound velocity tends to -1 / chi),
    and hunt_crossley_damping as its inverse."""
    for av in (1e-6, 1e-4, 1e-3):
        assert hunt_crossley_restitution(av, 1.0) == pytest.approx(1 - av + av**2, abs=3 * av**3)
    assert hunt_crossley_restitution(1e4, 1.0) == pytest.approx(1 / 1.5e4, rel=1e-6)
    for e, v in ((0.9, 1.0), (0.5, 0.01), (0.99, 2e-3), (0.05, 3.0)):
        alpha = hunt_crossley_damping(e, v)
        assert hunt_crossley_restitution(alpha, v) == pytest.approx(e, rel=1e-12)
    assert hunt_crossley_restitution(0.0, 1.0) == 1.0 and hunt_crossley_damping(1.0, 1.0) == 0.0
    assert math.isclose(hunt_crossley_restitution(0.1, 0.01), 0.999, abs_tol=1.1e-6)
