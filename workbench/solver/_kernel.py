"""Compiled adaptive Runge–Kutta integration loop (a template, specialised per model).

The whole loop runs in numba-compiled code: embedded-pair step-size control, dense output,
records at exactly requested times, and event location by root finding on the dense output with
the state update an event asks for. The model's compiled hooks are imported by name; the line
marked ``@@HOOKS@@`` is rewritten by :mod:`workbench.solver._compile` to import them from the
model's module, so that every model gets its own cacheable compiled loop and adding a model never
touches this file. Only what calls a hook lives here; the hook-free numerics (tableaux, error
norms, dense output, root-finding updates) are compiled once for all models in
:mod:`workbench.solver._numerics`, and the loop's arguments are grouped in the named tuples of
:mod:`workbench.solver._loop`.

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
from workbench.solver._jacobian_template import HAS_ANALYTIC, jacobian  # @@JACOBIAN@@
from workbench.solver._loop import (  # noqa: F401 (the loop's vocabulary, read by callers)
    ARK548,
    AUTO,
    CT_F_INSIDE,
    CT_H,
    CT_NONFINITE,
    CT_T,
    DONE,
    DOP853,
    DOPRI5,
    IS_JAC,
    IS_LU,
    IS_NEWTON,
    IS_NEWTON_FAIL,
    IS_REJECTED,
    IS_RHS,
    IS_STEPS,
    MAX_STEPS,
    MODEL_FAILURE,
    N_CTRL,
    N_STATS,
    NON_FINITE,
    PAUSED,
    RADAU5,
    RC_CURRENT,
    RC_ERR_ACC,
    RC_FACCON,
    RC_H_ACC,
    RC_H_FAIL,
    RC_H_LU,
    RC_H_OLD,
    RC_JAC,
    RC_JAC_FRESH,
    RC_RHO,
    RC_THETA,
    RC_TIME_IMPLICIT,
    ST_EVENT_RETRIES,
    ST_EVENTS,
    ST_MODEL_CODE,
    ST_RECORDED,
    ST_REJECTED,
    ST_RHS,
    ST_STEPS,
    STEP_UNDERFLOW,
    TERMINATED,
    Scratch,
)
from workbench.solver._numerics import (  # noqa: F401 (crossed: tests read it here)
    ark_cubic,
    ark_quartic,
    crossed,
    dense_eval,
    dop853_dense,
    dop853_stiffness,
    dopri5_dense,
    error_norm,
    illinois_point,
    illinois_update,
    initial_difference,
    initial_norms,
    n_stages,
    read_decay,
    reject_factor,
    root_tolerance,
    stage_point,
    step_factor,
)
from workbench.solver._problem import EVENT_INSIDE_STEP
from workbench.solver._radau import (
    CONVERGED,
    FAILED,
    KEEP_HIGH,
    KEEP_LOW,
    NEWTON_MAX,
    SLOW,
    THETA_KEEP_ANALYTIC,
    THETA_KEEP_DIFFERENCED,
    apply_increment,
    dense_coefficients,
    error_vector,
    explicit_test,
    factor_matrices,
    forget_jacobian,
    implicit_cost,
    implicit_test,
    newton_increment,
    newton_limit,
    newton_tolerance,
    predictive_ratio,
    refine_error,
    scaled_rms,
    spectral_radius,
    starting_values,
    step_ratio,
)
from workbench.solver._tableaux import (
    ARK_AE,
    ARK_AI,
    ARK_B,
    ARK_C,
    ARK_GAMMA,
    DOP853_A,
    DOP853_A_EXTRA,
    DOP853_B,
    DOP853_C,
    DOP853_C_EXTRA,
    RADAU_C,
    RK45_A,
    RK45_B,
    RK45_C,
)

_crossed = crossed  # the name tests and older callers use


@njit(cache=True)
def _call_rhs(t, y, m, aux, dydt):
    return rhs(t, y, m.p, m.ip, aux, m.work, dydt)


@njit(cache=True)
def _rk_step(method, t, h, m, st, w):
    """One RK step from (t, st.y, st.f); stages in K, derivative at the step's end in K[ns]
    (FSAL).

    For ARK548 the stiff states' stages use the implicit table (the model's ``rhs`` solves
    them); ``decay_new`` receives the decay rates at the step's end.

    Returns ``(code, inside_stage, inside_end)``: the first model failure
    code (0 if none) and whether an intermediate stage, and the step's end, returned
    EVENT_INSIDE_STEP.
    """
    y = st.y
    aux = st.aux
    stats = st.stats
    K = w.K
    ytmp = w.ytmp
    y_new = w.y_new
    ns = n_stages(method)
    n = y.size
    ms = m.stiff_idx.size
    inside_stage = False
    for i in range(n):
        K[0, i] = st.f[i]
    for s in range(1, ns):
        if method == DOP853:
            stage_point(K, DOP853_A[s], s, h, y, ytmp)
            c = DOP853_C[s]
        elif method == ARK548:
            stage_point(K, ARK_AE[s], s, h, y, ytmp)
            c = ARK_C[s]
            # stiff states: B_k = y_k + h sum_{j<s} AI_sj f_k(Y_j)
            for k in range(ms):
                i = m.stiff_idx[k]
                acc = 0.0
                for j in range(s):
                    acc += ARK_AI[s, j] * K[j, i]
                ytmp[i] = y[i] + h * acc
        else:
            stage_point(K, RK45_A[s], s, h, y, ytmp)
            c = RK45_C[s]
        stats[ST_RHS] += 1
        if method == ARK548 and m.implicit_slot >= 0:
            m.work[m.implicit_slot] = h * ARK_GAMMA  # rhs solves Y_k = B_k + h gamma f_k(Y)
            code = _call_rhs(t + c * h, ytmp, m, aux, K[s])
            m.work[m.implicit_slot] = 0.0
        else:
            code = _call_rhs(t + c * h, ytmp, m, aux, K[s])
        if code == EVENT_INSIDE_STEP:
            inside_stage = True
        elif code != 0:
            return code, inside_stage, False
    if method == DOP853:
        stage_point(K, DOP853_B, ns, h, y, y_new)
    elif method == ARK548:
        stage_point(K, ARK_B, ns, h, y, y_new)
    else:
        stage_point(K, RK45_B, ns, h, y, y_new)
    stats[ST_RHS] += 1
    code = _call_rhs(t + h, y_new, m, aux, K[ns])
    read_decay(m.work, m.stiff_slot, w.decay_new)
    if code == EVENT_INSIDE_STEP:
        return 0, inside_stage, True
    return code, inside_stage, False


@njit(cache=True)
def _dense_prepare(method, t, h, m, st, w, im):
    """Coefficients of the continuous extension over the last step (t, t + h). Returns the
    hook code. DOP853 needs 3 extra stages, ARK548 one extra derivative (at t + h/3, see
    :func:`workbench.solver._numerics.ark_quartic`), Radau IIA none (its collocation
    polynomial)."""
    if im is not None:
        if method == RADAU5:
            dense_coefficients(im.Z, w.F)
            return 0
    y = st.y
    K = w.K
    F = w.F
    ytmp = w.ytmp
    y_new = w.y_new
    if method == DOP853:
        for r in range(3):
            s = 13 + r
            stage_point(K, DOP853_A_EXTRA[r], s, h, y, ytmp)
            st.stats[ST_RHS] += 1
            code = _call_rhs(t + DOP853_C_EXTRA[r] * h, ytmp, m, st.aux, K[s])
            if code != 0 and code != EVENT_INSIDE_STEP:
                return code
        dop853_dense(K, h, y, y_new, F)
    elif method == ARK548:
        ark_cubic(K, h, y, y_new, F, ytmp)
        st.stats[ST_RHS] += 1
        code = _call_rhs(t + h / 3.0, ytmp, m, st.aux, K[9])
        if code != 0 and code != EVENT_INSIDE_STEP:
            return code
        ark_quartic(K, h, F, m.stiff_idx)
    else:
        dopri5_dense(K, F)
    return 0


@njit(cache=True)
def _any_crossed(t, y, m, aux, g_old, g):
    """Whether any event function crosses between ``g_old`` and its values at (t, y), which are
    written into ``g``."""
    if m.ev_dir.size == 0:
        return False
    event_values(t, y, m.p, m.ip, aux, m.work, g)
    for k in range(m.ev_dir.size):
        if crossed(m.ev_dir[k], g_old[k], g[k]):
            return True
    return False


@njit(cache=True)
def _locate(method, k, t_old, h, y_old, F, t_a, g_a, t_b, g_b, m, aux, yint, gtmp):
    """Root of event k in [t_a, t_b] by the Illinois method on the dense output.

    Returns the right end of the final bracket, where the event function already has its
    post-crossing sign, so that the event does not fire again at the same root.
    """
    side = 0
    tol = root_tolerance(t_a, t_b, h)
    for _ in range(200):
        if t_b - t_a <= tol:
            break
        t_m = illinois_point(t_a, g_a, t_b, g_b)
        dense_eval(method, t_old, h, y_old, F, t_m, yint)
        event_values(t_m, yint, m.p, m.ip, aux, m.work, gtmp)
        t_a, g_a, t_b, g_b, side = illinois_update(t_a, g_a, t_b, g_b, side, t_m, gtmp[k])
    return t_b


@njit(cache=True)
def start(t, m, st):
    """Derivative, event functions and stiff decay rates (into ``ctrl[N_CTRL:]``) at the
    point (t, st.y, st.aux). Returns the hook code (0, a failure code, or EVENT_INSIDE_STEP when
    the point lies beyond an event surface)."""
    st.stats[ST_RHS] += 1
    code = _call_rhs(t, st.y, m, st.aux, st.f)
    read_decay(m.work, m.stiff_slot, st.ctrl[N_CTRL:])
    if st.g_old.size > 0:
        event_values(t, st.y, m.p, m.ip, st.aux, m.work, st.g_old)
    return code


@njit(cache=True)
def initial_step(method, t0, t_end, s, m, st):
    """Initial step size (Hairer et al. 1993, Sec. II.4, "starting step size") from the point
    (t0, st.y) with derivative st.f, s."""
    y0 = st.y
    f0 = st.f
    n = y0.size
    interval = abs(t_end - t0)
    if interval == 0.0:
        return 0.0
    order = 7 if method == DOP853 or method == AUTO else 4  # of the error estimator
    if method == RADAU5:
        order = 3
    d0, d1 = initial_norms(y0, f0, s.rtol, s.atol)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, interval)
    y1 = np.empty(n)
    f1 = np.empty(n)
    for i in range(n):
        y1[i] = y0[i] + h0 * f0[i]
    st.stats[ST_RHS] += 1
    _call_rhs(t0 + h0, y1, m, st.aux, f1)
    d2 = initial_difference(y0, f0, f1, s.rtol, s.atol, h0)
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100.0 * h0, h1, interval, s.max_step)


@njit(cache=True)
def _explicit_attempts(method, t, t_end, h_abs, f_inside, s, m, st, w):
    """Try explicit steps from t until one is accepted or the step underflows.

    Returns ``(failed, last_code, t_new, h, h_abs, inside_end)``: whether no step could be
    taken, the last model failure code met, the accepted step's end and size, the next step
    size, and whether the accepted step's end returned EVENT_INSIDE_STEP.
    """
    stats = st.stats
    ctrl = st.ctrl
    exponent = -1.0 / 8.0 if method == DOP853 else -1.0 / 5.0
    ms = m.stiff_idx.size
    decay = ctrl[N_CTRL : N_CTRL + ms]
    min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
    rejected = False
    last_code = 0
    h = 0.0
    t_new = t
    while True:
        if h_abs < min_step:
            return True, last_code, t_new, h, h_abs, False
        t_new = t + h_abs
        if t_new > t_end:
            t_new = t_end
        h = t_new - t
        code, inside_stage, inside_end = _rk_step(method, t, h, m, st, w)
        if code != 0:
            last_code = code
            err = np.inf
        else:
            err = error_norm(method, w.K, h, st.y, w.y_new, s.rtol, s.atol, m.stiff_idx, decay)
            if not np.isfinite(err):
                ctrl[CT_NONFINITE] = 1.0
                err = np.inf
        if (
            err < 1.0
            and not f_inside
            and (
                (inside_stage and not inside_end)
                or (inside_end and not _any_crossed(t_new, w.y_new, m, st.aux, st.g_old, w.g_new))
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
            h_next = h * step_factor(err, exponent, rejected)
            return False, last_code, t_new, h, h_next, inside_end
        stats[ST_REJECTED] += 1
        h_abs = h * reject_factor(err, exponent)
        rejected = True


@njit(cache=True)
def _jacobian(t, m, st, im):
    """The model's Jacobian at the current point into im.J (analytic, or central differences
    of rhs: 2n evaluations, counted), and its spectral radius. Returns the hook code."""
    code = jacobian(t, st.y, m.p, m.ip, st.aux, m.work, im.jac_scale, im.J)
    im.stats[IS_JAC] += 1
    if not HAS_ANALYTIC:
        st.stats[ST_RHS] += 2 * st.y.size
        im.stats[IS_RHS] += 2 * st.y.size
    rc = im.rc
    rc[RC_JAC] = 1.0
    rc[RC_JAC_FRESH] = 1.0
    rc[RC_H_LU] = 0.0
    rc[RC_RHO] = spectral_radius(im.J, im.jac_scale, im.v, im.u)
    return code


@njit(cache=True)
def _newton(t, h, fnewt, m, st, im, ytmp):
    """Simplified Newton iteration for Radau IIA's collocation system from the starting values
    in im.Z, im.W (Hairer & Wanner 1996, Sec. IV.8; RADAU5's stopping criteria).

    Returns ``(outcome, iterations, inside_stage, code, ratio)``: CONVERGED, SLOW (retry with
    the step times ``ratio``) or FAILED (retry with half the step); whether an inner stage
    returned EVENT_INSIDE_STEP at the last iteration; a model failure code (0 if none).
    """
    y = st.y
    n = y.size
    rc = im.rc
    faccon = max(rc[RC_FACCON], 2.220446049250313e-16) ** 0.8
    theta = 0.0  # no rate measured: a first-iteration convergence keeps the Jacobian
    dynold = 1.0
    thqold = 1.0
    inside = False
    for newt in range(1, NEWTON_MAX + 1):
        inside = False
        for j in range(3):
            for i in range(n):
                ytmp[i] = y[i] + im.Z[j, i]
            st.stats[ST_RHS] += 1
            im.stats[IS_RHS] += 1
            code = _call_rhs(t + RADAU_C[j] * h, ytmp, m, st.aux, im.Fs[j])
            if code == EVENT_INSIDE_STEP:
                inside = inside or j < 2  # the last stage is the step's end, tested there
            elif code != 0:
                return FAILED, newt, inside, code, 0.5
        for j in range(3):
            for i in range(n):
                if not np.isfinite(im.Fs[j, i]):
                    st.ctrl[CT_NONFINITE] = 1.0
                    return FAILED, newt, inside, 0, 0.5
        dyno = newton_increment(
            im.Fs, im.W, h, im.LUr, im.pivr, im.LUc, im.pivc, im.scale, im.dW, im.br, im.bc
        )
        im.stats[IS_NEWTON] += 1
        if newt > 1 and newt < NEWTON_MAX:
            thq = dyno / dynold
            theta = thq if newt == 2 else np.sqrt(thq * thqold)
            thqold = thq
            if theta < 0.99:
                faccon = theta / (1.0 - theta)
                # predicted error after the remaining iterations
                dyth = faccon * dyno * theta ** (NEWTON_MAX - 1 - newt) / fnewt
                if dyth >= 1.0:
                    qnewt = max(1e-4, min(20.0, dyth))
                    ratio = 0.8 * qnewt ** (-1.0 / (4.0 + NEWTON_MAX - 1 - newt))
                    return SLOW, newt, inside, 0, ratio
            else:
                return FAILED, newt, inside, 0, 0.5
        dynold = max(dyno, 2.220446049250313e-16)
        apply_increment(im.dW, im.W, im.Z)
        if faccon * dyno <= fnewt:
            rc[RC_FACCON] = faccon
            rc[RC_THETA] = theta
            return CONVERGED, newt, inside, 0, 1.0
    return FAILED, NEWTON_MAX, inside, 0, 0.5


@njit(cache=True)
def _radau_attempts(t, t_end, h_abs, f_inside, s, m, st, im, w):
    """Try Radau IIA steps from t until one is accepted or the step underflows (Hairer & Wanner
    1996, Sec. IV.8; RADAU5's step control, Jacobian and LU reuse).

    Returns ``(failed, last_code, t_new, h, h_next, inside_end)`` as
    :func:`_explicit_attempts`; the accepted step's stage increments are in im.Z, the derivative
    at its end in im.f_new.
    """
    y = st.y
    y_new = w.y_new
    ytmp = w.ytmp
    n = y.size
    rc = im.rc
    ist = im.stats
    stats = st.stats
    min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
    for i in range(n):
        im.scale[i] = im.atol[i] + im.rtol * abs(y[i])
    fnewt = newton_tolerance(im.rtol)
    theta_keep = THETA_KEEP_ANALYTIC if HAS_ANALYTIC else THETA_KEEP_DIFFERENCED
    rejected = False
    last_code = 0
    h = 0.0
    t_new = t
    while True:
        if h_abs < min_step:
            return True, last_code, t_new, h, h_abs, False
        t_new = t + h_abs
        if t_new > t_end:
            t_new = t_end
        h = t_new - t
        if rc[RC_JAC] == 0.0:
            code = _jacobian(t, m, st, im)
            if code > 0:
                return True, code, t_new, h, h_abs, False
        if rc[RC_H_LU] != h:
            ist[IS_LU] += 1
            rc[RC_H_LU] = h
            if factor_matrices(im.J, h, im.LUr, im.pivr, im.LUc, im.pivc) != 0:
                rc[RC_H_LU] = 0.0  # singular: a smaller step moves the matrices off it
                stats[ST_REJECTED] += 1
                ist[IS_REJECTED] += 1
                h_abs = 0.5 * h
                rejected = True
                continue
        starting_values(im.Q, rc[RC_H_OLD], h, im.Z, im.W)
        outcome, newt, inside_stage, code, ratio = _newton(t, h, fnewt, m, st, im, ytmp)
        if outcome != CONVERGED:
            if code != 0:
                last_code = code
            stats[ST_REJECTED] += 1
            ist[IS_REJECTED] += 1
            ist[IS_NEWTON_FAIL] += 1
            h_abs = h * ratio
            rc[RC_H_FAIL] = h
            if rc[RC_JAC_FRESH] == 0.0:
                rc[RC_JAC] = 0.0  # an old Jacobian may be why: evaluate it here
            rejected = True
            continue
        for i in range(n):
            y_new[i] = y[i] + im.Z[2, i]
        error_vector(im.Z, st.f, h, im.LUr, im.pivr, im.ez, im.e)
        err = scaled_rms(im.e, y, y_new, im.rtol, im.atol)
        if err >= 1.0 and (rejected or rc[RC_H_ACC] == 0.0):
            for i in range(n):
                ytmp[i] = y[i] + im.e[i]
            stats[ST_RHS] += 1
            ist[IS_RHS] += 1
            code = _call_rhs(t, ytmp, m, st.aux, im.Fs[0])
            if code == 0 or code == EVENT_INSIDE_STEP:
                refine_error(im.Fs[0], im.ez, im.LUr, im.pivr, im.e)
                err = scaled_rms(im.e, y, y_new, im.rtol, im.atol)
        if not np.isfinite(err):
            st.ctrl[CT_NONFINITE] = 1.0
            err = 1e10
        err = max(err, 1e-10)
        ratio = step_ratio(err, newt)
        if err >= 1.0:
            stats[ST_REJECTED] += 1
            ist[IS_REJECTED] += 1
            h_abs = h * ratio
            if rc[RC_JAC_FRESH] == 0.0:
                rc[RC_JAC] = 0.0
            rejected = True
            continue
        # the derivative at the end: the next step's error estimate, and the event protocol
        stats[ST_RHS] += 1
        ist[IS_RHS] += 1
        code = _call_rhs(t_new, y_new, m, st.aux, im.f_new)
        inside_end = code == EVENT_INSIDE_STEP
        if code != 0 and not inside_end:
            last_code = code
            stats[ST_REJECTED] += 1
            ist[IS_REJECTED] += 1
            h_abs = 0.5 * h
            rejected = True
            continue
        if not f_inside and (
            (inside_stage and not inside_end)
            or (inside_end and not _any_crossed(t_new, y_new, m, st.aux, st.g_old, w.g_new))
        ):
            # as in _explicit_attempts: an event began and ended inside the step
            stats[ST_REJECTED] += 1
            stats[ST_EVENT_RETRIES] += 1
            ist[IS_REJECTED] += 1
            h_abs = 0.5 * h
            rejected = True
            continue
        ratio = predictive_ratio(ratio, h, err, rc[RC_H_ACC], rc[RC_ERR_ACC])
        rc[RC_H_ACC] = h
        rc[RC_ERR_ACC] = max(1e-2, err)
        h_next = h * ratio
        if rejected:
            h_next = min(h_next, h)
        h_next = min(h_next, s.max_step)
        h_next = newton_limit(rc, h, h_next)
        if rc[RC_THETA] <= theta_keep:
            if KEEP_LOW <= h_next / h <= KEEP_HIGH:
                h_next = h  # same step, same LU factors
        else:
            rc[RC_JAC] = 0.0  # slow convergence: a new Jacobian at the next point
        rc[RC_JAC_FRESH] = 0.0
        dense_coefficients(im.Z, im.Q)
        rc[RC_H_OLD] = h
        ist[IS_STEPS] += 1
        return False, last_code, t_new, h, h_next, inside_end


@njit(cache=True)
def _attempts(current, t, t_end, h_abs, f_inside, s, m, st, im, w):
    """A step of the method in use (``current``): Radau IIA or an explicit pair."""
    if im is not None:
        if current == RADAU5:
            return _radau_attempts(t, t_end, h_abs, f_inside, s, m, st, im, w)
    return _explicit_attempts(current, t, t_end, h_abs, f_inside, s, m, st, w)


@njit(cache=True)
def _switch(current, h, h_next, s, st, im, K, before):
    """The automatic method's stiffness tests after an accepted step (see
    :func:`workbench.solver._radau.explicit_test` and ``implicit_test``). Returns the method
    for the next step. ``before``: the counters of evaluations, implicit evaluations and LU
    decompositions before the step."""
    if im is None:
        return current
    if s.method != AUTO:
        return current
    rhs_before, imp_rhs_before, lu_before = before
    if current == RADAU5:
        cost = implicit_cost(im.stats, imp_rhs_before, lu_before, st.y.size)
        if implicit_test(im.rc, im.stats, h_next, cost):
            return DOP853
        return RADAU5
    h_lambda = dop853_stiffness(K, h, im.jac_scale)
    if explicit_test(im.rc, im.stats, h_lambda, st.stats[ST_RHS] - rhs_before):
        return RADAU5
    return DOP853


@njit(cache=True)
def advance(t_end, t_pause, s, m, st, im):
    """Integrate from st.ctrl[CT_T] until t_end (or the first step ending at or after t_pause).

    ``s``, ``m``, ``st``, ``im``: the run's :class:`~workbench.solver._loop.Settings`, the
    model's :class:`~workbench.solver._loop.Hooks`, the loop's
    :class:`~workbench.solver._loop.State` and the implicit method's
    :class:`~workbench.solver._loop.Implicit` (None for an explicit method: the loop is then
    compiled without it). All loop state lives in the caller's arrays, so calling again
    continues exactly where the last call stopped: a run split into pauses is bit-identical to
    an unbroken one. Records ``Yrec[i] = y(t_rec[i])`` and ``AUXrec[i] = aux(t_rec[i])``.
    Returns DONE, PAUSED, TERMINATED or a negative failure code.
    """
    current = s.method
    if im is not None:
        current = int(im.rc[RC_CURRENT])
    y = st.y
    aux = st.aux
    ctrl = st.ctrl
    stats = st.stats
    g_old = st.g_old
    t_rec = s.t_rec
    n = y.size
    ne = m.ev_dir.size
    nrec = t_rec.size
    ms = m.stiff_idx.size
    decay = ctrl[N_CTRL : N_CTRL + ms]
    w = Scratch(
        np.empty((16, n)),
        np.empty((7, n)),
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty(ne),
        np.empty(ne),
        np.empty(ms),
    )
    K = w.K
    F = w.F
    y_new = w.y_new
    yint = w.yint
    g_new = w.g_new
    gtmp = w.gtmp
    t = ctrl[CT_T]
    h_abs = ctrl[CT_H]
    f_inside = ctrl[CT_F_INSIDE] > 0.0
    i_rec = stats[ST_RECORDED]
    status = DONE
    while i_rec < nrec and t_rec[i_rec] <= t:
        st.Yrec[i_rec, :] = y
        st.AUXrec[i_rec, :] = aux
        i_rec += 1
    while True:
        if t >= t_end:
            status = DONE
            break
        if t >= t_pause:
            status = PAUSED
            break
        if stats[ST_STEPS] >= s.max_steps:
            status = MAX_STEPS
            break
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs > s.max_step:
            h_abs = s.max_step
        elif h_abs < min_step:
            h_abs = min_step
        before = (stats[ST_RHS], 0, 0)
        if im is not None:
            before = (stats[ST_RHS], im.stats[IS_RHS], im.stats[IS_LU])
        failed, last_code, t_new, h, h_abs, inside_end = _attempts(
            current, t, t_end, h_abs, f_inside, s, m, st, im, w
        )
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
            event_values(t_new, y_new, m.p, m.ip, aux, m.work, g_new)
            for k in range(ne):
                if crossed(m.ev_dir[k], g_old[k], g_new[k]):
                    if not dense_ready:
                        code = _dense_prepare(current, t, h, m, st, w, im)
                        if code != 0:
                            stats[ST_MODEL_CODE] = code
                            status = MODEL_FAILURE
                            break
                        dense_ready = True
                    t_k = _locate(
                        current, k, t, h, y, F, t, g_old[k], t_new, g_new[k], m, aux, yint, gtmp
                    )
                    if fired < 0 or t_k < t_stop:
                        fired = k
                        t_stop = t_k
            if status == MODEL_FAILURE:
                break
        while i_rec < nrec and t_rec[i_rec] <= t_stop:
            if t_rec[i_rec] == t_new and fired < 0:
                st.Yrec[i_rec, :] = y_new
            else:
                if not dense_ready:
                    code = _dense_prepare(current, t, h, m, st, w, im)
                    if code != 0:
                        stats[ST_MODEL_CODE] = code
                        status = MODEL_FAILURE
                        break
                    dense_ready = True
                dense_eval(current, t, h, y, F, t_rec[i_rec], yint)
                st.Yrec[i_rec, :] = yint
            st.AUXrec[i_rec, :] = aux
            i_rec += 1
        if status == MODEL_FAILURE:
            break
        if im is not None:
            if current == RADAU5:
                im.rc[RC_TIME_IMPLICIT] += t_stop - t
        next_method = _switch(current, h, h_abs, s, st, im, K, before)
        if fired >= 0:
            if t_stop == t_new:
                # the root is the step's end: its state is y_new, where g already has its
                # post-crossing sign (the dense output can differ from it by rounding)
                y[:] = y_new
            else:
                dense_eval(current, t, h, y, F, t_stop, yint)
                y[:] = yint
            t = t_stop
            stats[ST_EVENTS] += 1
            stop = apply_event(fired, t, y, m.p, m.ip, aux, m.work)
            # simultaneous events: any other event function that has crossed by t_stop has its
            # root there too (within the root's tolerance, or the same double), so its update
            # is applied now; left for the next step, it would start beyond its surface and
            # never fire
            if ne > 1:
                event_values(t, y, m.p, m.ip, aux, m.work, gtmp)
                for k in range(ne):
                    if k != fired and crossed(m.ev_dir[k], g_old[k], gtmp[k]):
                        stats[ST_EVENTS] += 1
                        if apply_event(k, t, y, m.p, m.ip, aux, m.work) != 0:
                            stop = 1
            if im is not None:
                forget_jacobian(im.rc)  # the discrete state, and with it the rhs, changed
            code = start(t, m, st)
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
            if current == RADAU5:
                if im is not None:
                    st.f[:] = im.f_new
                    read_decay(m.work, m.stiff_slot, decay)
            else:
                st.f[:] = K[n_stages(current)]
                decay[:] = w.decay_new
            f_inside = inside_end
            if ne > 0:
                g_old[:] = g_new
        current = next_method
        if im is not None:
            im.rc[RC_CURRENT] = current
    ctrl[CT_T] = t
    ctrl[CT_F_INSIDE] = 1.0 if f_inside else 0.0
    ctrl[CT_H] = h_abs
    stats[ST_RECORDED] = i_rec
    return status
