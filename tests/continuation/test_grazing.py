"""Bifurcations at contact events (issue 38): the contact sequence of an orbit, grazings located
on the local extremum that reaches zero, and labels that their defining quantity confirms.

The stop oscillator's non-impacting orbit is the linear one, so it grazes where the linear
amplitude F / sqrt((k - m w^2)^2 + (c w)^2) equals the gap: a closed form for every parameter
set, here for sets the package's other tests do not use, found with scipy's brentq."""

import math

import numpy as np
import pytest
from helpers import STIFF_STOP
from scipy.optimize import brentq

import workbench
from workbench.continuation import branch_bifurcations, continue_orbit
from workbench.continuation._branch import (
    MARGIN_TOLERANCE,
    MULTIPLIER_TOLERANCE,
    _grazings,
    flips_at,
)
from workbench.continuation._contacts import (
    ContactSequence,
    ambiguous,
    contact_sequence,
    match_extrema,
)
from workbench.continuation._newton import OrbitPoint
from workbench.continuation._strobe import MapValue
from workbench.models.stop_oscillator import grazing_amplitude

#: the issue's stop oscillator (none of the suite's other sets): grazing near 1.0645 rad/s
ISSUE = {
    "mass": 2.0,
    "damping": 0.3,
    "stiffness": 3.0,
    "stop_stiffness": 1000.0,
    "gap": 0.5,
    "force": 0.4,
}
#: two more, drawn once at random (np.random.default_rng(1), cases 1 and 3 of a study script,
#: rounded): grazing near 0.7057 and 0.5815 rad/s
DRAWN = [
    {
        "mass": 2.5693,
        "damping": 0.54,
        "stiffness": 1.9322,
        "stop_stiffness": 193.22,
        "gap": 0.2938,
        "force": 0.222,
    },
    {
        "mass": 1.5078,
        "damping": 0.1917,
        "stiffness": 1.2121,
        "stop_stiffness": 36.36,
        "gap": 1.1256,
        "force": 0.8003,
    },
]


def lower_grazing(params: dict) -> float:
    """The lowest forcing frequency (rad s-1) where the linear orbit reaches the stop."""
    full = {"mass": 1.0, "stiffness": 1.0, **params}
    w0 = math.sqrt(full["stiffness"] / full["mass"])
    f = lambda w: grazing_amplitude({**full, "omega": w}) - full["gap"]  # noqa: E731
    grid = np.linspace(0.2 * w0, w0, 400)
    values = [f(w) for w in grid]
    i = next(i for i in range(grid.size - 1) if values[i] < 0 <= values[i + 1])
    return brentq(f, grid[i], grid[i + 1], xtol=1e-15, rtol=1e-15)


def _branch(params: dict, start: float, stop: float, **kw):
    scene = {
        "model": {"name": "stop_oscillator"},
        "parameters": dict(params, omega=start),
        "run": {"transient_cycles": 300},
    }
    return continue_orbit(scene, "omega", stop=stop, **kw)


def _assert_labels_confirmed(r, parameter: str = "omega") -> None:
    """Every stored label agrees with the quantity that defines it, and the located points lie
    in order of arclength (between the points before and after them)."""
    names = r.label.attrs["flag_meanings"].split()
    mu = r.multiplier_real.values + 1j * r.multiplier_imag.values
    for i in np.flatnonzero(r.label.values >= 3):
        kind = names[int(r.label.values[i])]
        m = mu[i][np.isfinite(mu[i])]
        if kind in ("fold", "branch_point"):
            assert np.min(np.abs(m - 1.0)) <= MULTIPLIER_TOLERANCE, (kind, m)
        elif kind == "period_doubling":
            assert np.min(np.abs(m + 1.0)) <= MULTIPLIER_TOLERANCE, (kind, m)
        elif kind == "neimark_sacker":
            c = m[np.abs(m.imag) > 0]
            assert np.min(np.abs(np.abs(c) - 1.0)) <= MULTIPLIER_TOLERANCE, (kind, m)
        elif kind == "grazing":
            values = r.extremum_value.values[i]
            scale = np.nanmax(values, axis=1) - np.nanmin(values, axis=1)
            rel = np.nanmin(np.abs(values), axis=1) / scale
            assert np.nanmin(rel) <= MARGIN_TOLERANCE, (kind, values)
        if 0 < i < r.sizes["point"] - 1 and r.branch[i - 1] == r.branch[i] == r.branch[i + 1]:
            p = r[parameter].values
            assert min(p[i - 1], p[i + 1]) - 1e-12 <= p[i] <= max(p[i - 1], p[i + 1]) + 1e-12


