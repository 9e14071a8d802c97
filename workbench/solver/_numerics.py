"""Hook-free numerics of the explicit and implicit–explicit pairs, compiled once for all models.

Everything here works on arrays only (stages, states, dense-output coefficients, event-function
values) and calls no model hook, so numba compiles and caches it once; the per-model loop
(:mod:`workbench.solver._templates.integration_loop`) links the cached code. Algorithms: Dormand
& Prince (1980)
DOPRI5 with Shampine's (1986) dense output; Hairer's DOP853 (Hairer, Nørsett & Wanner 1993,
Sec. II.10) and its stiffness detection (Hairer & Wanner 1996, Sec. IV.2); the ARK5(4)8L[2]SA
of Kennedy & Carpenter (2003) with quartic Hermite dense output; the error norms of Hairer
et al. (1993, Eq. II.4.11); the Illinois variant of regula falsi (Dowell & Jarratt 1971).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from workbench.solver._loop_types import ARK548, DOP853, DOPRI5
from workbench.solver._tableaux import (
    ARK_E,
    ARK_GAMMA,
    DOP853_A,
    DOP853_B,
    DOP853_D,
    DOP853_E3,
    DOP853_E5,
    MAX_FACTOR,
    MIN_FACTOR,
    RK45_E,
    RK45_P,
    SAFETY,
)

#: DOP853's stability bound on the negative real axis, |h lambda| < 6.1 (Hairer's DOP853 code)
DOP853_STABILITY = 6.1


@njit(cache=True, nogil=True)
def n_stages(method):
    """Stages of an explicit (or implicit–explicit) method before its end derivative (FSAL)."""
    if method == DOP853:
        return 12
    return 8 if method == ARK548 else 6


@njit(cache=True, nogil=True)
def read_decay(work, stiff_slot, decay):
    """Copy the stiff states' decay rates (s-1) that the last ``rhs`` call wrote into work."""
    for k in range(stiff_slot.size):
        decay[k] = work[stiff_slot[k]]


@njit(cache=True, nogil=True)
def stiff_position(stiff_idx, i):
    """Position k of state i in ``stiff_idx`` (-1 if state i is not stiff)."""
    for k in range(stiff_idx.size):
        if stiff_idx[k] == i:
            return k
    return -1


@njit(cache=True, nogil=True)
def stage_point(K, a, s, h, y, out):
    """out = y + h * sum_{j<s} a[j] K[j]."""
    n = y.size
    for i in range(n):
        acc = 0.0
        for j in range(s):
            acc += a[j] * K[j, i]
        out[i] = y[i] + h * acc


@njit(cache=True, nogil=True)
def error_norm(method, K, h, y, y_new, rtol, atol, stiff_idx, decay, blocks):
    """Scaled RMS error estimate of the step (Hairer et al. 1993, Eq. II.4.11; DOP853's
    combination of its 5th- and 3rd-order estimators; for DOPRI5 and ARK548 the difference of
    the 5th- and 4th-order solutions), the largest over the state's blocks (boundaries
    ``blocks``, see :attr:`workbench.solver.Problem.error_blocks`).

    For ARK548 the stiff states' estimates are filtered by (1 + h gamma a)^-1, the diagonal form
    of Hairer & Wanner's (1996, Sec. IV.8) (I - h gamma J)^-1: the embedded solution is not
    L-stable, so the raw difference stays O(1) for |h a| >> 1 where both solutions are exact
    to the tolerance, and would bound the step by the decay rate again."""
    worst = 0.0
    for b in range(blocks.size - 1):
        lo = blocks[b]
        hi = blocks[b + 1]
        err = _block_error(method, K, h, y, y_new, rtol, atol, stiff_idx, decay, lo, hi)
        if not err <= worst:  # a NaN block wins
            worst = err
    return worst


