"""The paper's qualitative conclusions as checks on our ensembles.

Every case of a study is an ensemble of realisations (:mod:`workbench.run._ensemble`), so every
statistic below is a sample with one value per realisation, and a verdict is one of
:data:`workbench.study._stats.VERDICTS`:

- ``statistic = "peak"`` (default): ``|peak|`` over the whole record of ``larger`` against
  ``factor`` (default 1) times that of ``smaller``, by the two-sample rule of
  :mod:`workbench.study._stats` (Mann-Whitney U, two-sided, 5 %, then the sign of the median
  difference): "reproduced" / "contradicted" only where the difference exceeds the
  realisations' scatter, else "not resolved";
- ``"strobe_spread"``: the stroboscopic spread (in units of c), same rule;
- ``"seconds_per_cycle"``: computing time per crank cycle of each realisation, same rule;
- ``"peak_ratio_near_one"``: ``r = |peak(larger)| / median |peak(smaller)|`` per realisation;
  reproduced when the upper quartile of ``|r - 1|`` is below ``tolerance``, contradicted when
  its lower quartile is above it, else not resolved;
- ``"chaos"``: the largest Lyapunov exponent from the equations (converged two-trajectory
  estimate, :func:`workbench.study._exponents.reference_exponent`) and the 0-1 test of the
  stroboscopic samples; reproduced when the exponent converged, exceeds two standard errors
  and the median K is above 0.8; contradicted when it is below minus two standard errors and
  K below 0.2; else not resolved (a Wolf exponent of a sampled series is not evidence: it
  depends on the sampling, see the chaos study's exponent table);
- ``"bifurcation_spread"``: the stroboscopic spreads of every point (and realisation) in the
  parameter range ``upper`` against those in ``lower`` (``expect = "upper_larger"`` or
  ``"lower_larger"``), two-sample rule: the points of a range are its sample.

Each evaluation returns ``{"text", "verdict", "evidence", "p_value", "reason"}``. ``reason`` is
empty for a reproduced claim; otherwise it says why, with numbers: for "not resolved" the
ensemble spread that swamps the difference; for "contradicted" the claim's ``reason`` from
``study.toml`` with the measured numbers of its ``evidence`` kind (``contact``: contact fraction
and 99th-percentile contact force of the two cases; ``strobe_contact``: share of stroboscopic
samples in contact over the two parameter ranges; ``friction_law``: the largest friction
coefficient |F_t| / F_n at the records and the time per crank cycle above mu_s and beyond the
LuGre law's envelope, :mod:`workbench.models._friction_report`). A claim with a ``why`` (the
physics behind the outcome, e.g. which friction law the case runs) shows it with the measured
numbers of its evidence kind whatever the verdict, after the spread of a "not resolved" one.
"""

from __future__ import annotations

import math

import numpy as np

from workbench.study._exponents import reference_exponent
from workbench.study._stats import ALPHA, compare_samples, describe

__all__ = ["evaluate_claim", "format_stats"]

_UNRESOLVED_CAUSE = (
    "no cause identified in the spec: the reconstructed geometry (known cause 1) is the first "
    "suspect"
)


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def format_stats(d: dict, unit: str = "") -> str:
    """'median u [IQR q25-q75, N n]' of a :func:`~workbench.study._stats.describe` result."""
    u = f" {unit}" if unit else ""
    if not d["n"]:
        return "no value"
    return f"{_fmt(d['median'])}{u} [IQR {_fmt(d['q25'])} to {_fmt(d['q75'])}, N {d['n']}]"


def evaluate_claim(claim: dict, measures: dict) -> dict:
    """Decide ``claim`` from ``measures``, the study's numbers per realisation (see
    :func:`workbench.study.run_study`); see the module docstring for the rules."""
    stat = claim.get("statistic", "peak")
    if stat == "chaos":
        out = _chaos(measures)
    elif stat == "bifurcation_spread":
        out = _bifurcation(claim, measures)
    else:
        out = _two_cases(claim, measures, stat)
    out["text"] = claim["text"]
    if claim.get("why"):
        own = out["reason"] if out["verdict"] == "not resolved" else ""
        why = _with_evidence(claim["why"], claim, measures)
        out["reason"] = f"{own}. {why}" if own else why
    elif out["verdict"] == "contradicted":
        out["reason"] = _with_evidence(claim.get("reason", _UNRESOLVED_CAUSE), claim, measures)
    return out


def _result(verdict: str, evidence: str, p: float = math.nan, reason: str = "") -> dict:
    return {"verdict": verdict, "evidence": evidence, "p_value": p, "reason": reason}