def test_the_sequence_sees_a_contact_between_two_samples():
    """A maximum of 1e-6 above zero whose samples all lie below zero: a crossing, found by the
    parabola through the samples; the margins are the extrema's values, matched by phase."""
    n = 400
    t = np.arange(n) / n
    g = np.cos(2 * np.pi * (t - 0.5 / n)) - 1.0 + 1e-6  # its top between samples 0 and 1
    assert g.max() < 0
    seq = contact_sequence(np.stack([g, g], axis=1), np.array([1, -1]), 1.0)
    assert seq.counts == (1, 1)
    top = seq.extrema[0][seq.extrema[0][:, 2] == 1][0]
    vertex = (2 * np.pi / n) ** 4  # the parabola's error on a cosine's top (its range is 2)
    assert top[1] == pytest.approx(1e-6, abs=vertex) and top[0] == pytest.approx(0.5 / n, abs=1e-6)
    below = contact_sequence(np.stack([g - 2e-6], axis=1), np.array([1]), 1.0)
    assert below.counts == (0,) and below.smallest_margin()[2] == pytest.approx(-1e-6, abs=vertex)
    # matched by phase and kind across two orbits whose extrema moved a little
    a = np.array([[0.1, -0.2, 1.0], [0.6, -1.0, -1.0]])
    b = np.array([[0.58, -1.0, -1.0], [0.12, 0.1, 1.0]])
    assert match_extrema(a, b, 1.0) == [(0, 1), (1, 0)]


def _rebounds(shift: float, depth: float, n: int = 5) -> ContactSequence:
    """The contact sequence of an orbit whose event function has a train of minima 0.4 ms
    apart (a journal's rebounds along the bearing's wall, as on the four-bar at 44 rad/s):
    values rising from -2e-7 by 1e-7 each, the train moved by ``shift`` (s) and lowered by
    ``depth`` (m); the first ``n`` of them."""
    phases = 0.134 + 4e-4 * np.arange(n) + shift
    values = -2e-7 + 1e-7 * np.arange(n) - depth
    rows = np.stack([phases, values, -np.ones(n)], axis=1)
    crossings = (np.array([0.1338 + shift]),)
    return ContactSequence(0.14, np.array([1]), crossings, (rows,), np.array([2.2e-6]))


def test_a_sign_change_is_no_grazing_where_the_matching_cannot_tell_the_rebounds_apart():
    """Two orbits whose train of rebound minima moved by 0.25 ms (0.6 of their spacing, as on
    the four-bar at 44.5 rad/s): matched by the nearest phase, a minimum is paired with its
    neighbour's partner, which seems 0.15 ms away, and a sign change appears that no extremum
    makes. The step is then not explained (it is halved); moved by 0.08 ms the pairs are told
    apart, and the one minimum that passes zero (+1e-8 -> -1e-8, the third) is the
    grazing."""
    a = _rebounds(0.0, -1e-8)  # the third minimum at +1e-8 above zero
    far = _rebounds(2.5e-4, 1e-8, 4)  # the last one moved out of the window
    near = _rebounds(0.8e-4, 1e-8)
    ea, eb = a.extrema[0], far.extrema[0]
    pairs = match_extrema(ea, eb, a.span)
    assert any(ambiguous(ea, eb, i, j, a.span) for i, j in pairs)
    assert not _grazings(a, far)[1]
    found, explained = _grazings(a, near)
    assert explained and found == [(0, pytest.approx(0.1348), -1.0)]
    en = near.extrema[0]
    assert not any(ambiguous(ea, en, i, j, a.span) for i, j in match_extrema(ea, en, a.span))


