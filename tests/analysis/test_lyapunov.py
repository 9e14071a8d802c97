"""Jacobians, the tangent system with saltation, the Lyapunov spectrum and the two-trajectory
largest exponent (issue: Lyapunov exponents that converge)."""

import dataclasses
import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from helpers import agrees, flow_map_copies, flow_map_tangent

from workbench import load_scene
from workbench.analysis import (
    ConvergenceWarning,
    floquet,
    lle_from_equations,
    lyapunov_spectrum,
)
from workbench.analysis._lyapunov import SUM_CHECK
from workbench.models import get_model
from workbench.solver import integrate
from workbench.solver._compile import jacobian_for
from workbench.solver._tangent import state_scale, tangent_problem, tangent_state

LORENZ_SPECTRUM = (0.9056, 0.0, -14.5723)  # Sprott (2003), Appendix A (sigma 10, rho 28, 8/3)


def _problem(scene):
    scene = load_scene(scene)
    model = get_model(scene.model)
    return model.problem(scene.resolved_parameters, scene.effects, scene.initial, ())


def _advanced(pb, t):
    res = integrate(pb, np.array([t]), rtol=1e-10, atol=1e-10)
    out = dataclasses.replace(pb, y0=res.Y[-1].copy(), aux0=res.AUX[-1].copy())
    out.t0 = t
    return out


@pytest.mark.parametrize(
    ("name", "states"),
    [
        ("lorenz", [[1.0, 2.0, 20.0], [-8.0, -3.0, 30.0]]),
        ("duffing", [[0.3, -0.2], [1.5, 0.7]]),
        ("bouncing_ball", [[0.4, -1.0]]),
    ],
)
def test_analytic_jacobians_match_finite_differences(name, states):
    """Each analytic `jacobian` hook against the compiled central differences of its `rhs`
    (relative error ~eps^(2/3) ~ 4e-11 for these polynomial right-hand sides)."""
    pb = _problem({"model": {"name": name}, "run": {"duration": 1.0}})
    jac = jacobian_for(pb.hooks)
    assert jac.HAS_ANALYTIC
    work = np.zeros(max(pb.work_size, 1))
    s = state_scale(pb)
    for y in states:
        y = np.array(y, dtype=float)
        J = np.empty((y.size, y.size))
        F = np.empty((y.size, y.size))
        assert jac.jacobian(0.7, y, pb.p, pb.ip, pb.aux0.copy(), work, s, J) == 0
        assert jac.fd_jacobian(0.7, y, pb.p, pb.ip, pb.aux0.copy(), work, s, F) == 0
        np.testing.assert_allclose(F, J, rtol=0, atol=1e-8 * np.abs(J).max())


def test_ninebar_finite_difference_jacobian_is_consistent():
    """The nine-bar has no analytic Jacobian: its compiled central differences (step eps^(1/3)
    of each state's size) must agree with a Richardson-extrapolated directional derivative of
    the rhs (steps 1e-4 and 5e-5 of the size) along random directions, at states of a run with
    contacts, to 1e-5 of the derivative's size: the two differ in step by ~20x, so agreement
    says both are in their truncation-free range."""
    pb = _problem("studies/ninebar.toml")
    jac = jacobian_for(pb.hooks)
    assert not jac.HAS_ANALYTIC
    from workbench.models.ninebar import _dynamics as hooks

    t_rec = np.linspace(0.012, 0.05, 40)
    res = integrate(pb, t_rec, rtol=1e-8, atol=1e-8)
    s = state_scale(pb)
    work = np.zeros(pb.work_size)
    rng = np.random.default_rng(1)
    n = pb.y0.size
    errors = []
    for t, y, aux in zip(res.t, res.Y, res.AUX, strict=True):
        J = np.empty((n, n))
        assert jac.fd_jacobian(t, y, pb.p, pb.ip, aux.copy(), work, s, J) == 0
        v = rng.standard_normal(n) * s

        def f(e, y=y, v=v, t=t, aux=aux):
            out = np.empty(n)
            hooks.rhs(t, y + e * v, pb.p, pb.ip, aux.copy(), work, out)
            return out

        def d(h):
            return (f(h) - f(-h)) / (2 * h)

        rich = (4 * d(5e-5) - d(1e-4)) / 3
        errors.append(np.abs(J @ v - rich).max() / np.abs(rich).max())
    # a contact's onset or a friction-law corner inside the wider stencil spoils a few records
    assert np.quantile(errors, 0.8) < 1e-5, np.sort(errors)