@njit(cache=True, nogil=True, inline="always")
def _block_error(method, K, h, y, y_new, rtol, atol, stiff_idx, decay, lo, hi):
    """:func:`error_norm` of the states ``lo:hi``."""
    n = hi - lo
    if method == DOP853:
        e5 = 0.0
        e3 = 0.0
        for i in range(lo, hi):
            sc = atol[i] + rtol * max(abs(y[i]), abs(y_new[i]))
            a5 = 0.0
            a3 = 0.0
            for j in range(13):
                a5 += DOP853_E5[j] * K[j, i]
                a3 += DOP853_E3[j] * K[j, i]
            e5 += (a5 / sc) ** 2
            e3 += (a3 / sc) ** 2
        if e5 == 0.0 and e3 == 0.0:
            return 0.0
        return abs(h) * e5 / np.sqrt((e5 + 0.01 * e3) * n)
    E = ARK_E if method == ARK548 else RK45_E
    acc = 0.0
    for i in range(lo, hi):
        sc = atol[i] + rtol * max(abs(y[i]), abs(y_new[i]))
        e = 0.0
        for j in range(E.size):
            e += E[j] * K[j, i]
        if method == ARK548:
            k = stiff_position(stiff_idx, i)
            if k >= 0:
                e /= 1.0 + h * ARK_GAMMA * decay[k]
        acc += (h * e / sc) ** 2
    return np.sqrt(acc / n)


@njit(cache=True, nogil=True, inline="always")
def min_step(t):
    """The smallest step (s) from time t (s): ten units in the last place of t."""
    return 10.0 * abs(np.nextafter(t, np.inf) - t)


@njit(cache=True, nogil=True, inline="always")
def trial_step(t, t_end, h_abs):
    """The end (s) and size (s) of a trial step of h_abs (s) from t, not beyond t_end."""
    t_new = t + h_abs
    if t_new > t_end:
        t_new = t_end
    return t_new, t_new - t


@njit(cache=True, nogil=True)
def step_factor(err, exponent, rejected):
    """Step-size ratio after an accepted step with error ``err`` < 1 (no growth right after a
    rejection)."""
    if err == 0.0:
        factor = MAX_FACTOR
    else:
        factor = min(MAX_FACTOR, SAFETY * err**exponent)
    if rejected:
        factor = min(1.0, factor)
    return factor


@njit(cache=True, nogil=True)
def reject_factor(err, exponent):
    """Step-size ratio after a rejected step with error ``err`` >= 1 (inf: a failed step)."""
    if np.isfinite(err):
        return max(MIN_FACTOR, SAFETY * err**exponent)
    return MIN_FACTOR


@njit(cache=True, nogil=True)
def dop853_dense(K, h, y, y_new, F):
    """DOP853's 7th-order continuous extension from its 16 stages (the 3 extra ones in
    K[13:16])."""
    n = y.size
    for i in range(n):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (K[12, i] + K[0, i])
        for r in range(4):
            acc = 0.0
            for s in range(16):
                acc += DOP853_D[r, s] * K[s, i]
            F[3 + r, i] = h * acc


@njit(cache=True, nogil=True)
def dopri5_dense(K, F):
    """Shampine's (1986) 4th-order continuous extension of DOPRI5."""
    n = K.shape[1]
    for i in range(n):
        for j in range(4):
            acc = 0.0
            for s in range(7):
                acc += K[s, i] * RK45_P[s, j]
            F[j, i] = acc


@njit(cache=True, nogil=True)
def ark_cubic(K, h, y, y_new, F, ytmp):
    """ARK548's cubic Hermite interpolant through both ends of the step, and its value at
    t + h/3 in ``ytmp`` (where the quartic's extra derivative is taken).

    y(t + x h) = y + x (F1 + x (F2 + x (F3 + x F4))); F1 = h f0. With d = y_new - y and h f1:
    F2 = 3 d - 2 h f0 - h f1, F3 = h f0 + h f1 - 2 d, F4 = 0.
    """
    x = 1.0 / 3.0
    n = y.size
    for i in range(n):
        d = y_new[i] - y[i]
        F[0, i] = d
        F[1, i] = h * K[0, i]
        F[2, i] = 3.0 * d - 2.0 * h * K[0, i] - h * K[8, i]
        F[3, i] = h * K[0, i] + h * K[8, i] - 2.0 * d
        F[4, i] = 0.0
        ytmp[i] = y[i] + x * (F[1, i] + x * (F[2, i] + x * F[3, i]))