def test_the_grazing_search_follows_its_extremum_along_the_step():
    """Inside a step the margin is read on the extremum the step's detection matched (at the
    bracket's ends), and in between nearest to the phase interpolated between theirs: here the
    train moves by 0.08 ms over the step and its third minimum passes zero; the search reads
    that minimum at every trial point, its value linear in the arclength as built."""
    from types import SimpleNamespace

    import workbench.continuation._branch as branch

    smap = SimpleNamespace(samples=0)
    orbit = lambda shift, depth: SimpleNamespace(sequence=_rebounds(shift, depth))  # noqa: E731
    A, B = orbit(0.0, -1e-8), orbit(0.8e-4, 1e-8)
    found, explained = _grazings(A.sequence, B.sequence)
    assert explained and found == [(0, pytest.approx(0.1348), -1.0)]
    follow = branch._margin_follower(smap, A, B, 1.0, found[0])
    assert follow(A, 0.0) == pytest.approx(1e-8) and follow(B, 1.0) == pytest.approx(-1e-8)
    for sigma in (0.75, 0.25, 0.5, 0.9):  # the train moved by 0.8e-4 sigma
        pt = orbit(0.8e-4 * sigma, (2.0 * sigma - 1.0) * 1e-8)
        assert follow(pt, sigma) == pytest.approx((1.0 - 2.0 * sigma) * 1e-8, abs=1e-20)


def _rigid_impact(n: int, phase: float, rebound: float) -> np.ndarray:
    """Samples of x - g over a period of a mass that strikes a rigid stop at ``phase`` (in
    samples) with speed 1 and leaves it at ``rebound`` (a free flight's parabola each side:
    a corner at exactly 0)."""
    t = np.arange(n) - phase
    t = (t + n / 2) % n - n / 2  # in (-n/2, n/2]: before the impact < 0 < after
    a = 8.0 / n  # the flight's deceleration per sample^2 (a parabola through 0 each side)
    return np.where(t < 0, t + a * t * t / 2, -rebound * t + a * t * t / 2) / n


@pytest.mark.parametrize("phase", [0.0, 0.03, 0.3, 0.5, 0.7, 0.97])
@pytest.mark.parametrize("rebound", [0.2, 0.8])
def test_a_rigid_impact_is_no_margin_whatever_the_samples_phase(phase, rebound):
    """A rigid impact (x - g reaches 0 and turns with a jump of its rate) sampled at any phase:
    no extremum is kept at the impact. The parabola's vertex through the corner's samples lies
    above zero at some phases (the rates differ, r v against v), and that sign flipping from
    one orbit to the next was labelled a grazing (an impact oscillator in the grazing audit, at
    2.2805 rad/s). The free flight's own turning point stays a margin; a smooth extremum near
    zero (a grazing) and a compliant impact resolved by a sample inside it stay too."""
    n = 512
    g = _rigid_impact(n, 100 + phase, rebound)
    seq = contact_sequence(g[:, None], np.array([1]), 1.0)
    phases = seq.extrema[0][:, 0] * n
    assert not np.any(np.abs(phases - (100 + phase)) < 2), seq.extrema[0]
    assert seq.extrema[0].shape[0] >= 1  # the flight's own top, far from the impact
    smooth = np.cos(2 * np.pi * np.arange(n) / n) - 1.0 - 1e-9
    assert contact_sequence(smooth[:, None], np.array([1]), 1.0).extrema[0].shape[0] == 2
    bump = g.copy()
    bump[100] = 2e-4  # a sample inside a compliant contact shorter than the spacing: its depth
    kept = contact_sequence(bump[:, None], np.array([1]), 1.0).extrema[0]
    assert np.any(np.abs(kept[:, 0] * n - 100) < 1)


def test_an_event_that_is_no_switching_surface_has_crossings_and_no_margins():
    """A locator's crossings are counted (they are events the integration locates) but give no
    margins, and two orbits are compared by the surfaces' crossings alone."""
    t = np.arange(400) / 400
    g = np.cos(2 * np.pi * t) - 0.5
    seq = contact_sequence(np.stack([g, g], axis=1), np.array([1, -1]), 1.0, 400, [True, False])
    assert seq.counts == (1, 1) and seq.surface_counts == (1,)
    assert seq.extrema[0].shape[0] == 2 and seq.extrema[1].shape[0] == 0
    assert seq.smallest_margin()[0] == 0


