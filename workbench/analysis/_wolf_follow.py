"""Stage 2 of the Wolf estimate (:func:`workbench.analysis.wolf_lle`): evolve.

The fixed-evolution-time program of Wolf, Swift, Swinney & Vastano (1985), Physica D 16, 285
(Appendix A, FET) on embedded points: a fiducial trajectory and one neighbour are followed for
``evolve`` samples, the log of the growth of their separation is accumulated, and the neighbour
is kept or replaced (:class:`Follower`); :func:`follow` runs it over the whole series.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["Followed", "Follower", "follow"]

#: the widened neighbour search (2-4 x scale_max) looks at this many nearest points at most: a
#: ball 4 x wider holds 4^D times as many points, most of the data in many dimensions (noise)
WIDE_CANDIDATES = 512


def _angle(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Angles (rad, 0..pi/2) between the lines along the rows of u and along w: the orientation
    counts, not the sense (Wolf et al. 1985, program FET: ``cth = abs(dot / (dnew * df))``)."""
    nu = np.linalg.norm(u, axis=1)
    nw = np.linalg.norm(w)
    c = np.abs(u @ w) / np.maximum(nu * nw, 1e-300)
    return np.arccos(np.clip(c, 0.0, 1.0))


class Follower:
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


@dataclass(frozen=True)
class Followed:
    """What the evolution stage measured: the log growth of the separation over each
    evolution step (``logs``), the number of replacements, of steps that kept their neighbour
    for want of a replacement (``kept``), and the KD-tree of the embedded points."""

    logs: np.ndarray
    replacements: int
    kept: int
    tree: cKDTree


def follow(
    Y: np.ndarray,
    *,
    flow: bool,
    evolve: int,
    scale_min: float,
    scale_max: float,
    max_angle: float,
    theiler: int,
) -> Followed:
    """Stage 2: follow neighbour pairs over the embedded points ``Y`` (rows) and return the log
    growth of every evolution step (empty if no pair could be followed)."""
    follower = Follower(
        Y,
        flow=flow,
        evolve=evolve,
        scale_min=scale_min,
        scale_max=scale_max,
        max_angle=max_angle,
        theiler=theiler,
    )
    logs, replacements, kept = follower.run()
    return Followed(logs, replacements, kept, follower.tree)