@njit(cache=True, nogil=True)
def ark_quartic(K, h, F, stiff_idx):
    """Raise :func:`ark_cubic` to the quartic Hermite interpolant (4th order: O(h^5) between the
    step's ends) with the derivative at t + h/3 in K[9]: p(1) = y_new, p'(0) = h f0,
    p'(1) = h f1, p'(1/3) = h f(t + h/3). With R1 = d - h f0, R2 = h (f1 - f0),
    R3 = h (f(t + h/3) - f0) the coefficients of x^2, x^3, x^4 are the rows of
    [[-6, 5/4, 27/4], [16, -7/2, -27/2], [-9, 9/4, 27/4]] @ R. Stiff states keep the cubic: their
    derivative at an interpolated point carries its error times the decay rate a, which would
    spoil the quartic for |h a| >> 1."""
    n = K.shape[1]
    for i in range(n):
        if stiff_position(stiff_idx, i) >= 0:
            continue
        r1 = F[0, i] - h * K[0, i]
        r2 = h * (K[8, i] - K[0, i])
        r3 = h * (K[9, i] - K[0, i])
        F[2, i] = -6.0 * r1 + 1.25 * r2 + 6.75 * r3
        F[3, i] = 16.0 * r1 - 3.5 * r2 - 13.5 * r3
        F[4, i] = -9.0 * r1 + 2.25 * r2 + 6.75 * r3


@njit(cache=True, nogil=True)
def dense_eval(method, t_old, h, y_old, F, t, out):
    """State at time t inside the last step from the continuous extension."""
    x = (t - t_old) / h
    n = y_old.size
    if method == DOP853:
        for i in range(n):
            acc = 0.0
            for r in range(6, -1, -1):
                acc += F[r, i]
                if (6 - r) % 2 == 0:
                    acc *= x
                else:
                    acc *= 1.0 - x
            out[i] = y_old[i] + acc
    elif method == ARK548:
        for i in range(n):
            out[i] = y_old[i] + x * (F[1, i] + x * (F[2, i] + x * (F[3, i] + x * F[4, i])))
    elif method == DOPRI5:
        for i in range(n):
            acc = 0.0
            xp = x
            for j in range(4):
                acc += F[j, i] * xp
                xp *= x
            out[i] = y_old[i] + h * acc
    else:  # Radau IIA: the collocation polynomial, y_old + sum_k F[k] x^(k+1)
        for i in range(n):
            out[i] = y_old[i] + x * (F[0, i] + x * (F[1, i] + x * F[2, i]))


@njit(cache=True, nogil=True)
def crossed(direction, g_a, g_b):
    """Whether event function g crossed between two points in the event's direction.

    The sides are g <= 0 ("before", for a rising event) and g > 0 ("beyond"), the partition the
    models use (a contact exists where the penetration is > 0), so that a state located exactly
    on g = 0 cannot hide the next crossing.
    """
    if direction >= 0 and g_a <= 0.0 and g_b > 0.0:
        return True
    if direction <= 0 and g_a > 0.0 and g_b <= 0.0:
        return True
    return False


@njit(cache=True, nogil=True)
def root_tolerance(t_a, t_b, h):
    """Width below which a bracket of an event's root is final (4 ulp of the times)."""
    return 4.0 * 2.220446049250313e-16 * max(abs(t_a), abs(t_b), abs(h))


@njit(cache=True, nogil=True)
def illinois_point(t_a, g_a, t_b, g_b):
    """The next trial point of regula falsi in the bracket [t_a, t_b] (its midpoint if the
    secant leaves it)."""
    t_m = (t_a * g_b - t_b * g_a) / (g_b - g_a)
    if not (t_m > t_a and t_m < t_b):
        t_m = 0.5 * (t_a + t_b)
    return t_m


