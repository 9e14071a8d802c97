"""Radau IIA's step with the model's Jacobian (a template, specialised per model like
:mod:`workbench.solver._templates.integration_loop`).

The Jacobian (analytic, or central differences of the compiled ``rhs``; from
:mod:`workbench.solver._templates.jacobian`), the simplified Newton iteration for the collocation
system and the step with its error estimate, step-size control and event location on the
collocation polynomial (Hairer & Wanner 1996, Sec. IV.8, after their code RADAU5). The
hook-free pieces (tableau transforms, LU, controller, stiffness tests) are in
:mod:`workbench.solver._radau` and :mod:`workbench.solver._linalg`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from workbench.solver._loop_types import (
    CT_NONFINITE,
    IS_JAC,
    IS_LU,
    IS_NEWTON,
    IS_NEWTON_FAIL,
    IS_REJECTED,
    IS_RHS,
    IS_STEPS,
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
    ST_EVENT_RETRIES,
    ST_REJECTED,
    ST_RHS,
)
from workbench.solver._numerics import min_step, trial_step
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
    factor_matrices,
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
    RADAU_C,
)
from workbench.solver._templates.explicit_steps import (  # @@STEPS@@
    _any_crossed,
)
from workbench.solver._templates.jacobian import HAS_ANALYTIC, jacobian  # @@JACOBIAN@@
from workbench.solver._templates.placeholder_hooks import rhs  # @@HOOKS@@


@njit(cache=True, nogil=True)
def _jacobian(t, m, st, im):
    """The model's Jacobian at the current point into im.J (analytic, or central differences
    of rhs: 2n evaluations, counted), and its spectral radius. Returns the hook code."""
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
    code = jacobian(t, st.y, p, ip, st.aux, work, im.jac_scale, im.J)
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


@njit(cache=True, nogil=True)
def _newton(t, h, fnewt, m, st, im, ytmp):
    """Simplified Newton iteration for Radau IIA's collocation system from the starting values
    in im.Z, im.W (Hairer & Wanner 1996, Sec. IV.8; RADAU5's stopping criteria).

    Returns ``(outcome, iterations, inside_stage, code, ratio)``: CONVERGED, SLOW (retry with
    the step times ``ratio``) or FAILED (retry with half the step); whether an inner stage
    returned EVENT_INSIDE_STEP at the last iteration; a model failure code (0 if none).
    """
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
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
            code = rhs(t + RADAU_C[j] * h, ytmp, p, ip, st.aux, work, im.Fs[j])
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


@njit(cache=True, nogil=True)
def _radau_attempts(t, t_end, h_abs, f_inside, s, m, st, im, w):
    """Try Radau IIA steps from t until one is accepted or the step underflows (Hairer & Wanner
    1996, Sec. IV.8; RADAU5's step control, Jacobian and LU reuse).

    Returns ``(failed, last_code, t_new, h, h_next, inside_end)`` as
    :func:`_explicit_attempts`; the accepted step's stage increments are in im.Z, the derivative
    at its end in im.f_new.
    """
    p, ip, work = m.p, m.ip, m.work  # unpacked once: no reference counting per call
    y = st.y
    y_new = w.y_new
    ytmp = w.ytmp
    n = y.size
    rc = im.rc
    ist = im.stats
    stats = st.stats
    h_min = min_step(t)
    for i in range(n):
        im.scale[i] = im.atol[i] + im.rtol * abs(y[i])
    fnewt = newton_tolerance(im.rtol)
    theta_keep = THETA_KEEP_ANALYTIC if HAS_ANALYTIC else THETA_KEEP_DIFFERENCED
    rejected = False
    last_code = 0
    h = 0.0
    t_new = t
    while True:
        if not h_abs >= h_min:  # written so that a NaN step fails it too
            if h_abs != h_abs:
                st.ctrl[CT_NONFINITE] = 1.0
            return True, last_code, t_new, h, h_abs, False
        t_new, h = trial_step(t, t_end, h_abs)
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
        err = scaled_rms(im.e, y, y_new, im.rtol, im.atol, im.blocks)
        if err >= 1.0 and (rejected or rc[RC_H_ACC] == 0.0):
            for i in range(n):
                ytmp[i] = y[i] + im.e[i]
            stats[ST_RHS] += 1
            ist[IS_RHS] += 1
            code = rhs(t, ytmp, p, ip, st.aux, work, im.Fs[0])
            if code == 0 or code == EVENT_INSIDE_STEP:
                refine_error(im.Fs[0], im.ez, im.LUr, im.pivr, im.e)
                err = scaled_rms(im.e, y, y_new, im.rtol, im.atol, im.blocks)
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
        code = rhs(t_new, y_new, p, ip, st.aux, work, im.f_new)
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
