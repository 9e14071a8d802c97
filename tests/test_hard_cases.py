"""Hard cases stay numerically stable: tiny and large clearances, slow and fast cranks, extreme
restitution and friction, stick-slip, gravity on/off, one or two joints, grazing contact, and a
long run without energy drift. Each case asserts finite results, the energy balance, bounded
penetration and agreement of two tolerances on statistics robust to chaotic divergence.
"""

import math

import numpy as np
import pytest

import workbench

pytestmark = pytest.mark.hard

ENERGY = ["driver_work", "dissipated_energy", "kinetic_energy", "potential_energy"]
STATS = ["eccentricity", "penetration", "contact_force"]


def run(changes: dict, rtol: float, cycles: int = 3, transient: int = 1, duration=None):
    base = workbench.load_scene("studies/ninebar.toml")
    effects = {**base.effects, **changes.get("effects", {})}
    effects["clearance"] = list(effects["clearance"])
    return workbench.simulate(
        base.replace(
            effects=effects,
            parameters={**base.parameters, **changes.get("parameters", {})},
            solver={**base.solver, "rtol": rtol, "atol": rtol},
            run={"cycles": cycles, "transient_cycles": transient}
            if duration is None
            else {"duration": duration, "transient": 0.0},
            record={"samples_per_period": 400, "variables": ENERGY + STATS}
            if duration is None
            else {"dt": duration / 400, "variables": ENERGY + STATS},
        )
    )


def energy_residual(ds) -> tuple[float, float]:
    res = (
        ds.driver_work
        - ds.dissipated_energy
        - (ds.kinetic_energy - ds.kinetic_energy[0])
        - (ds.potential_energy - ds.potential_energy[0])
    )
    return float(abs(res).max()), float(abs(ds.driver_work).max())


def robust(ds, c: float) -> dict[str, float]:
    """Statistics of the recorded cycles that two correct runs share despite chaos."""
    return {
        "mean eccentricity / c": float(ds.eccentricity.mean()) / c,
        "contact time fraction": float((ds.penetration > 0).mean()),
    }


CASES = {
    "clearance 1 um": {"parameters": {"clearance": 1e-6}, "cycles": 2, "transient": 0},
    "clearance 1 mm": {"parameters": {"clearance": 1e-3}},
    "omega 0.1 pi": {"parameters": {"omega": 0.1 * math.pi}},
    "omega 4 pi (Sec. 6)": {"parameters": {"omega": 4 * math.pi, "clearance": 0.5e-3}},
    "restitution 0.3": {"parameters": {"restitution": 0.3}},
    "restitution 0.99": {"parameters": {"restitution": 0.99}},
    "friction 0": {"parameters": {"friction_coefficient": 0.0}},
    "friction 0.25": {"parameters": {"friction_coefficient": 0.25}},
    "lugre low speed (stick-slip)": {
        "effects": {"friction": "lugre"},
        "parameters": {"omega": 0.5 * math.pi},
        "duration": 1.0,  # s; LuGre costs ~4x Coulomb per simulated second (see README)
    },
    "gravity off": {"effects": {"gravity": False}},
    "one joint (A)": {"effects": {"clearance": ["A"]}},
}


@pytest.mark.parametrize("name", list(CASES))
def test_hard_case(name):
    case = CASES[name]
    c = case.get("parameters", {}).get("clearance", 0.5e-3)
    length = {
        "cycles": case.get("cycles", 3),
        "transient": case.get("transient", 1),
        "duration": case.get("duration"),
    }
    coarse = run(case, 1e-6, **length)
    fine = run(case, 1e-8, **length)
    for ds in (coarse, fine):
        for var in ds.data_vars.values():
            assert np.isfinite(var.values).all(), var.name
        worst, swing = energy_residual(ds)
        assert worst < 1e-4 * swing, f"energy residual {worst:.3g} J of {swing:.3g} J"
        # penetration stays a small fraction of the journal radius (Hertz contact valid)
        assert float(ds.penetration.max()) < 0.01 * 10e-3
    a, b = robust(coarse, c), robust(fine, c)
    for key in a:
        assert a[key] == pytest.approx(b[key], abs=0.1), (key, a[key], b[key])


def test_grazing_contact_below_1e6_m_per_s():
    """A journal reaching the wall at 1e-7 m/s: finite, no damping spike. Below the onset
    velocity floor (1e-4 m/s) the damping is that of a 1e-4 m/s impact, so the rebound is
    elastic to within (v / v_floor) (1 - c_e^2) ~ 2e-4 (see workbench.models.contact)."""
    c = 0.5e-3
    ds = workbench.simulate(
        {
            "model": {"name": "free_journal"},
            "parameters": {"speed": 1e-7, "restitution": 0.9},
            "initial": {"x": c - 1e-10},
            "run": {"duration": 0.02},
            "record": {"dt": 1e-5},
            "solver": {"rtol": 1e-10, "atol": 1e-10},
        }
    )
    assert np.isfinite(ds.vx).all()
    assert float(ds.onset_velocity.max()) < 1e-6
    assert -float(ds.vx[-1]) / 1e-7 == pytest.approx(1.0, abs=0.002)


def test_long_run_has_no_energy_drift():
    """1000 crank cycles at omega = pi with one clearance joint: the energy residual stays below
    1e-4 of the work swing and does not grow with time."""
    ds = run(
        {"effects": {"clearance": ["A"]}, "parameters": {"omega": math.pi}},
        1e-6,
        cycles=1000,
        transient=0,
    )
    worst, swing = energy_residual(ds)
    assert worst < 1e-4 * swing
    res = (
        ds.driver_work
        - ds.dissipated_energy
        - (ds.kinetic_energy - ds.kinetic_energy[0])
        - (ds.potential_energy - ds.potential_energy[0])
    )
    half = res.sizes["time"] // 2
    assert float(abs(res[half:]).max()) < 1e-4 * swing


def test_penetration_beyond_bound_is_a_clear_error():
    with pytest.raises(workbench.SolverError, match=r"t = .*max_penetration") as info:
        run({"parameters": {"max_penetration": 1e-7}}, 1e-6, cycles=1, transient=0)
    assert info.value.status is workbench.Status.MODEL_FAILURE and info.value.model_code > 0