def test_an_impact_shorter_than_the_samples_spacing_is_in_the_sequence():
    """A stop of 1e8 N/m against a 1 kg mass: each impact lasts about pi sqrt(m / k_s) = 0.3 ms,
    a tenth of the 2048 samples' spacing over the 7.9 s period (3.8 ms), and reaches about
    v sqrt(m / k_s) ~ 1e-4 m into the stop. Sampled at 2048 points the orbit read as a free
    flight that misses the stop by 0.5 mm (its 2 events per period in no crossing); the map now
    samples densely enough for its crossings to be the events the integration located, and the
    impact's depth is the margin."""
    from workbench.continuation import periodic_orbit
    from workbench.continuation._strobe import SAMPLES, StrobeMap

    params = {"mass": 1.0, "damping": 0.2, "stiffness": 1.0, "stop_stiffness": 1e8}
    params |= {"gap": 1.0, "force": 0.8, "omega": 0.8}
    scene = {"model": {"name": "stop_oscillator"}, "parameters": params}
    orbit = periodic_orbit(dict(scene, run={"transient_cycles": 300}), tolerance=1e-9)
    assert float(orbit.events_per_period[0]) == 2.0
    assert orbit.crossings_per_orbit.values[0].tolist() == [1, 1]
    depth = 0.8 * math.sqrt(1.0 / 1e8)  # order of magnitude: the speed ~0.8 m/s times sqrt(m/k_s)
    assert depth / 3 < float(orbit.event_max.values[0, 0]) < 3 * depth
    # the density stays with the map: a neighbour is read at the same one
    smap = StrobeMap(scene, "omega", rtol=1e-9)
    y = np.array([float(orbit.orbit_x[0]), float(orbit.orbit_v[0])])
    aux = orbit.orbit_discrete_state.values[0]
    assert smap.samples == SAMPLES
    seq = smap.contact_sequence(y, aux, 0.8)
    assert seq.counts == (1, 1) and seq.samples == smap.samples > SAMPLES
    assert smap.with_rtol(1e-10).samples == smap.samples


@pytest.mark.parametrize(
    "params, start, stop",
    [
        (ISSUE, 0.6, 1.15),
        (ISSUE, 0.6, 1.1),
        (DRAWN[0], 0.64, 0.74),
        (DRAWN[1], 0.52, 0.61),
    ],
    ids=["issue-1.15", "issue-1.1", "drawn-0", "drawn-1"],
)
def test_grazing_of_stop_oscillators_against_the_closed_form(params, start, stop):
    """Omega continued upwards through the lower grazing: one grazing, within 1e-6 of the
    closed form (relative), whatever the stop of the range (the step sequence); every label
    confirmed by its defining quantity. Before, the issue's set was labelled at 1.0798 against
    1.06454 (+1.4 %), with a "period doubling" whose multiplier was -0.082."""
    exact = lower_grazing(params)
    r = _branch(params, start, stop)
    found = branch_bifurcations(r, "omega")
    grazings = [b for b in found if b["type"] == "grazing" and b["resolved"]]
    assert len(grazings) == 1, found
    assert abs(grazings[0]["value"] - exact) < 1e-6 * exact, (grazings, exact)
    _assert_labels_confirmed(r)
    # below the grazing the orbit misses the stop, past it each period has one contact
    before = r.omega.values < exact * (1 - 1e-6)
    assert (r.crossings_per_orbit.values[before] == 0).all()
    assert (r.crossings_per_orbit.values[r.omega.values > exact * (1 + 1e-6)] == 1).all()