def _spread_reason(test: dict, unit: str, what: str = "realisations") -> str:
    u = f" {unit}" if unit else ""
    iqr = [test[s]["q75"] - test[s]["q25"] for s in ("larger", "smaller")]
    return (
        f"ensemble spread: the difference of the medians, {_fmt(test['median_difference'])}{u}, "
        f"is not beyond the scatter of the {what} (IQR widths {_fmt(iqr[0])} and "
        f"{_fmt(iqr[1])}{u}; Mann-Whitney p = {test['p_value']:.2g} >= {ALPHA})"
    )


def _two_cases(claim: dict, measures: dict, stat: str) -> dict:
    key = _key(claim)
    table = measures.get("peak_record" if stat in ("peak", "peak_ratio_near_one") else stat, {})
    a = table.get(claim["larger"], {}).get(key)
    b = table.get(claim["smaller"], {}).get(key)
    if a is None or b is None or not (np.isfinite(a).any() and np.isfinite(b).any()):
        return _result(
            "undecided",
            f"{key}: no number to compare",
            reason=f"{key} is not recorded in both cases (e.g. a contact force of ideal joints)",
        )
    unit = {"seconds_per_cycle": "s", "strobe_spread": "c"}.get(
        stat, measures.get("units", {}).get(key, "")
    )
    mag_a, mag_b = np.abs(np.asarray(a, float)), np.abs(np.asarray(b, float))
    label = f"{key} ({stat.replace('_', ' ')})" if key else stat.replace("_", " ")
    if stat == "peak_ratio_near_one":
        return _ratio_near_one(claim, label, mag_a, mag_b)
    factor = claim.get("factor", 1.0)
    test = compare_samples(mag_a, factor * mag_b)
    scaled = f" x {factor:g}" if factor != 1 else ""
    what = ", magnitude" if stat == "peak" else ""
    evidence = (
        f"{label}{what}: {claim['larger']} {format_stats(describe(mag_a), unit)} against "
        f"{claim['smaller']}{scaled} {format_stats(test['smaller'], unit)}; "
        f"Mann-Whitney p = {test['p_value']:.2g}"
    )
    reason = _spread_reason(test, unit) if test["verdict"] == "not resolved" else ""
    return _result(test["verdict"], evidence, test["p_value"], reason)


def _ratio_near_one(claim: dict, label: str, mag_a: np.ndarray, mag_b: np.ndarray) -> dict:
    tol = claim.get("tolerance", 0.02)
    ref = float(np.nanmedian(mag_b))
    dev = describe(np.abs(mag_a / ref - 1.0))
    if dev["n"] == 0:
        return _result("undecided", f"{label}: no number to compare")
    verdict = (
        "reproduced" if dev["q75"] < tol else "contradicted" if dev["q25"] > tol else "not resolved"
    )
    evidence = (
        f"{label}: | |peak| ({claim['larger']}) / median |peak| ({claim['smaller']}, "
        f"{_fmt(ref)}) - 1 | = {format_stats(dev)}, tolerance {tol:g}"
    )
    reason = (
        f"ensemble spread: the quartiles of the deviation ({_fmt(dev['q25'])}, "
        f"{_fmt(dev['q75'])}) straddle the tolerance {tol:g}"
        if verdict == "not resolved"
        else ""
    )
    return _result(verdict, evidence, reason=reason)


#: 0-1 test: K above this is chaotic, below 1 - this regular (Gottwald & Melbourne 2009)
K_CHAOTIC = 0.8


def _chaos(measures: dict) -> dict:
    ref = reference_exponent(measures.get("exponents", {}))
    ks = [k for values in measures.get("zero_one_K", {}).values() for k in values]
    ks = np.asarray([k for k in ks if k is not None and math.isfinite(k)], float)
    if ref is None or not ks.size:
        return _result(
            "undecided",
            "no converged exponent or no 0-1 test was measured",
            reason="the chaos verdict needs the exponent from the equations and the 0-1 test",
        )
    k_med = float(np.median(ks))
    lle, err = ref["lle"], ref["stderr"] or 0.0
    evidence = (
        f"largest Lyapunov exponent from the equations {lle:.3g} +/- {err:.2g} 1/s "
        f"({ref['lle_per_cycle']:.3g} per crank cycle; {ref['note']}; "
        f"{'converged' if ref['trusted'] else 'not converged'}); 0-1 test K median "
        f"{k_med:.3g} over {ks.size} coordinates and realisations"
    )
    if ref["trusted"] and lle > 2 * err and k_med > K_CHAOTIC:
        return _result("reproduced", evidence)
    if ref["trusted"] and lle < -2 * err and k_med < 1 - K_CHAOTIC:
        return _result("contradicted", evidence, reason="a negative exponent and K near 0")
    why = []
    if not ref["trusted"]:
        why.append("the exponent's separation and renormalisation variants disagree")
    elif abs(lle) <= 2 * err:
        why.append(f"the exponent is within two standard errors ({err:.2g} 1/s) of 0")
    if K_CHAOTIC >= k_med >= 1 - K_CHAOTIC:
        why.append(f"K = {k_med:.3g} is neither near 0 nor near 1")
    if not why:
        why.append("the exponent and the 0-1 test disagree")
    return _result("not resolved", evidence, reason="; ".join(why))


