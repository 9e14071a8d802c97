"""The paper's qualitative conclusions as checks on our runs.

A claim in ``study.toml`` compares a statistic of two cases, or of two parameter ranges of a
campaign:

- ``statistic = "peak"`` (default): ``|peak(larger)| > factor * |peak(smaller)|`` (factor 1),
  peaks over the whole record (all recorded cycles);
- ``"strobe_spread"``: the stroboscopic spread (in units of c) of ``larger`` exceeds ``smaller``;
- ``"seconds_per_cycle"``: computing time per crank cycle;
- ``"peak_ratio_near_one"``: ``| |peak(larger)| / |peak(smaller)| - 1 | < tolerance``;
- ``"chaos"``: every Wolf LLE measured in the study is positive;
- ``"bifurcation_spread"``: the mean stroboscopic spread over the parameter range ``upper``
  exceeds (``expect = "upper_larger"``) or falls below (``"lower_larger"``) that over ``lower``.

Each evaluation returns ``{"text", "reproduced": bool | None, "evidence": str}``; ``None`` when
the runs hold no number to decide on.
"""

from __future__ import annotations

import math

__all__ = ["evaluate_claim"]


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def evaluate_claim(claim: dict, measures: dict) -> dict:
    """Decide ``claim`` from ``measures``, the study's numbers (see :func:`run_study`)."""
    stat = claim.get("statistic", "peak")
    text = claim["text"]
    if stat == "chaos":
        lles = measures.get("wolf_lle", {})
        if not lles:
            return {"text": text, "reproduced": None, "evidence": "no LLE was measured"}
        ok = all(v > 0 for v in lles.values())
        shown = ", ".join(f"{k}: {_fmt(v)} 1/s" for k, v in lles.items())
        return {"text": text, "reproduced": ok, "evidence": f"Wolf LLE {shown}"}
    if stat == "bifurcation_spread":
        spread = measures.get("bifurcation_spread", {})
        values = spread.get("values", [])
        spreads = spread.get("spread", [])
        lo = [s for v, s in zip(values, spreads, strict=True) if _within(v, claim["lower"])]
        hi = [s for v, s in zip(values, spreads, strict=True) if _within(v, claim["upper"])]
        if not lo or not hi:
            return {"text": text, "reproduced": None, "evidence": "no points in a range"}
        m_lo, m_hi = sum(lo) / len(lo), sum(hi) / len(hi)
        ok = m_hi > m_lo if claim["expect"] == "upper_larger" else m_lo > m_hi
        evidence = (
            f"mean stroboscopic spread {_fmt(m_lo)} c over {claim['parameter']} in "
            f"{claim['lower']} ({len(lo)} points) against {_fmt(m_hi)} c over {claim['upper']} "
            f"({len(hi)} points)"
        )
        return {"text": text, "reproduced": ok, "evidence": evidence}
    key = _key(claim)
    peaks = "peak_record" if "peak_record" in measures else "peak"
    table = measures.get(peaks if stat in ("peak", "peak_ratio_near_one") else stat, {})
    a, b = table.get(claim["larger"], {}).get(key), table.get(claim["smaller"], {}).get(key)
    if a is None or b is None or not (math.isfinite(a) and math.isfinite(b)):
        return {"text": text, "reproduced": None, "evidence": f"{key}: no number to compare"}
    if stat == "peak_ratio_near_one":
        ratio = abs(a) / abs(b)
        ok = abs(ratio - 1) < claim.get("tolerance", 0.02)
        evidence = (
            f"{key}: |peak| {_fmt(abs(a))} ({claim['larger']}) / {_fmt(abs(b))} = {ratio:.4f}"
        )
        return {"text": text, "reproduced": ok, "evidence": evidence}
    factor = claim.get("factor", 1.0)
    ok = abs(a) > factor * abs(b)
    unit = {"seconds_per_cycle": " s", "strobe_spread": " c"}.get(stat, "")
    evidence = (
        f"{key} ({stat.replace('_', ' ')}): {claim['larger']} {_fmt(a)}{unit} against "
        f"{claim['smaller']} {_fmt(b)}{unit}"
        + (f" (factor {factor:g} asked)" if factor != 1 else "")
    )
    return {"text": text, "reproduced": ok, "evidence": evidence}


def _within(v: float, bounds: list[float]) -> bool:
    lo, hi = bounds
    return lo * (1 - 1e-9) <= v <= hi * (1 + 1e-9)


def _key(entry: dict) -> str:
    """``var`` or ``var[dim=label]``: the name of a measured quantity."""
    var = entry.get("var", "")
    sel = entry.get("select", {})
    return var + "".join(f"[{k}={v}]" for k, v in sel.items())
