"""The declared four-bar of studies/mechanisms/fourbar.toml (issue 42, item 4): its ideal-joint
kinematics, as the compiled hooks and a run compute them, against the four-bar's loop-closure
equations solved in closed form here; and its energy balance with the clearance at B."""

import math
from pathlib import Path

import numpy as np
import pytest

import workbench
from workbench.models import get_model

ROOT = Path(__file__).resolve().parents[2]
FOURBAR = ROOT / "studies" / "mechanisms" / "fourbar.toml"

# the four-bar's geometry (m) and bodies (kg, kg m2), as studies/mechanisms/fourbar.toml has them
FRAME, CRANK, COUPLER, ROCKER = 0.30, 0.08, 0.25, 0.20
MASS = {"crank": 0.2, "coupler": 0.5, "rocker": 0.4}
INERTIA = {
    name: m * length**2 / 12
    for (name, m), length in zip(MASS.items(), (CRANK, COUPLER, ROCKER), strict=True)
}


def wrap(angle):
    """Angles (rad) into (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(angle), 2 * np.pi)


def loop_closure(theta2, omega2):
    """Coupler and rocker angles (rad) and angular velocities (rad s-1) of the open four-bar
    (B left of A -> O4) at the crank angles theta2 (rad), crank speed omega2 (rad s-1).

    Positions: B is where the circles about A (radius AB) and O4 (radius O4B) meet, left of the
    line A -> O4. Velocities: the time derivative of the loop closure
    a e^{i t2} + b e^{i t3} - c e^{i t4} - d = 0, projected on i e^{-i t4} and i e^{-i t3}."""
    a, b, c, d = CRANK, COUPLER, ROCKER, FRAME
    ax, ay = a * np.cos(theta2), a * np.sin(theta2)
    rx, ry = d - ax, -ay  # A -> O4
    length = np.hypot(rx, ry)
    ux, uy = rx / length, ry / length
    along = (b * b - c * c + length * length) / (2 * length)
    up = np.sqrt(b * b - along * along)
    bx, by = ax + along * ux - up * uy, ay + along * uy + up * ux
    theta3 = np.arctan2(by - ay, bx - ax)
    theta4 = np.arctan2(by, bx - d)
    omega3 = a * omega2 * np.sin(theta4 - theta2) / (b * np.sin(theta3 - theta4))
    omega4 = a * omega2 * np.sin(theta2 - theta3) / (c * np.sin(theta4 - theta3))
    # the loop closes, and its velocity equations hold, to round-off
    assert np.abs(np.hypot(bx - d, by) - c).max() < 1e-15
    vx = -a * omega2 * np.sin(theta2) - b * omega3 * np.sin(theta3) + c * omega4 * np.sin(theta4)
    vy = a * omega2 * np.cos(theta2) + b * omega3 * np.cos(theta3) - c * omega4 * np.cos(theta4)
    assert np.abs(np.hypot(vx, vy)).max() < 1e-12 * a * abs(omega2)
    return theta3, theta4, omega3, omega4


def kinetic_energy(theta2, omega2):
    """The four-bar's kinetic energy (J) from the closed form: uniform bars, centres of mass at
    their middles."""
    theta3, theta4, omega3, omega4 = loop_closure(theta2, omega2)
    va = CRANK * omega2 * np.stack([-np.sin(theta2), np.cos(theta2)])
    v_crank = va / 2
    v_coupler = va + COUPLER / 2 * omega3 * np.stack([-np.sin(theta3), np.cos(theta3)])
    v_rocker = ROCKER / 2 * omega4 * np.stack([-np.sin(theta4), np.cos(theta4)])
    total = 0.0
    for name, v, w in (
        ("crank", v_crank, omega2),
        ("coupler", v_coupler, omega3),
        ("rocker", v_rocker, omega4),
    ):
        total = total + 0.5 * MASS[name] * (v**2).sum(axis=0) + 0.5 * INERTIA[name] * w**2
    return total


@pytest.fixture(scope="module")
def scene():
    return workbench.load_scene(FOURBAR)


def test_the_file_declares_the_geometry_this_test_solves(scene):
    model = get_model(scene.model)
    linkage = model.linkage
    params = scene.resolved_parameters
    assert dict(linkage.ground) == {"O2": (0.0, 0.0), "O4": (FRAME, 0.0)}
    lengths = {link.name: math.dist(*link.points.values()) for link in linkage.links}
    assert lengths == pytest.approx({"crank": CRANK, "coupler": COUPLER, "rocker": ROCKER})
    for name in MASS:
        assert params[f"mass_{name}"] == pytest.approx(MASS[name], rel=1e-15)
        assert params[f"inertia_{name}"] == pytest.approx(INERTIA[name], rel=1e-15)


def test_compiled_kinematics_equal_the_loop_closure(scene):
    """The generated hooks' kinematics (what the solver integrates) at ideal joints (clearance
    vector 0), every 0.1 deg of a crank turn: the coupler and rocker angles within 1e-12 rad and
    their rates within 1e-12 of the crank speed (the closed form is exact to round-off, ~1e-15;
    a wrong branch, sign or lever is off by order 1)."""
    model = get_model(scene.model)
    hooks = model.dynamics
    omega = scene.resolved_parameters["omega"]
    nq, nb, npt = hooks.N_Q, hooks.N_BODIES, hooks.N_POINTS
    rows = {name: i for i, name in enumerate(b.name for b in model.linkage.links)}
    theta = np.arange(3600) * (2 * np.pi / 3600)
    got = np.empty((theta.size, 4))
    for k, th in enumerate(theta):
        q = np.zeros(nq)
        qd = np.zeros(nq)
        q[0], qd[0] = th, omega
        pos, vel, gam = np.empty((nb, 3)), np.empty((nb, 3)), np.empty((nb, 3))
        pts, velp, gamp = np.empty((npt, 2)), np.empty((npt, 2)), np.empty((npt, 2))
        J, Jp = np.empty((nb, 3, nq)), np.empty((npt, 2, nq))
        assert hooks.kinematics(q, qd, pos, pts, J, Jp, gam, gamp, vel, velp) == 0
        got[k] = [
            pos[rows["coupler"], 2],
            pos[rows["rocker"], 2],
            vel[rows["coupler"], 2],
            vel[rows["rocker"], 2],
        ]
    theta3, theta4, omega3, omega4 = loop_closure(theta, omega)
    assert np.abs(wrap(got[:, 0] - theta3)).max() < 1e-12
    assert np.abs(wrap(got[:, 1] - theta4)).max() < 1e-12
    np.testing.assert_allclose(got[:, 2], omega3, rtol=0, atol=1e-12 * omega)
    np.testing.assert_allclose(got[:, 3], omega4, rtol=0, atol=1e-12 * omega)
    # the crank turns fully and the rocker rocks (Grashof crank-rocker)
    assert np.ptp(theta4) < np.pi / 2


def test_an_ideal_run_has_the_closed_forms_kinetic_energy(scene):
    """A run with ideal joints over one cycle: its kinetic energy, which every body's velocity
    enters, equals the closed form's within 1e-12 of its largest value."""
    ds = workbench.simulate(
        scene.replace(
            effects={**scene.effects, "clearance": []},
            run={"cycles": 1},
            record={"samples_per_period": 720, "variables": ["kinetic_energy"]},
        )
    )
    omega = scene.resolved_parameters["omega"]
    expected = kinetic_energy(omega * ds.time.values, omega)
    np.testing.assert_allclose(
        ds.kinetic_energy.values, expected, rtol=0, atol=1e-12 * expected.max()
    )