def test_bouncing_ball_flow_map_and_volume_change_are_exact():
    """Two bounces (e = 0.8) before t = 1.3 s: the tangent map with saltation equals the
    derivative of the closed-form flow, and each bounce changes phase-space area by e^2
    (det S = e^2)."""
    pb = _problem({"model": {"name": "bouncing_ball"}, "run": {"duration": 2.0}})
    g, e = 9.81, 0.8

    def flow(h, v, t1):
        t = 0.0
        while True:
            tb = (v + math.sqrt(v * v + 2 * g * h)) / g
            if t + tb > t1:
                dt = t1 - t
                return np.array([h + v * dt - g / 2 * dt * dt, v - g * dt])
            t, v, h = t + tb, -e * (v - g * tb), 0.0

    eps = 1e-7
    exact = np.column_stack(
        [
            (flow(1 + eps, 0, 1.3) - flow(1 - eps, 0, 1.3)) / (2 * eps),
            (flow(1, eps, 1.3) - flow(1, -eps, 1.3)) / (2 * eps),
        ]
    )
    M, log_det, events = flow_map_tangent(pb, 1.3, 1e-11)
    assert events == 2
    np.testing.assert_allclose(M, exact, rtol=1e-6, atol=1e-6)
    assert log_det == pytest.approx(2 * 2 * math.log(e), rel=1e-9)


def test_one_step_cannot_jump_over_a_whole_flight():
    """A ball recorded only at t = 1.3 s bounces twice (at 0.4515 and 1.1740 s). The free
    flight is a parabola, which the error estimate cannot see, so steps grow until one rises
    off the floor and falls back through it between its ends; the kernel now retries a step
    whose end lies beyond an event surface that the sign test saw no crossing of."""
    pb = _problem({"model": {"name": "bouncing_ball"}, "run": {"duration": 2.0}})
    res = integrate(pb, np.array([1.3]), rtol=1e-10, atol=1e-10)
    assert res.stats["events"] == 2
    assert res.AUX[-1, 1] == pytest.approx(0.4515236409 + 2 * 0.8 * 0.4515236409, rel=1e-9)
    assert res.Y[-1, 0] > 0


def test_tangent_map_with_contact_memory_matches_copies():
    """A free journal launched obliquely: impacts whose damping depends on the held onset
    velocity (a discrete state). The tangent map with saltation and the discrete-state
    components equals the shared-step finite differences of the flow map."""
    pb = _problem(
        {"model": {"name": "free_journal"}, "initial": {"vy": 0.2}, "run": {"duration": 0.01}}
    )
    M, _, events = flow_map_tangent(pb, 0.006, 1e-11)
    assert events >= 4
    F = flow_map_copies(pb, 0.006, 1e-11)
    assert np.abs(M - F).max() < 1e-4 * np.abs(F).max()


@pytest.mark.slow
def test_ninebar_tangent_map_through_impacts_matches_copies():
    """Default scene from 11 to 13 ms (four contact onsets and ends at A and B): the tangent
    map with saltation equals shared-step finite differences of the flow map to 1e-3 of its
    largest entry (measured 7.0e-5 at rtol 1e-10; separately integrated differences scatter
    by 2 % here)."""
    pb = _advanced(_problem("studies/ninebar.toml"), 0.011)
    M, _, events = flow_map_tangent(pb, 0.013, 1e-10)
    assert events >= 4
    F = flow_map_copies(pb, 0.013, 1e-10)
    assert np.abs(M - F).max() < 1e-3 * np.abs(F).max()


# The chaos case (studies/chaos/chaos.toml) at the start of the re-orthonormalisation intervals
# where the tangent run failed with a step-size underflow while the model's own run integrates
# fine (issue 24): time (s), state, tangent vector of the extended state (state, then the two
# held onset velocities), discrete state; the rtol of the run and the end of the interval (s).
# `lyapunov_spectrum(chaos with cycles=80, transient_cycles=20, exponents=1, check=False)`
# failed at t = 91.4888603 s (h = 1.28e-13 s); with `cycles=60, rtol=1e-8` at t = 20.9548803 s
# (h = 3.45e-14 s).
_CHAOS_FAILURES = {
    "80 cycles, rtol 1e-6": (
        90.5,
        [
            -7.9653341745762139e-06, -1.0042882108330272e-04, -7.8199347495379478e-05,
            6.3844339311797308e-05, -2.2912578019708765e-03, 1.9456190406294234e-04,
            -7.8841662368328927e-04, -9.8996545793977333e-04,
        ],
        [
            -1.5697763744037891e-06, 1.2094504054656915e-07, -1.7349056070170183e-07,
            -2.0631528343868022e-07, -5.1493324463236508e-05, 3.5796029089615815e-05,
            4.0698587644843337e-04, 4.7446077334505743e-04, -5.5357129610088653e-04,
            -1.8207334186250807e-04,
        ],
        [0.00037913402889153944, 0.002444758617695497],
        1e-6,
        91.5,
    ),
    "60 cycles, rtol 1e-8": (
        20.5,
        [
            -7.5389977753536467e-06, -1.0045574982514270e-04, -7.8400858318991925e-05,
            6.3587513864554667e-05, 1.5338097252134018e-03, -1.5445103996331649e-04,
            9.2828568394625482e-04, 1.2134316814036844e-03,
        ],
        [
            1.8287770747255500e-06, -1.7155426087899840e-07, 3.1876710365508878e-07,
            4.6408265573188100e-07, -4.0258247441138286e-04, 1.0944960003517255e-04,
            3.4095344353554056e-04, 3.2301293030860616e-04, -3.3827320919629141e-03, 0.0,
        ],
        [0.0010250260997295276, 0.0019045081603784588],
        1e-8,
        21.0,
    ),
}  # fmt: skip
# where each failed (s), and the tangent vector's growth from the interval's start to there (its
# log, rounded, on the processor that met the failures): docs/analysis.md quotes e^22 and e^25.
# The interval is chaotic: another processor's rounding gives another growth of that order
# (28.2 for the first with numba's generic target), so the test asserts the order, not the value
_FAILED_AT = {"80 cycles, rtol 1e-6": (91.4888603, 25), "60 cycles, rtol 1e-8": (20.9548803, 22)}


