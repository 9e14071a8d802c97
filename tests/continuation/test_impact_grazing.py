"""Grazing in the impact oscillator against Nordmark's square-root map (issue 38, item 8: a
nonsmooth case with a published answer).

The system (``impact_oscillator``): m x'' + c x' + k x = F cos(omega t) for x < sigma, v -> -r v
at the stop x = sigma. Here m = k = F = 1 (SI), so that it is the literature's
x'' + 2 zeta x' + x = cos(omega t), with zeta = 1.25 (c = 2.5 N s/m), r = 0.8, sigma = 0.17 m:
an overdamped oscillator, whose non-impacting periodic orbit (the linear one) has the real
Floquet multipliers lambda_i = exp(s_i T), s_i the roots of m s^2 + c s + k (-0.5 and -2 s-1),
T = 2 pi / omega: lambda_1 = 0.2099 and lambda_2 = lambda_1^4 at the grazing, omega_g = 2.0122
rad/s, where the linear amplitude equals sigma. Omega decreasing through omega_g, the orbit
starts to impact.

**The normal form.** Near the grazing the stroboscopic map is, to leading order, Nordmark's
(1991) square-root map in the virtual penetration X of the next swing (the depth the free
motion would reach beyond the stop): X -> lambda_1 X + (1 - lambda_1)(A - sigma) while X <= 0
(the linear map; A the linear amplitude), and an impact with velocity sqrt(2 a X), a = omega^2
sigma the deceleration at the grazing top, kicks the velocity by -(1 + r) sqrt(2 a X), which
moves the next top by that kick times the free response to a unit velocity after one period,
lambda_1 / (s_1 - s_2) (the lambda_2 part is lambda_1^3 smaller). Scaled by gamma^2, gamma =
(1 + r) sqrt(2 a) lambda_1 / (s_1 - s_2), this is the map of di Bernardo, Budd, Champneys &
Kowalczyk (2008, Ch. 4):

    x -> mu + lambda x  (x <= 0),    x -> mu - sqrt(x)  (x > 0),
    lambda = lambda_1,  mu = (1 - lambda_1) (A(omega) - sigma) / gamma^2.

Its periodic orbits with one impact (x_1 > 0, then n - 1 free iterates) are in closed form:
with S_n = (1 - lambda^n) / (1 - lambda) and s = sqrt(x_1), s^2 + lambda^(n-1) s = mu S_n; the
orbit is stable while its multiplier -lambda^(n-1) / (2 s) lies above -1, i.e. for mu above
mu_flip(n) = 3 lambda^(2n-2) / (4 S_n), and exists (its last free iterate x_n <= 0, i.e. x_1 <=
mu) for mu below mu_BC(n) = lambda^(2n-4) / S_(n-1)^2, where it collides with the border. The
windows (mu_flip(n), mu_BC(n)) accumulate at mu = 0 with ratio -> lambda^2 (here 0.044): the
period adds one per window as the grazing is approached (period adding). Adjacent windows
overlap (mu_BC(n+1) > mu_flip(n)) for every n iff lambda < 1/4, and a window is non-empty for
large n iff lambda < 2/3. Hence the published condition (Nordmark 1991; Chin, Ott, Nusse &
Grebogi 1994, Phys. Rev. E 50:4427; di Bernardo et al. 2008, Ch. 4), for real positive
lambda: 0 < lambda < 1/4, period adding with overlapping windows (a stable period-n orbit for
every small mu > 0, no chaos); 1/4 < lambda < 2/3, period adding with chaos between the
windows; 2/3 < lambda < 1, no periodic window at small mu (robust chaos). The restitution
enters only gamma (the factor 1 + r > 0), never the condition. The impacting period-1 orbit
exists past the grazing but is unstable (multiplier ~ -1 / (2 mu)): no period-1 attractor.
With lambda_1 = 0.21 < 1/4 the impact oscillator here is in the first case.

The flow's windows are compared with the map's in mu computed from omega with no fitted
constant; the normal form drops terms of relative order sqrt(mu), so each comparison allows
three times sqrt(mu). (The flips of the period-3 .. 6 orbits measured -3.8 %, -0.74 %, -0.15 %
and -0.028 % from mu_flip(n) = 1.2e-3, 5.1e-5, 2.2e-6 and 9.8e-8: about -sqrt(mu) each.)
"""

import math
import re

import numpy as np
import pytest
from scipy.optimize import brentq

import workbench
from workbench.continuation import (
    StrobeMap,
    branch_bifurcations,
    continue_orbit,
    periodic_orbit,
    strobe_period,
)
from workbench.models.impact_oscillator import grazing_amplitude

