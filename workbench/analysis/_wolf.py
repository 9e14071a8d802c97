"""Largest Lyapunov exponent from a scalar time series: the fixed-evolution-time program of
Wolf, Swift, Swinney & Vastano (1985), Physica D 16, 285, with a KD-tree neighbour search, for
maps (and stroboscopic sections) and for sampled flows, which it tells apart from the series;
for a flow, separations are measured between orbits (the flow direction projected out)."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from scipy.spatial import cKDTree

from workbench.analysis._delay import delay_ami
from workbench.analysis._embedding import embed, embedding_cao, embedding_fnn
from workbench.analysis._series import Series, as_series, require_samples

__all__ = ["wolf_lle", "mean_period", "smoothness", "correlation_dimension"]

#: a series is a resolved sampled flow when the lag-1 autocorrelation of its successive
#: differences (:func:`smoothness`) is at least this: a sinusoid sampled at n points per cycle
#: gives cos(2 pi / n), so 0.9 means at least ~14 samples per dominant cycle and no kinks at
#: the sample scale (unresolved impacts lower it). Development set: Lorenz x 0.97-0.998 at dt
#: 0.005-0.02 s, 0.94 at 0.03, 0.85 at 0.05, 0.51 at 0.1, -0.05 at 0.2; Rossler x 0.98-0.996
#: at 0.05-0.1, 0.88 at 0.3, 0.68 at 0.6; the clearance coordinates of the nine-bar mechanism
#: (Sec. 5.1 run) -0.42..0.21 at 100 samples per crank period, 0.25-0.58 at 1 000, 0.95-0.98
#: at 10 000; maps and noise <= 0 (Henon -0.70, white noise -0.50).
FLOW_SMOOTHNESS = 0.9
#: below 0.9 but at least this (about 6 or more samples per cycle), a coarsely sampled flow:
#: the flow program still applies (Lorenz x at dt = 0.05-0.1 s: -3 % .. +7 %; as a map with
#: delay 1: +19 .. +46 %) but the estimate is flagged; below it the series is taken for a map
FLOW_MIN_SMOOTHNESS = 0.5
#: largest exponent per sample (lambda dt) at which a sampled flow's separations are resolved:
#: beyond it a separation grows by more than ~10 % between samples
MAX_LAMBDA_DT = 0.1
#: fewest samples per mean period (power-weighted mean frequency) of a sampled flow
MIN_SAMPLES_PER_PERIOD = 10
#: fewest samples for any estimate at all
MIN_SAMPLES = 100
#: fewest points for an attractor of (correlation) dimension D: 10**D (Eckmann & Ruelle 1992,
#: Physica D 56, 185: a neighbourhood a tenth of the attractor's size must hold points; Wolf
#: et al. 1985, Sec. 7: "10^D to 30^D points"). D is measured on the embedded points at the
#: scales the neighbours are taken from (the embedding dimension would overstate it: Ikeda
#: x needs dim 4 for an attractor of dimension 1.7)
POINTS_BASE = 10
#: fewest mean periods a sampled flow must span: its neighbours come from other passes
MIN_PERIODS = 20
#: the sampled-flow scale: this fraction of the median distance to the 50th nearest point
#: (development set: Lorenz and Rossler x, 30 series of 10 000 points; 0.5 and 1.0 scattered
#: more), and the map scale: the median distance to the 20th nearest point (Henon)
FLOW_SCALE_FRACTION, FLOW_SCALE_POINTS, MAP_SCALE_POINTS = 0.7, 50, 20
#: the widened neighbour search (2-4 x scale_max) looks at this many nearest points at most: a
#: ball 4 x wider holds 4^D times as many points, most of the data in many dimensions (noise)
WIDE_CANDIDATES = 512
#: reference points of the false-neighbour statistics (FNN, Cao) behind the dimension: a
#: fraction to about +-1.3 % (binomial error)
EVIDENCE_POINTS = 1500


def mean_period(v: np.ndarray) -> float:
    """Mean period (samples) from the power-weighted mean frequency of the spectrum.

    Examples
    --------
    >>> round(mean_period(np.sin(2 * np.pi * np.arange(1000) / 50)))
    50
    """
    v = np.asarray(v, dtype=float)
    p = np.abs(np.fft.rfft(v - v.mean())) ** 2
    f = np.fft.rfftfreq(v.size)
    total = float(np.sum(p[1:]))
    fbar = float(np.sum(f[1:] * p[1:]) / total) if total > 0 else 0.0
    return 1.0 / fbar if fbar > 0 else float(v.size)


def smoothness(v: np.ndarray) -> float:
    """Lag-1 autocorrelation of the successive differences of a series: near 1 for a finely
    sampled flow (cos(2 pi / n) for a sinusoid at n samples per cycle), at or below 0 for a map
    or noise (-0.5 for white noise). NaN for a constant series.

    Examples
    --------
    >>> t = np.arange(2000)
    >>> round(smoothness(np.sin(2 * np.pi * t / 20)), 2)   # cos(2 pi / 20) = 0.951
    0.95
    >>> smoothness(np.random.default_rng(0).standard_normal(20000)) < -0.45
    True
    """
    d = np.diff(np.asarray(v, dtype=float))
    d = d - d.mean()
    den = float(np.dot(d, d))
    return float(np.dot(d[1:], d[:-1]) / den) if den > 0 else math.nan


def _angle(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Angles (rad, 0..pi/2) between the lines along the rows of u and along w: the orientation
    counts, not the sense (Wolf et al. 1985, program FET: ``cth = abs(dot / (dnew * df))``)."""
    nu = np.linalg.norm(u, axis=1)
    nw = np.linalg.norm(w)
    c = np.abs(u @ w) / np.maximum(nu * nw, 1e-300)
    return np.arccos(np.clip(c, 0.0, 1.0))


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