def _chaos_at_failure(case):
    t0, y0, v0, aux0, rtol, t1 = _CHAOS_FAILURES[case]
    pb = _problem("studies/chaos/chaos.toml")
    start = dataclasses.replace(pb, y0=np.array(y0), aux0=np.array(aux0), t0=t0)
    tangent = tangent_problem(start, np.array(v0)[:, None], time_scale=1.0)
    return start, tangent, rtol, t1


@pytest.mark.chaotic
@pytest.mark.parametrize("case", list(_CHAOS_FAILURES))
def test_tangent_run_completes_where_the_model_does(case):
    """Over each interval where the tangent run failed, both the model and its tangent system
    integrate (the tangent vector grows by e^15 or more there: stored as a direction and its
    log size, every component is measured against the vector's size instead of its own, which
    was ~1e-9 of the vector's size at the failures). By the time of each failure the vector
    had grown by e^25 (rtol 1e-6) and e^22 (rtol 1e-8)."""
    start, tp, rtol, t1 = _chaos_at_failure(case)
    t_failed, grown = _FAILED_AT[case]
    n, na = start.y0.size, start.aux0.size
    plain = integrate(start, np.array([t1]), rtol=rtol, atol=rtol)
    assert plain.status.name == "OK"
    res = integrate(tp, np.array([t_failed, t1]), rtol=rtol, atol=rtol)
    assert res.status.name == "OK", res.message
    growths = []
    for y in res.Y:
        _, U, log_size, _ = tangent_state(y, n, na, 1)
        growths.append(log_size[0] + math.log(np.linalg.norm(U[:n, 0] / state_scale(start))))
    # grown by e^15 or more when it failed (docs/analysis.md quotes e^22 and e^25): within a
    # factor e^10 of the growth met there
    assert 15.0 < growths[0] and abs(growths[0] - grown) < 10.0, growths
    assert 15.0 < growths[1] < 60.0  # chaotic bursts: the vector grew by e^15 .. e^60


def test_tangent_run_costs_few_more_steps_than_the_model():
    """Both joints in contact for 0.2 s at rtol 1e-10: the tangent run needs fewer than twice
    the model's steps (measured 3396 vs 2073). With the central-difference step along the
    tangent vector at eps^(1/3) its rounding noise needed 190 515 steps."""
    start, tp, _, _ = _chaos_at_failure("60 cycles, rtol 1e-8")
    t1 = start.t0 + 0.2
    plain = integrate(start, np.array([t1]), rtol=1e-10, atol=1e-10)
    res = integrate(tp, np.array([t1]), rtol=1e-10, atol=1e-10)
    assert res.status.name == "OK" and plain.status.name == "OK"
    assert res.stats["events"] == plain.stats["events"] == 0
    assert res.stats["steps"] < 2 * plain.stats["steps"], (res.stats, plain.stats)


def test_lorenz_spectrum_and_its_sum():
    """Spectrum within 2 % of (0.9056, 0, -14.572) (|lambda_2| < 2 % of lambda_1) over 4000
    time units; the sum equals the divergence -(sigma + 1 + beta) = -13.667 (Liouville)."""
    r = lyapunov_spectrum(
        {"model": {"name": "lorenz"}, "run": {"duration": 4000.0, "transient": 10.0}},
        check=False,
    )
    lam = r.exponent.values
    assert lam[0] == pytest.approx(LORENZ_SPECTRUM[0], rel=0.02)
    assert abs(lam[1]) < 0.02 * LORENZ_SPECTRUM[0]
    assert lam[2] == pytest.approx(LORENZ_SPECTRUM[2], rel=0.02)
    assert float(r.spectrum_sum) == pytest.approx(-(10 + 1 + 8 / 3), rel=1e-6)
    assert float(r.divergence) == pytest.approx(-(10 + 1 + 8 / 3), rel=1e-9)
    assert r.attrs["memory"] == 0
    assert r.exponent.attrs["units"] == "s-1"


