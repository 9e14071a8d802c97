"""Compiled adaptive Runge–Kutta integration loop (a template, specialised per model).

The whole loop runs in numba-compiled code: embedded-pair step-size control, dense output,
records at exactly requested times, and event location by root finding on the dense output with
the state update an event asks for. The model's compiled hooks are imported by name; the line
marked ``@@HOOKS@@`` is rewritten by :mod:`workbench.solver._compile` to import them from the
model's module, so that every model gets its own cacheable compiled loop and adding a model never
touches this file.

Hooks (all ``numba.njit``), in SI units of the model's state:

``rhs(t, y, p, ip, aux, work, dydt) -> int``
    Writes dy/dt; returns 0, or a positive model failure code (the step is then rejected and
    retried smaller; if it persists the run fails with that code).
``event_values(t, y, p, ip, aux, work, g) -> None``
    Writes the event functions g_k; an event fires where g_k changes sign in its direction.
``apply_event(k, t, y, p, ip, aux, work) -> int``
    Applies the update of event k in place (state ``y`` and discrete state ``aux``); returns 1 to
    stop the integration, else 0.

``work`` is a scratch array of the model's ``Problem.work_size`` floats, allocated once per run,
so that the hot right-hand side allocates nothing.

Algorithms: Dormand & Prince (1980) DOPRI5 with Shampine's (1986) dense output; Hairer's DOP853
(Hairer, Nørsett & Wanner 1993, Sec. II.10); the additive implicit–explicit ARK5(4)8L[2]SA of
Kennedy & Carpenter (2003) with quartic Hermite dense output, for problems that declare *stiff
states*: states k whose rate has the form ``dy_k/dt = r_k(y) - a_k(y) y_k`` with a decay rate
``a_k >= 0`` (s-1), where ``r_k`` and ``a_k`` depend on the non-stiff states only (a LuGre
bristle deflection: ``dz/dt = v - a(v) z``). ARK548 integrates the stiff states' whole rate
with the ESDIRK table and the rest with the explicit one, so that the step is no longer bounded
by ``|h a| < ~6`` as for the explicit pairs. (Treating only ``-a y_k`` implicitly would leave
the forcing ``r_k ~ a y_k`` explicit, and the stages off the slow manifold y_k = r_k / a_k by
O(h) in the stiff limit.) The implicit stage equation ``Y_k = B_k + h gamma (r_k - a_k Y_k)``
is linear in ``Y_k`` with coefficients explicit in the stage, so the model's ``rhs`` solves it:
one division, no Jacobian, no Newton iteration. Protocol: before an implicit stage the kernel
writes ``h gamma`` (s) into ``work[implicit_slot]`` (0 for every other evaluation) and ``B_k``
into ``y[k]``; ``rhs`` replaces ``y[k]`` by ``(B_k + h gamma r_k) / (1 + h gamma a_k)`` and
writes ``a_k`` into ``work[stiff_slot[k]]`` on every call.

Step-size control and initial step as in Hairer's
codes and ``scipy.integrate`` (Hairer et al. 1993, Sec. II.4); event location by the Illinois
variant of regula falsi (Dowell & Jarratt 1971) on the dense output.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from workbench.solver._hooks_template import apply_event, event_values, rhs  # @@HOOKS@@
from workbench.solver._problem import EVENT_INSIDE_STEP
from workbench.solver._tableaux import (
    ARK_AE,
    ARK_AI,
    ARK_B,
    ARK_C,
    ARK_E,
    ARK_GAMMA,
    DOP853_A,
    DOP853_A_EXTRA,
    DOP853_B,
    DOP853_C,
    DOP853_C_EXTRA,
    DOP853_D,
    DOP853_E3,
    DOP853_E5,
    MAX_FACTOR,
    MIN_FACTOR,
    RK45_A,
    RK45_B,
    RK45_C,
    RK45_E,
    RK45_P,
    SAFETY,
)

DOPRI5 = 0
DOP853 = 1
ARK548 = 2

# Return codes of `advance`.
DONE = 0
PAUSED = 1
TERMINATED = 2
STEP_UNDERFLOW = -1
NON_FINITE = -2
MAX_STEPS = -3
MODEL_FAILURE = -4

# Indices of the int64 statistics array.
ST_STEPS = 0
ST_REJECTED = 1
ST_RHS = 2
ST_EVENTS = 3
ST_RECORDED = 4
ST_MODEL_CODE = 5
ST_EVENT_RETRIES = 6  # steps retried because an event happened between their ends
N_STATS = 7

# Indices of the float64 controller array: current time (s), next step size (s), flag "last
# failure was non-finite", flag "the current derivative f was flagged EVENT_INSIDE_STEP"; then
# one entry per stiff state: its decay rate a_k (s-1) at the current point.
CT_T = 0
CT_H = 1
CT_NONFINITE = 2
CT_F_INSIDE = 3
N_CTRL = 4


@njit(cache=True)
def _n_stages(method):
    if method == DOP853:
        return 12
    return 8 if method == ARK548 else 6


@njit(cache=True)
def _read_decay(work, stiff_slot, decay):
    """Copy the stiff states' decay rates (s-1) that the last ``rhs`` call wrote into work."""
    for k in range(stiff_slot.size):
        decay[k] = work[stiff_slot[k]]