class _Follower:
    """The fiducial trajectory and its neighbour (Wolf et al. 1985, FET), on embedded points."""

    def __init__(self, Y, *, flow, evolve, scale_min, scale_max, max_angle, theiler):
        self.Y, self.flow, self.evolve = Y, flow, evolve
        self.scale_min, self.scale_max, self.max_angle = scale_min, scale_max, max_angle
        self.theiler = theiler
        self.tree = cKDTree(Y)
        n = Y.shape[0]
        # a flow's neighbours need a sample on either side to be slid along their orbit
        self.lo, self.hi = (1, n - 2) if flow else (0, n - 1)
        if flow:
            t = np.empty_like(Y)
            t[1:-1] = Y[2:] - Y[:-2]
            t[0], t[-1] = Y[1] - Y[0], Y[-1] - Y[-2]
            t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)
            self.tangent = t

    def separation(self, i: int, c: np.ndarray) -> np.ndarray:
        """Rows Y[c] - Y[i], less their component along the flow at Y[i] for a flow."""
        sep = self.Y[c] - self.Y[i]
        if self.flow:
            t = self.tangent[i]
            sep -= np.multiply.outer(sep @ t, t)
        return sep

    def separation1(self, i: int, j: int) -> np.ndarray:
        """Y[j] - Y[i], less its component along the flow at Y[i] for a flow."""
        sep = self.Y[j] - self.Y[i]
        if self.flow:
            t = self.tangent[i]
            sep -= float(np.dot(sep, t)) * t
        return sep

    def closest_approach(self, i: int, j: int) -> int:
        """Slide j along its own samples to its closest approach to Y[i] (flows)."""
        if not self.flow:
            return j
        Y, yi = self.Y, self.Y[i]
        dj = float(np.dot(Y[j] - yi, Y[j] - yi))
        for step in (1, -1):
            while self.lo <= j + step <= self.hi and abs(j + step - i) > self.theiler:
                e = Y[j + step] - yi
                dn = float(np.dot(e, e))
                if dn >= dj:
                    break
                j, dj = j + step, dn
        return j

    def _candidates(self, i: int, radius: float, wide: bool) -> tuple[np.ndarray, ...]:
        """Candidate neighbours of Y[i] within ``radius``: indices, separations, their lengths
        and the full distances. More than theiler samples away in time, ``evolve`` samples
        ahead in the data, for a flow one per passing strand (its closest approach), none with
        a separation below scale_min. ``wide``: the nearest WIDE_CANDIDATES points only (a
        wide ball in many dimensions holds most of the data)."""
        Y, lo, hi = self.Y, self.lo, self.hi
        if wide:
            full, cand = self.tree.query(
                Y[i], k=min(WIDE_CANDIDATES, Y.shape[0]), distance_upper_bound=radius
            )
            cand = np.asarray(cand[np.isfinite(full)], dtype=np.int64)
        else:
            cand = np.asarray(self.tree.query_ball_point(Y[i], radius), dtype=np.int64)
        cand = cand[(np.abs(cand - i) > self.theiler) & (cand >= lo)]
        cand = cand[cand + self.evolve <= hi]
        full2 = np.sum((Y[cand] - Y[i]) ** 2, axis=1)
        if self.flow and cand.size:
            before = np.sum((Y[cand - 1] - Y[i]) ** 2, axis=1)
            after = np.sum((Y[cand + 1] - Y[i]) ** 2, axis=1)
            keep = (full2 <= before) & (full2 <= after)
            cand, full2 = cand[keep], full2[keep]
        sep = self.separation(i, cand)
        d = np.linalg.norm(sep, axis=1)
        ok = d >= self.scale_min
        return cand[ok], sep[ok], d[ok], np.sqrt(full2[ok])

    def replace(self, i: int, direction: np.ndarray | None) -> tuple[int, float]:
        """A neighbour of Y[i] within scale_max (more than theiler samples away in time) whose
        separation lies within max_angle of ``direction``: for a flow the nearest such, for a
        map the one at the smallest angle (FET); the search widens the scale (2 x, 4 x), then
        the angle (2 x, 4 x). (-1, nan) if none. The ball is searched at scale_max and, if that
        fails, once at 4 x scale_max for all the wider stages."""
        stages = [(1.0, 1.0), (2.0, 1.0), (4.0, 1.0), (4.0, 2.0), (4.0, 4.0)]
        for first, last in ((0, 1), (1, len(stages))):
            radius = stages[last - 1][0] * self.scale_max
            cand, sep, d, full = self._candidates(i, radius, wide=first > 0)
            if not cand.size:
                continue
            if direction is None:  # the first neighbour: the nearest point
                k = int(np.argmin(d))
                return int(cand[k]), float(d[k])
            ang = _angle(sep, direction)
            for widen, turn in stages[first:last]:
                amax = min(turn * self.max_angle, math.pi / 2)
                ok = np.flatnonzero((full <= widen * self.scale_max) & (ang <= amax))
                if ok.size:
                    k = int(ok[np.argmin(d[ok] if self.flow else ang[ok])])
                    return int(cand[k]), float(d[k])
        return -1, math.nan

    def run(self) -> tuple[np.ndarray, int, int]:
        """Log growth of each evolution step, replacements, steps that kept their neighbour."""
        ev, hi = self.evolve, self.hi
        i = self.lo
        j, d0 = self.replace(i, None)
        while j < 0 and i + ev < hi:
            i += 1
            j, d0 = self.replace(i, None)
        logs: list[float] = []
        replacements = kept = 0
        while j >= 0 and i + ev <= hi:
            if j + ev > hi:  # the neighbour runs out of data before the fiducial point
                j, d0 = self.replace(i, self.separation1(i, j))
                if j < 0:
                    break
            i += ev
            j_old = self.closest_approach(i, j + ev)
            if j_old + ev > hi:
                j_old = j + ev
            sep1 = self.separation1(i, j_old)
            d1 = math.sqrt(float(np.dot(sep1, sep1)))
            logs.append(math.log(d1 / d0) if d1 > 0 and d0 > 0 else 0.0)
            if self.scale_min <= d1 <= self.scale_max:
                j, d0 = j_old, d1  # the evolved neighbour is still a good one: keep it
                continue
            k, dk = self.replace(i, sep1)
            if k >= 0 and k != j_old:
                j, d0 = k, dk
                replacements += 1
            else:
                j, d0 = j_old, d1
                kept += 1
        return np.asarray(logs), replacements, kept