ENERGY = ["driver_work", "dissipated_energy", "kinetic_energy", "potential_energy"]


@pytest.mark.parametrize("friction", ["none", "coulomb"])
def test_energy_balance_with_the_clearance_at_b(scene, friction):
    """Energy residual over one cycle, with the clearance at B: the driver's work minus the
    change of the kinetic energy, minus the change of the potential energy (gravity and the
    contact's elastic energy: the record ``potential_energy``), minus the energy dissipated by
    the contact's damping and friction (``dissipated_energy``), all since the first record. It
    stays within 1e-6 of the largest driver work of the cycle at the solver's rtol = atol =
    1e-10 (the quadratures of the work and the dissipation are integrated with the state)."""
    ds = workbench.simulate(
        scene.replace(
            effects={**scene.effects, "friction": friction},
            parameters={"friction_coefficient": 0.1 if friction == "coulomb" else 0.0},
            solver={"method": "dop853", "rtol": 1e-10, "atol": 1e-10},
            run={"cycles": 1},
            record={"samples_per_period": 2000, "variables": ENERGY},
        )
    )
    residual = (
        ds.driver_work
        - (ds.kinetic_energy - ds.kinetic_energy[0])
        - (ds.potential_energy - ds.potential_energy[0])
        - ds.dissipated_energy
    )
    work = float(abs(ds.driver_work).max())
    assert work > 0.1  # J: the crank does work on the mechanism
    assert float(ds.dissipated_energy[-1]) > 0  # the impacts dissipate
    assert float(abs(residual).max()) <= 1e-6 * work