@njit(cache=True)
def _stiff_position(stiff_idx, i):
    """Position k of state i in ``stiff_idx`` (-1 if state i is not stiff)."""
    for k in range(stiff_idx.size):
        if stiff_idx[k] == i:
            return k
    return -1


@njit(cache=True)
def _stage_point(K, a, s, h, y, out):
    """out = y + h * sum_{j<s} a[j] K[j]."""
    n = y.size
    for i in range(n):
        acc = 0.0
        for j in range(s):
            acc += a[j] * K[j, i]
        out[i] = y[i] + h * acc


@njit(cache=True)
def _rk_step(
    method, t, y, f, h, p, ip, aux, work, K, y_new, ytmp, stats,
    stiff_idx, stiff_slot, implicit_slot, decay_new,
):  # fmt: skip
    """One RK step; stages in K, derivative at the step's end in K[ns] (FSAL).

    For ARK548 the stiff states' stages use the implicit table (the model's ``rhs`` solves
    them); ``decay_new`` receives the decay rates at the step's end.

    Returns ``(code, inside_stage, inside_end)``: the first model failure
    code (0 if none) and whether an intermediate stage, and the step's end, returned
    EVENT_INSIDE_STEP.
    """
    ns = _n_stages(method)
    n = y.size
    ms = stiff_idx.size
    inside_stage = False
    for i in range(n):
        K[0, i] = f[i]
    for s in range(1, ns):
        if method == DOP853:
            _stage_point(K, DOP853_A[s], s, h, y, ytmp)
            c = DOP853_C[s]
        elif method == ARK548:
            _stage_point(K, ARK_AE[s], s, h, y, ytmp)
            c = ARK_C[s]
            # stiff states: B_k = y_k + h sum_{j<s} AI_sj f_k(Y_j)
            for k in range(ms):
                i = stiff_idx[k]
                acc = 0.0
                for j in range(s):
                    acc += ARK_AI[s, j] * K[j, i]
                ytmp[i] = y[i] + h * acc
        else:
            _stage_point(K, RK45_A[s], s, h, y, ytmp)
            c = RK45_C[s]
        stats[ST_RHS] += 1
        if method == ARK548 and implicit_slot >= 0:
            work[implicit_slot] = h * ARK_GAMMA  # rhs solves Y_k = B_k + h gamma f_k(Y)
            code = rhs(t + c * h, ytmp, p, ip, aux, work, K[s])
            work[implicit_slot] = 0.0
        else:
            code = rhs(t + c * h, ytmp, p, ip, aux, work, K[s])
        if code == EVENT_INSIDE_STEP:
            inside_stage = True
        elif code != 0:
            return code, inside_stage, False
    if method == DOP853:
        _stage_point(K, DOP853_B, ns, h, y, y_new)
    elif method == ARK548:
        _stage_point(K, ARK_B, ns, h, y, y_new)
    else:
        _stage_point(K, RK45_B, ns, h, y, y_new)
    stats[ST_RHS] += 1
    code = rhs(t + h, y_new, p, ip, aux, work, K[ns])
    _read_decay(work, stiff_slot, decay_new)
    if code == EVENT_INSIDE_STEP:
        return 0, inside_stage, True
    return code, inside_stage, False


