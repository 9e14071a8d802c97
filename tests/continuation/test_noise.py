"""Newton's tolerance against the map's noise along a branch (issue 38 item 4).

The noise is measured at a branch's first orbit; an orbit further on can be noisier (the
declared four-bar's 16-event orbit at 50.21 rad/s: Newton's residual stagnated at 1.1e-7,
scaled, against a tolerance of 1e-8, the steps collapsed to 8e-7 and the branch ended, with
its multipliers well inside the unit circle). Here the Duffing's map is made to behave so
beyond gamma = 0.255: the corrector fails below a tolerance of 1e-6, and the map's noise reads
1e-7 from 0.254 on (the last orbits before it)."""

import pytest

import workbench.continuation._branch as branch
from workbench.continuation import continue_orbit
from workbench.continuation._newton import NewtonFailure
from workbench.continuation._strobe import StrobeMap

DUFFING = {
    "model": {"name": "duffing"},
    "parameters": {"gamma": 0.25},
    "run": {"transient_cycles": 100},
}
#: past this gamma the emulated map is noisy
NOISY = 0.255


def _noisy_map(monkeypatch, noise: float) -> None:
    correct = branch.correct

    def stagnating(smap, pred, *args, tolerance, **kwargs):
        if pred.p > NOISY and tolerance < 1e-6:
            raise NewtonFailure("the corrector did not converge (the residual stagnates)")
        return correct(smap, pred, *args, tolerance=tolerance, **kwargs)

    monkeypatch.setattr(branch, "correct", stagnating)
    monkeypatch.setattr(
        StrobeMap,
        "jitter",
        lambda self, value, y, aux, p, size: noise if p > NOISY - 1e-3 else 1e-14,
    )


def test_where_the_map_outgrows_newtons_tolerance_the_tolerance_is_raised(monkeypatch):
    """The corrector fails at the smallest step past 0.255 and the noise there reads 1e-7: the
    tolerance is raised to 1e-6 (ten times the noise) and the branch goes on to its stop,
    saying where and why."""
    _noisy_map(monkeypatch, 1e-7)
    r = continue_orbit(DUFFING, "gamma", stop=0.26)
    assert float(r.gamma.max()) == pytest.approx(0.26, abs=1e-12)
    assert r.attrs["branch_ended"].startswith("the parameter reached its bound")
    raised = r.attrs["tolerance_raised"]
    at = float(raised.split("at ")[1].split(":")[0])
    assert NOISY - 1e-3 < at <= NOISY + 1e-3, raised
    assert "from 1e-08 to 1e-06 (the map's noise there 1e-07, scaled)" in raised


def test_where_the_map_is_quiet_a_failing_corrector_ends_the_branch(monkeypatch):
    """The same failures with the noise reading 1e-14: no tolerance is raised (a failure that
    is not the map's noise is not papered over), and the branch ends there, saying so."""
    _noisy_map(monkeypatch, 1e-14)
    r = continue_orbit(DUFFING, "gamma", stop=0.26)
    assert float(r.gamma.max()) < NOISY + 1e-3
    assert "tolerance_raised" not in r.attrs
    assert "at the smallest step" in r.attrs["branch_ended"]


def _noisy_start(monkeypatch, noise: float) -> None:
    """Newton at the branch's start stagnates below a tolerance of 1e-6 (it stops at the orbit
    found to 1e-6, as the four-bar's from 50 rad/s stopped at a scaled residual of 8.7e-8),
    and the map's noise reads ``noise`` everywhere."""
    orbit_at = branch.orbit_at

    def stagnating(smap, y, aux, p, *, tolerance, max_iterations=30):
        if tolerance < 1e-6:
            pt = orbit_at(smap, y, aux, p, tolerance=1e-6, max_iterations=max_iterations)
            raise NewtonFailure("Newton's method did not converge (emulated)", last=pt)
        return orbit_at(smap, y, aux, p, tolerance=tolerance, max_iterations=max_iterations)

    monkeypatch.setattr(branch, "orbit_at", stagnating)
    monkeypatch.setattr(StrobeMap, "jitter", lambda self, value, y, aux, p, size: noise)


def test_a_branch_that_starts_on_a_noisy_map_raises_its_tolerance_there(monkeypatch):
    """Newton stagnates at the start and the noise reads 1e-7: the tolerance is raised to 1e-6
    at the start (not a failure the user must work around) and the branch reaches its stop."""
    _noisy_start(monkeypatch, 1e-7)
    r = continue_orbit(DUFFING, "gamma", stop=0.26)
    assert float(r.gamma.max()) == pytest.approx(0.26, abs=1e-12)
    assert r.attrs["tolerance_raised"].startswith(
        "at 0.25: from 1e-08 to 1e-06 (the map's noise there 1e-07, scaled)"
    )


def test_a_start_that_fails_on_a_quiet_map_still_fails(monkeypatch):
    """The same stagnation with the noise reading 1e-14 is not the noise's: the start's
    failure is raised as it was."""
    _noisy_start(monkeypatch, 1e-14)
    with pytest.raises(NewtonFailure, match="did not converge"):
        continue_orbit(DUFFING, "gamma", stop=0.26)
