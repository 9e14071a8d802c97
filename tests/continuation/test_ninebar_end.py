"""How the nine-bar's impacting period-1 orbit ends (issue 38, item 6b), on Fig. 32's scene
(c = 0.1 mm at A and B, c_f = 0.01, Lankarani-Nikravesh contact) at rtol 1e-10.

Just below 1.8611 pi the orbit (40 contact events per period) is stable and far from any
smooth bifurcation (multipliers 0.33 and -0.13), yet past 1.8611 pi Newton finds no period-1
orbit. What ends it is a lasting contact at joint A that nearly lifts off at phase 0.952 s: its
penetration dips to a few hundredths of a nanometre. The dip is narrower than the default
samples' spacing, so the contact sequence reads it only with the near-grazing refinement
(:data:`workbench.continuation._strobe.NEAR_MARGIN`); read at the old fixed density it seemed
1.7 nm deep, and the branch's end looked like no grazing at all. Across that lift-off the map
is not even continuous: the contact splits in two, the second starts with an onset velocity
near zero, and the Lankarani-Nikravesh damping holds that velocity for the rest of the contact
(the law's memory), so the map jumps.
"""

import math
from pathlib import Path

import numpy as np
import pytest

import workbench
from workbench.continuation import _strobe
from workbench.continuation._branch import BranchSettings, _with_tangent
from workbench.continuation._newton import orbit_at
from workbench.continuation._strobe import StrobeMap

SCENE = Path(__file__).resolve().parents[2] / "studies" / "bifurcation_speed" / "sweep.toml"
#: just below the end of the 40-event orbit, rad/s
OMEGA = 1.8610999 * math.pi


@pytest.fixture(scope="module")
def end():
    scene = workbench.load_scene(SCENE).replace(sweep={})
    smap = StrobeMap(scene, "omega", rtol=1e-10)
    y, aux = smap.initial(OMEGA, 200)
    return smap, orbit_at(smap, y, aux, OMEGA, tolerance=1e-6, max_iterations=15)


@pytest.mark.slow
def test_the_orbit_just_below_the_end_is_stable_and_far_from_a_smooth_bifurcation(end):
    smap, pt = end
    assert pt.value.events == 40
    mu = np.sort(np.abs(pt.multipliers))[::-1]
    assert 0.2 < mu[0] < 0.5 and mu[1] < 0.2, mu  # no multiplier near +1 or -1


@pytest.mark.slow
def test_a_lasting_contact_at_joint_a_is_within_a_tenth_of_a_nanometre_of_lifting_off(end):
    """Read at the fixed density of before (8192 samples per period) the shallowest dip looked
    1.7 nm deep; refined near the grazing it is below 0.1 nm, 1e-4 of its event function's
    range at most, at joint A (event function 0) and phase 0.952 s."""
    smap, pt = end
    coarse = smap.contact_sequence(pt.y, pt.aux, pt.p, samples=8192)
    _, _, shallow = coarse.smallest_margin()
    seq = smap.contact_sequence(pt.y, pt.aux, pt.p)
    k, phase, value = seq.smallest_margin()
    assert seq.counts == (14, 14, 6, 6)
    assert k == 0 and abs(phase - 0.9519) < 1e-3, (k, phase)
    assert 0.0 < value < 1e-10 and value / seq.scale[k] < 1e-4, (value, seq.scale[k])
    assert shallow > 10 * value, (shallow, value)


@pytest.mark.slow
def test_the_map_jumps_where_that_contact_lifts_off(end):
    """From the orbit, states moved along the branch's tangent (towards the end): 3e-3 scaled
    units on, the map still moves linearly (|change| well below the move); 1e-2 on, the lasting
    contact has split (42 events, 15 crossings at A's onset function) and the map has jumped by
    more than ten times the move."""
    smap, pt = end
    cfg = BranchSettings(pscale=0.01 * math.pi, bounds=(1.8 * math.pi, 1.9 * math.pi))
    direction = np.zeros(pt.y.size + pt.value.live.size + 1)
    direction[-1] = 1.0
    _with_tangent(smap, pt, direction, cfg)
    s = smap.scale()
    v = pt.tau[: pt.y.size] / np.linalg.norm(pt.tau[: pt.y.size])
    base = smap(pt.y, pt.aux, pt.p, tangent=False)

    def moved(size):
        out = smap(pt.y + size * s * v, pt.aux, pt.p, tangent=False)
        return out, float(np.max(np.abs((out.y1 - base.y1) / s))) / size

    near, ratio_near = moved(3e-3)
    far, ratio_far = moved(1e-2)
    assert near.events == 40 and ratio_near < 1.0, ratio_near
    assert far.events == 42 and ratio_far > 10.0, ratio_far