def test_a_stiff_stop_grazes_then_doubles_within_a_step_of_the_branch():
    """The audit's stiff stop (``STIFF_STOP``, tests/helpers.py): the grazing within 1e-6 of
    the closed form, then, 3.1e-6 rad/s on, where the contact's square-root law has swung the
    multipliers from a complex pair of modulus 0.44 past -1, a period doubling with its
    critical multiplier at -1. The branch cannot be stepped through the grazing; the doubling
    lies between the grazing orbit and the orbit the branch resumes from, and is located there
    at fixed parameter values. Before, the first contact, shorter than a solver step, was
    missed by the contact sequence: the grazing was labelled 2.8e-4 (relative) too far on."""
    exact = lower_grazing(STIFF_STOP)
    r = _branch(STIFF_STOP, 1.49, 1.74)
    found = branch_bifurcations(r, "omega")
    grazings = [b for b in found if b["type"] == "grazing" and b["resolved"]]
    assert len(grazings) == 1 and abs(grazings[0]["value"] - exact) < 1e-6 * exact, found
    flips = [b for b in found if b["type"] == "period_doubling"]
    assert len(flips) == 1 and flips[0]["resolved"], found
    assert abs(flips[0]["value"] - exact - 3.1e-6) < 0.05e-6  # docs/continuation.md
    assert abs(flips[0]["critical"] + 1) < MULTIPLIER_TOLERANCE
    # the multiplier beyond -1 past the grazing is the doubling's, located between: no flip
    assert grazings[0]["transition"] == "persistent", found
    _assert_labels_confirmed(r)
    before = r.omega.values < exact * (1 - 1e-6)
    assert (r.crossings_per_orbit.values[before] == 0).all()
    assert (r.crossings_per_orbit.values[r.omega.values > exact * (1 + 1e-6)] == 1).all()


def _orbit_with(multipliers) -> OrbitPoint:
    """An orbit whose monodromy has these eigenvalues (a complex one with its conjugate)."""
    blocks = []
    for mu in multipliers:
        mu = complex(mu)
        if mu.imag == 0.0:
            blocks.append(np.array([[mu.real]]))
        else:
            blocks.append(np.array([[mu.real, -mu.imag], [mu.imag, mu.real]]))
    n = sum(b.shape[0] for b in blocks)
    M, i = np.zeros((n, n)), 0
    for b in blocks:
        M[i : i + b.shape[0], i : i + b.shape[0]] = b
        i += b.shape[0]
    value = MapValue(np.zeros(n), np.zeros(0), np.zeros(0, int), M, 0, {})
    return OrbitPoint(1.0, np.zeros(n), np.zeros(0), value, 0, 0.0)


@pytest.mark.parametrize(
    "near, far, doublings, flip",
    [
        ([-0.5236, -0.0063], [-1.1105, -0.039], 0, True),  # the declared four-bar at 50.2374
        ([-0.5236, -0.0063], [-1.1105, -0.039], 1, False),  # a doubling located between
        ([0.3 + 0.3j, 0.1], [-1.2, 0.1], 1, False),  # the stiff stop: a pair swung past -1
        ([-0.9, 0.2], [-0.95, 0.3], 0, False),  # inside on both sides
        ([-1.3, 0.2], [-1.2, -1.1], 0, True),  # one beyond -1, then two
        ([0.5, 0.1], [0.7 + 0.9j, 0.1], 0, False),  # a complex pair leaves: no flip
    ],
)
def test_a_multiplier_jumping_across_minus_one_at_a_grazing_is_a_flip(near, far, doublings, flip):
    """Feigin's rule (di Bernardo, Feigin, Hogan & Homer 1999): the real multipliers below -1
    on the grazing's two sides and the period doublings located between them sum to an odd
    number exactly where a real multiplier jumps across -1 at the grazing itself."""
    assert flips_at(_orbit_with(near), _orbit_with(far), doublings) is flip


def test_a_grazing_the_corrector_cannot_cross_is_located_at_fixed_parameters(monkeypatch):
    """A map that is not smooth at a grazing (the nine-bar's, where a lift-off so short that
    the contact after it starts with an onset velocity near zero) lets steps cross it but not
    the corrector between: here the corrector is made to fail within 2e-6 of the grazing. The
    grazing is then located at fixed parameter values from the side the branch came from,
    within 1e-6 of the closed form, and typed persistent (the branch went on past it). Before,
    the search stopped at its first failure: unresolved, or labelled off the closed form."""
    import workbench.continuation._branch as branch
    from workbench.continuation._newton import NewtonFailure

    exact = lower_grazing(ISSUE)
    correct = branch.correct

    def rough(smap, pred, *args, **kwargs):
        pt = correct(smap, pred, *args, **kwargs)
        if abs(pt.p - exact) < 2e-6 * exact:
            raise NewtonFailure("the map is not smooth here")
        return pt

    monkeypatch.setattr(branch, "correct", rough)
    r = _branch(ISSUE, 0.6, 1.1)
    found = [b for b in branch_bifurcations(r, "omega") if b["type"] == "grazing"]
    assert len(found) == 1 and found[0]["resolved"], found
    assert abs(found[0]["value"] - exact) < 1e-6 * exact, (found, exact)
    assert found[0]["transition"] == "persistent"
    assert "located at fixed parameter values" in r.attrs["bifurcation_notes"]
    _assert_labels_confirmed(r)


