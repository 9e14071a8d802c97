"""The analysis layer's one pipeline for the largest exponent from the equations
(workbench.analysis.largest_exponent): its protocols' rules, its result type's codes, and a
value against a known exponent."""

from __future__ import annotations

import math
import warnings

import pytest

import workbench
from workbench.analysis import ConvergenceWarning, LargestExponent, largest_exponent
from workbench.analysis._exponent import MAP_SIGN, MAP_TARGET, UNMET, protocol_knobs

DUFFING = {
    "model": {"name": "duffing"},
    "parameters": {"delta": 0.3, "gamma": 0.2},
    "run": {"cycles": 40, "transient_cycles": 150},
    "record": {"samples_per_period": 1},
}


def test_the_protocols_rules():
    """Full: the 3 % target, no sign rule; fast: needs its start, the map's target and sign
    rule by default; an unknown protocol is one line naming it and the allowed ones."""
    start = (0.0, [0.0, 0.0], None)
    assert protocol_knobs("full", target=None, sign=None, start=None) == (0.03, None)
    assert protocol_knobs("fast", target=None, sign=None, start=start) == (MAP_TARGET, MAP_SIGN)
    assert protocol_knobs("fast", target=0.2, sign=5.0, start=start) == (0.2, 5.0)
    with pytest.raises(ValueError, match=r"protocol='fast' starts where a run ended"):
        largest_exponent(DUFFING, protocol="fast")
    with pytest.raises(ValueError, match=r"^sign=3\.0: the full protocol has no sign rule"):
        largest_exponent(DUFFING, sign=3.0)
    with pytest.raises(ValueError) as bad:
        largest_exponent(DUFFING, protocol="quick")
    assert str(bad.value) == "protocol='quick': must be one of ('full', 'fast')"
    with pytest.raises(ValueError, match=r"^method='wolf': must be one of \('variational', "):
        largest_exponent(DUFFING, method="wolf")


def test_the_result_types_codes():
    """Converged on the target (1) or on the sign rule (2); each unmet condition its bit of
    UNMET; a failed run and a bound never converged; an unknown condition refused."""
    assert LargestExponent(1.0, 0.01, "copies", rule="error target").converged_code == 1
    assert LargestExponent(1.0, 0.2, "copies", rule="sign").converged_code == 2
    unmet = LargestExponent(1.0, 0.5, "variational", unmet=("error target", "sum check"))
    assert unmet.converged_code == 0 and unmet.unmet_code == 1 + 8
    assert UNMET.index("variational") == 8 and UNMET.index("other") == 7
    failed = LargestExponent(math.nan, math.nan, "copies", True)
    assert failed.unmet == ("failed",) and failed.unmet_code == 1 << 6 and not failed.converged
    bound = LargestExponent(-3.0, math.nan, "floquet", bound=True)
    assert bound.unmet == ("upper bound",) and bound.unmet_code == 1 << 5
    with pytest.raises(ValueError, match=r"unmet=\('wrong',\): each must be one of"):
        LargestExponent(1.0, 0.1, "copies", unmet=("wrong",))
    assert workbench.continuation.PointExponent is LargestExponent  # old archives' name


def test_the_periodic_duffings_exponent_from_its_trajectory():
    """The Duffing's stable period-1 orbit at gamma = 0.2: its multipliers are a complex pair
    (tests/analysis/test_stability.py), so the largest exponent is -delta / 2 = -0.15 1/s
    exactly (Liouville); the variational trajectory method reads it within three of its
    standard errors, which meet the 5 % target; the estimator's dataset is kept."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)  # it converges: no warning
        r = largest_exponent(DUFFING, target=0.05)
    assert r.method == "variational" and r.converged and r.rule == "error target"
    assert 0 < r.error <= 0.05 * abs(r.value)
    assert abs(r.value + 0.15) < 3 * r.error, (r.value, r.error)
    assert float(r.estimate.exponent[0]) == r.value and r.estimate.attrs["stopped_by"] == r.rule


def test_a_fast_estimate_starts_where_the_run_ended():
    """Fast protocol from a run's end: the window begins at the given time, and the tolerance
    check it leaves out is not counted against it."""
    scene = workbench.load_scene(DUFFING)
    run = workbench.simulate(scene)
    start = (run.attrs["end_time"], run.attrs["end_state"], None)
    r = largest_exponent(scene, protocol="fast", start=start)
    assert r.estimate.attrs["start_time"] == run.attrs["end_time"]
    assert "tolerance check" in r.detail and "tolerance check" not in r.unmet
    assert r.converged and r.rule in ("error target", "sign") and r.value < 0