@pytest.mark.slow
def test_a_grazing_curve_starts_from_that_dip_not_from_a_broader_extremum(end):
    """A grazing curve (:func:`workbench.continuation.continue_curve`) starts Newton's method
    at the touch its ``_touch`` finds. Sampled at a fixed 1024 points per period (the code
    before) it picked another extremum of A's event function, 12 ms from the dip, with
    h = -1.1e-4 of its scale and dh/dt far from 0; read off the refined contact sequence it
    starts at the dip itself."""
    from workbench.continuation._curve import _touch

    smap, pt = end
    span = smap.periods * smap.prepared(pt.p).period
    k, theta, value = _touch(smap, pt.y, pt.aux, pt.p, 0)
    assert k == 0 and abs(theta * span - 0.9519) < 1e-3, (k, theta * span)
    assert 0.0 < value < 1e-10, value
    assert _touch(smap, pt.y, pt.aux, pt.p, None)[:2] == (k, theta)


@pytest.mark.slow
def test_another_member_of_the_lasting_contact_family_has_not_lifted_off_past_its_grazing():
    """The lasting-contact orbit is a family, one per held onset velocity (docs/continuation.md).
    The member the route study continues from 1.8 pi lifts off at 1.843 pi (studies/REPORT.md).
    At 1.845 pi, past that, Newton's method from a 200-period transient finds another member,
    held velocities about 0.11 and 1.68 mm/s, with no event at all and its shallowest
    penetration 3.2e-8 m, 5 % of its range: under the Lankarani-Nikravesh law the lift-off is
    not one value of omega but one per member."""
    scene = workbench.load_scene(SCENE).replace(sweep={})
    smap = StrobeMap(scene, "omega", rtol=1e-10)
    omega = 1.845 * math.pi
    y, aux = smap.initial(omega, 200)
    pt = orbit_at(smap, y, aux, omega, tolerance=1e-6, max_iterations=15)
    assert pt.value.events == 0
    assert abs(pt.aux[0] - 1.14e-4) < 1e-5 and abs(pt.aux[1] - 1.68e-3) < 1e-4, pt.aux
    seq = smap.contact_sequence(pt.y, pt.aux, pt.p)
    k, _, value = seq.smallest_margin()
    assert seq.counts == (0, 0, 0, 0)
    assert 2e-8 < value < 5e-8 and 0.02 < value / seq.scale[k] < 0.1, (value, seq.scale[k])


#: the last orbit of the route study's lasting-contact branch from 1.8 pi (make studies on
#: d2151e2, rtol 1e-8): omega (rad s-1), the states (m, m s-1) and the held onset velocities
#: (m s-1); its smallest penetration 6.3e-9 m, at A
LIFTING = (
    5.789278794352008,
    [-3.542336105985143e-05, -9.398240120230492e-05, -8.047408965093882e-05,
     6.0434958779149184e-05, 0.004570793690678481, -0.0017190678322721402,
     -1.0686663200902096e-05, -3.036195575738164e-05],
    [0.0007245480609672624, 0.0019186538408065821],
)  # fmt: skip