def _bifurcation(claim: dict, measures: dict) -> dict:
    spread = measures.get("bifurcation_spread", {})
    values = spread.get("values", [])
    samples = spread.get("spread", [])
    lo = _in_range(values, samples, claim["lower"])
    hi = _in_range(values, samples, claim["upper"])
    if not lo.size or not hi.size:
        return _result("undecided", "no points in a range", reason="no points in a range")
    big, small = (hi, lo) if claim["expect"] == "upper_larger" else (lo, hi)
    test = compare_samples(big, small)
    param = claim["parameter"]
    evidence = (
        f"stroboscopic spread over {param} in {claim['lower']}: "
        f"{format_stats(describe(lo), 'c')} against {claim['upper']}: "
        f"{format_stats(describe(hi), 'c')} (one value per point and realisation); "
        f"Mann-Whitney p = {test['p_value']:.2g}"
    )
    reason = (
        _spread_reason(test, "c", "points within each range")
        if test["verdict"] == "not resolved"
        else ""
    )
    return _result(test["verdict"], evidence, test["p_value"], reason)


def _in_range(values: list, samples: list, bounds: list[float]) -> np.ndarray:
    rows = [
        np.asarray(s, float) for v, s in zip(values, samples, strict=True) if _within(v, bounds)
    ]
    return np.concatenate(rows) if rows else np.zeros(0)


def _with_evidence(cause: str, claim: dict, measures: dict) -> str:
    """A stated cause with the measured numbers of the claim's evidence kind."""
    kind = claim.get("evidence")
    numbers = ""
    if kind == "contact":
        numbers = _contact_evidence(claim, measures)
    elif kind == "strobe_contact":
        numbers = _strobe_contact_evidence(claim, measures)
    elif kind == "friction_law":
        numbers = _friction_law_evidence(claim, measures)
    return f"{cause.rstrip('.')}. Measured: {numbers}" if numbers else cause


def _friction_law_evidence(claim: dict, measures: dict) -> str:
    law = measures.get("friction_law", {})
    parts = []
    for member in (claim["larger"], claim["smaller"]):
        m = law.get(member)
        if not m:
            continue
        text = (
            f"{member}: |F_t|/F_n {_fmt(describe(m['mu_median'])['median'])} in contact (median), "
            f"up to {_fmt(describe(m['mu_max'])['median'])}"
        )
        if np.isfinite(np.asarray(m["above"], float)).any():
            text += (
                f", {_fmt(1e3 * describe(m['above'])['median'])} ms per cycle above mu_s and "
                f"{_fmt(1e3 * describe(m['beyond'])['median'])} ms beyond 2 mu_s + s2 |v_t|"
            )
        parts.append(text)
    return "; ".join(parts) + " (medians over the realisations)." if parts else ""


def _contact_evidence(claim: dict, measures: dict) -> str:
    contact = measures.get("contact", {})
    joint = claim.get("select", {}).get("joint")
    parts = []
    for member in (claim["larger"], claim["smaller"]):
        per_joint = contact.get(member, {})
        for j, c in per_joint.items():
            if joint not in (None, j):
                continue
            frac = describe(c["fraction"])["median"]
            p99 = describe(c["p99"])["median"]
            parts.append(
                f"{member} at {j}: in contact {100 * frac:.0f} % of the time, 99th-percentile "
                f"force {_fmt(p99)} N"
            )
    return "; ".join(parts) + " (medians over the realisations)." if parts else ""


def _strobe_contact_evidence(claim: dict, measures: dict) -> str:
    spread = measures.get("bifurcation_spread", {})
    values, share = spread.get("values", []), spread.get("in_contact", [])
    if not share:
        return ""
    parts = []
    for bounds in (claim["lower"], claim["upper"]):
        x = _in_range(values, share, bounds)
        if x.size:
            parts.append(f"{100 * float(np.nanmean(x)):.0f} % over {bounds}")
    return f"stroboscopic samples with a journal in contact: {' against '.join(parts)}."


def _within(v: float, bounds: list[float]) -> bool:
    lo, hi = bounds
    return lo * (1 - 1e-9) <= v <= hi * (1 + 1e-9)


def _key(entry: dict) -> str:
    """``var`` or ``var[dim=label]``: the name of a measured quantity."""
    var = entry.get("var", "")
    sel = entry.get("select", {})
    return var + "".join(f"[{k}={v}]" for k, v in sel.items())