def test_duffing_spectrum_sums_to_minus_delta():
    r = lyapunov_spectrum(
        {"model": {"name": "duffing"}, "run": {"cycles": 40, "transient_cycles": 5}},
        check=False,
    )
    assert float(r.spectrum_sum) == pytest.approx(-0.3, rel=1e-6)
    assert float(r.divergence) == pytest.approx(-0.3, rel=1e-9)
    assert r.exponent_per_period.attrs["units"] == "1"


@pytest.mark.chaotic
def test_two_trajectory_lorenz_converges_from_independent_starts():
    """Lorenz over 4 starts x 100 s, grown to 200 s (realisations 0-3 of the scene): the error
    is the larger of
    the starts' spread and their batch means, so that it is never below what the independent
    starts show; the estimate lies within three of its errors of Sprott's value and the
    variational exponent on the same trajectories differs by far less than the error (the
    copies at sqrt(eps) follow the linearised flow)."""
    scene = {"model": {"name": "lorenz"}, "run": {"duration": 400.0, "transient": 20.0}}
    b = lle_from_equations(scene)
    assert bool(b.converged), b.attrs["failed"]
    assert b.sizes["start"] == 4 and b.attrs["starts"] == 4
    # 400 s shared among the starts, 100 s each, read 0.9086 +/- 0.0280 on one processor (3.1 %,
    # above the 3 % target: the windows doubled once); whether they double depends on where
    # the error falls beside the target, which another processor's rounding moves
    assert b.attrs["duration"] in (400.0, 800.0, 1600.0)
    assert b.attrs["duration_per_start"] == b.attrs["duration"] / 4
    starts = b.start_lle.values
    assert len(set(starts.tolist())) == 4  # four different trajectories
    assert float(b.lle) == pytest.approx(starts.mean(), rel=1e-12)
    assert float(b.stderr_starts) == pytest.approx(starts.std(ddof=1) / 2, rel=1e-12)
    assert float(b.stderr_batches) == pytest.approx(
        np.sqrt(np.sum(b.start_stderr.values**2)) / 4, rel=1e-12
    )
    assert float(b.stderr) == max(float(b.stderr_starts), float(b.stderr_batches))
    assert abs(float(b.lle) - LORENZ_SPECTRUM[0]) < 3 * float(b.stderr)
    assert abs(float(b.difference)) < 0.01 * float(b.stderr)  # the linearised flow, exactly
    assert float(b.separation[0]) == pytest.approx(np.sqrt(np.finfo(float).eps))


def test_two_trajectory_lorenz_same_at_two_tolerances():
    """The default call at rtol 1e-6 and 1e-10 returns the same exponent within the errors
    (the windows are other realisations at each tolerance) and at each tolerance the variational
    exponent on the same trajectories within its error."""
    scene = {"model": {"name": "lorenz"}, "run": {"duration": 200.0, "transient": 20.0}}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        loose = lle_from_equations(scene, rtol=1e-6, check=False, budget=200.0)
        tight = lle_from_equations(scene, rtol=1e-10, check=False, budget=200.0)
    assert list(loose.attempt_rtol.values) == [1e-6] and list(tight.attempt_rtol.values) == [1e-10]
    assert abs(float(loose.lle) - float(tight.lle)) <= 2 * np.hypot(
        float(loose.stderr), float(tight.stderr)
    )
    for r in (loose, tight):
        assert abs(float(r.difference)) <= 2 * float(r.stderr)
        assert "variational" not in r.attrs["failed"]


def test_two_trajectory_verdict_refuses_converged_and_names_each_failure():
    """Every condition the estimate could not show is named, and the estimate is never
    ``converged`` then: no variational exponent and no tolerance check (not run), a separation
    far outside the linear range (0.3 of Lorenz's state size: the variants part)."""
    scene = {"model": {"name": "lorenz"}, "run": {"duration": 200.0, "transient": 20.0}}
    with pytest.warns(ConvergenceWarning) as caught:
        r = lle_from_equations(scene, check=False, variational=False)
    assert not bool(r.converged)
    assert "variational: not run" in r.attrs["failed"]
    assert "tolerance check: not run" in r.attrs["failed"]
    assert "error target" not in r.attrs["failed"] and "variants" not in r.attrs["failed"]
    assert "variational: not run" in str(caught[0].message)
    with pytest.warns(ConvergenceWarning, match="variants"):
        r = lle_from_equations(scene, separation=0.3, check=False, tighten=False)
    assert not bool(r.converged) and "variants" in r.attrs["failed"]
    with pytest.raises(ValueError, match="starts=0"):
        lle_from_equations(scene, starts=0)