PARAMS = {
    "mass": 1.0,
    "damping": 2.5,
    "stiffness": 1.0,
    "gap": 0.17,
    "restitution": 0.8,
    "force": 1.0,
}


def scene(omega: float, **extra) -> dict:
    return {
        "model": {"name": "impact_oscillator"},
        "parameters": dict(PARAMS, omega=omega),
        "run": {"transient_cycles": 300},
        **extra,
    }


def omega_grazing() -> float:
    """Where the linear amplitude equals the gap (rad s-1): the closed form of the grazing."""
    f = lambda w: grazing_amplitude({**PARAMS, "omega": w}) - PARAMS["gap"]  # noqa: E731
    return brentq(f, 1.5, 3.0, xtol=1e-15, rtol=1e-15)


OMEGA_G = omega_grazing()


def free_roots() -> tuple[float, float]:
    """The roots s_1 > s_2 (s-1) of m s^2 + c s + k: the overdamped free motion."""
    m, c, k = PARAMS["mass"], PARAMS["damping"], PARAMS["stiffness"]
    root = math.sqrt(c * c - 4 * m * k)
    return (-c + root) / (2 * m), (-c - root) / (2 * m)


S1, S2 = free_roots()
LAMBDA = math.exp(S1 * 2 * math.pi / OMEGA_G)  # the leading multiplier at the grazing
GAMMA = (1 + PARAMS["restitution"]) * math.sqrt(2 * OMEGA_G**2 * PARAMS["gap"]) * LAMBDA / (S1 - S2)


def mu_of(omega: float) -> float:
    """The square-root map's parameter at omega (positive past the grazing)."""
    amplitude = grazing_amplitude({**PARAMS, "omega": omega})
    return (1 - LAMBDA) * (amplitude - PARAMS["gap"]) / GAMMA**2


def omega_of(mu: float) -> float:
    """The forcing frequency (rad s-1) where the map's parameter is mu (> 0: impacting)."""
    return brentq(lambda w: mu_of(w) - mu, OMEGA_G * 0.9, OMEGA_G, xtol=1e-15, rtol=1e-15)


def S(n: int, lam: float = LAMBDA) -> float:
    return (1 - lam**n) / (1 - lam)


def mu_flip(n: int, lam: float = LAMBDA) -> float:
    """Below this mu the period-n orbit (one impact) has a multiplier below -1."""
    return 3 * lam ** (2 * n - 2) / (4 * S(n, lam))


def mu_border(n: int, lam: float = LAMBDA) -> float:
    """Above this mu the period-n orbit's last free iterate reaches the border (x_n > 0)."""
    return lam ** (2 * n - 4) / S(n - 1, lam) ** 2


def impact_point(n: int, mu: float, lam: float = LAMBDA) -> float:
    """x_1 > 0 of the map's period-n orbit with one impact: sqrt(x_1) solves
    s^2 + lam^(n-1) s = mu S_n."""
    s = (-(lam ** (n - 1)) + math.sqrt(lam ** (2 * n - 2) + 4 * mu * S(n, lam))) / 2
    return s * s


def only_stable(n: int) -> float:
    """The middle (geometric) of the mu where period n is the map's only stable orbit."""
    return math.sqrt(max(mu_border(n + 1), mu_flip(n)) * mu_border(n))


def predicted_period(mu: float) -> int:
    """The period of the map's attractor at mu where only one orbit is stable (else 0)."""
    found = [n for n in range(2, 40) if mu_flip(n) < mu < mu_border(n)]
    return found[0] if len(found) == 1 else 0


def square_root_map(x: np.ndarray, mu, lam: float) -> np.ndarray:
    return np.where(x <= 0.0, mu + lam * x, mu - np.sqrt(np.abs(x)))


def map_period(mu, lam: float, x0=0.0, transient: int = 20000, keep: int = 400) -> np.ndarray:
    """The least period (up to 64; 0: none) of the square-root map's motion from x0 after a
    transient, per mu (vectorised)."""
    mu = np.asarray(mu, dtype=float)
    x = np.broadcast_to(np.asarray(x0, dtype=float), mu.shape).copy()
    for _ in range(transient):
        x = square_root_map(x, mu, lam)
    xs = np.empty((keep, *mu.shape))
    for i in range(keep):
        x = square_root_map(x, mu, lam)
        xs[i] = x
    tol = 1e-9 * np.abs(xs).max(axis=0)
    out = np.zeros(mu.shape, dtype=int)
    for k in range(64, 0, -1):
        out = np.where(np.all(np.abs(xs[k:] - xs[:-k]) <= tol, axis=0), k, out)
    return out