@njit(cache=True, nogil=True)
def illinois_update(t_a, g_a, t_b, g_b, side, t_m, g_m):
    """Shrink the bracket to the side of ``t_m`` where g changes sign, halving the retained
    end's value when the same end is kept twice (the Illinois modification, which makes
    regula falsi superlinear). Returns the new (t_a, g_a, t_b, g_b, side)."""
    if (g_m > 0.0) == (g_a > 0.0):
        t_a = t_m
        g_a = g_m
        if side == -1:
            g_b *= 0.5
        side = -1
    else:
        t_b = t_m
        g_b = g_m
        if side == 1:
            g_a *= 0.5
        side = 1
    return t_a, g_a, t_b, g_b, side


@njit(cache=True, nogil=True)
def initial_norms(y0, f0, rtol, atol):
    """Scaled RMS norms of y0 and f0 (Hairer et al. 1993, Sec. II.4, "starting step size")."""
    n = y0.size
    d0 = 0.0
    d1 = 0.0
    for i in range(n):
        sc = atol[i] + abs(y0[i]) * rtol
        d0 += (y0[i] / sc) ** 2
        d1 += (f0[i] / sc) ** 2
    return np.sqrt(d0 / n), np.sqrt(d1 / n)


@njit(cache=True, nogil=True)
def initial_difference(y0, f0, f1, rtol, atol, h0):
    """Scaled RMS norm of (f1 - f0) / h0, an estimate of the second derivative."""
    n = y0.size
    d2 = 0.0
    for i in range(n):
        sc = atol[i] + abs(y0[i]) * rtol
        d2 += ((f1[i] - f0[i]) / sc) ** 2
    return np.sqrt(d2 / n) / h0


@njit(cache=True, nogil=True)
def dop853_stiffness(K, h, scale):
    """Hairer's estimate of |h lambda| from DOP853's last step (Hairer & Wanner 1996,
    Sec. IV.2; the test of his code DOP853): the 12th stage and the step's end lie at the same
    time t + h, so ``h |f(y_new) - f(Y12)| / |y_new - Y12|`` estimates h times the Jacobian's
    dominant eigenvalue along their difference. Norms in the state divided by ``scale``.
    Returns 0 where the two points coincide."""
    n = K.shape[1]
    num = 0.0
    den = 0.0
    for i in range(n):
        acc = 0.0
        for j in range(12):
            acc += (DOP853_B[j] - DOP853_A[11, j]) * K[j, i]
        d = h * acc / scale[i]
        den += d * d
        num += ((K[12, i] - K[11, i]) / scale[i]) ** 2
    if den <= 0.0:
        return 0.0
    return abs(h) * np.sqrt(num / den)


# -- monitoring of the event functions inside a step ----------------------------------------------
#: sqrt of the unit roundoff of a double, 2^-26
SQRT_EPS = 1.4901161193847656e-08
#: the unit roundoff, 2^-52
EPS = 2.220446049250313e-16
#: samples of the corrected quartic in (0, 1) before its extremum is polished by Newton's method
QUARTIC_SAMPLES = 64


@njit(cache=True, nogil=True)
def rate_step(y, f, rtol, atol):
    """Time step (s) of the forward difference ``(g(t + d, y + d f) - g(t, y)) / d`` that gives
    the event functions' rates dg/dt along the derivative ``f`` at ``y``: the time in which the
    state moves by sqrt(eps) of its size in the RMS norm of the error control,
    ``d = sqrt(eps) / rms(f_i / (|y_i| + atol_i / rtol))``. This balances the difference's two
    errors for an event function that varies on the scale of the state: its rounding,
    ``eps |g| / d``, and its truncation, ``d/2`` times g's second derivative along ``f``, are then
    both about sqrt(eps) times g's rate at the state's pace (the classical step of a
    directional difference, e.g. Dennis & Schnabel 1983, Sec. 5.4). The result depends on the
    point only (not on the step size), so that a run split into pauses recomputes the same
    rates. Returns 0 where ``f`` vanishes or is not finite (no rate can be differenced)."""
    n = y.size
    acc = 0.0
    for i in range(n):
        acc += (f[i] / (abs(y[i]) + atol[i] / rtol)) ** 2
    speed = np.sqrt(acc / n)
    if not (speed > 0.0 and np.isfinite(speed)):
        return 0.0
    return SQRT_EPS / speed


