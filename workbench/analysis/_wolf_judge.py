"""Stage 3 of the Wolf estimate (:func:`workbench.analysis.wolf_lle`): judge.

Whether the estimate can be trusted, from the series, its embedding and what the evolution
measured: the sampling must resolve the orbit of a flow (smoothness, samples per mean period,
lambda dt per sample), the series must be long enough for the attractor's correlation dimension
(Eckmann & Ruelle 1992) and span enough mean periods, and a positive exponent must come from a
series that looks deterministic: not one whose Cao E2 stays near 1 (Cao 1997) nor one that its
IAAFT surrogates predict as well as it predicts itself (Theiler et al. 1992; Kennel & Isabelle
1992). Each failed check is one sentence of the verdict's message, which says what to do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy.spatial import cKDTree

from workbench.analysis._series import Series
from workbench.analysis._surrogate import surrogate_test
from workbench.analysis._wolf_embedding import (
    FLOW_MIN_SMOOTHNESS,
    FLOW_SMOOTHNESS,
    Embedding,
    Scales,
)

__all__ = ["Verdict", "correlation_dimension", "wolf_verdict"]

#: largest exponent per sample (lambda dt) at which a sampled flow's separations are resolved:
#: beyond it a separation grows by more than ~10 % between samples
MAX_LAMBDA_DT = 0.1
#: fewest samples per mean period (power-weighted mean frequency) of a sampled flow
MIN_SAMPLES_PER_PERIOD = 10
#: fewest points for an attractor of (correlation) dimension D: 10**D (Eckmann & Ruelle 1992,
#: Physica D 56, 185: a neighbourhood a tenth of the attractor's size must hold points; Wolf
#: et al. 1985, Sec. 7: "10^D to 30^D points"). D is measured on the embedded points at the
#: scales the neighbours are taken from (the embedding dimension would overstate it: Ikeda
#: x needs dim 4 for an attractor of dimension 1.7)
POINTS_BASE = 10
#: fewest mean periods a sampled flow must span: its neighbours come from other passes
MIN_PERIODS = 20


@dataclass(frozen=True)
class Verdict:
    """The judgement of an estimate: ``reliable`` unless one of the ``reasons`` holds;
    ``correlation_dimension`` D of the embedded points and ``min_points`` (10**D) behind the
    length check; ``surrogate`` the Dataset of the surrogate test (None if not run)."""

    reliable: bool
    reasons: list[str]
    correlation_dimension: float
    min_points: int
    surrogate: xr.Dataset | None = None

    @property
    def message(self) -> str:
        """The reasons joined by "; ", or "no warning"."""
        return "; ".join(self.reasons) if self.reasons else "no warning"


def correlation_dimension(
    Y: np.ndarray, tree: cKDTree, theiler: int, r_hi: float, ratio: float = 4.0
) -> float:
    """Local slope of the correlation sum C(r) between ``r_hi / ratio`` and ``r_hi``
    (Grassberger & Procaccia 1983, Physica D 9, 189), over up to 500 reference points and with
    the pairs within ``theiler`` samples in time left out (Theiler 1986, Phys. Rev. A 34,
    2427). NaN if either count is zero."""
    n = Y.shape[0]
    ref = np.unique(np.linspace(0, n - 1, min(n, 500)).astype(np.int64))
    offsets = np.arange(-theiler, theiler + 1)
    near = ref[:, None] + offsets
    inside = (near >= 0) & (near < n)
    gap = np.linalg.norm(Y[np.clip(near, 0, n - 1)] - Y[ref][:, None, :], axis=2)
    counts = []
    for r in (r_hi / ratio, r_hi):
        total = np.asarray(tree.query_ball_point(Y[ref], r, return_length=True)).sum()
        counts.append(float(total - np.sum(inside & (gap <= r))))
    if min(counts) <= 0:
        return math.nan
    return math.log(counts[1] / counts[0]) / math.log(ratio)


def _sampling_messages(s: Series, *, flow, chosen_flow, smooth, per_sample, spp) -> list[str]:
    """Why the sampling does not resolve what is measured (empty if it does)."""
    step = f"dt = {s.dt:g} s" if s.time_units == "s" else "a step of one sample"
    msgs = []
    if not flow:
        if s.sampling == "time" and chosen_flow:
            msgs.append(
                f"the series has a time step ({step}) but does not look like a sampled flow "
                f"(smoothness {smooth:.2f} < {FLOW_MIN_SMOOTHNESS}: fewer than ~6 samples per "
                f"dominant cycle; {spp:.1f} samples per mean period), so it was taken for a map: "
                f"if it samples a flow, {step} is far too long for its exponent to be measured; "
                "record it more finely. If it is a map or a stroboscopic section, pass "
                "flow=False (CLI: --kind map), or the section as poincare_section returns it, "
                "and the exponent per sample stands"
            )
        return msgs
    if smooth < FLOW_SMOOTHNESS:
        msgs.append(
            f"smoothness {smooth:.2f} < {FLOW_SMOOTHNESS} at {step}: the samples do not resolve "
            "the orbit (fewer than ~14 samples per dominant cycle, or fast events such as "
            "impacts between samples); record the flow more finely"
        )
    if spp < MIN_SAMPLES_PER_PERIOD:
        msgs.append(
            f"{spp:.1f} samples per mean period (< {MIN_SAMPLES_PER_PERIOD}) at {step}: the "
            "orbit is not resolved"
        )
    if per_sample > MAX_LAMBDA_DT:
        msgs.append(
            f"lambda dt = {per_sample:.3g} per sample (> {MAX_LAMBDA_DT}) at {step}: the "
            "samples are too coarse for the exponent they measure"
        )
    return msgs


def wolf_verdict(
    s: Series,
    emb: Embedding,
    scales: Scales,
    tree: cKDTree,
    per_sample: float,
    *,
    surrogates: int = 19,
) -> Verdict:
    """Stage 3: the verdict on an estimate of ``per_sample`` (lambda dt) from the series ``s``
    embedded as ``emb`` (``tree``: the KD-tree of its points), with the neighbours' scales.

    A positive estimate is tested against ``surrogates`` IAAFT surrogates
    (:func:`~workbench.analysis.surrogate_test`, in the same embedding, predicting a delay
    ahead for a flow and one step for a map; 0: no test)."""
    v = s.values
    n = emb.points.shape[0]
    msgs = _sampling_messages(
        s,
        flow=emb.flow,
        chosen_flow=emb.chosen_flow,
        smooth=emb.smoothness,
        per_sample=per_sample,
        spp=emb.samples_per_period,
    )
    d2 = correlation_dimension(emb.points, tree, emb.theiler, scales.scale_max)
    min_points = int(math.ceil(POINTS_BASE ** (d2 if np.isfinite(d2) else emb.dim)))
    if n < min_points:
        msgs.append(
            f"{n} embedded points are fewer than 10^D = {min_points} for the correlation "
            f"dimension D = {d2:.2f} at the scales of the neighbours (Eckmann & Ruelle 1992; "
            "Wolf et al. 1985: 10^D to 30^D points): record a longer series"
        )
    periods = v.size / emb.samples_per_period
    if emb.flow and periods < MIN_PERIODS:
        msgs.append(
            f"the series spans {periods:.1f} mean periods (< {MIN_PERIODS}): too few passes "
            "for neighbours from other parts of the orbit; record a longer series"
        )
    if emb.stochastic:
        msgs.append(
            "Cao's E2 is within 0.1 of 1 at every dimension: the series looks stochastic, and "
            "a positive exponent is then no evidence of chaos"
        )
    surrogate = None
    if surrogates and per_sample > 0:
        surrogate = surrogate_test(
            v,
            dim=emb.dim,
            delay=emb.delay,
            horizon=emb.delay if emb.flow else 1,
            theiler=emb.theiler,
            surrogates=surrogates,
        )
        if int(surrogate.stochastic):
            es = surrogate.surrogate_error.values
            msgs.append(
                f"the series is predicted no better than its {es.size} IAAFT surrogates "
                f"(nonlinear prediction error {float(surrogate.error):.3g} against "
                f"{es.min():.3g}-{es.max():.3g}; Theiler et al. 1992): nothing tells it from "
                "linear correlated noise, so a positive exponent is no evidence of chaos"
            )
    return Verdict(not msgs, msgs, d2, min_points, surrogate)