def flow_period(omega: float, cycles: int = 64) -> int:
    """The strobe period of the impact oscillator's motion after the scene's transient."""
    run = workbench.simulate(
        {
            **scene(omega),
            "run": {"transient_cycles": 300, "cycles": cycles},
            "record": {"samples_per_period": 1},
        }
    )
    return strobe_period(np.stack([run.x.values, run.v.values], axis=1))


# -- the model ---------------------------------------------------------------------------------


def test_a_start_beyond_the_stop_is_refused_in_one_line():
    with pytest.raises(workbench.SceneError, match=r"^initial\.x: got 0\.2 m, beyond the stop"):
        workbench.prepare({**scene(2.1), "initial": {"x": 0.2}})


def test_chattering_ends_in_a_rest_on_the_stop():
    """Slow forcing that presses the mass on the stop (F cos(omega t) > k g for 40 % of each
    period): the impacts accumulate (infinitely many in finite time without a rest), the mass
    comes to rest on the stop and is let go where the forcing stops pressing it. The run ends
    with a bounded number of events; it rests only while pressed, and is never beyond the
    stop. Without the rest (a rest speed of 1e-300 m/s) the same run does not end."""
    pressed_case = {
        "model": {"name": "impact_oscillator"},
        "parameters": {"gap": 0.3, "omega": 0.2, "damping": 0.2, "restitution": 0.8},
        "run": {"cycles": 10},
        "record": {"samples_per_period": 400, "variables": ["x", "v", "sticking"]},
    }
    run = workbench.simulate(pressed_case)
    pressed = np.cos(0.2 * run.time.values) > 0.3  # F cos(omega t) > k g
    resting = run.sticking.values > 0
    assert 0.15 < resting.mean() < pressed.mean()
    assert not (resting & ~pressed).any()
    assert np.all(run.v.values[resting] == 0.0) and np.all(run.x.values[resting] == 0.3)
    assert run.x.values.max() <= 0.3
    assert run.attrs["solver_events"] < 100 * 10
    endless = dict(pressed_case, solver={"max_steps": 100_000})
    endless["parameters"] = dict(pressed_case["parameters"], rest_speed=1e-300)
    with pytest.raises(workbench.SolverError, match="max_steps"):
        workbench.simulate(endless)


def test_shallow_impacts_are_located_at_the_default_steps():
    """Where the square-root map's only stable orbit has period 6 (mu ~ 2e-7, 1e-7 past the
    grazing in omega), the impact reaches a virtual depth of ~1e-8 m: an excursion beyond the
    stop some 3e-4 s long, which the default steps (~T/40) step over. Located all the same, the
    motion has period 6 and its orbit's multiplier is the map's, -lambda^5 / (2 sqrt(x_1)),
    within three times sqrt(mu); the monodromy by copies, whose offsets (1e-6 of the state's
    size) reach past so shallow an impact, is not asked for."""
    mu = only_stable(6)
    omega = omega_of(mu)
    assert flow_period(omega) == 6
    orbit = periodic_orbit(scene(omega), periods=6)
    expected = -(LAMBDA**5) / (2 * math.sqrt(impact_point(6, mu)))
    measured = float(orbit.multiplier_real[0, 0])
    assert abs(measured / expected - 1) < 3 * math.sqrt(mu), (measured, expected)


# -- (a) the non-impacting orbit up to its grazing ----------------------------------------------


def test_the_non_impacting_orbit_grazes_at_the_closed_form_and_adds_periods_past_it():
    """Omega continued down from 2.3 rad/s: the linear orbit with its real multipliers
    (exp(s_i T), closed form, to 1e-6) up to one grazing, labelled and confirmed within 1e-6 of
    the closed form (relative), where the branch ends: no period-1 orbit is found past it, and
    the transition is a border collision whose note names the period of the motion past it,
    the square-root map's period there (its only stable orbit at the note's mu)."""
    r = continue_orbit(scene(2.3), "omega", stop=1.9)
    found = branch_bifurcations(r, "omega")
    assert [b["type"] for b in found] == ["grazing"] and found[0]["resolved"], found
    assert abs(found[0]["value"] - OMEGA_G) < 1e-6 * OMEGA_G
    i = found[0]["index"]
    period = 2 * math.pi / float(r.omega[i])
    exact = np.exp(np.array([S1, S2]) * period)
    assert np.allclose(r.multiplier_real.values[i], exact, rtol=1e-6, atol=1e-9)
    assert np.all(r.multiplier_imag.values[i] == 0.0)
    flags = r.bifurcation_transition.attrs["flag_meanings"].split()
    assert flags[int(r.bifurcation_transition[0])] == "border_collision"
    assert found[0]["transition"] == "border_collision"
    note = r.attrs["bifurcation_notes"]
    match = re.search(r"no period-1 orbit found past it; period (\d+) at ([0-9.eE+-]+)", note)
    assert match, note
    k, where = int(match.group(1)), float(match.group(2))
    assert where < OMEGA_G and predicted_period(mu_of(where)) == k >= 2
    # found from the first step that failed across it, not after halving to the least step
    assert "the grazing ahead lies within a step that failed" in r.attrs["branch_ended"]