@pytest.mark.chaotic
def test_two_trajectory_exponent_of_a_damped_linear_oscillator_is_its_closed_form():
    """A contracting orbit: the forced underdamped linear oscillator x'' + 2 zeta w x' + w^2 x
    = F cos(omega t) (the Duffing model with beta = 0; w = 1 1/s, zeta = 0.5) has both
    exponents -zeta w = -delta / 2 = -0.5 1/s on every orbit. Renormalised on growth alone
    the copies shrank onto the fiducial trajectory (e^-52 over one start's 105 s) until they
    coincided with it and the run failed; renormalised on shrinkage as well (each shrink by
    10x adds -ln 10: ~0.5 x 105 / ln 10 = 23 per start) the estimate is the closed form
    within its error, converged, as is the variational exponent on the same trajectories."""
    scene = {
        "model": {"name": "duffing"},
        "parameters": {"delta": 1.0, "alpha": 1.0, "beta": 0.0, "gamma": 0.5, "omega": 1.2},
        "run": {"cycles": 80, "transient_cycles": 10},
    }
    r = lle_from_equations(scene)
    assert bool(r.converged), r.attrs["failed"]
    assert abs(float(r.lle) + 0.5) <= 2 * float(r.stderr)
    assert float(r.stderr) < 0.01  # 1/s: 2 % of the exponent
    # docs/analysis.md quotes -0.4993 +/- 0.0023 (one processor's estimate)
    assert agrees(float(r.lle), float(r.stderr), -0.4993, 0.0023), (r.lle, r.stderr)
    assert abs(float(r.lle_variational) + 0.5) <= 2 * float(r.stderr_variational)
    # every renormalisation is a shrinkage: ln 10 each, over the 4 x 104.7 s followed
    shrinks = r.shrink_renormalisations.values
    assert np.array_equal(shrinks, r.renormalisations.values)
    length = r.attrs["cycles"] * 2 * math.pi / 1.2
    assert shrinks[0] == pytest.approx(0.5 * length / math.log(10), abs=r.attrs["starts"])


@pytest.mark.chaotic
def test_two_trajectory_exponent_of_a_stable_duffing_orbit_is_floquets():
    """A stable period-1 orbit of the Duffing oscillator (delta = 1, gamma = 0.3: real
    multipliers 0.1129 and 0.0471, exponents ln |mu| / T = -0.4166 and -0.5834 1/s): the
    two-trajectory estimate is the largest Floquet exponent (workbench.analysis.floquet,
    Newton-refined orbit, monodromy from the tangent system at rtol 1e-10) within its error.
    Renormalised on growth alone the copies coincided with the fiducial trajectory and the run
    failed."""
    scene = {
        "model": {"name": "duffing"},
        "parameters": {"delta": 1.0, "gamma": 0.3},
        "run": {"cycles": 80, "transient_cycles": 10},
    }
    period = 2 * math.pi / 1.2
    reference = math.log(float(floquet(scene).modulus[0])) / period
    assert reference == pytest.approx(-0.4166, abs=1e-4)
    r = lle_from_equations(scene)
    assert bool(r.converged), r.attrs["failed"]
    assert abs(float(r.lle) - reference) <= 2 * float(r.stderr)
    assert int(r.shrink_renormalisations[0]) > 0
    # docs/analysis.md quotes -0.4191 +/- 0.0023 against -0.4166 (one processor's estimate)
    assert agrees(float(r.lle), float(r.stderr), -0.4191, 0.0023), (r.lle, r.stderr)


def test_bad_arguments_are_refused():
    scene = {"model": {"name": "lorenz"}, "run": {"duration": 1.0}}
    with pytest.raises(ValueError, match="exponents=5"):
        lyapunov_spectrum(scene, exponents=5)
    with pytest.raises(ValueError, match="compiled method"):
        lyapunov_spectrum({**scene, "solver": {"method": "scipy:RK45"}})
    with pytest.raises(ValueError, match="separation=-1"):
        lle_from_equations(scene, separation=-1.0)
    with pytest.raises(ValueError, match="growth=0"):
        lle_from_equations(scene, growth=0.0)


