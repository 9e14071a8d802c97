"""The impact oscillator's period-one impacting orbits against an independent reference
(``_impact_reference``: the linear flow between impacts in closed form and the impact map,
written for these checks alone): a period doubling, a fold and a grazing of an interior turning
point, each labelled where the reference puts it, and no label where nothing happens.

The system: x'' + c x' + x = cos(omega t) while x < g, v -> -r v at the stop (m = k = F = 1,
SI), underdamped (c = 0.1 N s/m, zeta = 0.05), r = 0.8. With the stop 0.2 m behind the rest
position (g = -0.2 m) the orbit that strikes once per period loses stability in a flip near
omega = 3.14 rad/s. With the stop 1.2 m ahead of it (beyond the static deflection of the
forcing, so nothing rests on it) the impacting orbit is born in a fold near 1.707 rad/s
(omega continued up, the branch turns back onto the unstable orbit of the same family) and,
continued down, meets the stop a second time per period near 0.677 rad/s: a free swing's
turning point reaches it (a grazing). On the way down, near 0.807 rad/s, the free flight
gains two turning points short of the stop, which is where the model's turning-point event
(its locator of shallow impacts) adds two crossings: nothing happens to the orbit there, and
no bifurcation may be labelled (before ``Problem.event_surface`` it was labelled a grazing).
"""

import math

import numpy as np
import pytest
from _impact_reference import ImpactReference, flip, fold, grazing, stable_orbit

from workbench.continuation import branch_bifurcations, continue_orbit

C, R = 0.1, 0.8  # N s/m, 1
#: the package locates a bifurcation to 1e-7 of the continued range (continue_orbit's
#: ``tolerance`` docs); the references to about 1e-10 rad/s (the flip moved by 7e-11 rad/s
#: when their difference step went from 1e-6 to 1e-7)
LOCATED = 1e-7


def branch(gap: float, start: float, stop: float) -> tuple:
    """The period-one impacting branch from the reference's stable orbit at ``start``."""
    ref = ImpactReference(C, gap, R, start)
    scene = {
        "model": {"name": "impact_oscillator"},
        "parameters": {"damping": C, "gap": gap, "restitution": R, "omega": start,
                       "x0": min(0.0, gap - 0.3)},
    }  # fmt: skip
    r = continue_orbit(
        scene, "omega", stop=stop, state=ref.strobe_state(stable_orbit(C, gap, R, start))
    )
    return r, branch_bifurcations(r, "omega")


def multipliers(r, i: int) -> np.ndarray:
    return r.multiplier_real.values[i] + 1j * r.multiplier_imag.values[i]


def test_the_flip_of_the_orbit_that_strikes_once_per_period():
    """g = -0.2 m, omega 3.0 -> 3.3 rad/s: one label, a period doubling within 1e-7 of the
    range of the reference's (det(J + I) = 0 of its impact map), critical multiplier -1; the
    product of the two multipliers at every point is r^2 exp(-c T) (closed form)."""
    r, found = branch(-0.2, 3.0, 3.3)
    assert [b["type"] for b in found] == ["period_doubling"] and found[0]["resolved"], found
    expected = flip(C, -0.2, R, 3.0, 3.3)
    assert abs(found[0]["value"] - expected) < LOCATED * 0.3, (found[0]["value"], expected)
    assert abs(found[0]["critical"] + 1) < 1e-6
    for i in range(r.sizes["point"]):
        period = 2 * math.pi / float(r.omega[i])
        product = np.prod(multipliers(r, i)).real
        assert product == pytest.approx(R**2 * math.exp(-C * period), rel=1e-6)


def test_the_fold_where_the_impacting_orbit_is_born():
    """g = 1.2 m, omega up from 1.5 rad/s: a fold within 1e-7 of the range of the reference's
    largest omega of the period-one orbits, critical multiplier +1; the branch returns to 1.5
    rad/s on the unstable orbit, whose largest multiplier is the reference's."""
    r, found = branch(1.2, 1.5, 1.9)
    assert [b["type"] for b in found] == ["fold"] and found[0]["resolved"], found
    expected = fold(C, 1.2, R, (0.95, 1.3), (1.6, 1.9))
    assert abs(found[0]["value"] - expected) < LOCATED * 0.4, (found[0]["value"], expected)
    assert abs(found[0]["critical"] - 1) < 1e-6
    assert float(r.omega[-1]) == pytest.approx(1.5, abs=1e-12)
    ref = ImpactReference(C, 1.2, R, 1.5)
    unstable = max(
        float(np.max(np.abs(np.linalg.eigvals(ref.jacobian(z))))) for z in ref.period_one()
    )
    assert float(np.max(np.abs(multipliers(r, -1)))) == pytest.approx(unstable, rel=1e-6)


def test_a_turning_point_that_reaches_the_stop_is_the_only_label():
    """g = 1.2 m, omega down from 0.9 rad/s: the one label is the grazing where a free swing's
    turning point reaches the stop, within 1e-7 of the range of the reference's (its margin
    zero); none near 0.807 rad/s, where the flight gains two turning points short of the stop
    (the turning-point event's crossings change there, and the orbit does not)."""
    r, found = branch(1.2, 0.9, 0.6)
    assert [b["type"] for b in found] == ["grazing"] and found[0]["resolved"], found
    expected = grazing(C, 1.2, R, 0.67, 0.68, 8.4)
    assert abs(found[0]["value"] - expected) < LOCATED * 0.3, (found[0]["value"], expected)
    assert int(r.bifurcation_event[0]) == 0  # the stop's own event function
    # the turning points short of the stop: where they appear, the turning-point event's
    # crossings (event 2) change by two along the branch, and the stop's (event 0) do not
    counts = r.crossings_per_orbit.values
    changed = np.flatnonzero(np.diff(counts[:, 2]) != 0)
    assert changed.size >= 1 and np.all(np.diff(counts[:, 0]) == 0)
    assert 0.75 < float(r.omega[changed[0]]) < 0.85