@pytest.mark.slow
def test_the_parameter_column_stays_on_the_lasting_contacts_side_of_its_lift_off():
    """At the lasting-contact orbit 1e-5 pi below where its contact lifts off (at fixed state),
    the central difference over the route's stencil (sqrt(rtol) of the parameter's scale 0.1 pi)
    straddles the lift-off: the map there has 2 more events and has jumped, and the difference
    was 58x the derivative, which turned the branch's tangent to the state axis and collapsed
    its steps (the route study's branch stopped at 1.8428 pi). The column is now the one-sided
    difference on the orbit's own side: within 1 % of the central difference over a 10x shorter
    stencil (clear of the lift-off) at rtol 1e-10 (noise 1e-5 of it), where the straddling one
    is more than 10x off."""
    p, y, aux = LIFTING
    scene = workbench.load_scene(SCENE).replace(sweep={})
    smap = StrobeMap(scene, "omega", rtol=1e-8)
    y, aux, none = np.array(y), np.array(aux), np.array([], int)
    pscale = 0.1 * math.pi
    h = math.sqrt(smap.rtol) * pscale
    here, up, down = (smap(y, aux, q, tangent=False) for q in (p, p + h, p - h))
    assert (here.events, down.events, up.events) == (0, 0, 2)  # the stencil straddles it
    s = smap.scale()
    central = (up.y1 - down.y1) / (2 * h) * pscale / s
    tight = smap.with_rtol(1e-10)
    up, down = (tight(y, aux, q, tangent=False) for q in (p + h / 10, p - h / 10))
    assert up.events == down.events == 0
    reference = (up.y1 - down.y1) / (2 * h / 10) * pscale / s
    column = smap.parameter_derivative(y, aux, p, none, pscale)
    ratio = np.linalg.norm(central) / np.linalg.norm(reference)
    assert 50.0 < ratio < 65.0, ratio  # docs/continuation.md: 58x
    assert np.linalg.norm(column - reference) < 1e-2 * np.linalg.norm(reference)
    # the tangent's parameter component (docs: 1e-4 with the straddling column, 8e-3 without)
    M = smap(y, aux, p).M
    m = M.shape[0]

    def parameter_component(Pp):
        t = np.linalg.solve(M - np.eye(m), -Pp)
        return 1.0 / np.linalg.norm(np.append(t, 1.0))

    assert 1e-4 < parameter_component(central) < 2e-4
    assert 7e-3 < parameter_component(column) < 1e-2


#: two lasting-contact orbits 2e-6 pi further on, 7.6e-9 rad/s apart (the branch continued from
#: LIFTING with the one-sided parameter column, rtol 1e-8): at the second, 1e-6 of a state's
#: scale moves it onto the lift-off
NEIGHBOUR = (
    5.789306682232579,
    [-3.543507791054074e-05, -9.39779688250565e-05, -8.047428660420295e-05,
     6.0434687357302536e-05, 0.004575808439302297, -0.0017215990615699235,
     -1.265689892869157e-05, -3.314834553114128e-05],
    [0.0007245480609672624, 0.0019186538408065821],
)  # fmt: skip
NEARER = (
    5.7893066898395595,
    [-3.543508112054039e-05, -9.397796761047747e-05, -8.047428665774988e-05,
     6.043468728343998e-05, 0.004575809806522182, -0.0017215997525865964,
     -1.265743149218244e-05, -3.314909952486871e-05],
    [0.0007245480609672624, 0.0019186538408065821],
)  # fmt: skip


@pytest.mark.slow
def test_the_copies_monodromy_stays_on_the_lasting_contacts_side_of_its_lift_off(monkeypatch):
    """At NEARER the copies moved +1e-6 (scaled) in y_A meet the lift-off (2 events, the base
    none), so that central column was the jump over the step (norm ~1.4e6) and the largest
    |multiplier| came out 3.3e3 for an orbit whose neighbour, 7.6e-9 rad/s back, has 0.0343
    (a fold and a branch point were then found between them), and the copies' mean count of
    events said 1 per period. Such a column is now the one-sided difference on its smaller
    side: the three largest multipliers within 1e-3 of the neighbour's (NEIGHBOUR, whose copies
    all stay on the orbit's side), no event, the column named."""
    p, y, aux = NEARER
    scene = workbench.load_scene(SCENE).replace(sweep={})
    smap = StrobeMap(scene, "omega", rtol=1e-8)
    y, aux = np.array(y), np.array(aux)
    s = smap.scale()
    d = np.zeros(y.size)
    d[1] = smap.step * s[1]
    moved = [smap(y + k * d, aux, p, tangent=False) for k in (-1, 0, 1)]
    assert [v.events for v in moved] == [0, 0, 2]
    fwd = np.linalg.norm((moved[2].y1 - moved[1].y1) / s) / smap.step
    bwd = np.linalg.norm((moved[1].y1 - moved[0].y1) / s) / smap.step
    assert fwd > 1e6 and 5.0 < bwd < 20.0, (fwd, bwd)  # docs/continuation.md: 1.4e6 against 10

    def largest(p, y, aux):
        return np.sort(np.abs(np.linalg.eigvals(smap(y, aux, p).M)))[::-1][:3]

    neighbour = largest(NEIGHBOUR[0], np.array(NEIGHBOUR[1]), np.array(NEIGHBOUR[2]))
    assert neighbour[0] < 0.05, neighbour
    np.testing.assert_allclose(largest(p, y, aux), neighbour, atol=1e-3)
    value = smap(y, aux, p)
    assert value.events == 0 and 1 in value.one_sided, (value.events, value.one_sided)
    # without the one-sided columns (the code before): docs/continuation.md's 3.3e3
    monkeypatch.setattr(_strobe, "STRADDLE_RATIO", math.inf)
    assert largest(p, y, aux)[0] > 1e3