def test_a_grazing_bracketed_on_a_jump_is_located_at_fixed_parameters(monkeypatch):
    """A contact law with memory can make the corrector converge, near the grazing, onto
    another orbit past it (the four-bar at 44.75 rad/s: the orbit just past holds the new
    contact's onset velocity, near zero; the bracket closed with the margin at 5.7e-12 m
    against a tolerance of 2.5e-12 m on one side and a jump on the other). Here every
    correction inside the search's bracket within 2e-5 short of the grazing returns the orbit
    2e-6 past it. The search along the
    arclength then closes on the jump, unconfirmed; the grazing is located at fixed parameter
    values from the side the branch came from, within 1e-6 of the closed form."""
    import workbench.continuation._branch as branch

    exact = lower_grazing(DRAWN[1])  # a branch whose steps cross it (ISSUE's fail there)
    correct, locate = branch.correct, branch._locate
    inside = []

    def jumping(smap, pred, *args, **kwargs):
        pt = correct(smap, pred, *args, **kwargs)
        if inside and -2e-5 * exact < pt.p - exact < 0.0:
            return branch.orbit_at(smap, pt.y, pt.aux, exact * (1 + 2e-6), tolerance=1e-9)
        return pt

    def search(*args, **kwargs):
        inside.append(True)
        try:
            return locate(*args, **kwargs)
        finally:
            inside.pop()

    monkeypatch.setattr(branch, "correct", jumping)
    monkeypatch.setattr(branch, "_locate", search)
    r = _branch(DRAWN[1], 0.9 * exact, 1.1 * exact)
    found = [b for b in branch_bifurcations(r, "omega") if b["type"] == "grazing"]
    assert len(found) == 1 and found[0]["resolved"], (found, r.attrs["bifurcation_notes"])
    assert abs(found[0]["value"] - exact) < 1e-6 * exact, (found, exact)
    assert branch.JUMPED_ACROSS in r.attrs["bifurcation_notes"]
    _assert_labels_confirmed(r)


def test_the_grazing_search_ahead_ends_where_its_bracket_closes(monkeypatch):
    """The search for a grazing ahead of the last orbits (Newton at fixed parameter values)
    can come back to a value it has (the nine-bar's 40-event orbit, whose existence ends at
    1.8611 pi with its shallowest impact still 1.7 nm deep: every trial past the end fails and
    the halvings lead back). Its bracket then closes to one value; the search ends there
    without a grazing instead of dividing by zero."""
    import workbench.continuation._branch as branch
    from workbench.continuation._strobe import StrobeMap

    scene = {"model": {"name": "stop_oscillator"}, "parameters": dict(ISSUE, omega=1.063)}
    smap = StrobeMap(scene, "omega")
    cfg = branch.BranchSettings(pscale=0.1, bounds=(0.9, 1.1), tolerance=1e-9)
    y0, a0 = smap.initial(1.063, 300)
    prev = branch.orbit_at(smap, y0, a0, 1.063, tolerance=1e-9)
    A = branch.orbit_at(smap, prev.y, prev.aux, 1.064, tolerance=1e-9)  # 5e-4 short of it
    # every trial converges back onto prev's value: the bracket closes at once
    monkeypatch.setattr(branch, "orbit_at", lambda *args, **kwargs: prev)
    assert branch._grazing_ahead(smap, prev, A, cfg) is None