@njit(cache=True)
def _error_norm(method, K, h, y, y_new, rtol, atol, stiff_idx, decay):
    """Scaled RMS error estimate of the step (Hairer et al. 1993, Eq. II.4.11; DOP853's
    combination of its 5th- and 3rd-order estimators; for DOPRI5 and ARK548 the difference of
    the 5th- and 4th-order solutions).

    For ARK548 the stiff states' estimates are filtered by (1 + h gamma a)^-1, the diagonal form
    of Hairer & Wanner's (1996, Sec. IV.8) (I - h gamma J)^-1: the embedded solution is not
    L-stable, so the raw difference stays O(1) for |h a| >> 1 where both solutions are exact
    to the tolerance, and would bound the step by the decay rate again."""
    n = y.size
    if method == DOP853:
        e5 = 0.0
        e3 = 0.0
        for i in range(n):
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
    for i in range(n):
        sc = atol[i] + rtol * max(abs(y[i]), abs(y_new[i]))
        e = 0.0
        for j in range(E.size):
            e += E[j] * K[j, i]
        if method == ARK548:
            k = _stiff_position(stiff_idx, i)
            if k >= 0:
                e /= 1.0 + h * ARK_GAMMA * decay[k]
        acc += (h * e / sc) ** 2
    return np.sqrt(acc / n)


@njit(cache=True)
def _dense_prepare(method, t, y, y_new, h, p, ip, aux, work, K, F, ytmp, stats, stiff_idx):
    """Coefficients of the continuous extension over the last step. Returns the hook code.

    ARK548: quartic Hermite interpolation (4th order: O(h^5) between the step's ends, like
    DOPRI5's) through the values and derivatives at both ends and the derivative at t + h/3,
    evaluated (one extra ``rhs`` call) at the cubic Hermite interpolant there, whose O(h^4)
    error enters the quartic only times h. Stiff states keep the cubic Hermite interpolant: their
    derivative at an interpolated point carries its error times the decay rate a, which would
    spoil the quartic for |h a| >> 1.
    """
    n = y.size
    if method == DOP853:
        for r in range(3):
            s = 13 + r
            _stage_point(K, DOP853_A_EXTRA[r], s, h, y, ytmp)
            stats[ST_RHS] += 1
            code = rhs(t + DOP853_C_EXTRA[r] * h, ytmp, p, ip, aux, work, K[s])
            if code != 0 and code != EVENT_INSIDE_STEP:
                return code
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
    elif method == ARK548:
        # y(t + x h) = y + x (F1 + x (F2 + x (F3 + x F4))); F1 = h f0. Cubic Hermite first,
        # with d = y_new - y and h f1: F2 = 3 d - 2 h f0 - h f1, F3 = h f0 + h f1 - 2 d.
        x = 1.0 / 3.0
        for i in range(n):
            d = y_new[i] - y[i]
            F[0, i] = d
            F[1, i] = h * K[0, i]
            F[2, i] = 3.0 * d - 2.0 * h * K[0, i] - h * K[8, i]
            F[3, i] = h * K[0, i] + h * K[8, i] - 2.0 * d
            F[4, i] = 0.0
            ytmp[i] = y[i] + x * (F[1, i] + x * (F[2, i] + x * F[3, i]))
        stats[ST_RHS] += 1
        code = rhs(t + h / 3.0, ytmp, p, ip, aux, work, K[9])
        if code != 0 and code != EVENT_INSIDE_STEP:
            return code
        # quartic: p(1) = y_new, p'(0) = h f0, p'(1) = h f1, p'(1/3) = h f(t + h/3); with
        # R1 = d - h f0, R2 = h (f1 - f0), R3 = h (f(t + h/3) - f0) the coefficients of x^2,
        # x^3, x^4 are the rows of [[-6, 5/4, 27/4], [16, -7/2, -27/2], [-9, 9/4, 27/4]] @ R
        for i in range(n):
            if _stiff_position(stiff_idx, i) >= 0:
                continue
            r1 = F[0, i] - h * K[0, i]
            r2 = h * (K[8, i] - K[0, i])
            r3 = h * (K[9, i] - K[0, i])
            F[2, i] = -6.0 * r1 + 1.25 * r2 + 6.75 * r3
            F[3, i] = 16.0 * r1 - 3.5 * r2 - 13.5 * r3
            F[4, i] = -9.0 * r1 + 2.25 * r2 + 6.75 * r3
    else:
        for i in range(n):
            for j in range(4):
                acc = 0.0
                for s in range(7):
                    acc += K[s, i] * RK45_P[s, j]
                F[j, i] = acc
    return 0