@njit(cache=True, nogil=True, inline="always")
def _side(direction, g0, g1):
    """+1 where a crossing of an event in ``direction`` can hide in a step whose ends are both
    on the "before" side of a rising crossing (g <= 0: a maximum of g), -1 where both are on the
    "beyond" side of a falling one (g > 0: a minimum), 0 where the step's ends show a crossing
    or an end lies on the side the event does not cross from."""
    if direction >= 0 and g0 <= 0.0 and g1 <= 0.0:
        return 1.0
    if direction <= 0 and g0 > 0.0 and g1 > 0.0:
        return -1.0
    return 0.0


@njit(cache=True, nogil=True, inline="always")
def _cubic(u0, u1, a, b, x):
    """The cubic Hermite interpolant on [0, 1] with values u0, u1 and slopes a, b (per unit x)
    at its ends, at x: ``u0 + x (a + x (c2 + x c3))``."""
    d = u1 - u0
    c2 = 3.0 * d - 2.0 * a - b
    c3 = a + b - 2.0 * d
    return u0 + x * (a + x * (c2 + x * c3))


@njit(cache=True, nogil=True)
def cubic_maximum(u0, u1, a, b):
    """The interior local maximum x in (0, 1) of the cubic Hermite interpolant with values u0,
    u1 and slopes a, b at its ends (-1 where it has none). Its derivative ``a + 2 c2 x + 3 c3
    x^2`` vanishes at ``(-c2 -+ r) / (3 c3)``, ``r = sqrt(c2^2 - 3 a c3)``; the maximum is the
    root where the second derivative, ``-2 r``, is negative, written without cancellation
    (as ``a / (r - c2)`` for c2 <= 0; also the quadratic's vertex where c3 = 0)."""
    d = u1 - u0
    c2 = 3.0 * d - 2.0 * a - b
    c3 = a + b - 2.0 * d
    disc = c2 * c2 - 3.0 * a * c3
    if not disc > 0.0:  # no critical point, or a double one (an inflection); NaN fails too
        return -1.0
    r = np.sqrt(disc)
    if c2 <= 0.0:
        x = a / (r - c2)
    elif c3 != 0.0:
        x = (-c2 - r) / (3.0 * c3)
    else:
        return -1.0  # a convex parabola: no maximum
    if x > 0.0 and x < 1.0:
        return x
    return -1.0


@njit(cache=True, nogil=True)
def hermite_extremum(direction, g0, g1, d0, d1, h):
    """Where in a step an event function's crossing could hide although its ends show none:
    the position x in (0, 1) of the extremum of the cubic Hermite interpolant of g from its
    values g0, g1 and rates d0, d1 (per s) at the step's ends (step h, s), or -1 where no
    crossing can hide.

    A crossing hides where both ends lie before it and g reaches beyond zero in between: a
    maximum with both ends g <= 0 (direction +1 or 0: a contact entered and left inside the
    step) or a minimum with both ends g > 0 (direction -1 or 0: a lasting contact that lifts
    off and touches again). The extremum is returned where the interpolant's value there lies
    beyond zero or closer to it than the band of the interpolant's own error, so that the
    caller checks the true g there:

    - the interpolation error, ``g''''(xi) h^4 x^2 (1 - x)^2 / 24`` for the cubic Hermite, is
      bounded by the interpolant's deviation from the chord at x, ``B = |p(x) - chord(x)|``,
      about ``g'' h^2 x (1 - x) / 2``: for g that varies at frequencies up to omega
      (``g'''' ~ omega^2 g''``) their ratio is ``(h omega)^2 x (1 - x) / 12 <= (h omega)^2
      / 48``, below 1/5 while h omega <= 3, longer than the steps an explicit pair takes on a
      harmonic motion at rtol 1e-3 or tighter (their error per step grows like
      ``(h omega)^(p + 1)``). B itself, a 100 % margin on the extremum's rise above the
      chord, is the band;
    - the rates' forward-difference error (:func:`rate_step`, about sqrt(eps) relative) moves
      the interpolant by ``sqrt(eps) h (|d0| + |d1|)`` at most, and g's rounding by a few eps
      of its size: both are added.

    The check of the true g costs one evaluation of the event functions on the dense output
    (prepared where no crossing or record needed it), only in the steps whose extremum lies
    within that band of zero: near a grazing.
    """
    s = _side(direction, g0, g1)
    if s == 0.0:
        return -1.0
    u0 = s * g0
    u1 = s * g1
    a = s * h * d0
    b = s * h * d1
    if not np.isfinite(u0 + u1 + a + b):
        return -1.0
    x = cubic_maximum(u0, u1, a, b)
    if x < 0.0:
        return -1.0
    u = _cubic(u0, u1, a, b, x)
    band = abs(u - (u0 + x * (u1 - u0)))
    band += SQRT_EPS * (abs(a) + abs(b)) + 4.0 * EPS * max(abs(u0), abs(u1))
    if u + band > 0.0:
        return x
    return -1.0