@pytest.mark.chaotic
@pytest.mark.slow
def test_chaos_case_two_trajectory_and_variational_agree():
    """The chaos study's case (A+B, c = 0.1 mm, omega = 2 pi, Coulomb c_f = 0.01), 4
    transient + 3 cycles, no room to grow and no tolerance check: the five separation/growth
    variants agree within 2 %, and the variational equations with saltation, carried by the same
    fiducial trajectory, give the same exponent within its error (measured: 23.59 and 23.84 1/s,
    variants 23.20-23.76), but three cycles are far from the error target (standard error 10.1
    1/s, 43 %), and the estimate says so.
    Before the kernel applied simultaneous events together, a copy whose contact onset fell on
    the fiducial's double in time missed it, and the variants spread by 20 %."""
    scene = load_scene("studies/chaos/chaos.toml").replace(run={"cycles": 3, "transient_cycles": 4})
    with pytest.warns(ConvergenceWarning):
        r = lle_from_equations(scene, budget=3, check=False, starts=1)
    assert float(r.spread) < 0.05, r.estimate.values  # the estimator's own bound (TOLERANCE)
    # docs/analysis.md quotes 23.6 +/- 10.1 1/s (one processor's estimate)
    assert agrees(float(r.lle), float(r.stderr), 23.6, 10.1), (r.lle, r.stderr)
    assert not bool(r.converged) and "error target" in r.attrs["failed"]
    assert float(r.method_difference) < 0.15
    assert 5.0 < float(r.lle) < 200.0  # 1/s: an impacting mechanism, chaotic
    assert r.lle_per_period.attrs["units"] == "1"
    # the copies at sqrt(eps) and the tangent vector on the same trajectory: the difference
    # within two of its own standard errors (at d0 = 1e-4 and rtol 1e-6 single contacts the
    # copies resolve differently added up to +3 1/s over 10 cycles; benchmarks/lle.py --scan)
    assert abs(float(r.difference)) <= 2 * float(r.stderr_difference)


@pytest.mark.chaotic
@pytest.mark.slow
def test_contracting_nine_bar_orbit_reads_a_negative_exponent():
    """The nine-bar at omega = 0.5 pi, c = 20 um (A+B, Coulomb c_f = 0.01; studies/chaos_maps/
    omega_clearance.toml) settles on a stable period-1 orbit (Floquet exponent -75.93 1/s from
    analysis.floquet run once, below the bound tests/continuation/test_continuation.py checks)
    that stays in
    contact: over one cycle its scaled separations swing by 10x up and down ~500 times a second,
    about half of the renormalisations on shrinkage. Renormalised on growth alone the copies sank
    into the integration's noise and read ~0 1/s (-0.5 .. +0.3 over the five variants, 1 cycle,
    rtol 1e-6) while the variational exponent on the same trajectory read -74; renormalised on
    shrinkage as well they read -68 (variants -66.6 .. -68.0, also at rtol 1e-8 and with the
    step capped at 1e-5 s). What remains, the copies ~8 % above the variational exponent on the
    same trajectory, depends on none of d0, growth, tolerance or step, and is not yet explained
    (docs/analysis.md): the two follow each other within 0.5 e-fold over the first 2.8 s (-107
    e-folds) and part after. The estimate is not converged over one cycle and says so."""
    scene = load_scene(
        Path(__file__).resolve().parents[2] / "studies/chaos_maps/omega_clearance.toml"
    )
    point = scene.replace(
        sweep={},
        run={"cycles": 1, "transient_cycles": 20},
        solver=dict(scene.solver, method="dop853"),
    ).with_parameters(omega=0.5 * math.pi, clearance=2e-5)
    with pytest.warns(ConvergenceWarning):
        r = lle_from_equations(point, starts=1, budget=1, check=False)
    assert not bool(r.converged)
    assert float(r.spread) < 0.05, r.estimate.values
    assert -80.0 < float(r.lle) < -55.0  # 1/s
    assert -80.0 < float(r.lle_variational) < -65.0
    # docs/analysis.md quotes -67.9 and -74.2 (one processor's): a contracting orbit with
    # thousands of located contact events, each rounded its own way per processor
    assert abs(float(r.lle) - -67.9) < 1.0 and abs(float(r.lle_variational) - -74.2) < 1.0
    assert float(r.method_difference) < 0.15
    shrinks = r.shrink_renormalisations.values
    assert np.all(shrinks > 0.3 * r.renormalisations.values)
    # docs/analysis.md: the chosen variant's separation swings by 10x up and down some 500 times
    # a second (measured 2 193 shrinkages and 2 075 growths in the 4-s cycle on one processor),
    # about half of the renormalisations shrinkages in every variant (0.51-0.56)
    period = r.attrs["forcing_period"]
    chosen_shrinks = float(r.shrink_renormalisations[0])
    chosen_growths = float(r.renormalisations[0]) - chosen_shrinks
    for rate in (chosen_shrinks / period, chosen_growths / period):
        assert 400.0 < rate < 650.0, rate  # 1/s: "some 500 times a second"
    assert np.all(np.abs(shrinks / r.renormalisations.values - 0.5) < 0.1)
    # docs/analysis.md: the copies' and the tangent vector's log growth within 0.5 e-fold of each
    # other over the first 2.8 s (-107 e-folds) but at isolated samples (at most 1 %, each
    # back within 0.5 at the next sample: the two copies on either side of a contact event
    # there), apart by more after (25 e-folds at the end)
    elapsed = r.elapsed.values
    copies, tangent = (r[v].values * elapsed for v in ("running", "running_variational"))
    first = elapsed <= 2.8 + 1e-9
    apart = np.abs(copies - tangent)[first] > 0.5
    assert apart.sum() <= 0.01 * first.sum() and not np.any(apart[:-1] & apart[1:])
    assert not apart[-1]
    assert abs(float(tangent[first][-1]) - -107) < 1.0
    assert abs(copies[-1] - tangent[-1]) > 10.0