@njit(cache=True)
def _dense_eval(method, t_old, h, y_old, F, t, out):
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
    else:
        for i in range(n):
            acc = 0.0
            xp = x
            for j in range(4):
                acc += F[j, i] * xp
                xp *= x
            out[i] = y_old[i] + h * acc


@njit(cache=True)
def _crossed(direction, g_a, g_b):
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


@njit(cache=True)
def _any_crossed(t, y, p, ip, aux, work, ev_dir, g_old, g):
    """Whether any event function crosses between ``g_old`` and its values at (t, y), which are
    written into ``g``."""
    if ev_dir.size == 0:
        return False
    event_values(t, y, p, ip, aux, work, g)
    for k in range(ev_dir.size):
        if _crossed(ev_dir[k], g_old[k], g[k]):
            return True
    return False


@njit(cache=True)
def _locate(method, k, t_old, h, y_old, F, t_a, g_a, t_b, g_b, p, ip, aux, work, yint, gtmp):
    """Root of event k in [t_a, t_b] by the Illinois method on the dense output.

    Returns the right end of the final bracket, where the event function already has its
    post-crossing sign, so that the event does not fire again at the same root.
    """
    side = 0
    tol = 4.0 * 2.220446049250313e-16 * max(abs(t_a), abs(t_b), abs(h))
    for _ in range(200):
        if t_b - t_a <= tol:
            break
        t_m = (t_a * g_b - t_b * g_a) / (g_b - g_a)
        if not (t_m > t_a and t_m < t_b):
            t_m = 0.5 * (t_a + t_b)
        _dense_eval(method, t_old, h, y_old, F, t_m, yint)
        event_values(t_m, yint, p, ip, aux, work, gtmp)
        g_m = gtmp[k]
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
    return t_b


@njit(cache=True)
def start(t, y, p, ip, aux, work, f, g, stats, stiff_slot, ctrl):
    """Derivative, event functions and stiff decay rates (into ``ctrl[N_CTRL:]``) at the
    initial point. Returns the hook code (0, a failure code, or EVENT_INSIDE_STEP when the
    point lies beyond an event surface)."""
    stats[ST_RHS] += 1
    code = rhs(t, y, p, ip, aux, work, f)
    _read_decay(work, stiff_slot, ctrl[N_CTRL:])
    if g.size > 0:
        event_values(t, y, p, ip, aux, work, g)
    return code


@njit(cache=True)
def initial_step(method, t0, y0, f0, p, ip, aux, work, rtol, atol, max_step, t_end, stats):
    """Initial step size (Hairer et al. 1993, Sec. II.4, "starting step size"), s."""
    n = y0.size
    interval = abs(t_end - t0)
    if interval == 0.0:
        return 0.0
    order = 7 if method == DOP853 else 4  # of the error estimator
    d0 = 0.0
    d1 = 0.0
    for i in range(n):
        sc = atol[i] + abs(y0[i]) * rtol
        d0 += (y0[i] / sc) ** 2
        d1 += (f0[i] / sc) ** 2
    d0 = np.sqrt(d0 / n)
    d1 = np.sqrt(d1 / n)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, interval)
    y1 = np.empty(n)
    f1 = np.empty(n)
    for i in range(n):
        y1[i] = y0[i] + h0 * f0[i]
    stats[ST_RHS] += 1
    rhs(t0 + h0, y1, p, ip, aux, work, f1)
    d2 = 0.0
    for i in range(n):
        sc = atol[i] + abs(y0[i]) * rtol
        d2 += ((f1[i] - f0[i]) / sc) ** 2
    d2 = np.sqrt(d2 / n) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100.0 * h0, h1, interval, max_step)


