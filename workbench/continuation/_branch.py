"""Branches of periodic orbits: pseudo-arclength continuation in one parameter, bifurcations
detected, located, checked against what defines them and labelled on the way, and the switch
to the doubled branch at a period doubling.

Between two consecutive points of a branch a bifurcation shows as a sign change of a test
function (Seydel 2010, Sec. 7.4-7.6; Kuznetsov 2004, Sec. 10.2):

* ``det(M - I)`` (a real multiplier through +1): a **fold** (cyclic fold, saddle-node of
  orbits) where the parameter turns back (the tangent's parameter component changes sign), a
  **branch point** where it does not (e.g. a symmetry-breaking pitchfork);
* ``det(M + I)`` (a real multiplier through -1): a **period doubling** (flip);
* the number of complex multipliers outside the unit circle: a **Neimark-Sacker** (torus)
  bifurcation;
* a local extremum of an event function along the orbit through zero (for the clearance
  mechanisms: a free flight that reaches the bearing wall, a contact that lifts off): a
  **grazing** (Nordmark 1991; di Bernardo et al. 2008, Ch. 2 and 7), each extremum followed by
  its phase (:mod:`workbench.continuation._contacts`), so that changes at two joints or two
  phases are found one by one;
* the tangent's parameter component changes sign while no multiplier passes +1: a
  **nonsmooth fold**, where the branch turns at a point the map is not smooth at (e.g. a
  contact about to lift off; a border-collision pair, di Bernardo et al. 2008, Ch. 3).

Each is located by the Illinois (regula falsi) method along the arclength between the two
points, each trial point corrected onto the branch, and the bracket kept between converged
points. A located point is **labelled** only where the quantity that defines its kind confirms
it: the critical multiplier within :data:`MULTIPLIER_TOLERANCE` of +1 (fold, branch point), of
-1 (period doubling) or of the unit circle (a complex pair: Neimark-Sacker), the margin of the
grazing extremum within :data:`MARGIN_TOLERANCE` of its event function's range. Otherwise it is
stored as **unresolved** between the two converged ends of its bracket, with its suspected kind
and the defining quantity's value; before that, the step that brackets it is rejected and
halved until the search confirms it or the step is ``BranchSettings.approach`` short. Located points
are stored in order of arclength; a step whose contact sequence changes in a way no extremum's
sign change explains is rejected and halved. A branch ends on the bound of its parameter
range (the last point is corrected at the bound), never beyond it.

At a period doubling the doubled branch (``P^{2k}``) leaves in the direction of the
multiplier's eigenvector ``v``: its first point is corrected on the hyperplane through
``u* + eps v`` normal to ``v`` (branch switching; Seydel 2010, Sec. 5.6).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from workbench.continuation._contacts import (
    ContactSequence,
    ambiguous,
    match_extrema,
    nearest_extremum,
)
from workbench.continuation._newton import (
    NewtonFailure,
    OrbitPoint,
    correct,
    next_step,
    orbit_at,
    tangent,
)
from workbench.continuation._strobe import StrobeMap, _active
from workbench.scene import SceneError
from workbench.solver import SolverError

__all__ = [
    "LABELS",
    "MARGIN_TOLERANCE",
    "MULTIPLIER_TOLERANCE",
    "BranchSettings",
    "Special",
    "trace",
    "switch_at_doubling",
]

#: point labels (CF flag_values / flag_meanings of the stored ``label``)
LABELS = {
    "regular": 0,
    "start": 1,
    "end": 2,
    "fold": 3,
    "branch_point": 4,
    "period_doubling": 5,
    "neimark_sacker": 6,
    "grazing": 7,
    "nonsmooth_fold": 8,
    "unresolved": 9,
}
#: a multiplier counts as complex when its imaginary part exceeds this fraction of its modulus
COMPLEX = 1e-6
#: a located fold, branch point, period doubling or Neimark-Sacker point is labelled only where
#: its critical multiplier lies this close to +1, -1 or the unit circle (located to 1e-7 of the
#: parameter's range, a transversal crossing leaves ~1e-7, a fold's square root ~3e-4)
MULTIPLIER_TOLERANCE = 1e-3
#: a located grazing is labelled only where the extremum's value is this small relative to
#: the range of its event function along the orbit
MARGIN_TOLERANCE = 1e-6
#: a corrected point lies at most this many steps (scaled arclength) from the point it was
#: predicted from: on the step's hyperplane the correction then moved it at most sqrt(3) steps
#: off the prediction. Further away, Newton has reached another part of the solution set
#: (branch jumping), where a turn of the tangent or a change of a test function would be
#: labelled a bifurcation that is not there
JUMP = 2.0
#: halvings towards the last orbit where Newton fails on the way to a grazing
GRAZE_HALVINGS = 12
#: a grazing searched at fixed parameter values is polished to this fraction of
#: MARGIN_TOLERANCE, or until the secant moves the parameter by less than POLISHED of its scale
POLISH = 1e-3
POLISHED = 1e-9
#: how a bifurcation's note starts where the corrector failed inside its bracket
CORRECTOR_FAILED = "the corrector failed inside the bracket"
#: note of a grazing whose bracket closed on a jump: its two ends further apart than their
#: arclength allows, the margin not within tolerance at either (a contact law with memory:
#: the orbit just past the grazing holds the new contact's onset velocity, near zero)
JUMPED_ACROSS = "the orbit jumps across the bracket"


def _distance(smap, A: OrbitPoint, B: OrbitPoint, pscale: float) -> float:
    """Distance of two orbits in the scaled states and parameter (the discrete states left
    out: their live sets may differ), in the units of the scaled arclength."""
    s = smap.scale()
    a = np.concatenate([A.y / s, [A.p / pscale]])
    b = np.concatenate([B.y / s, [B.p / pscale]])
    return float(np.linalg.norm(b - a))


@dataclass
class BranchSettings:
    """Knobs of the continuation (scaled units: states by their sizes, the parameter by
    ``pscale``)."""

    pscale: float
    bounds: tuple[float, float]
    tolerance: float = 1e-8
    step: float = 0.02
    max_step: float = 0.1
    min_step: float = 1e-6
    max_points: int = 300
    locate_tolerance: float = 1e-7  # of pscale, for the located bifurcations
    max_iterations: int = 8
    #: a bifurcation that its search cannot confirm from a longer step is approached with
    #: halved steps until the step is this short (scaled arclength)
    approach: float = 1e-4


@dataclass
class Special:
    """A bifurcation found between two points of a branch.

    ``point`` is the converged orbit at the located value (the bracket's end nearer to it);
    ``lower`` and ``upper`` the parameter at the two converged ends of the final bracket;
    ``resolved`` whether the defining quantity confirms the kind there; ``test`` that quantity
    (the critical multiplier's distance from +1, -1 or the unit circle; for a grazing the
    extremum's value, event units); ``critical`` the critical multiplier; for a grazing
    ``event`` and ``phase`` (s after the strobe time) of the extremum."""

    kind: str
    point: OrbitPoint
    sigma: float
    lower: float
    upper: float
    resolved: bool
    test: float
    critical: complex
    event: int = -1
    phase: float = math.nan
    note: str = ""
    #: for a grazing, how the orbit passes it (see :func:`_beyond_grazing`)
    transition: str = ""


@dataclass
class Traced:
    """A traced branch: its points (special points included, in order of arclength), their
    labels, the map, the bifurcations found and the reason it ended."""

    smap: StrobeMap
    points: list[OrbitPoint] = field(default_factory=list)
    labels: list[str] = field(default_factory=list)
    critical: list[complex] = field(default_factory=list)
    ended: str = ""
    evaluations: int = 0
    wall_time: float = 0.0
    specials: list[Special] = field(default_factory=list)
    #: where Newton's tolerance was raised to the map's noise: (parameter, old, new, noise)
    raised: list[tuple[float, float, float, float]] = field(default_factory=list)


def _tests(pt: OrbitPoint) -> dict:
    M = pt.value.M
    m = M.shape[0]
    mu = pt.multipliers
    cplx = np.abs(mu.imag) > COMPLEX * np.maximum(np.abs(mu), 1e-300)
    return {
        "size": m,
        "fold": float(np.linalg.det(M - np.eye(m))),
        "pd": _pd_value(pt),
        "ns": int(np.sum(cplx & (np.abs(mu) > 1.0))),
        "turn": float(pt.tau[-1]),
    }


def _pd_value(pt: OrbitPoint) -> float:
    M = pt.value.M
    return float(np.linalg.det(M + np.eye(M.shape[0])))


def _ns_value(pt: OrbitPoint) -> float:
    mu = pt.multipliers
    cplx = np.abs(mu.imag) > COMPLEX * np.maximum(np.abs(mu), 1e-300)
    return float(np.max(np.abs(mu[cplx])) - 1.0) if cplx.any() else float("nan")


def _detect(a: dict, b: dict) -> list[str]:
    """The kinds of bifurcation the multipliers and the tangent show between two points."""
    if a["size"] != b["size"]:
        return []
    found = []
    turned = np.sign(a["turn"]) != np.sign(b["turn"])
    if np.sign(a["fold"]) != np.sign(b["fold"]):
        found.append("fold" if turned else "branch_point")
    elif turned:
        found.append("nonsmooth_fold")
    if np.sign(a["pd"]) != np.sign(b["pd"]):
        found.append("period_doubling")
    if a["ns"] != b["ns"]:
        found.append("neimark_sacker")
    return found


def sequence_of(smap: StrobeMap, pt: OrbitPoint) -> ContactSequence:
    """The contact sequence of a converged orbit (computed once per point, and again where the
    map has since read sequences at a higher density: neighbours are compared at one)."""
    if pt.sequence is None or pt.sequence.samples < smap.samples:
        pt.sequence = smap.contact_sequence(pt.y, pt.aux, pt.p)
    return pt.sequence


def _surfaces(seq: ContactSequence) -> list[int]:
    """One event function per event surface: functions whose extrema coincide (the onset and
    end functions of one joint share its penetration) are the same surface."""
    keep: list[int] = []
    for k, e in enumerate(seq.extrema):
        if not any(
            e.shape == seq.extrema[j].shape and np.array_equal(e, seq.extrema[j]) for j in keep
        ):
            keep.append(k)
    return keep


def _grazings(seq_a: ContactSequence, seq_b: ContactSequence) -> tuple[list[tuple], bool]:
    """The grazings between two orbits: ``(k, phase, kind)`` of each local extremum whose value
    changes sign (matched by phase), and whether the step is explained by them (False: the
    sequence changed in a way no extremum accounts for, or a sign change comes from a pair the
    matching cannot tell from its neighbours, :func:`~._contacts.ambiguous`: a shorter step
    is needed to compare the two)."""
    found, unclear = [], False
    for k in _surfaces(seq_a):
        ea, eb = seq_a.extrema[k], seq_b.extrema[k]
        for i, j in match_extrema(ea, eb, seq_a.span):
            if np.sign(ea[i, 1]) != np.sign(eb[j, 1]):
                found.append((k, float(ea[i, 0]), float(ea[i, 2])))
                unclear |= ambiguous(ea, eb, i, j, seq_a.span)
    changed = seq_a.surface_counts != seq_b.surface_counts
    return found, not unclear and (not changed or bool(found))


def _extremum_value(smap: StrobeMap, k: int, phase: float, kind: float):
    """The test function of a grazing: the value of event function ``k``'s local extremum of
    ``kind`` nearest to ``phase`` along an orbit."""

    def value(pt: OrbitPoint) -> float:
        seq = sequence_of(smap, pt)
        i = nearest_extremum(seq.extrema[k], phase, kind, seq.span)
        return float(seq.extrema[k][i, 1]) if i >= 0 else math.nan

    return value


def _margin_follower(smap: StrobeMap, A: OrbitPoint, B: OrbitPoint, h: float, graze: tuple):
    """The test function of a grazing inside the step from A to B (arclength ``h``):
    ``value(pt, sigma)``, the value of event function ``k``'s extremum of ``kind`` (``graze``)
    on the orbit ``pt`` at arclength ``sigma``, read nearest to the phase interpolated between
    the extremum's phases on the orbits already read on either side of ``sigma``. The extremum
    moves along the orbit with the parameter; where others of its kind lie close by (rebounds
    along a wall), a fixed phase would read one, then the next, and the jump from one to the
    other would pass for a zero. B's extremum is the one matched to A's, as the step's
    detection (:func:`_grazings`) matched it."""
    k, phase, kind = graze
    seq_a, seq_b = sequence_of(smap, A), sequence_of(smap, B)
    span = seq_a.span
    i = nearest_extremum(seq_a.extrema[k], phase, kind, span)
    j = dict(match_extrema(seq_a.extrema[k], seq_b.extrema[k], span)).get(i, -1)
    seen = {0.0: float(seq_a.extrema[k][i, 0]) if i >= 0 else phase}
    seen[h] = float(seq_b.extrema[k][j, 0]) if j >= 0 else seen[0.0]

    def value(pt: OrbitPoint, sigma: float) -> float:
        below = max((s for s in seen if s <= sigma), default=min(seen))
        above = min((s for s in seen if s >= sigma), default=max(seen))
        p0, p1 = seen[below], seen[above]
        w = (sigma - below) / (above - below) if above != below else 0.0
        ref = (p0 + w * ((p1 - p0 + 0.5 * span) % span - 0.5 * span)) % span  # the short way
        seq = sequence_of(smap, pt)
        n = nearest_extremum(seq.extrema[k], ref, kind, span)
        if n < 0:
            return math.nan
        seen[sigma] = float(seq.extrema[k][n, 0])
        return float(seq.extrema[k][n, 1])

    return value


def _predict(smap: StrobeMap, A: OrbitPoint, u: np.ndarray, pscale: float) -> OrbitPoint:
    s = smap.scale()
    n = A.y.size
    live = A.value.live
    y = s * u[:n]
    aux = A.aux.copy()
    aux[live] = u[n:-1]
    return OrbitPoint(float(u[-1] * pscale), y, aux, A.value, 0, np.inf)


def _at(smap, A: OrbitPoint, sigma: float, cfg: BranchSettings) -> OrbitPoint:
    """The branch point at arclength ``sigma`` from A along A's tangent."""
    s = smap.scale()
    u_pred = A.u(s, cfg.pscale) + sigma * A.tau
    pred = _predict(smap, A, u_pred, cfg.pscale)
    B = correct(
        smap,
        pred,
        A.tau,
        u_pred,
        cfg.pscale,
        tolerance=cfg.tolerance,
        max_iterations=cfg.max_iterations,
    )
    if B.Pp is None:  # converged at the prediction: the column there
        try:
            B.Pp = smap.parameter_derivative(B.y, B.aux, B.p, B.value.live, cfg.pscale)
        except (SceneError, SolverError) as exc:
            raise NewtonFailure(f"no parameter derivative at p = {B.p:.10g}: {exc}") from exc
        B.evaluations += 2
    B.tau = tangent(B, A.tau)
    return B


def _value_function(smap, kind: str, graze: tuple | None):
    if kind in ("fold", "branch_point"):
        return lambda pt: _tests(pt)["fold"]
    if kind == "period_doubling":
        return lambda pt: _tests(pt)["pd"]
    if kind == "neimark_sacker":
        return _ns_value
    if kind == "nonsmooth_fold":
        return lambda pt: float(pt.tau[-1])
    return _extremum_value(smap, *graze)


def _critical(pt: OrbitPoint, kind: str) -> complex:
    mu = pt.multipliers
    if kind in ("fold", "branch_point"):
        return complex(mu[np.argmin(np.abs(mu - 1.0))])
    if kind == "period_doubling":
        return complex(mu[np.argmin(np.abs(mu + 1.0))])
    if kind == "neimark_sacker":
        cplx = np.abs(mu.imag) > COMPLEX * np.abs(mu)
        if cplx.any():
            c = mu[cplx]
            return complex(c[np.argmin(np.abs(np.abs(c) - 1.0))])
        return complex(np.nan, np.nan)
    return complex(mu[0])


def _confirm(smap, kind: str, pt: OrbitPoint, f: float, graze) -> tuple[bool, float, str]:
    """Whether the quantity that defines ``kind`` confirms it at the located point; that
    quantity; and, if not, why."""
    if kind in ("fold", "branch_point", "period_doubling", "neimark_sacker"):
        c = _critical(pt, kind)
        if kind == "neimark_sacker":
            d = abs(abs(c) - 1.0) if np.isfinite(c) else math.inf
            target = "a complex pair on the unit circle"
        else:
            one = 1.0 if kind != "period_doubling" else -1.0
            d = abs(c - one)
            target = f"{one:+g}"
        if d <= MULTIPLIER_TOLERANCE:
            return True, d, ""
        return False, d, f"critical multiplier {c:.4g}, {d:.3g} from {target}"
    if kind == "grazing":
        scale = float(sequence_of(smap, pt).scale[graze[0]])
        if abs(f) <= MARGIN_TOLERANCE * scale:
            return True, f, ""
        return (
            False,
            f,
            f"the extremum's value {f:.3g} exceeds {MARGIN_TOLERANCE:g} of its range {scale:.3g}",
        )
    return True, f, ""  # nonsmooth_fold: the tangent's turn, bracketed to the tolerance


def _went_back(A: OrbitPoint, B: OrbitPoint, cfg: BranchSettings) -> bool:
    """Whether the corrected point B lies back from A in the parameter, against A's tangent
    (by more than Newton's tolerance, scaled), with det(M - I) of one sign at both: no curve
    of a continuous map turns so (:func:`_turn_without_fold`), so B lies on another part of
    the solution set, e.g. on the branch's own past, where the continuation would go back
    along itself. Only where the two orbits locate as many events: across a grazing the map of
    an impacting system is not even Lipschitz (Nordmark's square root), and a branch can turn
    there whatever det(M - I) does (typed by the grazing's transition)."""
    if A.value.M.shape != B.value.M.shape or A.value.events != B.value.events:
        return False
    back = (B.p - A.p) / cfg.pscale * np.sign(A.tau[-1]) < -cfg.tolerance
    return bool(back and _turn_without_fold(_tests(A)["fold"], _tests(B)["fold"]))


def _turn_without_fold(det_lo: float, det_hi: float) -> str:
    """Why the tangent's turn between two orbits with these values of det(M - I) is no fold,
    or "" where it can be one. Along one curve of a continuous map, smooth or piecewise
    smooth, with its tangent oriented consistently, the tangent's parameter component has the
    sign of det(M - I) (Cramer's rule on the bordered system; at a border collision this is
    Feigin's rule, di Bernardo, Feigin, Hogan & Homer 1999: a nonsmooth fold where the number
    of real multipliers above +1 changes parity, persistence where it does not). A turn where
    det(M - I) keeps its sign is then no fold: the map jumps there (contact memory) or the
    corrector moved to another part of the solution set."""
    if np.sign(det_lo) != np.sign(det_hi):
        return ""
    return (
        f"the tangent turns but det(M - I) keeps its sign ({det_lo:.3g} and {det_hi:.3g} at "
        "the bracket's ends: no real multiplier passes +1), which no fold of a continuous map "
        "allows (Feigin's parity): the map jumps there, or the corrector reached another part "
        "of the solution set"
    )


def _locate(
    smap, A: OrbitPoint, B: OrbitPoint, h: float, kind: str, cfg: BranchSettings, graze=None
) -> Special:
    """The bifurcation ``kind`` between A and B (B at arclength h from A): the Illinois method
    on its test function, the bracket kept between converged points; returns the
    :class:`Special` (confirmed or unresolved). A grazing's margin is followed along the bracket
    (:func:`_margin_follower`); where it has one sign at A and B, the step's sign change came
    from another extremum and nothing is located (unresolved: the step is shortened)."""
    if kind == "grazing":
        value = _margin_follower(smap, A, B, h, graze)
    else:
        plain = _value_function(smap, kind, graze)

        def value(pt: OrbitPoint, sigma: float) -> float:
            return plain(pt)

    lo, hi, f_lo, f_hi = 0.0, h, value(A, 0.0), value(B, h)
    pt_lo, pt_hi = A, B
    side = 0
    note = ""
    one_sign = kind == "grazing" and f_lo * f_hi > 0.0
    if one_sign:
        note = (
            f"the extremum followed from one end of the step to the other keeps its sign "
            f"({f_lo:.3g} and {f_hi:.3g}): the sign change seen was another extremum's"
        )
    for _ in range(0 if one_sign else 60):
        if abs(hi - lo) * max(abs(A.tau[-1]), 1e-3) < cfg.locate_tolerance:
            break
        if not (np.isfinite(f_lo) and np.isfinite(f_hi)) or f_lo == f_hi:
            mid = 0.5 * (lo + hi)
        else:
            mid = hi - f_hi * (hi - lo) / (f_hi - f_lo)
            if not lo < mid < hi:
                mid = 0.5 * (lo + hi)
        try:
            pt = _at(smap, A, mid, cfg)
        except NewtonFailure as exc:
            if mid != 0.5 * (lo + hi):  # the secant's trial failed: try the bisection's
                side = 0
                try:
                    mid = 0.5 * (lo + hi)
                    pt = _at(smap, A, mid, cfg)
                except NewtonFailure as exc2:
                    note = f"{CORRECTOR_FAILED} ({exc2})"
                    break
            else:
                note = f"{CORRECTOR_FAILED} ({exc})"
                break
        f = value(pt, mid)
        if not np.isfinite(f):
            note = "the test function is not defined inside the bracket"
            break
        if np.sign(f) == np.sign(f_lo):
            lo, f_lo, pt_lo = mid, f, pt
            if side == -1:
                f_hi /= 2.0
            side = -1
        else:
            hi, f_hi, pt_hi = mid, f, pt
            if side == 1:
                f_lo /= 2.0
            side = 1
        if f == 0.0:
            break
    # the located point: the bracket's end with the smaller test value (both converged)
    f_a, f_b = value(pt_lo, lo), value(pt_hi, hi)
    best, sigma, f_best = (pt_lo, lo, f_a) if abs(f_a) <= abs(f_b) else (pt_hi, hi, f_b)
    ok, test, why = _confirm(smap, kind, best, f_best, graze)
    ok = ok and not one_sign
    if kind == "grazing" and not ok and not note:
        gap = _distance(smap, pt_lo, pt_hi, cfg.pscale)
        if gap > JUMP * abs(hi - lo) + 10.0 * cfg.tolerance:
            note = f"{JUMPED_ACROSS} ({gap:.3g} apart, scaled, over {abs(hi - lo):.3g})"
    if ok and kind == "nonsmooth_fold":
        why = _turn_without_fold(_tests(pt_lo)["fold"], _tests(pt_hi)["fold"])
        # a turn is where one curve folds back: the bracket's two ends lie on it, no further
        # apart than their arclength allows; further, they lie on two parts of the solution set
        gap = _distance(smap, pt_lo, pt_hi, cfg.pscale)
        allowed = JUMP * abs(hi - lo) + 10.0 * cfg.tolerance
        if not why and gap > allowed:
            why = (
                f"the bracket's ends lie {gap:.3g} apart (scaled), more than {allowed:.3g} for "
                "their arclength: two parts of the solution set, not a turn of one"
            )
        ok = not why
    special = Special(
        kind=kind,
        point=best,
        sigma=sigma,
        lower=min(pt_lo.p, pt_hi.p),
        upper=max(pt_lo.p, pt_hi.p),
        resolved=ok,
        test=test,
        critical=_critical(best, kind),
        event=graze[0] if graze else -1,
        phase=graze[1] if graze else math.nan,
        note="; ".join(x for x in (note, why) if x),
    )
    return special


def _on_bound(
    smap, A: OrbitPoint, B: OrbitPoint, bound: float, cfg: BranchSettings
) -> OrbitPoint | None:
    """The orbit at the parameter's bound between A and B (the state interpolated along the
    step, then Newton at the fixed parameter), or None where it does not converge."""
    w = (bound - A.p) / (B.p - A.p) if B.p != A.p else 1.0
    y = A.y + w * (B.y - A.y)
    aux = B.aux.copy()
    try:
        pt = orbit_at(
            smap, y, aux, bound, tolerance=cfg.tolerance, max_iterations=cfg.max_iterations
        )
        pt.Pp = smap.parameter_derivative(pt.y, pt.aux, pt.p, pt.value.live, cfg.pscale)
        pt.evaluations += 2
    except NewtonFailure:
        return None
    pt.tau = tangent(pt, A.tau) if pt.value.M.shape == A.value.M.shape else A.tau
    return pt


#: how far past a grazing (a fraction of the parameter's range) the orbits on its other side
#: are sought at least when the branch cannot be stepped through it
BEYOND = 1e-5
#: ... and at least where the grazing margin, extrapolated along the branch, lies this many
#: confirmation tolerances (MARGIN_TOLERANCE of its range) on the other side: a grazing is
#: confirmed anywhere within one tolerance of zero, on either side, so a fixed short distance
#: can leave the probe short of the grazing itself, where the branch's own orbit still exists
PAST_MARGINS = 10.0
#: ... but never further than this fraction of the parameter's range
FARTHEST = 1e-2
#: transitions at a grazing (``transition`` of a grazing bifurcation): the orbit crosses it with
#: the new contact (persistent); the branch turns back at it (a nonsmooth fold, di Bernardo et
#: al. 2008, Sec. 3.5); no orbit of the branch's period found beyond it, the motion there of
#: another period (a border collision, with the period in the text) or of none up to 16; the
#: orbit crosses it and a real multiplier jumps across -1 there (persistent_flip,
#: :func:`flips_at`). Appended in this order: an archive's flag values keep their meaning.
TRANSITIONS = ("persistent", "nonsmooth_fold", "border_collision", "not_typed", "persistent_flip")


def beyond_minus_one(pt: OrbitPoint) -> int:
    """Feigin's count sigma-: the orbit's real Floquet multipliers below -1."""
    mu = pt.multipliers
    return int(np.sum((mu.imag == 0.0) & (mu.real < -1.0)))


def flips_at(a: OrbitPoint, b: OrbitPoint, smooth: int = 0) -> bool:
    """Whether a real multiplier jumps across -1 at a grazing between the orbits ``a`` and
    ``b`` on its two sides, where ``smooth`` period doublings were located between them: the
    counts :func:`beyond_minus_one` of the two sides and ``smooth`` sum to an odd number.
    Feigin's rule for a border collision of a fixed point (di Bernardo, Feigin, Hogan & Homer
    1999, Chaos Solitons Fractals 10:1881): in a continuous piecewise-smooth map a period-2
    orbit is born there, and the orbit is unstable on one side (docs/continuation.md: the
    declared four-bar)."""
    return (beyond_minus_one(a) + beyond_minus_one(b) + smooth) % 2 == 1


#: strobe samples per look at the motion, and looks at most after the transient
ATTRACTOR_SAMPLES = 64
ATTRACTOR_LOOKS = 4
#: Newton's tolerance (scaled) on the orbit a repeating stretch of the motion approaches, and
#: how close (scaled) two of its strobe states must be to count as one (its least period)
ATTRACTOR_TOLERANCE = 1e-8
SAME_STATE = 1e-6


def _attractor_period(smap: StrobeMap, y, aux, p: float, cycles: int = 200) -> int:
    """The period (in forcing periods; 0: none found up to 16) of the motion from (y, aux) at
    ``p`` (:func:`_attractor`)."""
    return _attractor(smap, y, aux, p, cycles)[0]


def _attractor(
    smap: StrobeMap, y, aux, p: float, cycles: int = 200
) -> tuple[int, OrbitPoint | None]:
    """The period (in forcing periods; 0: none found up to 16) of the motion from (y, aux) at
    ``p``, and the stable orbit it settles on (None where none is found): after ``cycles``
    forcing periods, the next :data:`ATTRACTOR_SAMPLES` strobe samples are looked at, and
    again up to :data:`ATTRACTOR_LOOKS` times. Where they repeat with some period k
    (:func:`strobe_period`), Newton's method on ``P^k`` from the last sample finds the orbit
    they approach; its least period is the answer if that orbit is stable, else the
    motion was passing an unstable orbit and is looked at again. A repeating stretch alone
    is not the attractor: near a grazing the motion can settle slowly, e.g. onto an orbit
    whose multiplier is near -1, whose strobe samples then repeat every two of its periods
    long before they repeat every one."""
    from workbench.continuation._indicators import strobe_period

    one = smap.with_periods(1)
    s = one.scale()
    y, aux = np.array(y, float), np.array(aux, float)
    for _ in range(cycles):
        v = one(y, aux, p, tangent=False)
        y, aux = v.y1, v.aux1
    for _ in range(ATTRACTOR_LOOKS):
        samples = []
        for _ in range(ATTRACTOR_SAMPLES):
            v = one(y, aux, p, tangent=False)
            y, aux = v.y1, v.aux1
            samples.append(y / s)
        k = strobe_period(np.array(samples))
        if k == 0:
            continue
        try:
            orbit = orbit_at(
                one.with_periods(k), y, aux, p, tolerance=ATTRACTOR_TOLERANCE, max_iterations=12
            )
        except NewtonFailure:
            continue
        if np.max(np.abs(orbit.multipliers)) > 1.0:
            continue
        states = one.with_periods(k).orbit_samples(orbit.y, orbit.aux, p) / s
        moved = [np.max(np.abs(np.roll(states, -d, axis=0) - states)) for d in range(1, k + 1)]
        least = next(d for d in range(1, k + 1) if k % d == 0 and moved[d - 1] <= SAME_STATE)
        return least, orbit
    return 0, None


def _beyond_grazing(
    smap: StrobeMap, A: OrbitPoint, G: OrbitPoint, cfg: BranchSettings
) -> tuple[str, OrbitPoint | None, str]:
    """What lies past the grazing ``G``, reached from ``A``, where the branch cannot be stepped
    through it: the orbit a little further on with the new contact (``persistent``: returned,
    for the branch to go on from; where it is unstable, the text adds the period of the motion
    there), or the same a little back (``nonsmooth_fold``: the branch turns at the grazing),
    or neither (``border_collision``: the motion beyond has another period, said in the text
    with the parameter value, or none); Newton from the grazing orbit, continued along the
    branch's tangent into the contact.

    "Further on" is the way the branch went at A (its tangent). "A little" is at least BEYOND
    of the parameter's range, and at least where the grazing margin, extrapolated from A
    through G, lies PAST_MARGINS confirmation tolerances on the other side; where A lies past
    G already, twice as far past as A; at most FARTHEST of the range."""
    lo, hi = cfg.bounds
    # the branch's way: A's tangent, not G - A (the steps may have passed the grazing before
    # they collapsed, and the grazing was then located behind A)
    tau_p = float(A.tau[-1]) if A.tau is not None else 0.0
    ahead = math.copysign(1.0, tau_p if tau_p != 0.0 else G.p - A.p)
    counts = sequence_of(smap, A).surface_counts
    s = smap.scale()
    n = G.y.size

    def distance() -> float:
        least = BEYOND * cfg.pscale
        if (G.p - A.p) * ahead <= 0.0:  # A lies past G: at least as far past as A
            return min(max(least, 2.0 * abs(G.p - A.p)), FARTHEST * cfg.pscale)
        seq = sequence_of(smap, G)
        k, phase, m_g = seq.smallest_margin()
        if k < 0:
            return least
        kind = float(seq.extrema[k][np.argmin(np.abs(seq.extrema[k][:, 1] - m_g)), 2])
        m_a = _extremum_value(smap, k, phase, kind)(A)
        if not (np.isfinite(m_a) and np.isfinite(m_g)) or m_a == m_g:
            return least
        target = -math.copysign(PAST_MARGINS * MARGIN_TOLERANCE * float(seq.scale[k]), m_a)
        need = abs((target - m_g) * (G.p - A.p) / (m_g - m_a))
        return min(max(least, need), FARTHEST * cfg.pscale)

    def motion(p: float) -> str:
        k, orbit = _attractor(smap, G.y, G.aux, p)
        if not k:
            return f"no period up to 16 at {p:.10g}"
        text = f"period {k} at {p:.10g}"
        if k == smap.periods and orbit is not None:  # another orbit of the branch's period
            far = float(np.linalg.norm((orbit.y - G.y) / s))
            text += f", on an orbit {far:.3g} (scaled) from the grazing orbit"
        return text

    past = distance()
    for side in (ahead, -ahead):
        p = G.p + side * past
        if not lo <= p <= hi:
            continue
        # the state a little past the grazing along the branch's tangent: into the contact
        y = G.y + s * (past / cfg.pscale * G.tau[:n] / max(abs(G.tau[-1]), 1e-3))
        try:
            pt = orbit_at(
                smap, y, G.aux, p, tolerance=cfg.tolerance, max_iterations=START_ITERATIONS
            )
        except NewtonFailure:
            continue
        # the new contact: the other side's orbit
        if sequence_of(smap, pt).surface_counts != counts:
            kind = "persistent" if side == ahead else "nonsmooth_fold"
            text = f"an orbit with the new contact at {p:.10g}"
            mu = float(np.max(np.abs(pt.multipliers)))
            if side == ahead and mu > 1.0:
                text += f", unstable (|multiplier| {mu:.3g})"
                try:
                    text += f"; {motion(p)}"
                except (SceneError, SolverError) as exc:  # the map failed: reported
                    text += f"; the motion there failed ({exc})"
            return kind, pt, text
    p = G.p + ahead * past
    if lo <= p <= hi:
        try:
            what = motion(p)
        except (SceneError, SolverError) as exc:  # the map failed: reported
            return "not_typed", None, f"the motion past it failed ({exc})"
        return "border_collision", None, f"no period-{smap.periods} orbit found past it; {what}"
    return "not_typed", None, "its other side lies outside the parameter's range"


def _with_tangent(smap: StrobeMap, pt: OrbitPoint, orientation: np.ndarray, cfg: BranchSettings):
    """``pt`` with its parameter column and unit tangent (oriented along ``orientation``)."""
    if pt.Pp is None:
        pt.Pp = smap.parameter_derivative(pt.y, pt.aux, pt.p, pt.value.live, cfg.pscale)
        pt.evaluations += 2
    pt.tau = tangent(pt, orientation)
    return pt


def _grazing_ahead(
    smap: StrobeMap,
    prev: OrbitPoint,
    A: OrbitPoint,
    cfg: BranchSettings,
    graze: tuple | None = None,
):
    """The grazing the branch runs into after A, where it cannot be corrected through it: the
    margin ``graze`` (``(k, phase, kind)``; default the smallest margin of A's orbit) followed at
    fixed parameter values (Newton at each, from A's side) by the Illinois method on the secant
    through prev and A; the :class:`Special` (confirmed by its margin) or None."""
    seq = sequence_of(smap, A)
    if graze is None:
        k, phase, value = seq.smallest_margin()
        if k < 0 or abs(value) > 1e-2 * float(seq.scale[k]):
            return None
        kind = float(seq.extrema[k][np.argmin(np.abs(seq.extrema[k][:, 1] - value)), 2])
    else:
        k, phase, kind = graze
    margin = _extremum_value(smap, k, phase, kind)
    pts = [prev, A]
    f = [margin(prev), margin(A)]
    if not (np.isfinite(f[0]) and np.isfinite(f[1])) or f[0] == f[1]:
        return None
    lo, hi = cfg.bounds
    best = A
    beyond = math.nan  # the nearest value past the last orbit where Newton did not converge
    for _ in range(40):
        if pts[1].p == pts[0].p:  # the bracket closed to one value
            break
        p = pts[1].p - f[1] * (pts[1].p - pts[0].p) / (f[1] - f[0])
        p = min(max(p, lo), hi)
        if (p - pts[1].p) * (p - beyond) >= 0.0 and (beyond - pts[1].p) * (p - pts[1].p) > 0.0:
            p = 0.5 * (pts[1].p + beyond)  # not past where it failed: halfway there
        w = (p - pts[0].p) / (pts[1].p - pts[0].p)
        y = pts[0].y + w * (pts[1].y - pts[0].y)
        try:
            pt = orbit_at(smap, y, pts[1].aux, p, tolerance=cfg.tolerance, max_iterations=12)
        except NewtonFailure:  # no orbit of this family there: halve towards the last one
            pt = None
            for _ in range(GRAZE_HALVINGS):
                beyond, p = p, 0.5 * (p + pts[1].p)
                try:
                    pt = orbit_at(smap, pts[1].y, pts[1].aux, p, tolerance=cfg.tolerance)
                    break
                except NewtonFailure:
                    continue
            if pt is None:
                return None
        fp = margin(pt)
        if not np.isfinite(fp):
            return None
        moved = abs(p - best.p)
        best = pt
        tol = MARGIN_TOLERANCE * float(sequence_of(smap, pt).scale[k])
        if abs(fp) <= POLISH * tol or (abs(fp) <= tol and moved <= POLISHED * cfg.pscale):
            break  # polished below the label's tolerance, or the secant no longer moves
        if np.sign(fp) != np.sign(f[1]):
            pts, f = [pts[1], pt], [f[1], fp]
        else:
            pts, f = [pts[0], pt], [f[0] / 2.0, fp]  # Illinois: the stale end counts half
    else:
        return None
    fb = margin(best)
    ok = abs(fb) <= MARGIN_TOLERANCE * float(sequence_of(smap, best).scale[k])
    if not ok:
        return None
    _with_tangent(smap, best, A.tau, cfg)
    return Special(
        "grazing", best, 0.0, best.p, best.p, True, fb, complex(np.nan, np.nan), k, phase
    )


def _grazing_across(
    smap: StrobeMap,
    out: Traced,
    A: OrbitPoint,
    B: OrbitPoint,
    h: float,
    sp: Special,
    graze: tuple,
    cfg: BranchSettings,
) -> Special:
    """A grazing stepped across (A and B converged on its two sides) whose search along the
    arclength failed because the corrector does not converge between them, or converges on
    either side of a jump (:data:`JUMPED_ACROSS`; the map is not smooth, or not even
    continuous, at the grazing: e.g. a lift-off so short that the contact after it starts
    with an onset velocity near zero, which a contact law with memory divides by): located at
    fixed parameter values from A's side (:func:`_grazing_ahead` on the extremum ``graze``
    that changed sign, with the point before A), with the distance from the grazing orbit to B
    in the note beside what the step allows (a jump: the orbit past the grazing is not the
    continuation of the grazing orbit). ``sp`` where that does not confirm it."""
    prev = next((q for q in reversed(out.points) if q is not A and abs(q.p - A.p) > 0), None)
    if prev is None:
        return sp
    try:
        G = _grazing_ahead(smap, prev, A, cfg, graze)
    except (NewtonFailure, SceneError, SolverError):
        return sp
    if G is None or not min(A.p, B.p) <= G.point.p <= max(A.p, B.p):
        return sp
    G.sigma = h * (G.point.p - A.p) / (B.p - A.p) if B.p != A.p else 0.0
    G.lower, G.upper = min(G.point.p, B.p), max(G.point.p, B.p)
    G.critical = _critical(G.point, "grazing")
    gap = _distance(smap, G.point, B, cfg.pscale)
    G.note = (
        f"located at fixed parameter values ({sp.note}); the orbit past it lies {gap:.3g} "
        f"(scaled) from the grazing orbit, {JUMP * abs(h - G.sigma):.3g} allowed by the step"
    )
    return G


#: a branch stalls where this many accepted steps in a row were all shorter than STALL_STEP
#: times the first step; it then ends with a diagnosis instead of creeping on
STALL_POINTS = 30
STALL_STEP = 1e-2


def diagnosis(pt: OrbitPoint, h: float) -> str:
    """Why steps collapse at ``pt``, in numbers: the step, the tangent's parameter component,
    the conditioning of the Newton matrix and the monodromy's singular values beside its
    multipliers (a monodromy far from normal in the scaled states, e.g. states scaled by a
    clearance that is small against the motion, makes (M - I) ill-conditioned although every
    multiplier lies well inside the unit circle)."""
    M = pt.value.M
    m = M.shape[0]
    sv = np.linalg.svd(M, compute_uv=False)
    cond = np.linalg.cond(M - np.eye(m))
    return (
        f"step {h:.3g} (scaled arclength), tangent's parameter component {float(pt.tau[-1]):.3g}, "
        f"cond(M - I) {cond:.3g}, largest singular values of M {sv[0]:.3g} and "
        f"{sv[1] if sv.size > 1 else float('nan'):.3g} against |mu| <= "
        f"{float(np.abs(pt.multipliers).max()):.3g}"
    )


#: how often a branch is taken through a grazing it could not be stepped through
MAX_RESUMES = 20
#: a margin at most this small (relative to its event function's range) can be the grazing
#: that makes a step fail (as in :func:`_grazing_ahead`)
NEAR_GRAZING = 1e-2


def _grazing_within(smap: StrobeMap, out: Traced, A: OrbitPoint, h: float, pscale: float) -> bool:
    """Whether the grazing ahead of A lies within the step ``h`` that just failed: A's smallest
    margin, extrapolated linearly in the scaled arclength from the point before A through A,
    reaches zero at most ``h`` beyond A. Where it does, halving the step down to its minimum
    (each failed correction costing several evaluations of the map with its monodromy) cannot
    do better than locating the grazing at once (:func:`_through`)."""
    prev = next((q for q in reversed(out.points) if q is not A and abs(q.p - A.p) > 0), None)
    if prev is None:
        return False
    seq = sequence_of(smap, A)
    k, phase, value = seq.smallest_margin()
    if k < 0 or abs(value) > NEAR_GRAZING * float(seq.scale[k]):
        return False
    kind = float(seq.extrema[k][np.argmin(np.abs(seq.extrema[k][:, 1] - value)), 2])
    before = _extremum_value(smap, k, phase, kind)(prev)
    if not np.isfinite(before) or np.sign(before) != np.sign(value) or abs(before) <= abs(value):
        return False  # not approaching zero
    span = _distance(smap, prev, A, pscale)
    return abs(value) * span / (abs(before) - abs(value)) <= h


#: the probe of :func:`_past_grazing`: an orbit this fraction of the way from the grazing to the
#: orbit past it, and the largest change of a multiplier from the grazing orbit's that is not a
#: jump (a compliant stop's multipliers move like the square root of the distance: by about
#: 0.03 of their change over the whole way)
PROBE = 1e-3
JUMPED = 0.5
#: Illinois iterations of :func:`_past_grazing` (each orbit a few evaluations of the map)
PAST_ITERATIONS = 16


def _past_grazing(smap: StrobeMap, G: OrbitPoint, pt: OrbitPoint, cfg: BranchSettings):
    """Period doublings and Neimark-Sacker points between the grazing orbit ``G`` and the orbit
    ``pt`` past it where the branch was resumed across the grazing (no step of the branch lies
    between them to locate them on): the Illinois method on the test function at fixed
    parameter values, each orbit by Newton from the bracket's end on pt's side. A point is
    stored only where its critical multiplier confirms the kind. Where the multipliers jump at
    the grazing itself (a rigid impact's square-root map, a contact law with memory: no
    bifurcation of either side) nothing is looked for: an orbit :data:`PROBE` of the way from
    the grazing to ``pt`` whose multipliers differ from the grazing orbit's by more than
    :data:`JUMPED` shows that. The list of :class:`Special`."""
    kinds = [
        k for k in _detect(_tests(G), _tests(pt)) if k in ("period_doubling", "neimark_sacker")
    ]
    if not kinds:
        return []
    # from the grazing orbit, the nearer start: from pt, Newton 1e-3 of the way to it may not
    # converge where the map is nearly nonsmooth (the declared four-bar at 50.1284 rad/s)
    near = orbit_at(
        smap, G.y, G.aux, G.p + PROBE * (pt.p - G.p), tolerance=cfg.tolerance, max_iterations=12
    )
    mu_g, mu_n = np.sort_complex(G.multipliers), np.sort_complex(near.multipliers)
    if mu_g.size != mu_n.size or np.max(np.abs(mu_g - mu_n)) > JUMPED:
        return []
    found = []
    for kind in kinds:
        f = _pd_value if kind == "period_doubling" else _ns_value  # orbits without tangents
        a, b = G, pt
        fa, fb = f(a), f(b)
        for _ in range(PAST_ITERATIONS):
            if not (np.isfinite(fa) and np.isfinite(fb)) or fa == fb:
                break
            p = b.p - fb * (b.p - a.p) / (fb - fa)
            if not min(a.p, b.p) < p < max(a.p, b.p):
                p = 0.5 * (a.p + b.p)
            try:
                q = orbit_at(smap, b.y, b.aux, p, tolerance=cfg.tolerance, max_iterations=12)
            except NewtonFailure:
                break
            fq = f(q)
            if np.sign(fq) == np.sign(fb):
                b, fb, fa = q, fq, fa / 2.0  # Illinois: the stale end counts half
            else:
                a, fa = q, fq
            if abs(b.p - a.p) <= cfg.locate_tolerance * cfg.pscale:
                break
        ends = [q for q in (a, b) if q is not G and q is not pt]
        if not ends:
            continue
        q = min(ends, key=lambda e: abs(f(e)))
        ok, d, _ = _confirm(smap, kind, q, f(q), None)
        if ok:
            found.append(
                Special(
                    kind,
                    q,
                    0.0,
                    min(a.p, b.p),
                    max(a.p, b.p),
                    True,
                    d,
                    _critical(q, kind),
                    note="located at fixed parameter values between the grazing and the orbit "
                    "past it",
                )  # fmt: skip
            )
    return sorted(found, key=lambda sp: abs(sp.point.p - G.p))


def _through(smap: StrobeMap, out: Traced, A: OrbitPoint, cfg: BranchSettings) -> OrbitPoint | None:
    """Where the steps collapsed at A: the grazing ahead, located and typed
    (:func:`_grazing_ahead`, :func:`_beyond_grazing`) and stored; the orbit on its other side
    to go on from (its tangent set), or None (the branch ends there)."""
    prev = next((q for q in reversed(out.points[:-1]) if q is not A and abs(q.p - A.p) > 0), None)
    if prev is None:
        return None
    G = _grazing_ahead(smap, prev, A, cfg)
    if G is None:
        return None
    transition, pt, text = _beyond_grazing(smap, A, G.point, cfg)
    G.transition = transition
    G.note = f"located at fixed parameter values ahead of {A.p:.10g}, where steps failed; {text}"
    if not any(sp.point is G.point for sp in out.specials):
        out.points.append(G.point)
        out.labels.append("grazing")
        out.critical.append(G.critical)
        out.specials.append(G)
    if pt is None:
        return None
    ahead = math.copysign(1.0, pt.p - G.point.p)
    direction = np.zeros(pt.value.M.shape[0] + 1)
    direction[-1] = ahead
    try:
        _with_tangent(smap, pt, direction, cfg)
    except (NewtonFailure, SceneError, SolverError):
        return None
    try:
        between = _past_grazing(smap, G.point, pt, cfg)
        for sp in between:
            _with_tangent(smap, sp.point, direction, cfg)
    except (NewtonFailure, SceneError, SolverError):
        between = []
    if transition == "persistent":
        # the near side's orbit: the grazing orbit where it still has A's contacts, else A
        # (located on the far side, its multipliers are the far side's: the four-bar at 50.1284)
        same = sequence_of(smap, G.point).surface_counts == sequence_of(smap, A).surface_counts
        doublings = sum(sp.kind == "period_doubling" for sp in between)
        if flips_at(G.point if same else A, pt, doublings):
            G.transition = "persistent_flip"
    for sp in between:
        out.points.append(sp.point)
        out.labels.append(sp.kind)
        out.critical.append(sp.critical)
        out.specials.append(sp)
    out.points.append(pt)
    out.labels.append("regular")
    out.critical.append(complex(np.nan, np.nan))
    return pt


def trace(
    smap: StrobeMap,
    first: OrbitPoint,
    direction: np.ndarray,
    cfg: BranchSettings,
    label="start",
    report: Callable[[float, int], None] | None = None,
) -> Traced:
    """Continue a branch from the converged point ``first`` along ``direction`` (scaled
    unknowns) until the parameter reaches a bound of ``cfg.bounds``, the step falls below
    ``cfg.min_step`` or ``cfg.max_points`` points are found; ``report(parameter, points)``
    after each point (progress)."""
    wall0 = time.perf_counter()
    spent0 = smap.evaluations
    out = Traced(smap)
    if first.Pp is None:
        first.Pp = smap.parameter_derivative(
            first.y, first.aux, first.p, first.value.live, cfg.pscale
        )
    first.tau = tangent(first, direction)
    out.points.append(first)
    out.labels.append(label)
    out.critical.append(complex(np.nan, np.nan))
    lo, hi = cfg.bounds
    events = smap.prepared(first.p).problem.event_direction.size > 0
    h = cfg.step
    A = first
    resumed = short = raised = 0
    tried = None  # the last point from which the grazing ahead was looked for (_through)
    while len(out.points) < cfg.max_points:
        try:
            B = _at(smap, A, h, cfg)
            sharp = float(A.tau @ B.tau) < 0.5  # too sharp a turn: halve
            failure = "the branch turns sharply however short the step" if sharp else ""
            far = _distance(smap, A, B, cfg.pscale)
            if not sharp and far > JUMP * h:  # Newton left the branch: halve
                sharp = True
                failure = (
                    f"the corrector reaches another part of the solution set however short the "
                    f"step ({far / h:.3g} steps away)"
                )
            if not sharp and _went_back(A, B, cfg):  # Newton went back along the branch
                sharp = True
                failure = (
                    "the corrector goes back in the parameter against the tangent, det(M - I) "
                    f"keeping its sign ({_tests(A)['fold']:.3g} and {_tests(B)['fold']:.3g}), "
                    "however short the step"
                )
        except NewtonFailure as exc:
            B, sharp, failure = None, True, f"the corrector failed ({exc})"
        if sharp:
            if (
                events
                and resumed < MAX_RESUMES
                and A is not tried
                and _grazing_within(smap, out, A, h, cfg.pscale)
            ):
                tried = A  # the grazing lies within the failed step: located at once
                located = len(out.specials)
                nxt = _through(smap, out, A, cfg)
                if nxt is not None:
                    resumed += 1
                    A, h = nxt, cfg.step
                    continue
                if len(out.specials) > located:  # located, and no orbit of the branch past it
                    why = f"the grazing ahead lies within a step that failed; {failure}"
                    _end(smap, out, A, h, why, cfg)
                    break
            h /= 2.0
            if h < cfg.min_step:
                nxt = None
                if events and resumed < MAX_RESUMES and A is not tried:
                    nxt = _through(smap, out, A, cfg)
                if nxt is not None:
                    resumed += 1
                    A, h = nxt, cfg.step
                    continue
                if failure.startswith("the corrector failed"):
                    if raised < MAX_RAISES and _raise_to_noise(smap, out, A, cfg):
                        raised += 1
                        h = cfg.step
                        continue
                    failure += ", at the smallest step"
                _end(smap, out, A, h, failure, cfg)
                break
            continue
        found = [(kind, None) for kind in _detect(_tests(A), _tests(B))]
        if events:
            grazes, explained = _grazings(sequence_of(smap, A), sequence_of(smap, B))
            if not explained and h / 2.0 >= cfg.min_step:
                h /= 2.0  # the contact sequence changed in a way no extremum explains
                continue
            found += [("grazing", g) for g in grazes]
        specials = []
        for kind, graze in found:
            sp = _locate(smap, A, B, h, kind, cfg, graze)
            if kind == "grazing":  # stepped through: the branch went on, or turned at it
                if not sp.resolved and sp.note.startswith((CORRECTOR_FAILED, JUMPED_ACROSS)):
                    sp = _grazing_across(smap, out, A, B, h, sp, graze, cfg)
                turned = np.sign(A.tau[-1]) != np.sign(B.tau[-1])
                doublings = sum(x.kind == "period_doubling" and x.resolved for x in specials)
                sp.transition = (
                    "nonsmooth_fold"
                    if turned
                    else "persistent_flip"
                    if flips_at(A, B, doublings)
                    else "persistent"
                )
            specials.append(sp)
        if any(not sp.resolved for sp in specials) and h / 2.0 >= cfg.approach:
            h /= 2.0  # approach it: a shorter step brackets it closer, with easier corrections
            continue
        for sp in sorted(specials, key=lambda x: x.sigma):
            if lo <= sp.point.p <= hi:
                out.points.append(sp.point)
                out.labels.append(sp.kind if sp.resolved else "unresolved")
                out.critical.append(sp.critical)
                out.specials.append(sp)
        if not lo <= B.p <= hi:
            bound = hi if B.p > hi else lo
            end = _on_bound(smap, A, B, bound, cfg)
            if end is not None:
                out.points.append(end)
                out.labels.append("end")
                out.critical.append(complex(np.nan, np.nan))
            out.ended = f"the parameter reached its bound {bound:.10g}"
            break
        out.points.append(B)
        out.labels.append("regular")
        out.critical.append(complex(np.nan, np.nan))
        A = B
        if report is not None:
            report(B.p, len(out.points))
        short = short + 1 if h < STALL_STEP * cfg.step else 0
        if short >= STALL_POINTS:
            out.ended = (
                f"the branch stalled at {B.p:.10g}: {STALL_POINTS} steps in a row shorter than "
                f"{STALL_STEP:g} of the first; {diagnosis(B, h)}; a tighter rtol (the map's noise) "
                "or another parameter range may go further"
            )
            break
        h = next_step(h, B.iterations, cfg.max_step)
    else:
        out.ended = f"{cfg.max_points} points reached"
    if len(out.points) > 1 and out.labels[-1] == "regular":
        out.labels[-1] = "end"
    if report is not None:
        report(out.points[-1].p, len(out.points))
    out.wall_time = time.perf_counter() - wall0
    out.evaluations = smap.evaluations - spent0
    return out


def _end(smap: StrobeMap, out: Traced, A: OrbitPoint, h: float, failure: str, cfg) -> None:
    """End the branch at A, where the step ``h`` failed with ``failure``: the reason, in
    numbers (:func:`diagnosis`, the last bifurcation's note, :func:`_mark_end`)."""
    out.ended = f"{failure} at {A.p:.10g}: {diagnosis(A, h)}" + (
        f"; {out.specials[-1].note}" if out.specials and out.specials[-1].note else ""
    )
    _mark_end(smap, A, h, cfg, out)


def _mark_end(smap: StrobeMap, A: OrbitPoint, h: float, cfg: BranchSettings, out: Traced) -> None:
    """Why a branch ends where it cannot be continued, said in ``out.ended``: the contact
    structure just beyond the last point (the events per period and the live discrete states at
    the prediction, not a converged orbit) and the last orbit's smallest margin. The last point
    is labelled a grazing only where its own margin confirms it (within MARGIN_TOLERANCE)."""
    s = smap.scale()
    u = A.u(s, cfg.pscale) + 4 * cfg.min_step * A.tau
    beyond = _predict(smap, A, u, cfg.pscale)
    try:
        v = smap(beyond.y, beyond.aux, beyond.p, tangent=False)
    except (SceneError, SolverError):  # the map fails beyond: the reason stays as it is
        return
    if smap.prepared(A.p).problem.event_direction.size:
        seq = sequence_of(smap, A)
        k, phase, value = seq.smallest_margin()
        if k >= 0:
            out.ended += (
                f"; the last orbit's smallest margin: event function {k} at phase {phase:.6g} s, "
                f"{value:.3g}"
            )
            if abs(value) <= MARGIN_TOLERANCE * float(seq.scale[k]) and out.points[-1] is A:
                out.labels[-1] = "grazing"
                out.specials.append(
                    Special(
                        "grazing", A, 0.0, A.p, A.p, True, value, complex(np.nan, np.nan), k, phase
                    )
                )
    if A.value.one_sided:
        out.ended += f"; {_jump_nearby(smap, A)}"
    changed = v.events != A.value.events or not np.array_equal(v.live, A.value.live)
    if changed:
        out.ended += (
            f"; the prediction beyond it (not converged) has another contact structure (events "
            f"per {smap.periods} period(s) {A.value.events} -> {v.events}, live discrete states "
            f"{A.value.live.tolist()} -> {v.live.tolist()})"
        )


def _jump_nearby(smap: StrobeMap, A: OrbitPoint) -> str:
    """What the last orbit's copies say where some of them lay past a jump of the map
    (:attr:`MapValue.one_sided`): which unknowns, moved by the copies' step, reach it."""
    pb = smap.prepared(A.p).problem
    unknowns = [q.name for q in pb.states] + [f"discrete state {k}" for k in _active(A.aux, pb)]
    which = [unknowns[c] for c in A.value.one_sided]
    return (
        f"the last orbit's copies moved by {smap.step:g} (scaled) in {', '.join(which)} lie past "
        "a jump of the map (their Jacobian columns taken one-sided): another contact "
        "structure lies that close to the orbit in its state"
    )


def switch_at_doubling(
    smap: StrobeMap, pd: OrbitPoint, cfg: BranchSettings, epsilon: float = 0.05
) -> tuple[StrobeMap, OrbitPoint, np.ndarray]:
    """The first point of the period-2k branch born at the period doubling ``pd`` of the
    period-k branch of ``smap``, and the direction to continue it in (away from ``pd``).

    The offset ``epsilon`` (scaled units) along the eigenvector is halved until the corrected
    point lies within ``1e-3`` of the parameter range from the bifurcation: the doubled
    branch leaves as a parabola (p - p* ~ epsilon^2) whose width shrinks down a cascade."""
    mu, vecs = np.linalg.eig(pd.value.M)
    i = int(np.argmin(np.abs(mu + 1.0)))
    v = np.real(vecs[:, i])
    v /= np.linalg.norm(v)
    double = smap.with_periods(2 * smap.periods)
    s = smap.scale()
    u_star = pd.u(s, cfg.pscale)
    m = v.size
    tau0 = np.concatenate([v, [0.0]])
    failure: Exception | None = None
    while epsilon >= 1e-5:
        u0 = u_star + epsilon * tau0
        pred = _predict(smap, pd, u0, cfg.pscale)
        try:
            first = correct(
                double,
                pred,
                tau0,
                u0,
                cfg.pscale,
                tolerance=cfg.tolerance,
                max_iterations=2 * cfg.max_iterations,
            )
        except NewtonFailure as exc:
            failure, epsilon = exc, epsilon / 2.0
            continue
        if abs(first.p - pd.p) <= 1e-3 * cfg.pscale:
            break
        epsilon /= 2.0
    else:
        raise NewtonFailure(f"no doubled orbit near the period doubling ({failure})")
    if first.value.M.shape[0] != m:
        raise NewtonFailure("the doubled orbit has other live discrete states; cannot switch")
    away = first.u(s, cfg.pscale) - u_star
    return double, first, away / np.linalg.norm(away)


#: Newton's iterations at most for the first orbit of a branch (from a guess, not a prediction)
START_ITERATIONS = 30


def start_point(
    smap: StrobeMap, y, aux, p: float, cfg: BranchSettings, max_iterations: int = START_ITERATIONS
) -> OrbitPoint:
    """The converged orbit at ``p`` from the guess (y, aux), in at most ``max_iterations``
    Newton iterations (:class:`NewtonFailure` otherwise)."""
    return orbit_at(smap, y, aux, p, tolerance=cfg.tolerance, max_iterations=max_iterations)


#: Newton's tolerance must lie this far above the map's noise (:meth:`StrobeMap.jitter`)
NOISE_MARGIN = 10.0
#: how often a branch's Newton tolerance is raised to the map's noise along it
MAX_RAISES = 3


def _noise_raise(smap: StrobeMap, pt: OrbitPoint, cfg: BranchSettings):
    """Whether the map's noise at ``pt`` (:meth:`StrobeMap.jitter`) lies above what Newton's
    tolerance allows (:data:`NOISE_MARGIN`); if so, the tolerance is raised to the noise times
    the margin in ``cfg``, and ``(p, old, new, noise)`` returned; else None (a quiet map, or the
    noise could not be measured: the failure is not the noise's)."""
    try:
        noise = smap.jitter(pt.value, pt.y, pt.aux, pt.p, cfg.tolerance)
    except (SceneError, SolverError):
        return None
    if not np.isfinite(noise) or NOISE_MARGIN * noise <= cfg.tolerance:
        return None
    raised = (pt.p, cfg.tolerance, NOISE_MARGIN * noise, noise)
    cfg.tolerance = NOISE_MARGIN * noise
    return raised


def _raise_to_noise(smap: StrobeMap, out: Traced, A: OrbitPoint, cfg: BranchSettings) -> bool:
    """Where the corrector fails at the smallest step from A: whether the map's noise at A has
    grown above what Newton's tolerance allows (:func:`_noise_raise`). :func:`settle_noise`
    measured it at the branch's first orbit; an orbit with many more contacts is noisier (the
    declared four-bar's 16-event orbit at 50.21 rad/s: the residual stagnated at 1.1e-7,
    scaled, against a tolerance of 1e-8, and the steps collapsed). If so, Newton's tolerance
    is raised to the noise times the margin for the rest of the branch, in ``cfg`` and in
    ``out.raised``; True."""
    raised = _noise_raise(smap, A, cfg)
    if raised is not None:
        out.raised.append(raised)
    return raised is not None


def noisy_start(smap: StrobeMap, y, aux, p: float, cfg: BranchSettings):
    """The branch's first orbit (:func:`start_point`). Where Newton runs out of iterations
    because the map's noise at its last iterate lies above what the tolerance allows
    (:func:`_noise_raise`: the declared four-bar from 50 rad/s, a scaled residual of 8.7e-8
    against 1e-8), the tolerance is raised to the noise times the margin and Newton goes on
    from that iterate. Returns the orbit and the raise, ``[(p, old, new, noise)]`` or ``[]``;
    a failure that is not the noise's is raised as it was."""
    try:
        return start_point(smap, y, aux, p, cfg), []
    except NewtonFailure as exc:
        last = exc.last
        raised = None if last is None else _noise_raise(smap, last, cfg)
        if raised is None:
            raise
    return start_point(smap, last.y, last.aux, p, cfg), [raised]


#: the tightest integration tolerance the map is taken to, to bring its noise under Newton's
TIGHTEST_RTOL = 1e-12


def settle_noise(smap: StrobeMap, first: OrbitPoint, cfg: BranchSettings):
    """The map's noise at the branch's first orbit against Newton's tolerance: the map is
    integrated 10x tighter (down to :data:`TIGHTEST_RTOL`, the orbit corrected again) until its
    noise lies :data:`NOISE_MARGIN` below the tolerance; if even that does not do it, the
    tolerance is raised to the noise times the margin. Returns the map, the orbit, the
    tolerance and the noise (scaled units) it measured last."""
    tolerance = cfg.tolerance
    while True:
        noise = smap.jitter(first.value, first.y, first.aux, first.p, tolerance)
        if NOISE_MARGIN * noise <= tolerance:
            return smap, first, tolerance, noise
        if smap.rtol / 10.0 < TIGHTEST_RTOL:
            return smap, first, NOISE_MARGIN * noise, noise
        smap = smap.with_rtol(smap.rtol / 10.0)
        first = orbit_at(smap, first.y, first.aux, first.p, tolerance=tolerance)