# -- (b) period adding in the flow ---------------------------------------------------------------


@pytest.mark.parametrize("n", [3, 4, 5, 6])
def test_the_attractor_adds_one_period_per_window(n):
    """Where the square-root map has period n as its only stable orbit (the middle of that mu
    range; from one n to the next it shrinks about 23-fold, the windows' ratio tending to
    lambda^2 = 0.044), the impact oscillator's motion has period n."""
    assert flow_period(omega_of(only_stable(n))) == n


def flip_of_period(n: int) -> float:
    """The mu where the impact oscillator's period-n orbit loses stability (multiplier -1),
    located along its branch from the middle of its window towards the grazing."""
    start = omega_of(only_stable(n))
    stop = omega_of(only_stable(n) / 30)
    r = continue_orbit(scene(start), "omega", stop=stop, periods=n)
    flips = [b for b in branch_bifurcations(r, "omega") if b["type"] == "period_doubling"]
    assert flips and flips[0]["resolved"], branch_bifurcations(r, "omega")
    assert abs(flips[0]["critical"] + 1) < 1e-3
    return mu_of(flips[0]["value"])


def test_the_windows_scale_as_the_square_root_map_predicts():
    """The flips of the period-n orbits (n = 3 .. 6) against mu_flip(n): within three times
    sqrt(mu) of the map's (no fitted constant); and their ratios, which need no constant at
    all, against lambda^2 S_n / S_(n+1) (-> lambda^2 = 0.044) within the sum of the two
    allowances."""
    measured = {n: flip_of_period(n) for n in (3, 4, 5, 6)}
    for n, mu in measured.items():
        allowed = 3 * math.sqrt(mu_flip(n))
        assert abs(mu / mu_flip(n) - 1) < allowed, (n, mu, mu_flip(n))
    for n in (3, 4, 5):
        ratio = measured[n + 1] / measured[n]
        expected = LAMBDA**2 * S(n) / S(n + 1)
        allowed = 3 * (math.sqrt(mu_flip(n)) + math.sqrt(mu_flip(n + 1)))
        assert abs(ratio / expected - 1) < allowed, (n, ratio, expected)


def test_a_border_collision_past_which_the_motion_has_one_period_less():
    """The period-4 orbit continued away from the grazing: its last free swing grazes the stop
    (a grazing labelled within three times sqrt(mu) of mu_BC(4)), past which no period-4 orbit
    exists and the only stable orbit of the map has period 3: the transition is a border
    collision with period 3 past it. (The probe 1e-5 of the range past the located grazing was
    still short of the border collision, and 200 periods after it the motion had not settled:
    it read period 4, then period 6.)"""
    start = omega_of(only_stable(4))
    stop = omega_of(mu_border(4) * 2)
    r = continue_orbit(scene(start), "omega", stop=stop, periods=4)
    grazings = [b for b in branch_bifurcations(r, "omega") if b["type"] == "grazing"]
    assert len(grazings) == 1 and grazings[0]["resolved"], branch_bifurcations(r, "omega")
    mu = mu_of(grazings[0]["value"])
    assert abs(mu / mu_border(4) - 1) < 3 * math.sqrt(mu_border(4)), (mu, mu_border(4))
    flags = r.bifurcation_transition.attrs["flag_meanings"].split()
    assert flags[int(r.bifurcation_transition[0])] == "border_collision"
    note = r.attrs["bifurcation_notes"]
    match = re.search(r"no period-4 orbit found past it; period (\d+) at ([0-9.eE+-]+)", note)
    assert match and int(match.group(1)) == 3, note
    assert mu_of(float(match.group(2))) > mu  # sampled past the grazing


