"""One step of each integration method and the location of events in it (a template,
specialised per model like :mod:`workbench.solver._templates.integration_loop`, whose docstring
gives the hooks'
protocol and the algorithms).

The functions here call the model's hooks: ``rhs`` for the stages, ``event_values`` to see and
locate sign changes of the event functions on the dense output. The explicit pairs' step with
its error control (``_explicit_attempts``) lives here; Radau IIA's in
:mod:`workbench.solver._templates.radau_step`; the loop that chooses between them, records and
applies events in :mod:`workbench.solver._templates.integration_loop`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from workbench.solver._loop_types import (
    ARK548,
    CT_NONFINITE,
    DOP853,
    N_CTRL,
    RADAU5,
    ST_EVENT_RETRIES,
    ST_REJECTED,
    ST_RHS,
)
from workbench.solver._numerics import (
    ark_cubic,
    ark_quartic,
    crossed,
    dense_eval,
    dop853_dense,
    dopri5_dense,
    error_norm,
    illinois_point,
    illinois_update,
    min_step,
    n_stages,
    quartic_extremum,
    rate_step,
    read_decay,
    reject_factor,
    root_tolerance,
    stage_point,
    step_factor,
    trial_step,
)
from workbench.solver._problem import EVENT_INSIDE_STEP
from workbench.solver._radau import (
    dense_coefficients,
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
    RK45_A,
    RK45_B,
    RK45_C,
)
from workbench.solver._templates.placeholder_hooks import event_values, rhs  # @@HOOKS@@


@njit(cache=True, nogil=True)
def _rk_step(method, t, h, m, st, w):
    """One RK step from (t, st.y, st.f); stages in K, derivative at the step's end in K[ns]
    (FSAL).

    For ARK548 the stiff states' stages use the implicit table (the model's ``rhs`` solves
    them); ``decay_new`` receives the decay rates at the step's end.

    Returns ``(code, inside_stage, inside_end)``: the first model failure
    code (0 if none) and whether an intermediate stage, and the step's end, returned
    EVENT_INSIDE_STEP.
    """
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
    y = st.y
    aux = st.aux
    stats = st.stats
    K = w.K
    ytmp = w.ytmp
    y_new = w.y_new
    f = st.f
    stiff_idx = m.stiff_idx
    ns = n_stages(method)
    n = y.size
    ms = stiff_idx.size
    inside_stage = False
    for i in range(n):
        K[0, i] = f[i]
    for s in range(1, ns):
        if method == DOP853:
            stage_point(K, DOP853_A[s], s, h, y, ytmp)
            c = DOP853_C[s]
        elif method == ARK548:
            stage_point(K, ARK_AE[s], s, h, y, ytmp)
            c = ARK_C[s]
            # stiff states: B_k = y_k + h sum_{j<s} AI_sj f_k(Y_j)
            for k in range(ms):
                i = stiff_idx[k]
                acc = 0.0
                for j in range(s):
                    acc += ARK_AI[s, j] * K[j, i]
                ytmp[i] = y[i] + h * acc
        else:
            stage_point(K, RK45_A[s], s, h, y, ytmp)
            c = RK45_C[s]
        stats[ST_RHS] += 1
        if method == ARK548 and m.implicit_slot >= 0:
            work[m.implicit_slot] = h * ARK_GAMMA  # rhs solves Y_k = B_k + h gamma f_k(Y)
            code = rhs(t + c * h, ytmp, p, ip, aux, work, K[s])
            work[m.implicit_slot] = 0.0
        else:
            code = rhs(t + c * h, ytmp, p, ip, aux, work, K[s])
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
    code = rhs(t + h, y_new, p, ip, aux, work, K[ns])
    read_decay(work, m.stiff_slot, w.decay_new)
    if code == EVENT_INSIDE_STEP:
        return 0, inside_stage, True
    return code, inside_stage, False


@njit(cache=True, nogil=True)
def _dense_prepare(method, t, h, m, st, w, im):
    """Coefficients of the continuous extension over the last step (t, t + h). Returns the
    hook code: a model failure code, else EVENT_INSIDE_STEP where an extra stage lay beyond an
    event surface (the continuous extension then holds the other side's law), else 0. DOP853
    needs 3 extra stages, ARK548 one extra derivative (at t + h/3, see
    :func:`workbench.solver._numerics.ark_quartic`), Radau IIA none (its collocation
    polynomial)."""
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
    if im is not None:
        if method == RADAU5:
            dense_coefficients(im.Z, w.F)
            return 0
    y = st.y
    K = w.K
    F = w.F
    ytmp = w.ytmp
    y_new = w.y_new
    inside = 0
    if method == DOP853:
        for r in range(3):
            s = 13 + r
            stage_point(K, DOP853_A_EXTRA[r], s, h, y, ytmp)
            st.stats[ST_RHS] += 1
            code = rhs(t + DOP853_C_EXTRA[r] * h, ytmp, p, ip, st.aux, work, K[s])
            if code == EVENT_INSIDE_STEP:
                inside = EVENT_INSIDE_STEP
            elif code != 0:
                return code
        dop853_dense(K, h, y, y_new, F)
    elif method == ARK548:
        ark_cubic(K, h, y, y_new, F, ytmp)
        st.stats[ST_RHS] += 1
        code = rhs(t + h / 3.0, ytmp, p, ip, st.aux, work, K[9])
        if code == EVENT_INSIDE_STEP:
            inside = EVENT_INSIDE_STEP
        elif code != 0:
            return code
        ark_quartic(K, h, F, m.stiff_idx)
    else:
        dopri5_dense(K, F)
    return inside


@njit(cache=True, nogil=True)
def _any_crossed(t, y, m, aux, g_old, g):
    """Whether any event function crosses between ``g_old`` and its values at (t, y), which are
    written into ``g``."""
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
    if m.ev_dir.size == 0:
        return False
    event_values(t, y, p, ip, aux, work, g)
    for k in range(m.ev_dir.size):
        if crossed(m.ev_dir[k], g_old[k], g[k]):
            return True
    return False


@njit(cache=True, nogil=True)
def _locate(method, k, t_old, h, y_old, F, t_a, g_a, t_b, g_b, m, aux, yint, gtmp):
    """Root of event k in [t_a, t_b] by the Illinois method on the dense output.

    Returns the right end of the final bracket, where the event function already has its
    post-crossing sign, so that the event does not fire again at the same root.
    """
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
    side = 0
    tol = root_tolerance(t_a, t_b, h)
    for _ in range(200):
        if t_b - t_a <= tol:
            break
        t_m = illinois_point(t_a, g_a, t_b, g_b)
        dense_eval(method, t_old, h, y_old, F, t_m, yint)
        event_values(t_m, yint, p, ip, aux, work, gtmp)
        t_a, g_a, t_b, g_b, side = illinois_update(t_a, g_a, t_b, g_b, side, t_m, gtmp[k])
    return t_b


@njit(cache=True, nogil=True)
def _event_rates(t, y, f, g, s, m, aux, ytmp, gtmp, dg):
    """The event functions' rates dg/dt at (t, y), where they are ``g`` and the state's
    derivative is ``f``, into ``dg``: one evaluation of the event functions at the point
    advanced by the step of :func:`workbench.solver._numerics.rate_step` along ``f`` (0 where
    ``f`` vanishes). ``ytmp``, ``gtmp``: scratch."""
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
    delta = rate_step(y, f, s.rtol, s.atol)
    if delta == 0.0:
        dg[:] = 0.0
        return
    for i in range(y.size):
        ytmp[i] = y[i] + delta * f[i]
    event_values(t + delta, ytmp, p, ip, aux, work, gtmp)
    for k in range(g.size):
        dg[k] = (gtmp[k] - g[k]) / delta


@njit(cache=True, nogil=True)
def _resolution(k, t, y, g_k, s, m, aux, ytmp, gtmp):
    """How far event function k moves when the state ``y`` at ``t`` (where it is ``g_k``) moves
    by one unit of the error control, ``atol_i + rtol |y_i|``, in each component in turn: the
    sum of those changes. A value of g_k beyond zero by no more than this lies within the
    integration's own error: not a crossing the steps resolve, but a grazing within the
    tolerance. ``ytmp``, ``gtmp``: scratch (n evaluations of the event functions)."""
    p, ip, work = m.p, m.ip, m.work
    total = 0.0
    ytmp[:] = y
    for i in range(y.size):
        ytmp[i] = y[i] + (s.atol[i] + s.rtol * abs(y[i]))
        event_values(t, ytmp, p, ip, aux, work, gtmp)
        total += abs(gtmp[k] - g_k)
        ytmp[i] = y[i]
    return total


@njit(cache=True, nogil=True)
def _hidden_root(
    method, k, t_old, h, y_old, F, g_a, g_b, dg_a, dg_b, x, s, m, aux, yint, ytmp, gtmp
):
    """A crossing of event k that both ends of the last step (t_old, t_old + h) hide, with
    the dense output prepared: the true g at the monitored extremum ``x`` (a fraction of the
    step, from :func:`workbench.solver._numerics.hermite_extremum`), and where that shows no
    crossing, once more at the extremum of the corrected quartic
    (:func:`workbench.solver._numerics.quartic_extremum`). Where g lies beyond zero there, the
    root before it is located as :func:`_locate` does for a crossing of the step's ends,
    unless it lies beyond zero by no more than the integration resolves (:func:`_resolution`:
    a grazing within the tolerance, which a step retried to end at its root would not show;
    the steps that followed it crawled through the contact, the state at the surface within
    rounding, the right-hand side's kink felt at random stages).
    ``g_a``, ``g_b``, ``dg_a``, ``dg_b``: g and dg/dt at the step's ends.

    Returns ``(found, t_root)``.
    """
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
    direction = m.ev_dir[k]
    for look in range(2):
        t_x = t_old + x * h
        dense_eval(method, t_old, h, y_old, F, t_x, yint)
        event_values(t_x, yint, p, ip, aux, work, gtmp)
        g_x = gtmp[k]
        if crossed(direction, g_a, g_x):
            if abs(g_x) <= _resolution(k, t_x, yint, g_x, s, m, aux, ytmp, gtmp):
                return False, t_old
            t_root = _locate(
                method, k, t_old, h, y_old, F, t_old, g_a, t_x, g_x, m, aux, yint, gtmp
            )
            return True, t_root
        if look == 0:
            x = quartic_extremum(direction, g_a, g_b, dg_a, dg_b, h, x, g_x)
            if x < 0.0:
                break
    return False, t_old


@njit(cache=True, nogil=True)
def _explicit_attempts(method, t, t_end, h_abs, f_inside, s, m, st, w):
    """Try explicit steps from t until one is accepted or the step underflows.

    Returns ``(failed, last_code, t_new, h, h_abs, inside_end)``: whether no step could be
    taken, the last model failure code met, the accepted step's end and size, the next step
    size, and whether the accepted step's end returned EVENT_INSIDE_STEP.
    """
    # the arrays taken out of the tuples once: each access of a tuple's array in the loop
    # would cost a pair of atomic reference-count operations
    stats = st.stats
    ctrl = st.ctrl
    y = st.y
    K = w.K
    y_new = w.y_new
    stiff_idx = m.stiff_idx
    exponent = -1.0 / 8.0 if method == DOP853 else -1.0 / 5.0
    ms = stiff_idx.size
    decay = ctrl[N_CTRL : N_CTRL + ms]
    h_min = min_step(t)
    rejected = False
    last_code = 0
    h = 0.0
    t_new = t
    while True:
        if not h_abs >= h_min:  # written so that a NaN step fails it too
            if h_abs != h_abs:
                ctrl[CT_NONFINITE] = 1.0
            return True, last_code, t_new, h, h_abs, False
        t_new, h = trial_step(t, t_end, h_abs)
        code, inside_stage, inside_end = _rk_step(method, t, h, m, st, w)
        if code != 0:
            last_code = code
            err = np.inf
        else:
            err = error_norm(method, K, h, y, y_new, s.rtol, s.atol, stiff_idx, decay, s.blocks)
            if not np.isfinite(err):
                ctrl[CT_NONFINITE] = 1.0
                err = np.inf
        if (
            err < 1.0
            and not f_inside
            and (
                (inside_stage and not inside_end)
                or (inside_end and not _any_crossed(t_new, y_new, m, st.aux, st.g_old, w.g_new))
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