_OBLIQUE_JOURNAL = {
    "model": {"name": "free_journal"},
    "initial": {"vy": 0.2, "vx": 0.05},
    "run": {"duration": 0.02},
    "solver": {"rtol": 1e-8, "atol": 1e-8},
}


def test_spectrum_sum_check_with_contact_memory_is_exact():
    """A free journal launched obliquely (12 impacts in 0.02 s, the damping set by the held
    onset velocity): the log volume the four tangent vectors span, integrated with the tangent
    system (the feedback of the held onset velocity included), equals the spectrum's sum to
    1e-5 (measured 2.1e-7 at rtol 1e-8); the trace of J and the volume jumps at events alone
    (divergence) leave out memory_rate. The spectrum is sorted (its accumulators were not, over
    so short a window) and no exponent is trusted without a tolerance check."""
    with pytest.warns(ConvergenceWarning, match="tolerance check: not run"):
        r = lyapunov_spectrum(_OBLIQUE_JOURNAL, check=False, budget=0.02)
    assert float(r.sum_check) < 1e-5
    assert float(r.spectrum_sum) == pytest.approx(float(r.volume_rate), rel=1e-5)
    assert float(r.divergence) + float(r.memory_rate) == pytest.approx(float(r.volume_rate))
    assert r.attrs["memory"] == 1 and float(r.memory_rate) != 0.0
    lam = r.exponent.values
    assert np.all(np.diff(lam) <= 0) and r.attrs["reordered"] == 1
    assert not bool(r.converged) and not r.trusted.values.any()
    assert r.stderr.attrs["units"] == "s-1" and r.volume_rate.attrs["units"] == "s-1"


@pytest.mark.chaotic
@pytest.mark.slow
def test_ninebar_spectrum_sum_check_closes():
    """The chaos case (A+B, c = 0.1 mm, omega = 2 pi, c_f = 0.01), all 8 exponents over 0.5
    cycles after the scene's 20 transient cycles at its rtol 1e-6: the log volume the vectors
    span, integrated with the tangent system (trace of the generator with the held onset
    velocity's feedback, plus the volume jumps at events), equals the sum of Benettin's
    accumulators within SUM_CHECK (1e-3), the check's own threshold (measured 2.2e-4 on one
    processor; over a chaotic window each rounds its way to another trajectory, so the figure
    varies, not the bound; with some 16 000 re-orthonormalisations at step ends: the contacts
    part the vectors within microseconds). Over 0.05 cycles, a few contacts, it measured 1.5e-3:
    the vectors follow their linear equations between steps' ends, so the accumulators no
    longer share the volume's quadrature error, and a window of a few contacts shows it. The run
    is dissipative: the sum is some -1300 1/s over this window."""
    scene = load_scene("studies/chaos/chaos.toml").replace(sweep={})
    with pytest.warns(ConvergenceWarning):
        r = lyapunov_spectrum(scene, cycles=0.5, budget=0.5, check=False)
    assert r.exponent.size == 8
    sum_check = float(r.sum_check)
    assert sum_check < SUM_CHECK, (sum_check, float(r.spectrum_sum), float(r.volume_rate))
    assert r.attrs["reorthonormalisations"] > 100
    assert float(r.spectrum_sum) < -100.0  # 1/s: contact damping
    assert float(r.divergence) + float(r.memory_rate) == pytest.approx(float(r.volume_rate))


def test_spectrum_that_misses_its_targets_says_which():
    """Lorenz over 20 s with no room to grow: the largest exponent's error is far above 3 %,
    so the estimate is not converged, says so in ``failed`` and warns; an exponent whose error
    exceeds 20 % of it is not trusted, whatever the tolerance check says."""
    scene = {"model": {"name": "lorenz"}, "run": {"duration": 20.0, "transient": 10.0}}
    with pytest.warns(ConvergenceWarning, match="error target"):
        r = lyapunov_spectrum(scene, budget=20.0)
    assert not bool(r.converged)
    assert "error target" in r.attrs["failed"] and r.attrs["duration"] == pytest.approx(20.0)
    rel = r.stderr.values / np.abs(r.exponent.values)
    assert rel[0] > 0.03
    assert not r.trusted.values.any()
    assert r.exponent_tight.attrs["long_name"] == f"exponent at rtol = {r.attrs['rtol'] / 100:g}"