#: orbits of the lasting-contact branch from pi (benchmarks/ninebar_branch.py --legs lasting):
#: omega (rad/s), strobe state (x_A, y_A, x_B, y_B m; vx_A, vy_A, vx_B, vy_B m/s), held onset
#: velocities (m/s)
LASTING_HELD = [0.003898158494854159, 0.0015337248002524385]
LASTING = {
    "1.54 pi": (4.830630302646175, [-3.69308150694779e-05, -9.340472476882394e-05,
                -8.004623267705319e-05, 6.1022002310486546e-05, 0.00012025181141201521,
                -4.723248271456106e-05, -8.261189117849969e-05, -0.0001077925094868075]),
    "1.80 pi": (5.65489045132968, [-3.6000119494217616e-05, -9.375738638633801e-05,
                -7.993755037762323e-05, 6.11449532594428e-05, -0.00016785578818796472,
                6.588655938829422e-05, -0.00011988914376522426, -0.00015750413707293177]),
}  # fmt: skip


def _tangential_oscillation(omega: float, y: list[float]) -> tuple[float, float, float]:
    """One forcing period of the lasting-contact orbit from its strobe state: Newton's residual
    of the state (scaled, the map based at omega), the oscillations per period of joint A's
    sliding velocity along the bearing's wall (m/s) about its mean over 1/64 period, and their
    RMS (m/s)."""
    from workbench.run import prepare

    scene = workbench.load_scene(SCENE).replace(sweep={})
    point = scene.with_parameters(omega=omega)
    smap = StrobeMap(point, "omega", rtol=1e-10)
    y, aux = np.array(y), np.array(LASTING_HELD)
    residual = float(np.max(np.abs((smap(y, aux, omega, tangent=False).y1 - y) / smap.scale())))
    n = 16384
    names = ["clearance_x", "clearance_y", "clearance_vx", "clearance_vy"]
    sc = point.replace(
        run={"cycles": 1, "transient_cycles": 0},
        record={"samples_per_period": n, "variables": names},
        solver={"rtol": 1e-10, "atol": 1e-10},
    )
    prep = prepare(sc)
    ds = workbench.simulate(prep.restart(prep.problem.t0, y, aux))
    x, yy, vx, vy = (ds[k].values[:, 0] for k in names)
    theta = np.arctan2(yy, x)
    sliding = -np.sin(theta) * vx + np.cos(theta) * vy
    k = n // 64
    fast = (sliding - np.convolve(sliding, np.ones(k) / k, mode="same"))[k:-k]
    crossings = np.count_nonzero(np.sign(fast[1:]) != np.sign(fast[:-1]))
    return residual, crossings / 2 / (1 - 2 / 64), float(np.std(fast))


@pytest.mark.slow
def test_the_lasting_contact_carries_a_fast_sliding_oscillation_past_1_75_pi():
    """Why the lasting-contact branch from pi needs short steps past 1.75 pi (docs/
    continuation.md): its orbits there carry an oscillation of the journal along the bearing's
    wall at about 205 cycles per forcing period (about 1160 rad/s). The strobe samples its
    phase, which turns by 2 pi per about 0.009 pi of omega (omega / 205), so the strobe
    velocities loop as omega grows; at 1.54 pi it is absent."""
    res_low, _, rms_low = _tangential_oscillation(*LASTING["1.54 pi"])
    res, cycles, rms = _tangential_oscillation(*LASTING["1.80 pi"])
    assert res_low < 1e-5 and res < 1e-5, (res_low, res)  # both are the periodic orbits
    assert rms_low < 1e-6, rms_low
    assert 200 < cycles < 210 and rms > 5e-4, (cycles, rms)
