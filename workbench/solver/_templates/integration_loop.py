"""Compiled adaptive Runge–Kutta integration loop (a template, specialised per model).

The whole loop runs in numba-compiled code: embedded-pair step-size control, dense output,
records at exactly requested times, and event location by root finding on the dense output with
the state update an event asks for. The model's compiled hooks are imported by name; the line
marked ``@@HOOKS@@`` is rewritten by :mod:`workbench.solver._compile` to import them from the
model's module, so that every model gets its own cacheable compiled loop and adding a model never
touches this file. This module is the loop (start, initial step, the choice of method, records,
events applied, pauses); the steps it takes are templates specialised beside it: the explicit
pairs' and ARK548's step and the location of events in a step in
:mod:`workbench.solver._templates.explicit_steps`, Radau IIA's step with the model's Jacobian in
:mod:`workbench.solver._templates.radau_step`. Only what calls a hook lives in these; the
hook-free numerics (tableaux, error norms, dense output, root-finding updates) are compiled once
for all models in
:mod:`workbench.solver._numerics`, and the loop's arguments are grouped in the named tuples of
:mod:`workbench.solver._loop_types`.

Hooks (all ``numba.njit``), in SI units of the model's state:

``rhs(t, y, p, ip, aux, work, dydt) -> int``
    Writes dy/dt; returns 0, or a positive model failure code (the step is then rejected and
    retried smaller; if it persists the run fails with that code).
``event_values(t, y, p, ip, aux, work, g) -> None``
    Writes the event functions g_k; an event fires where g_k changes sign in its direction,
    between the ends of a step or inside it (monitoring, below).
``apply_event(k, t, y, p, ip, aux, work) -> int``
    Applies the update of event k in place (state ``y`` and discrete state ``aux``); returns 1 to
    stop the integration, else 0.
``step_end(t, y, p, ip, aux, work, dydt) -> int`` (optional)
    Called at the end of every accepted step that no event ended, with the state and its
    derivative there (the next step's first stage): may change how the state is represented,
    both in place, where that changes neither the solution nor the event functions (the tangent
    system's re-orthonormalisation of its vectors, :mod:`workbench.solver._templates.
    tangent_hooks`); returns 1 where it changed them, else 0. A model without it is compiled
    without the call.

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

Monitoring of the event functions inside a step: the sign test at a step's ends misses a
crossing that both ends hide, a contact entered and left within one step (g <= 0 at both ends,
> 0 in between) or a lasting contact that lifts off and touches again (g > 0 at both ends);
the step-size control does not see it either where few stages fall into the contact. So after
every accepted step each event function that did not cross is interpolated by the cubic
Hermite polynomial of its values and rates dg/dt at the step's ends (the rates by a forward
difference along the state's derivative there, the explicit pairs' last stage or Radau's
``f_new``: one more call of ``event_values`` per step, none for a model without events;
:func:`workbench.solver._numerics.rate_step`). Where that interpolant has an extremum of the
crossing kind (a maximum between two ends g <= 0 for a rising event, a minimum between two
ends g > 0 for a falling one, either for direction 0) whose value lies beyond zero or within
the band of the interpolant's own error (:func:`workbench.solver._numerics.
hermite_extremum`), the dense output is prepared and the true g evaluated there, and once
more at the extremum of the interpolant corrected by that value
(:func:`workbench.solver._numerics.quartic_extremum`). Where g lies beyond zero there, its
first root in the step is located on the dense output as for a crossing of the ends; where it
is the step's earliest event, the step is retried to end at that root: the dense output of a
step whose stages straddled a whole contact does not follow the motion before the contact to
the tolerance, although the step's end, which the error control checked, does. The crossing
then shows at the end of that step or of a later one and is located and applied as any
other. The rates at a step's start are recomputed from the point alone wherever the loop
restarts (after an event, at each call of ``advance``), so that pauses stay invisible; where
no hidden crossing is found nothing but the evaluation count of the monitoring's dense outputs
differs from a loop without it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from workbench.solver._loop_types import (  # noqa: F401 (the loop's vocabulary, read by callers)
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
from workbench.solver._numerics import (
    crossed,
    dense_eval,
    dop853_stiffness,
    hermite_extremum,
    initial_difference,
    initial_norms,
    min_step,
    n_stages,
    read_decay,
)
from workbench.solver._problem import EVENT_INSIDE_STEP
from workbench.solver._radau import (
    explicit_test,
    forget_jacobian,
    implicit_cost,
    implicit_test,
)
from workbench.solver._templates.explicit_steps import (  # @@STEPS@@
    _dense_prepare,
    _event_rates,
    _explicit_attempts,
    _hidden_root,
    _locate,
)
from workbench.solver._templates.placeholder_hooks import (  # @@HOOKS@@
    apply_event,
    event_values,
    rhs,
)
from workbench.solver._templates.placeholder_hooks import (
    step_end as hooks_step_end,  # @@STEP_END@@
)
from workbench.solver._templates.radau_step import (  # @@IMPLICIT@@
    _radau_attempts,
)

#: whether the hooks define ``step_end`` (set per model by :mod:`workbench.solver._compile`;
#: False compiles the loop without the call)
HAS_STEP_END = True  # @@FLAG@@

_crossed = crossed  # the name tests and older callers use


@njit(cache=True, nogil=True)
def start(t, m, st):
    """Derivative, event functions and stiff decay rates (into ``ctrl[N_CTRL:]``) at the
    point (t, st.y, st.aux). Returns the hook code (0, a failure code, or EVENT_INSIDE_STEP when
    the point lies beyond an event surface)."""
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
    st.stats[ST_RHS] += 1
    code = rhs(t, st.y, p, ip, st.aux, work, st.f)
    read_decay(work, m.stiff_slot, st.ctrl[N_CTRL:])
    if st.g_old.size > 0:
        event_values(t, st.y, p, ip, st.aux, work, st.g_old)
    return code


@njit(cache=True, nogil=True)
def initial_step(method, t0, t_end, s, m, st):
    """Initial step size (Hairer et al. 1993, Sec. II.4, "starting step size") from the point
    (t0, st.y) with derivative st.f, s; NaN where none can be formed (the state or its
    derivative overflows its norm scaled by the tolerances, e.g. a state of 1e50)."""
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
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
    if not (np.isfinite(d0) and np.isfinite(d1)):
        return np.nan  # the state or its derivative overflows its scaled norm: no step
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, interval)
    if not h0 > 0.0:  # d0 / d1 underflowed (NaN fails this test too)
        return np.nan
    y1 = np.empty(n)
    f1 = np.empty(n)
    for i in range(n):
        y1[i] = y0[i] + h0 * f0[i]
    st.stats[ST_RHS] += 1
    rhs(t0 + h0, y1, p, ip, st.aux, work, f1)
    d2 = initial_difference(y0, f0, f1, s.rtol, s.atol, h0)
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100.0 * h0, h1, interval, s.max_step)


@njit(cache=True, nogil=True, inline="always")  # no call boundary per step
def _attempts(current, t, t_end, h_abs, f_inside, s, m, st, im, w):
    """A step of the method in use (``current``): Radau IIA or an explicit pair."""
    if im is not None:
        if current == RADAU5:
            return _radau_attempts(t, t_end, h_abs, f_inside, s, m, st, im, w)
    return _explicit_attempts(current, t, t_end, h_abs, f_inside, s, m, st, w)


@njit(cache=True, nogil=True, inline="always")  # no call boundary per step
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


@njit(cache=True, nogil=True)
def advance(t_end, t_pause, step_pause, s, m, st, im):
    """Integrate from st.ctrl[CT_T] until t_end (or the first step ending at or after t_pause,
    or until st.stats[ST_STEPS] reaches ``step_pause``: the caller's chance to see signals).

    ``s``, ``m``, ``st``, ``im``: the run's :class:`~workbench.solver._loop_types.Settings`, the
    model's :class:`~workbench.solver._loop_types.Hooks`, the loop's
    :class:`~workbench.solver._loop_types.State` and the implicit method's
    :class:`~workbench.solver._loop_types.Implicit` (None for an explicit method: the loop is then
    compiled without it). All loop state lives in the caller's arrays, so calling again
    continues exactly where the last call stopped: a run split into pauses is bit-identical to
    an unbroken one. Records ``Yrec[i] = y(t_rec[i])`` and ``AUXrec[i] = aux(t_rec[i])``.
    Returns DONE, PAUSED, TERMINATED or a negative failure code.
    """
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
    current = s.method
    if im is not None:
        current = int(im.rc[RC_CURRENT])
    # the arrays taken out of the tuples once (an access in the loop costs a pair of atomic
    # reference-count operations)
    y = st.y
    aux = st.aux
    ctrl = st.ctrl
    stats = st.stats
    g_old = st.g_old
    Yrec = st.Yrec
    AUXrec = st.AUXrec
    f = st.f
    ev_dir = m.ev_dir
    t_rec = s.t_rec
    n = y.size
    ne = ev_dir.size
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
        np.empty(ne),
        np.empty(ne),
        np.empty(ne),
    )
    K = w.K
    F = w.F
    y_new = w.y_new
    yint = w.yint
    g_new = w.g_new
    gtmp = w.gtmp
    decay_new = w.decay_new
    dg_old = w.dg_old
    dg_new = w.dg_new
    x_ext = w.x_ext
    t = ctrl[CT_T]
    h_abs = ctrl[CT_H]
    f_inside = ctrl[CT_F_INSIDE] > 0.0
    i_rec = stats[ST_RECORDED]
    status = DONE
    # one test per step for both limits: the run's max_steps and the pause the caller asked for
    step_limit = min(s.max_steps, step_pause)
    while i_rec < nrec and t_rec[i_rec] <= t:
        Yrec[i_rec, :] = y
        AUXrec[i_rec, :] = aux
        i_rec += 1
    if ne > 0:  # the rates at the start: a function of the point, as at every restart
        _event_rates(t, y, f, g_old, s, m, aux, w.ytmp, gtmp, dg_old)
    while True:
        if t >= t_end:
            status = DONE
            break
        if t >= t_pause:
            status = PAUSED
            break
        if stats[ST_STEPS] >= step_limit:
            status = MAX_STEPS if stats[ST_STEPS] >= s.max_steps else PAUSED
            break
        h_min = min_step(t)
        if h_abs > s.max_step:
            h_abs = s.max_step
        elif h_abs < h_min:
            h_abs = h_min
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
        fired = -1
        t_stop = t_new
        # the dense output is needed where an event function crossed (to locate its root) or a
        # record lies inside the step (the records before an event's root lie before t_new)
        dense = i_rec < nrec and t_rec[i_rec] < t_new
        monitor = False
        ends_cross = False  # an event function changes sign between the step's ends
        if ne > 0:
            event_values(t_new, y_new, p, ip, aux, work, g_new)
            # the rates at the end (the derivative there: FSAL stage, or Radau's f_new), and
            # the extremum of each event function's cubic Hermite interpolant where a crossing
            # could hide between ends that show none
            f_end = K[n_stages(current)]
            if im is not None:
                if current == RADAU5:
                    f_end = im.f_new
            _event_rates(t_new, y_new, f_end, g_new, s, m, aux, w.ytmp, gtmp, dg_new)
            for k in range(ne):
                x_ext[k] = -1.0
                if crossed(ev_dir[k], g_old[k], g_new[k]):
                    dense = True
                    ends_cross = True
                else:
                    x_ext[k] = hermite_extremum(
                        ev_dir[k], g_old[k], g_new[k], dg_old[k], dg_new[k], h
                    )
                    if x_ext[k] > 0.0:
                        monitor = True
        polluted = False
        if dense or monitor:
            rhs_dense = stats[ST_RHS]
            code = _dense_prepare(current, t, h, m, st, w, im)
            # an extra stage of the continuous extension beyond an event surface that neither
            # end of the step is beyond (below: the step is retried shorter)
            polluted = code == EVENT_INSIDE_STEP and not ends_cross and not f_inside
            if code != 0 and code != EVENT_INSIDE_STEP:
                stats[ST_MODEL_CODE] = code
                status = MODEL_FAILURE
                break
            if not dense:
                # evaluations for the monitoring alone: not the method's cost in the automatic
                # method's comparison
                before = (before[0] + stats[ST_RHS] - rhs_dense, before[1], before[2])
        hidden = False
        for k in range(ne):
            found = False
            ends = crossed(ev_dir[k], g_old[k], g_new[k])
            t_k = t_new
            if ends:
                found = True
                t_k = _locate(
                    current, k, t, h, y, F, t, g_old[k], t_new, g_new[k], m, aux, yint, gtmp
                )
            elif x_ext[k] > 0.0:
                found, t_k = _hidden_root(
                    current, k, t, h, y, F, g_old[k], g_new[k], dg_old[k], dg_new[k], x_ext[k],
                    s, m, aux, yint, w.ytmp, gtmp,
                )  # fmt: skip
            if found:
                if fired < 0 or t_k < t_stop:
                    fired = k
                    t_stop = t_k
                    hidden = not ends
        retry = 0.0
        if polluted and 0.5 * h > 2.0 * min_step(t):
            # an extra stage of the continuous extension lay beyond an event surface that the
            # step's own stages and both its ends are short of: an excursion beyond it hides
            # inside the step, and the extension, which holds the other side's law at that
            # stage, follows neither side (its monitored g is not the motion's). The step is
            # retried at half its size until no stage of it or of its extension lies beyond,
            # or an end does and the crossing is located.
            retry = 0.5 * h
        elif hidden and t_stop - t > 2.0 * min_step(t):
            # the earliest event is a crossing that the step's ends hide: the step's stages
            # straddled a whole excursion beyond the surface, which its dense output does not
            # follow (it passed the error control without resolving it). The step is retried
            # to end at the located root, with every stage before the excursion; its end or a
            # later step then shows the crossing. (A root within the smallest step of the
            # start fires at once, as a crossing of the ends would.)
            retry = t_stop - t
        if retry > 0.0:
            stats[ST_STEPS] -= 1
            stats[ST_REJECTED] += 1
            stats[ST_EVENT_RETRIES] += 1
            if im is not None:
                if current == RADAU5:
                    # the step's collocation polynomial and its place in the predictive
                    # controller's history are discarded with it
                    im.stats[IS_STEPS] -= 1
                    im.stats[IS_REJECTED] += 1
                    im.rc[RC_H_OLD] = 0.0
                    im.rc[RC_H_ACC] = 0.0
            h_abs = retry
            continue
        while i_rec < nrec and t_rec[i_rec] <= t_stop:
            if t_rec[i_rec] == t_new and fired < 0:
                Yrec[i_rec, :] = y_new
            else:
                dense_eval(current, t, h, y, F, t_rec[i_rec], yint)
                Yrec[i_rec, :] = yint
            AUXrec[i_rec, :] = aux
            i_rec += 1
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
            stop = apply_event(fired, t, y, p, ip, aux, work)
            # simultaneous events: any other event function that has crossed by t_stop has its
            # root there too (within the root's tolerance, or the same double), so its update
            # is applied now; left for the next step, it would start beyond its surface and
            # never fire
            if ne > 1:
                event_values(t, y, p, ip, aux, work, gtmp)
                for k in range(ne):
                    if k != fired and crossed(ev_dir[k], g_old[k], gtmp[k]):
                        stats[ST_EVENTS] += 1
                        if apply_event(k, t, y, p, ip, aux, work) != 0:
                            stop = 1
            if im is not None:
                forget_jacobian(im.rc)  # the discrete state, and with it the rhs, changed
            code = start(t, m, st)
            f_inside = code == EVENT_INSIDE_STEP
            if code != 0 and not f_inside:
                stats[ST_MODEL_CODE] = code
                status = MODEL_FAILURE
                break
            _event_rates(t, y, f, g_old, s, m, aux, w.ytmp, gtmp, dg_old)
            if stop != 0:
                status = TERMINATED
                break
        else:
            t = t_new
            y[:] = y_new
            if current == RADAU5:
                if im is not None:
                    f[:] = im.f_new
                    read_decay(work, m.stiff_slot, decay)
            else:
                f[:] = K[n_stages(current)]
                decay[:] = decay_new
            f_inside = inside_end
            if ne > 0:
                g_old[:] = g_new
                dg_old[:] = dg_new
            if HAS_STEP_END:
                if hooks_step_end(t, y, p, ip, aux, work, f) != 0:
                    if im is not None:
                        forget_jacobian(im.rc)  # the state's representation changed
                    if ne > 0:  # the rates' difference step follows the state and f
                        _event_rates(t, y, f, g_old, s, m, aux, w.ytmp, gtmp, dg_old)
        current = next_method
        if im is not None:
            im.rc[RC_CURRENT] = current
    ctrl[CT_T] = t
    ctrl[CT_F_INSIDE] = 1.0 if f_inside else 0.0
    ctrl[CT_H] = h_abs
    stats[ST_RECORDED] = i_rec
    return status