@pytest.mark.chaotic
def test_spectrum_window_grows_to_its_error_target():
    """Lorenz from 50 s with a budget of 800 s: the run is continued (doubled) until the
    largest exponent's standard error is 3 % of it, and the spectrum then matches Sprott's
    within that error; the sum check closes (the trace of Lorenz is constant)."""
    scene = {"model": {"name": "lorenz"}, "run": {"duration": 50.0, "transient": 10.0}}
    r = lyapunov_spectrum(scene, budget=800.0, check=False)
    followed = r.attrs["duration"]
    assert followed in (100.0, 200.0, 400.0, 800.0)
    assert float(r.elapsed[-1]) == pytest.approx(followed)
    err = float(r.stderr[0])
    assert err <= 0.03 * float(r.exponent[0]) or followed == 800.0
    assert float(r.exponent[0]) == pytest.approx(LORENZ_SPECTRUM[0], abs=3 * err + 0.02)
    assert float(r.sum_check) < 1e-6  # measured 1.1e-9


def test_implicit_method_is_refused_in_a_lyapunov_window():
    """radau (and auto, ark548) would be silently replaced by DOP853 for the tangent system:
    refused with what to do, and measured with DOP853 when asked."""
    scene = {
        "model": {"name": "lorenz"},
        "run": {"duration": 1.0},
        "solver": {"method": "radau"},
    }
    with pytest.raises(ValueError, match="solver.method='radau'.*method='dop853'"):
        lyapunov_spectrum(scene, check=False)
    with pytest.raises(ValueError, match="solver.method='radau'"):
        lle_from_equations(scene)
    with pytest.warns(ConvergenceWarning):
        r = lyapunov_spectrum(scene, check=False, method="dop853", budget=1.0)
    assert r.exponent.size == 3


def test_two_trajectory_estimate_that_misses_its_targets_says_which():
    """Lorenz over 30 s with no room to grow: not converged, the error target named."""
    scene = {"model": {"name": "lorenz"}, "run": {"duration": 30.0, "transient": 10.0}}
    with pytest.warns(ConvergenceWarning, match="error target"):
        r = lle_from_equations(scene, budget=30.0, separation=1e-7)
    assert not bool(r.converged) and "error target" in r.attrs["failed"]
    assert r.lle_tight.attrs["units"] == "s-1"


RESULTS = Path(__file__).resolve().parents[2] / "benchmarks" / "results"


def lle_doc_tables() -> tuple[str, str]:
    """The tables docs/analysis.md quotes, from what `benchmarks/lle.py --scan` and `--chaos`
    measured (benchmarks/results/lle_separation_scan.json, lle_chaos.json)."""
    scan = json.loads((RESULTS / "lle_separation_scan.json").read_text())["scan"]
    first = next(iter(scan.values()))
    rows = ["| rtol | " + " | ".join(f"d0 {d:.0e}" for d in first["separations"]) + " |"]
    rows.append("|---" * (1 + len(first["separations"])) + "|")
    for rtol, e in scan.items():
        cells = [
            f"{m:+.2f} +/- {s:.2f}"
            for m, s in zip(e["mean_difference"], e["stderr_difference"], strict=True)
        ]
        rows.append(f"| {rtol} (4 x {e['cycles_per_start']} cycles) | " + " | ".join(cells) + " |")
    chaos = json.loads((RESULTS / "lle_chaos.json").read_text())
    out = [
        "| rtol | two trajectories [1/s] | cycles | converged | variational, same "
        "trajectories [1/s] | difference [1/s] | at rtol/100 [1/s] | CPU [s] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for rtol, e in chaos.items():
        out.append(
            f"| {rtol} | {e['lle']:.2f} +/- {e['stderr']:.2f} | {e['starts']} x "
            f"{e['cycles'] / e['starts']:g} | {'yes' if e['converged'] else 'no'} | "
            f"{e['lle_variational']:.2f} +/- {e['stderr_variational']:.2f} | "
            f"{e['difference']:+.2f} +/- {e['stderr_difference']:.2f} | "
            f"{e['lle_tight']:.2f} +/- {e['stderr_tight']:.2f} | {e['cpu_s']:.0f} |"
        )
    return "\n".join(rows), "\n".join(out)


def test_the_lyapunov_page_quotes_the_benchmark():
    """docs/analysis.md's separation scan and default calls on the chaos case are the numbers
    benchmarks/lle.py wrote (rerun it and paste lle_doc_tables() when they change)."""
    page = (Path(__file__).resolve().parents[2] / "docs" / "analysis.md").read_text()
    for table in lle_doc_tables():
        assert table in page
    # and the count of renormalisations on shrinkage it quotes for the chaos case
    e = json.loads((RESULTS / "lle_chaos.json").read_text())["1e-06"]
    quoted = (
        f"{e['shrink_renormalisations'][0]:.0f} of the estimate's "
        f"{e['renormalisations'][0]:.0f} renormalisations"
    )
    assert quoted in " ".join(page.split())