@njit(cache=True)
def advance(
    method,
    t_end,
    t_pause,
    t_rec,
    p,
    ip,
    rtol,
    atol,
    max_step,
    max_steps,
    ev_dir,
    ctrl,
    y,
    f,
    aux,
    work,
    g_old,
    stats,
    Yrec,
    AUXrec,
    stiff_idx,
    stiff_slot,
    implicit_slot,
):
    """Integrate from ctrl[CT_T] until t_end (or the first step ending at or after t_pause).

    ``stiff_idx`` and ``stiff_slot`` (int64) name the stiff states and the work slots of their
    decay rates, ``implicit_slot`` the work slot of h gamma (empty and -1 for none; used by
    ARK548, see the module docstring).
    All loop state lives in the caller's arrays (ctrl, y, f, aux, g_old, stats), so calling
    again continues exactly where the last call stopped: a run split into pauses is bit-identical
    to an unbroken one. Records ``Yrec[i] = y(t_rec[i])`` and ``AUXrec[i] = aux(t_rec[i])``.
    Returns DONE, PAUSED, TERMINATED or a negative failure code.
    """
    n = y.size
    ne = ev_dir.size
    nrec = t_rec.size
    ns = _n_stages(method)
    exponent = -1.0 / 8.0 if method == DOP853 else -1.0 / 5.0
    ms = stiff_idx.size
    decay = ctrl[N_CTRL : N_CTRL + ms]
    decay_new = np.empty(ms)
    K = np.empty((16, n))
    F = np.empty((7, n))
    y_new = np.empty(n)
    ytmp = np.empty(n)
    yint = np.empty(n)
    g_new = np.empty(ne)
    gtmp = np.empty(ne)
    t = ctrl[CT_T]
    h_abs = ctrl[CT_H]
    f_inside = ctrl[CT_F_INSIDE] > 0.0
    i_rec = stats[ST_RECORDED]
    status = DONE
    while i_rec < nrec and t_rec[i_rec] <= t:
        Yrec[i_rec, :] = y
        AUXrec[i_rec, :] = aux
        i_rec += 1
    while True:
        if t >= t_end:
            status = DONE
            break
        if t >= t_pause:
            status = PAUSED
            break
        if stats[ST_STEPS] >= max_steps:
            status = MAX_STEPS
            break
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step
        rejected = False
        last_code = 0
        failed = False
        while True:
            if h_abs < min_step:
                failed = True
                break
            t_new = t + h_abs
            if t_new > t_end:
                t_new = t_end
            h = t_new - t
            code, inside_stage, inside_end = _rk_step(
                method, t, y, f, h, p, ip, aux, work, K, y_new, ytmp, stats,
                stiff_idx, stiff_slot, implicit_slot, decay_new,
            )  # fmt: skip
            if code != 0:
                last_code = code
                err = np.inf
            else:
                err = _error_norm(method, K, h, y, y_new, rtol, atol, stiff_idx, decay)
                if not np.isfinite(err):
                    ctrl[CT_NONFINITE] = 1.0
                    err = np.inf
            if (
                err < 1.0
                and not f_inside
                and (
                    (inside_stage and not inside_end)
                    or (
                        inside_end
                        and not _any_crossed(t_new, y_new, p, ip, aux, work, ev_dir, g_old, g_new)
                    )
                )
            ):
                # a stage lay beyond an event surface that both ends of the step are short of:
                # the event began and ended inside the step, invisible to the sign test on g
                # and, when few stages see it, to the error estimate. Or the step's end lies
                # beyond a surface that the sign test sees no crossing of (the step crossed it
                # twice, e.g. left it and came back). Halve until an end of a step lands beyond
                # the surface with a crossing, so that the event is located.
                stats[ST_REJECTED] += 1
                stats[ST_EVENT_RETRIES] += 1
                h_abs = 0.5 * h
                rejected = True
                continue
            if err < 1.0:
                if err == 0.0:
                    factor = MAX_FACTOR
                else:
                    factor = min(MAX_FACTOR, SAFETY * err**exponent)
                if rejected:
                    factor = min(1.0, factor)
                h_abs = h * factor
                break
            stats[ST_REJECTED] += 1
            if np.isfinite(err):
                h_abs = h * max(MIN_FACTOR, SAFETY * err**exponent)
            else:
                h_abs = h * MIN_FACTOR
            rejected = True
        if failed:
            if last_code != 0:
                stats[ST_MODEL_CODE] = last_code
                status = MODEL_FAILURE
            elif ctrl[CT_NONFINITE] > 0.0:
                status = NON_FINITE
            else:
                status = STEP_UNDERFLOW
            break
        ctrl[CT_NONFINITE] = 0.0
        stats[ST_STEPS] += 1
        dense_ready = False
        fired = -1
        t_stop = t_new
        if ne > 0:
            event_values(t_new, y_new, p, ip, aux, work, g_new)
            for k in range(ne):
                if _crossed(ev_dir[k], g_old[k], g_new[k]):
                    if not dense_ready:
                        code = _dense_prepare(
                            method, t, y, y_new, h, p, ip, aux, work, K, F, ytmp, stats, stiff_idx
                        )
                        if code != 0:
                            stats[ST_MODEL_CODE] = code
                            status = MODEL_FAILURE
                            break
                        dense_ready = True
                    t_k = _locate(
                        method,
                        k,
                        t,
                        h,
                        y,
                        F,
                        t,
                        g_old[k],
                        t_new,
                        g_new[k],
                        p,
                        ip,
                        aux,
                        work,
                        yint,
                        gtmp,
                    )
                    if fired < 0 or t_k < t_stop:
                        fired = k
                        t_stop = t_k
            if status == MODEL_FAILURE:
                break
        while i_rec < nrec and t_rec[i_rec] <= t_stop:
            if t_rec[i_rec] == t_new and fired < 0:
                Yrec[i_rec, :] = y_new
            else:
                if not dense_ready:
                    code = _dense_prepare(
                        method, t, y, y_new, h, p, ip, aux, work, K, F, ytmp, stats, stiff_idx
                    )
                    if code != 0:
                        stats[ST_MODEL_CODE] = code
                        status = MODEL_FAILURE
                        break
                    dense_ready = True
                _dense_eval(method, t, h, y, F, t_rec[i_rec], yint)
                Yrec[i_rec, :] = yint
            AUXrec[i_rec, :] = aux
            i_rec += 1
        if status == MODEL_FAILURE:
            break
        if fired >= 0:
            if t_stop == t_new:
                # the root is the step's end: its state is y_new, where g already has its
                # post-crossing sign (the dense output can differ from it by rounding)
                y[:] = y_new
            else:
                _dense_eval(method, t, h, y, F, t_stop, yint)
                y[:] = yint
            t = t_stop
            stats[ST_EVENTS] += 1
            stop = apply_event(fired, t, y, p, ip, aux, work)
            # simultaneous events: any other event function that has crossed by t_stop has its
            # root there too (within the root's tolerance, or the same double), so its update
            # is applied now; left for the next step, it would start beyond its surface and
            # never fire
            if ne > 1:
                event_values(t, y, p, ip, aux, work, gtmp)
                for k in range(ne):
                    if k != fired and _crossed(ev_dir[k], g_old[k], gtmp[k]):
                        stats[ST_EVENTS] += 1
                        if apply_event(k, t, y, p, ip, aux, work) != 0:
                            stop = 1
            code = start(t, y, p, ip, aux, work, f, g_old, stats, stiff_slot, ctrl)
            f_inside = code == EVENT_INSIDE_STEP
            if code != 0 and not f_inside:
                stats[ST_MODEL_CODE] = code
                status = MODEL_FAILURE
                break
            if stop != 0:
                status = TERMINATED
                break
        else:
            t = t_new
            y[:] = y_new
            f[:] = K[ns]
            decay[:] = decay_new
            f_inside = inside_end
            if ne > 0:
                g_old[:] = g_new
    ctrl[CT_T] = t
    ctrl[CT_F_INSIDE] = 1.0 if f_inside else 0.0
    ctrl[CT_H] = h_abs
    stats[ST_RECORDED] = i_rec
    return status