@pytest.mark.parametrize("beyond", [3e-6, 1e-5])
def test_the_motion_past_a_border_collision_is_sampled_until_it_settles(beyond):
    """From the period-4 orbit at its border collision, 3e-6 and 1e-5 rad/s past it (the
    located grazing lies within 1e-7 rad/s of it): the strobe samples repeat every 6 periods
    within 1e-4 for hundreds of periods while the motion settles onto the period-3 orbit (whose
    multiplier is near -1 there), the only stable orbit past the border collision; the
    attractor's period is 3 (before: 6)."""
    from workbench.continuation._branch import _attractor_period

    start = omega_of(only_stable(4))
    r = continue_orbit(scene(start), "omega", stop=omega_of(mu_border(4) * 2), periods=4)
    i = int(r.bifurcation_point[0])
    y = np.array([float(r.orbit_x[i]), float(r.orbit_v[i])])
    smap = StrobeMap(scene(OMEGA_G), "omega")
    assert _attractor_period(smap, y, np.zeros(2), float(r.omega[i]) - beyond) == 3


def test_an_underdamped_grazing_whose_motion_jumps_to_a_distant_orbit():
    """An underdamped impact oscillator the other tests do not contain (damping ratio 0.144,
    r = 0.335, drawn by ``benchmarks/grazing_audit.py``): omega continued down through the
    grazing, located within 1e-6 of its closed form. Newton finds no period-1 orbit near the
    grazing one past it, yet the motion there has period 1: it has jumped to a stable impacting
    orbit far from the grazing orbit (its family folds and grazes again before it returns to
    the grazing orbit), and the note says how far (before it said "no period-1 orbit found
    past it; period 1", which read as a contradiction)."""
    params = {"mass": 1.0, "damping": 0.2872845058753153, "stiffness": 1.0, "force": 1.0}
    params["restitution"] = 0.33505495654807665
    params["gap"] = grazing_amplitude({**params, "gap": 1.0, "omega": 1.951727097335381})
    exact = brentq(
        lambda w: grazing_amplitude({**params, "omega": w}) - params["gap"], 1.9, 2.0, xtol=1e-15
    )
    r = continue_orbit(
        {
            "model": {"name": "impact_oscillator"},
            "parameters": dict(params, omega=1.15 * exact),
            "run": {"transient_cycles": 300},
        },
        "omega",
        stop=0.95 * exact,
    )
    found = branch_bifurcations(r, "omega")
    assert [b["type"] for b in found] == ["grazing"] and found[0]["resolved"], found
    assert abs(found[0]["value"] - exact) < 1e-6 * exact
    assert found[0]["transition"] == "border_collision"
    note = r.attrs["bifurcation_notes"]
    match = re.search(r"period 1 at ([0-9.eE+-]+), on an orbit ([0-9.eE+-]+) \(scaled\)", note)
    assert match, note
    assert float(match.group(1)) < exact and 0.235 < float(match.group(2)) < 0.245


# -- (c) the square-root map itself ---------------------------------------------------------------


def test_the_square_root_map_has_the_closed_form_windows():
    """Iterated directly (numpy): at lambda = lambda_1 the middle of each window has period n
    (n = 2 .. 8); the period-n orbit is stable just above mu_flip(n) and not just below; it
    exists just below mu_BC(n) and not just above (from the orbit's own points, the motion
    leaves it for period n - 1)."""
    for n in range(2, 9):
        assert map_period(np.array(only_stable(n)), LAMBDA) == n
    for n in range(3, 8):
        for side, want in ((1 + 1e-3, n), (1 - 1e-3, 2 * n)):
            mu = mu_flip(n) * side
            x0 = impact_point(n, mu) * (1 + 1e-9)
            assert map_period(np.array(mu), LAMBDA, x0=x0) == want
        for side, want in ((1 - 1e-3, n), (1 + 1e-3, n - 1)):
            mu = mu_border(n) * side
            assert map_period(np.array(mu), LAMBDA, x0=impact_point(n, mu)) == want


@pytest.mark.parametrize(
    "lam, periodic",
    [(0.21, "everywhere"), (0.5, "in the windows only"), (0.8, "nowhere")],
)
def test_the_published_condition_on_the_multiplier(lam, periodic):
    """Below 1/4 every small mu > 0 has a periodic attractor; between 1/4 and 2/3 the windows
    are periodic and the gaps between them are not; above 2/3 no small mu is periodic."""
    mu = np.logspace(-7, -2, 300)
    period = map_period(mu, lam)
    if periodic == "everywhere":
        assert np.all(period > 0)
    elif periodic == "nowhere":
        assert np.all(period == 0)
    else:
        for n in range(3, 9):
            assert mu_border(n + 1, lam) < mu_flip(n, lam)  # a gap below each window
            gap = math.sqrt(mu_border(n + 1, lam) * mu_flip(n, lam))
            window = math.sqrt(mu_flip(n, lam) * mu_border(n, lam))
            assert map_period(np.array([gap, window]), lam).tolist() == [0, n]