def _check_choice(name: str, value, lowest: int) -> int | None:
    if value is None:
        return None
    if int(value) != value or int(value) < lowest:
        raise ValueError(
            f"{name}={value!r}; allowed: a whole number >= {lowest}, or None (automatic)"
        )
    return int(value)


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
                "flow=False (or the section as poincare_section returns it) and the exponent "
                "per sample stands"
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


def wolf_lle(
    x,
    *,
    dt: float | None = None,
    dim: int | None = None,
    delay: int | None = None,
    evolve: int | None = None,
    scale_min: float | None = None,
    scale_max: float | None = None,
    max_angle: float = 0.3,
    theiler: int | None = None,
    period: float | None = None,
    flow: bool | None = None,
) -> xr.Dataset:
    """Largest Lyapunov exponent of a scalar series of a map or a sampled flow by the method of
    Wolf, Swift, Swinney & Vastano (1985), Physica D 16, 285 (their fixed-evolution-time
    program FET, Appendix A), every choice automatic and reported, with a reliability flag.

    A fiducial trajectory and one neighbour in the delay embedding are followed for
    ``evolve`` samples and the log of the growth of their separation is accumulated; the
    exponent is that sum over the total time followed. The neighbour is kept while the
    separation stays within [``scale_min``, ``scale_max``], else replaced by a point within
    ``scale_max`` of the fiducial point (and more than ``theiler`` samples away in time) whose
    separation lies within ``max_angle`` of the evolved separation's orientation, in either
    sense (FET: ``cth = abs(dot / (dnew * df))``): "its separation from the evolved fiducial
    point is small, and the angular separation between the evolved and replacement elements is
    small" (Sec. 6). For a map, the one at the smallest angle (FET); for a flow the nearest
    within the angle, so that each pair is followed over the widest range of scales. If none
    qualifies, the search widens the scale (up to 4 x), then the angle (up to 4 x), and only
    then keeps the old neighbour (FET).

    **Map or flow.** The series is a sampled flow when the lag-1 autocorrelation of its
    successive differences (:func:`smoothness`) is at least 0.5 (about 6 or more samples per
    dominant cycle; a resolved one from 0.9, ~14 samples), else it is treated as a map (delay
    1, one iteration per step); a stroboscopic section as
    :func:`~workbench.analysis.poincare_section` returns it is a map.
    For a sampled flow, separations are measured between orbits, not between samples: the
    flow direction carries a zero exponent (Haken 1983, Phys. Lett. A 94, 71), so the
    component of each separation along the fiducial trajectory (centred difference) is
    removed, and a neighbour is slid along its own samples to its closest approach (candidates
    too: one per passing strand).

    **Automatic choices** (parameters left as None; listed in the ``chosen`` attribute):
    ``flow`` by :func:`smoothness`; ``delay`` by the first minimum of the average mutual
    information (Fraser & Swinney 1986) for a flow, 1 for a map; ``dim`` by false nearest
    neighbours (Kennel et al. 1992) at that delay, with Cao's E1/E2 (Cao 1997) as a second
    opinion and E2 as a noise test; ``theiler`` = the mean period (power-weighted mean
    frequency); ``evolve`` = a quarter of the delay for a flow, 1 for a map; ``scale_max`` = 0.7
    times the median distance to the 50th nearest point for a flow, the median distance to the
    20th for a map (it follows the density of the data); ``scale_min`` = scale_max / 1000
    (noise-free data: Wolf et al. put it above the noise level, so raise it for noisy data).
    They were tuned on a development set (Henon; Lorenz and Rossler x, 30 series) and checked
    on held-out maps and flows (tests/test_wolf_heldout.py).

    **Reliability.** ``reliable`` is 0, with the reasons in its ``message`` attribute (and the
    ``warning`` attribute of the Dataset), when: a series with a time step does not look like
    a sampled flow (too coarse a sampling of a flow, or a map given a time step: pass
    ``flow=False`` for a map); a flow's smoothness is below 0.9 (coarse sampling, or fast
    events between samples), its lambda dt above 0.1 per sample or it has fewer than 10
    samples per mean period, or spans fewer than 20 mean periods; the series has fewer than
    10**D points, D the correlation dimension (Grassberger & Procaccia 1983) of the embedded
    points at the neighbours' scales (Eckmann & Ruelle 1992; Wolf et al. 1985, Sec. 7); or
    Cao's E2 is within 0.1 of 1 at every dimension (noise: a positive exponent is then no
    evidence of chaos).

    Parameters
    ----------
    x : array or DataArray
        The scalar series, at least 100 samples (a DataArray with ``time`` gives dt; one with
        dim ``strobe`` and coordinate ``strobe_time`` is a stroboscopic section).
    dt : float, optional
        Sampling step (s) of a plain array; without it, exponents are per sample.
    dim, delay, evolve, theiler : int, optional
        Embedding dimension, delay (samples), evolution time (samples), Theiler window
        (samples: neighbours are at least this far apart in time).
    scale_min, scale_max : float, optional
        Separations (units of x) between which a neighbour is kept.
    max_angle : float
        Largest angle (rad, 0 < max_angle <= pi/2) between a replacement and the evolved
        separation.
    period : float, optional
        Forcing period (s) for ``lle_per_period`` (default: the series' ``forcing_period``).
    flow : bool, optional
        Force a sampled flow (True) or a map (False) instead of detecting it.

    Returns
    -------
    xarray.Dataset
        ``lle`` (s-1 with dt; else "1", per sample: per iteration of a map), ``lle_per_sample``
        (lambda dt), ``lle_per_period`` (with a forcing period), ``running`` (the estimate over
        ``elapsed`` time), ``reliable`` (1/0 with ``message``), the detection evidence
        ``smoothness`` and ``samples_per_period``, ``flow`` (1: a sampled flow); the evidence
        for the embedding: ``ami`` over ``lag`` (the delay), ``fnn_fraction``, ``cao_E1`` and
        ``cao_E2`` over ``dimension``, ``cao_dim``, ``stochastic``; the settings ``dim``,
        ``delay``, ``evolve``, ``theiler``, ``scale_min``, ``scale_max`` (units of x),
        ``max_angle`` (rad); and ``replacements``, ``kept`` (steps that kept their neighbour
        for want of a replacement), ``steps``, ``points`` (embedded points), the
        ``correlation_dimension`` D and ``min_points`` (10**D).

    Raises
    ------
    ValueError
        For fewer than 100 samples, a series too short for the chosen embedding, or a
        setting out of its range (the message names it and what is allowed).

    References
    ----------
    Wolf, Swift, Swinney & Vastano (1985), Physica D 16, 285. Fraser & Swinney (1986), Phys.
    Rev. A 33, 1134. Kennel, Brown & Abarbanel (1992), Phys. Rev. A 45, 3403. Cao (1997),
    Physica D 110, 43. Eckmann & Ruelle (1992), Physica D 56, 185. Theiler (1986), Phys. Rev.
    A 34, 2427 (the Theiler window).

    Examples
    --------
    >>> import numpy as np
    >>> x = np.empty(3000); a, b = 0.1, 0.0
    >>> for i in range(3000):             # Henon map: 0.41922 per iteration
    ...     a, b = 1 - 1.4 * a * a + b, 0.3 * a
    ...     x[i] = a
    >>> r = wolf_lle(x[100:])
    >>> int(r.flow), int(r.delay), int(r.dim), bool(r.reliable)
    (0, 1, 2, True)
    >>> abs(float(r.lle) / 0.41922 - 1) < 0.05
    True
    >>> import workbench
    >>> ds = workbench.simulate({"model": {"name": "lorenz"},
    ...                          "run": {"duration": 200.0, "transient": 20.0},
    ...                          "record": {"dt": 0.01}})
    >>> r = wolf_lle(ds.x)
    >>> int(r.flow), bool(r.reliable), 0.8 < float(r.lle) < 1.0   # 0.9056 1/s
    (1, True, True)
    >>> bool(wolf_lle(ds.x[::20]).reliable)   # dt = 0.2 s: flagged
    False
    """
    s = as_series(x, dt)
    require_samples(s, MIN_SAMPLES, "wolf_lle")
    v = s.values
    dim = _check_choice("dim", dim, 1)
    delay = _check_choice("delay", delay, 1)
    evolve = _check_choice("evolve", evolve, 1)
    theiler = _check_choice("theiler", theiler, 0)
    if not 0 < max_angle <= math.pi / 2:
        raise ValueError(f"max_angle={max_angle!r}; allowed: 0 < max_angle <= pi/2 (rad)")
    for name, value in (("scale_min", scale_min), ("scale_max", scale_max)):
        if value is not None and not (np.isfinite(value) and value >= 0):
            raise ValueError(f"{name}={value!r}; allowed: a finite separation >= 0 (units of x)")
    if period is not None and not period > 0:
        raise ValueError(f"period={period!r}; allowed: a positive forcing period (s)")
    if np.ptp(v) == 0:
        raise ValueError(f"x ({s.name!r}) is constant: no separations to follow")
    chosen = []
    smooth = smoothness(v)
    spp = mean_period(v)
    chosen_flow = flow is None
    if flow is None:
        flow = s.sampling != "strobe" and smooth >= FLOW_MIN_SMOOTHNESS
        chosen.append("flow")
    flow = bool(flow)
    ami = delay_ami(v, max_lag=max(2, min(v.size // 10, 2000)))
    if delay is None:
        delay = int(ami.delay) if flow else 1
        chosen.append("delay")
    fits = max(1, (v.size - 20) // delay - 2)  # dimensions whose embedding the series can hold
    fnn = embedding_fnn(v, delay=delay, max_dim=min(10, fits), points=EVIDENCE_POINTS)
    if dim is None:
        dim = int(fnn.dim)
        chosen.append("dim")
    cao_max = min(max(dim + 2, 4), fits)
    cao = embedding_cao(v, delay=delay, max_dim=cao_max, points=EVIDENCE_POINTS)
    # Cao's E2 stays near 1 at every dimension for a stochastic series (Cao 1997): such a
    # series gets a positive "LLE" from any estimator, which is no evidence of chaos
    stochastic = bool(np.all(np.abs(cao.E2.values[: min(4, cao_max)] - 1.0) < 0.1))
    if theiler is None:
        theiler = max(1, int(round(spp)))
        chosen.append("theiler")
    if evolve is None:
        evolve = max(1, int(round(delay / 4))) if flow else 1
        chosen.append("evolve")
    Y = np.ascontiguousarray(embed(v, dim, delay))
    n = Y.shape[0]
    if n < 4 * theiler + 4 * evolve + 4:
        raise ValueError(
            f"x ({s.name!r}) has {v.size} samples, too few for dim={dim}, delay={delay}, "
            f"theiler={theiler}, evolve={evolve}: it needs at least "
            f"{4 * theiler + 4 * evolve + 4 + (dim - 1) * delay}; record a longer series"
        )
    if scale_max is None:
        tree = cKDTree(Y)
        k = FLOW_SCALE_POINTS if flow else MAP_SCALE_POINTS
        probe = np.linspace(0, n - 1, min(n, 500)).astype(np.int64)
        dk, _ = tree.query(Y[probe], k=min(k + 1, n))
        scale_max = float(np.median(dk[:, -1])) * (FLOW_SCALE_FRACTION if flow else 1.0)
        chosen.append("scale_max")
    if scale_min is None:
        scale_min = 1e-3 * scale_max
        chosen.append("scale_min")
    if not 0 <= scale_min < scale_max:
        raise ValueError(
            f"scale_min={scale_min!r} and scale_max={scale_max!r}: need 0 <= scale_min < scale_max"
        )
    follower = _Follower(
        Y,
        flow=flow,
        evolve=evolve,
        scale_min=scale_min,
        scale_max=scale_max,
        max_angle=max_angle,
        theiler=theiler,
    )
    logs, replacements, kept = follower.run()
    if logs.size == 0:
        raise ValueError(
            f"no neighbour pair could be followed in x ({s.name!r}, {v.size} samples): the "
            "series is too short or too sparse for the chosen scales"
        )
    elapsed_samples = evolve * np.arange(1, logs.size + 1)
    running_per_sample = np.cumsum(logs) / elapsed_samples
    per_sample = float(running_per_sample[-1])
    lle = per_sample / s.dt

    msgs = _sampling_messages(
        s, flow=flow, chosen_flow=chosen_flow, smooth=smooth, per_sample=per_sample, spp=spp
    )
    d2 = correlation_dimension(Y, follower.tree, theiler, scale_max)
    min_points = int(math.ceil(POINTS_BASE ** (d2 if np.isfinite(d2) else dim)))
    if n < min_points:
        msgs.append(
            f"{n} embedded points are fewer than 10^D = {min_points} for the correlation "
            f"dimension D = {d2:.2f} at the scales of the neighbours (Eckmann & Ruelle 1992; "
            "Wolf et al. 1985: 10^D to 30^D points): record a longer series"
        )
    periods = v.size / spp
    if flow and periods < MIN_PERIODS:
        msgs.append(
            f"the series spans {periods:.1f} mean periods (< {MIN_PERIODS}): too few passes "
            "for neighbours from other parts of the orbit; record a longer series"
        )
    if stochastic:
        msgs.append(
            "Cao's E2 is within 0.1 of 1 at every dimension: the series looks stochastic, and "
            "a positive exponent is then no evidence of chaos"
        )
    reliable = not msgs
    message = "; ".join(msgs) if msgs else "no warning"

    timed = s.time_units == "s"
    t_units = "s-1" if timed else "1"
    per = "" if timed else (" per iteration" if not flow else " per sample")
    dims = cao.dimension.values
    fnn_curve = np.full(dims.size, np.nan)
    m = min(dims.size, fnn.fnn_fraction.size)
    fnn_curve[:m] = fnn.fnn_fraction.values[:m]
    out = xr.Dataset(
        {
            "lle": ((), lle, {"units": t_units, "long_name": "largest Lyapunov exponent" + per}),
            "lle_per_sample": (
                (),
                per_sample,
                {"units": "1", "long_name": "largest Lyapunov exponent per sample (lambda dt)"},
            ),
            "running": (
                "elapsed",
                running_per_sample / s.dt,
                {"units": t_units, "long_name": "running estimate of the LLE" + per},
            ),
            "reliable": (
                (),
                np.int8(reliable),
                {
                    "units": "1",
                    "long_name": "estimate not flagged by the sampling, length and noise checks",
                    "flag_values": np.array([0, 1], dtype=np.int8),
                    "flag_meanings": "flagged reliable",
                    "message": message,
                },
            ),
            "smoothness": (
                (),
                smooth,
                {
                    "units": "1",
                    "long_name": "lag-1 autocorrelation of successive differences (map/flow)",
                    "resolved_flow_threshold": FLOW_SMOOTHNESS,
                    "flow_threshold": FLOW_MIN_SMOOTHNESS,
                },
            ),
            "samples_per_period": (
                (),
                spp,
                {"units": "1", "long_name": "samples per mean period (mean frequency)"},
            ),
            "flow": (
                (),
                np.int8(flow),
                {"units": "1", "long_name": "sampled flow (1; flow direction projected out)"},
            ),
            "ami": (
                "lag",
                ami.ami.values,
                {"units": "nat", "long_name": "average mutual information"},
            ),
            "fnn_fraction": (
                "dimension",
                fnn_curve,
                {"units": "1", "long_name": "fraction of false nearest neighbours"},
            ),
            "cao_E1": ("dimension", cao.E1.values, {"units": "1", "long_name": "Cao E1(d)"}),
            "cao_E2": ("dimension", cao.E2.values, {"units": "1", "long_name": "Cao E2(d)"}),
            "cao_dim": ((), int(cao.dim), {"units": "1", "long_name": "dimension by Cao E1"}),
            "stochastic": (
                (),
                np.int8(stochastic),
                {"units": "1", "long_name": "Cao's E2 within 0.1 of 1 for d = 1..4 (noise)"},
            ),
            "dim": ((), dim, {"units": "1", "long_name": "embedding dimension"}),
            "delay": ((), delay, {"units": "1", "long_name": "delay (samples)"}),
            "evolve": ((), evolve, {"units": "1", "long_name": "evolution time (samples)"}),
            "theiler": ((), theiler, {"units": "1", "long_name": "Theiler window (samples)"}),
            "scale_min": ((), scale_min, {"units": s.units, "long_name": "smallest separation"}),
            "scale_max": ((), scale_max, {"units": s.units, "long_name": "largest separation"}),
            "max_angle": (
                (),
                max_angle,
                {"units": "rad", "long_name": "largest angle (orientation, either sense)"},
            ),
            "replacements": ((), replacements, {"units": "1", "long_name": "replacements"}),
            "kept": ((), kept, {"units": "1", "long_name": "old neighbour kept (none found)"}),
            "steps": ((), logs.size, {"units": "1", "long_name": "evolution steps"}),
            "points": ((), n, {"units": "1", "long_name": "embedded points"}),
            "correlation_dimension": (
                (),
                d2,
                {"units": "1", "long_name": "correlation dimension at the neighbours' scales"},
            ),
            "min_points": ((), min_points, {"units": "1", "long_name": "10^D points"}),
        },
        coords={
            "elapsed": (
                "elapsed",
                elapsed_samples * s.dt,
                {"units": s.time_units, "long_name": "time followed"},
            ),
            "lag": ("lag", ami.lag.values, {"units": "1", "long_name": "lag (samples)"}),
            "dimension": ("dimension", dims, {"units": "1", "long_name": "embedding dimension"}),
        },
        attrs={
            "method": "Wolf et al. (1985), fixed evolution time",
            "series_kind": "sampled flow" if flow else "map",
            "chosen": ", ".join(chosen),
            "warning": "" if reliable else message,
        },
    )
    period = period or s.period
    if period and timed:
        out["lle_per_period"] = (
            (),
            lle * period,
            {"units": "1", "long_name": "largest Lyapunov exponent per forcing period"},
        )
    return out