def test_an_unconfirmed_bifurcation_is_stored_unresolved(monkeypatch):
    """Where the defining quantity does not confirm the kind (here: a tolerance no multiplier
    meets), the point is labelled unresolved and the bifurcation kept with its suspected kind,
    its bracket and the quantity's value; nothing is labelled a period doubling."""
    import workbench.continuation._branch as branch

    monkeypatch.setattr(branch, "MULTIPLIER_TOLERANCE", 1e-300)
    r = continue_orbit(
        {
            "model": {"name": "duffing"},
            "parameters": {"gamma": 0.25},
            "run": {"transient_cycles": 100},
        },
        "gamma",
        stop=0.27,
    )
    names = r.label.attrs["flag_meanings"].split()
    labels = [names[int(v)] for v in r.label.values]
    assert "period_doubling" not in labels and "unresolved" in labels
    (b,) = branch_bifurcations(r, "gamma")
    assert b["type"] == "period_doubling" and not b["resolved"]
    assert int(r.bifurcation_resolved[0]) == 0
    lo, hi = float(r.bifurcation_lower[0]), float(r.bifurcation_upper[0])
    assert lo <= float(r.bifurcation_parameter[0]) <= hi and hi - lo < 1e-6
    assert 0 < float(r.bifurcation_test[0]) < 1e-3  # |mu + 1| at the located point


def test_the_parameter_never_leaves_its_valid_range():
    """Damping continued from 0.1 N s/m down to a bound below its valid range (>= 0): the branch
    ends inside the range with the reason, never with an error (the issue: omega stepped to a
    negative value and ended in a SceneError traceback)."""
    params = dict(ISSUE, gap=10.0, omega=0.5)
    scene = {"model": {"name": "stop_oscillator"}, "parameters": params}
    r = continue_orbit(scene, "damping", stop=-0.05, start=0.1, state={"x": 0.0, "v": 0.0})
    assert (r.damping.values >= 0.0).all()
    assert "damping" in r.attrs["branch_ended"] or "corrector" in r.attrs["branch_ended"]
    assert float(r.damping.min()) < 1e-3  # it went as far as the range allows


def test_a_branch_ends_on_its_bound():
    """The last point of a branch is the orbit at the bound of its range, not beyond it."""
    r = _branch(dict(ISSUE, gap=10.0), 0.6, 0.7)
    assert float(r.omega[-1]) == pytest.approx(0.7, abs=1e-12)
    assert r.omega.values.max() <= 0.7 and "bound 0.7" in r.attrs["branch_ended"]
    assert workbench.continuation.branch_bifurcations(r, "omega") == []


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_the_parameter_column_is_taken_on_the_points_own_side_of_a_jump(side):
    """A map whose contact structure changes, and whose value jumps, 0.3 of the stencil's step
    from p (above or below): the parameter column is the derivative on p's own side, not the
    jump over the step (the central difference across it is off by 1 / (2 h), ~1e3 here)."""
    from workbench.continuation._strobe import MapValue, StrobeMap

    slope = np.array([0.7, -1.3])  # d y1 / d omega, state units per rad s-1
    p = 1.0
    pscale = 0.5
    h = math.sqrt(1e-8) * pscale
    jump_at = p + side * 0.3 * h

    class Jumping(StrobeMap):
        def __call__(self, y, aux, q, *, tangent=True):
            self._spent[0] += 1
            touching = (q - jump_at) * side > 0.0
            y1 = np.asarray(y, float) + slope * q + (1.0 if touching else 0.0)
            none = np.array([], int)
            return MapValue(y1, np.asarray(aux, float), none, None, 2 * touching, {})

    scene = {"model": {"name": "stop_oscillator"}, "parameters": dict(ISSUE, omega=p)}
    smap = Jumping(workbench.load_scene(scene), "omega", rtol=1e-8)
    y = np.array([0.1, 0.0])
    column = smap.parameter_derivative(y, np.zeros(0), p, np.array([], int), pscale)
    exact = slope * pscale / smap.scale()
    np.testing.assert_allclose(column, exact, rtol=1e-6)
    # without a jump nearby: the central difference, two evaluations
    jump_at = p + side * 10.0 * h
    spent = smap.evaluations
    column = smap.parameter_derivative(y, np.zeros(0), p, np.array([], int), pscale)
    np.testing.assert_allclose(column, exact, rtol=1e-6)
    assert smap.evaluations - spent == 2