@njit(cache=True, nogil=True, inline="always")
def _quartic(u0, u1, a, b, kappa, x):
    """The cubic Hermite interpolant plus ``kappa x^2 (1 - x)^2``, and its first and second
    derivatives in x."""
    d = u1 - u0
    c2 = 3.0 * d - 2.0 * a - b
    c3 = a + b - 2.0 * d
    w = x * (1.0 - x)
    value = u0 + x * (a + x * (c2 + x * c3)) + kappa * w * w
    slope = a + x * (2.0 * c2 + 3.0 * x * c3) + kappa * 2.0 * w * (1.0 - 2.0 * x)
    curvature = 2.0 * c2 + 6.0 * c3 * x + kappa * (2.0 - 12.0 * x + 12.0 * x * x)
    return value, slope, curvature


@njit(cache=True, nogil=True)
def quartic_extremum(direction, g0, g1, d0, d1, h, x1, gx):
    """A second look where the true g at the cubic's extremum x1 (:func:`hermite_extremum`)
    showed no crossing: the cubic Hermite interpolant's error is, to leading order,
    ``kappa x^2 (1 - x)^2`` (its error term's shape), whose coefficient the true value
    ``gx`` at x1 measures; the extremum x2 of the corrected quartic is returned where it
    predicts g beyond zero, or short of it by less than its rise over ``gx`` (the same 100 %
    margin as the cubic's band), else -1. Arguments as :func:`hermite_extremum`."""
    s = _side(direction, g0, g1)
    w1 = x1 * (1.0 - x1)
    if s == 0.0 or not w1 > 0.0:
        return -1.0
    u0 = s * g0
    u1 = s * g1
    a = s * h * d0
    b = s * h * d1
    ux = s * gx
    kappa = (ux - _cubic(u0, u1, a, b, x1)) / (w1 * w1)
    if not np.isfinite(kappa):
        return -1.0
    best = -1.0
    top = -np.inf
    for i in range(1, QUARTIC_SAMPLES):
        x = i / QUARTIC_SAMPLES
        v, _, _ = _quartic(u0, u1, a, b, kappa, x)
        if v > top:
            top = v
            best = x
    lo = best - 1.0 / QUARTIC_SAMPLES
    hi = best + 1.0 / QUARTIC_SAMPLES
    x = best
    for _ in range(8):  # Newton on the slope, kept in the sample's neighbourhood
        _, slope, curvature = _quartic(u0, u1, a, b, kappa, x)
        if not curvature < 0.0:
            break
        step = -slope / curvature
        x = min(max(x + step, lo), hi)
        if abs(step) <= 1e-12:
            break
    v, _, _ = _quartic(u0, u1, a, b, kappa, x)
    if v < top:
        v = top
        x = best
    if not (x > 0.0 and x < 1.0):
        return -1.0
    if v + (v - ux) > 0.0:
        return x
    return -1.0
