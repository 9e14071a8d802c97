"""Hook-free numerics of the implicit Radau IIA method (order 5) and of the automatic switching
between it and DOP853, compiled once for all models.

Radau IIA after Hairer & Wanner (1996), *Solving ODEs II*, Sec. IV.8 and their code RADAU5:
the collocation system for the stage increments ``Z_i = Y_i - y`` is solved by a simplified
Newton iteration with the Jacobian ``J`` at the step's start, in the variables ``W = T^-1 Z``
that split the 3n x 3n Newton matrix into one real (``gamma/h - J``) and one complex
(``(alpha - i beta)/h - J``) n x n system (Eq. 8.17-8.18); starting values extrapolate the last
step's collocation polynomial; the convergence rate ``theta`` of the iteration decides when the
Jacobian is recomputed and the Newton iteration is abandoned early (Sec. IV.8, "Stopping
criterion"); the error estimate ``(I - h gamma0 J)^-1 (gamma0 h f(y0) + e^T Z)`` is the
embedded 3rd-order solution's filtered by the L-stable factor, so that it stays bounded for stiff
components (Eq. 8.19-8.20); step sizes follow the predictive controller of Gustafsson (1994) as
in RADAU5. The estimate is held to the run's own tolerances, as in scipy's ``Radau``, not to
RADAU5's transformed ones (``rtol' = 0.1 rtol^(2/3)``): the estimate is of order 3 while the
solution is of order 5, so the global error lies below the tolerance.
"""

from __future__ import annotations

import math

from numba import njit

from workbench.solver._linalg import lu_factor, lu_solve
from workbench.solver._loop_types import (
    DOP853,
    IS_LU,
    IS_RHS,
    IS_TO_EXPLICIT,
    IS_TO_IMPLICIT,
    RADAU5,
    RC_COST_EXPLICIT,
    RC_COST_IMPLICIT,
    RC_CURRENT,
    RC_ERR_ACC,
    RC_EXPLICIT_OK,
    RC_FACCON,
    RC_H_ACC,
    RC_H_FAIL,
    RC_H_LAMBDA,
    RC_H_LU,
    RC_H_OLD,
    RC_HITS_NEEDED,
    RC_JAC,
    RC_JAC_FRESH,
    RC_NONSTIFF_RUN,
    RC_PHASE_STEPS,
    RC_RHO,
    RC_STIFF_HITS,
)
from workbench.solver._tableaux import (
    RADAU_ALPHA,
    RADAU_BETA,
    RADAU_C,
    RADAU_E,
    RADAU_GAMMA,
    RADAU_P,
    RADAU_T,
    RADAU_TI,
)

EPS = 2.220446049250313e-16

#: most Newton iterations per step (RADAU5's NIT)
NEWTON_MAX = 7
#: safety factor of the step-size controller
SAFE = 0.9
#: bounds of the step-size ratio: h_new / h in [1/8, 5] after a step (RADAU5's FACR, FACL)
FAC_GROW = 8.0
FAC_SHRINK = 5.0
#: the Jacobian is kept while the Newton iteration contracts faster than this (RADAU5's THET:
#: 0.001 for cheap Jacobians, larger where they are costly); an analytic Jacobian costs no
#: evaluation, a finite-difference one 2n (measured: on Van der Pol, analytic, 0.001 took
#: fewer evaluations than 0.1; on the nine-bar, differenced, 0.3 fewer than 0.1 and 0.001)
THETA_KEEP_ANALYTIC = 0.001
THETA_KEEP_DIFFERENCED = 0.3
#: the step (and with it the LU factors) is kept while the controller asks for a ratio in
#: [1, 1.2] (RADAU5's QUOT1, QUOT2)
KEEP_LOW = 1.0
KEEP_HIGH = 1.2

#: after a Newton failure at step h_f, later steps stay below NEWTON_BACKOFF h_f, a bound that
#: grows by NEWTON_RELAX per accepted step
NEWTON_BACKOFF = 0.7
NEWTON_RELAX = 1.2

# Outcomes of the Newton iteration.
CONVERGED = 0
SLOW = 1  # converging, but not within NEWTON_MAX iterations: retry with the predicted step
FAILED = 2  # diverging, a model failure or a non-finite stage: retry with half the step

#: Hairer's stiffness test (his code DOP853) counts a step as stability-bound where
#: |h lambda| > 6.1, DOP853's stability bound on the negative real axis. On the nine-bar in
#: contact (0.1 pi, a lightly damped contact mode at ~7e3 1/s) DOP853's steps settle below
#: 6.1 with no rejections: the bound there is that of the error estimator, which the 6.1 test
#: never sees. So a step counts as stability-bound above EXPLICIT_TRIGGER, below 6.1, and the
#: explicit method's stability-bound step is taken as EXPLICIT_STEP / rho.
EXPLICIT_TRIGGER = 3.5
EXPLICIT_STEP = 4.0
#: the problem is declared stiff after STIFF_HITS positive tests with fewer than
#: NONSTIFF_RESET negative ones in a row between them (DOP853: 15 and 6). A switch costs about
#: what 15 explicit steps do (a Jacobian, LU decompositions, the implicit step-size ramp), so
#: switching after 15 stability-bound steps wastes at most twice the best choice made knowing
#: how long the stiffness lasts (the "ski rental" argument; Karlin et al. 1988). Where the
#: stiffness is short-lived or the implicit steps are no longer (the nine-bar's contacts keep
#: DOP853 at its bound for 20-200 steps at a time at 2.5-3 pi), the trial ends unprofitable;
#: the count needed then doubles after each implicit phase shorter than SHORT_PHASE steps (up
#: to MAX_HITS) and returns to STIFF_HITS after a longer one, so that such a problem makes a
#: few trials, not one per contact.
STIFF_HITS = 15
NONSTIFF_RESET = 6
SHORT_PHASE = 50
MAX_HITS = 15 * 64
#: consecutive implicit steps with the explicit method estimated cheaper before switching back
EXPLICIT_RUN = 10
#: weight of the exponential averages of the cost per accepted step
COST_WEIGHT = 0.1
#: cost of one LU pair (real and complex) in right-hand-side evaluations for n = 8 states,
#: measured on the nine-bar mechanism (scaled by (n / 8)^3 for other sizes)
LU_COST_8 = 1.0


@njit(cache=True, nogil=True)
def newton_tolerance(rtol):
    """Bound on the Newton iteration's scaled increment (RADAU5's FNEWT)."""
    return max(10.0 * EPS / rtol, min(0.03, math.sqrt(rtol)))


@njit(cache=True, nogil=True)
def factor_matrices(J, h, LUr, pivr, LUc, pivc):
    """LU factors of gamma/h - J and (alpha - i beta)/h - J. Returns 0, or nonzero when one is
    singular."""
    n = J.shape[0]
    mr = RADAU_GAMMA / h
    mc = complex(RADAU_ALPHA, -RADAU_BETA) / h
    for i in range(n):
        for j in range(n):
            LUr[i, j] = -J[i, j]
            LUc[i, j] = -J[i, j]
        LUr[i, i] += mr
        LUc[i, i] += mc
    code = lu_factor(LUr, pivr)
    if code != 0:
        return code
    return lu_factor(LUc, pivc)


@njit(cache=True, nogil=True)
def starting_values(Q, h_old, h, Z, W):
    """Stage increments of the next step from the last step's collocation polynomial
    y(t_old + x h_old) = y_old + sum_k Q[k] x^(k+1), extrapolated to the new stages
    x = 1 + c_i h / h_old (Hairer & Wanner 1996, Sec. IV.8, "starting values"); zero without
    a last step (h_old = 0). Writes Z and W = T^-1 Z."""
    n = Z.shape[1]
    if h_old <= 0.0:
        for j in range(3):
            for i in range(n):
                Z[j, i] = 0.0
                W[j, i] = 0.0
        return
    for j in range(3):
        x = 1.0 + RADAU_C[j] * h / h_old
        for i in range(n):
            Z[j, i] = Q[0, i] * (x - 1.0) + Q[1, i] * (x * x - 1.0) + Q[2, i] * (x * x * x - 1.0)
    for j in range(3):
        for i in range(n):
            W[j, i] = RADAU_TI[j, 0] * Z[0, i] + RADAU_TI[j, 1] * Z[1, i] + RADAU_TI[j, 2] * Z[2, i]


@njit(cache=True, nogil=True)
def newton_increment(Fs, W, h, LUr, pivr, LUc, pivc, scale, dW, br, bc):
    """One simplified Newton step for the transformed increments W with the stage derivatives
    Fs (Hairer & Wanner 1996, Eq. 8.17-8.18, in the form of scipy's ``Radau``): writes dW and
    returns its scaled RMS norm over the 3n components."""
    n = W.shape[1]
    mr = RADAU_GAMMA / h
    a = RADAU_ALPHA / h
    b = RADAU_BETA / h
    for i in range(n):
        f0 = Fs[0, i]
        f1 = Fs[1, i]
        f2 = Fs[2, i]
        t0 = RADAU_TI[0, 0] * f0 + RADAU_TI[0, 1] * f1 + RADAU_TI[0, 2] * f2
        t1 = RADAU_TI[1, 0] * f0 + RADAU_TI[1, 1] * f1 + RADAU_TI[1, 2] * f2
        t2 = RADAU_TI[2, 0] * f0 + RADAU_TI[2, 1] * f1 + RADAU_TI[2, 2] * f2
        br[i] = t0 - mr * W[0, i]
        # (T^-1 F)_2 + i (T^-1 F)_3 - (alpha - i beta) / h (W_2 + i W_3)
        bc[i] = complex(t1 - a * W[1, i] - b * W[2, i], t2 - a * W[2, i] + b * W[1, i])
    lu_solve(LUr, pivr, br)
    lu_solve(LUc, pivc, bc)
    acc = 0.0
    for i in range(n):
        dW[0, i] = br[i]
        dW[1, i] = bc[i].real
        dW[2, i] = bc[i].imag
        for j in range(3):
            acc += (dW[j, i] / scale[i]) ** 2
    return math.sqrt(acc / (3 * n))


@njit(cache=True, nogil=True)
def apply_increment(dW, W, Z):
    """W += dW; Z = T W."""
    n = W.shape[1]
    for j in range(3):
        for i in range(n):
            W[j, i] += dW[j, i]
    for j in range(3):
        for i in range(n):
            Z[j, i] = RADAU_T[j, 0] * W[0, i] + RADAU_T[j, 1] * W[1, i] + RADAU_T[j, 2] * W[2, i]


@njit(cache=True, nogil=True)
def error_vector(Z, f0, h, LUr, pivr, ez, e):
    """The error estimate's vector (gamma/h - J)^-1 (f0 + e^T Z / h) into ``e``, and
    ``ez = e^T Z / h`` (Hairer & Wanner 1996, Eq. 8.19-8.20)."""
    n = Z.shape[1]
    for i in range(n):
        ez[i] = (RADAU_E[0] * Z[0, i] + RADAU_E[1] * Z[1, i] + RADAU_E[2] * Z[2, i]) / h
        e[i] = f0[i] + ez[i]
    lu_solve(LUr, pivr, e)


@njit(cache=True, nogil=True)
def refine_error(f1, ez, LUr, pivr, e):
    """The refined estimate (gamma/h - J)^-1 (f(y0 + e) + e^T Z / h), with ``f1 = f(y0 + e)``,
    used after a rejection or on a first step, where the plain one can be off for stiff
    components (Hairer & Wanner 1996, Sec. IV.8, after Eq. 8.20)."""
    n = e.size
    for i in range(n):
        e[i] = f1[i] + ez[i]
    lu_solve(LUr, pivr, e)


@njit(cache=True, nogil=True)
def scaled_rms(e, y, y_new, rtol, atol, blocks):
    """RMS of e / (atol + rtol max(|y|, |y_new|)), the largest over the state's blocks
    (boundaries ``blocks``, see :attr:`workbench.solver.Problem.error_blocks`)."""
    worst = 0.0
    for b in range(blocks.size - 1):
        acc = 0.0
        for i in range(blocks[b], blocks[b + 1]):
            sc = atol[i] + rtol * max(abs(y[i]), abs(y_new[i]))
            acc += (e[i] / sc) ** 2
        err = math.sqrt(acc / (blocks[b + 1] - blocks[b]))
        if not err <= worst:  # a NaN block wins
            worst = err
    return worst


@njit(cache=True, nogil=True)
def step_ratio(err, newt):
    """h_new / h after a step with error ``err`` and ``newt`` Newton iterations (RADAU5: the
    safety factor shrinks with the iterations a step needed)."""
    fac = min(SAFE, SAFE * (1.0 + 2.0 * NEWTON_MAX) / (newt + 2.0 * NEWTON_MAX))
    quot = max(1.0 / FAC_GROW, min(FAC_SHRINK, err**0.25 / fac))
    return 1.0 / quot


@njit(cache=True, nogil=True)
def predictive_ratio(ratio, h, err, h_acc, err_acc):
    """Gustafsson's (1994) predictive step-size ratio, as in RADAU5: the smaller of the
    classical ratio and the one that also uses the last accepted step (h_acc, err_acc); the
    classical one alone on a first step (h_acc = 0)."""
    if h_acc <= 0.0:
        return ratio
    fac = (h_acc / h) * (err * err / err_acc) ** 0.25 / SAFE
    fac = max(1.0 / FAC_GROW, min(FAC_SHRINK, fac))
    return min(ratio, 1.0 / fac)


@njit(cache=True, nogil=True)
def newton_limit(rc, h, h_next):
    """The next step after an accepted one, limited where the Newton iteration has recently
    failed: at most NEWTON_BACKOFF times the failed step (but never below the accepted one), a
    bound that relaxes by NEWTON_RELAX per accepted step. Where a contact's or a friction law's
    steep rate limits the Newton iteration, not the error, the error-based controller keeps
    proposing steps 2-4x larger than the iteration converges for, each failure costing a
    Jacobian and two iterations (measured on the nine-bar at 0.1 pi: without this bound most
    steps failed their Newton iteration first)."""
    h_fail = rc[RC_H_FAIL]
    if h_fail <= 0.0:
        return h_next
    rc[RC_H_FAIL] = h_fail * NEWTON_RELAX
    return min(h_next, max(h, NEWTON_BACKOFF * h_fail))


@njit(cache=True, nogil=True)
def dense_coefficients(Z, F):
    """The collocation polynomial's coefficients F[k] (of x^(k+1)) over the last step."""
    n = Z.shape[1]
    for k in range(3):
        for i in range(n):
            F[k, i] = RADAU_P[0, k] * Z[0, i] + RADAU_P[1, k] * Z[1, i] + RADAU_P[2, k] * Z[2, i]


@njit(cache=True, nogil=True)
def spectral_radius(J, scale, v, u):
    """Estimate of the largest |eigenvalue| of J (1/s) by 24 power iterations in the scaled
    state (D^-1 J D with D = diag(scale): the same eigenvalues, balanced units); the growth is
    averaged over the last 12, which also measures a dominant complex pair. 0 for J = 0."""
    n = J.shape[0]
    norm = 0.0
    for i in range(n):
        v[i] = 1.0 + 0.5 * math.sin(1.0 + i)  # fixed, generic start
        norm += v[i] * v[i]
    norm = math.sqrt(norm)
    log_growth = 0.0
    for it in range(24):
        for i in range(n):
            v[i] /= norm
        new = 0.0
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += J[i, j] * scale[j] * v[j]
            u[i] = acc / scale[i]
            new += u[i] * u[i]
        norm = math.sqrt(new)
        if not (norm > 0.0) or not math.isfinite(norm):
            return 0.0 if norm == 0.0 else math.inf
        if it >= 12:
            log_growth += math.log(norm)
        for i in range(n):
            v[i] = u[i]
    return math.exp(log_growth / 12.0)


@njit(cache=True, nogil=True)
def lu_cost(n):
    """Cost of one LU pair in right-hand-side evaluations (see LU_COST_8)."""
    return LU_COST_8 * (n / 8.0) ** 3


@njit(cache=True, nogil=True)
def forget_jacobian(rc):
    """After an event or a switch: the Jacobian, its LU factors, the starting values and the
    predictive controller's history belong to another discrete state or method."""
    rc[RC_JAC] = 0.0
    rc[RC_JAC_FRESH] = 0.0
    rc[RC_H_LU] = 0.0
    rc[RC_H_OLD] = 0.0
    rc[RC_H_ACC] = 0.0
    rc[RC_ERR_ACC] = 0.0
    rc[RC_H_FAIL] = 0.0
    rc[RC_FACCON] = 1.0


@njit(cache=True, nogil=True)
def to_implicit(rc, ist):
    """Switch the automatic method to Radau IIA."""
    rc[RC_CURRENT] = RADAU5
    rc[RC_STIFF_HITS] = 0.0
    rc[RC_NONSTIFF_RUN] = 0.0
    rc[RC_EXPLICIT_OK] = 0.0
    rc[RC_PHASE_STEPS] = 0.0
    ist[IS_TO_IMPLICIT] += 1
    forget_jacobian(rc)


@njit(cache=True, nogil=True)
def to_explicit(rc, ist):
    """Switch the automatic method to DOP853; a short implicit phase doubles the stiffness
    tests needed to come back."""
    if rc[RC_PHASE_STEPS] < SHORT_PHASE:
        rc[RC_HITS_NEEDED] = min(MAX_HITS, 2.0 * max(rc[RC_HITS_NEEDED], STIFF_HITS))
    else:
        rc[RC_HITS_NEEDED] = STIFF_HITS
    rc[RC_CURRENT] = DOP853
    rc[RC_STIFF_HITS] = 0.0
    rc[RC_NONSTIFF_RUN] = 0.0
    rc[RC_EXPLICIT_OK] = 0.0
    ist[IS_TO_EXPLICIT] += 1


@njit(cache=True, nogil=True)
def average(old, new):
    """Exponential average of a cost per step (the first value taken as it is)."""
    if old <= 0.0:
        return new
    return old + COST_WEIGHT * (new - old)


@njit(cache=True, nogil=True)
def explicit_test(rc, ist, h_lambda, cost):
    """Hairer's stiffness test after an accepted DOP853 step of the automatic method (his code
    DOP853; Hairer & Wanner 1996, Sec. IV.2), with the trigger EXPLICIT_TRIGGER and the
    adaptive count RC_HITS_NEEDED (see their definitions): ``h_lambda`` above the trigger is a
    positive test; enough of them, with fewer than NONSTIFF_RESET negative ones in a row between
    them, switch to the implicit method. ``cost``: evaluations the step took (rejected attempts
    included). Returns whether it switched."""
    rc[RC_COST_EXPLICIT] = average(rc[RC_COST_EXPLICIT], cost)
    rc[RC_H_LAMBDA] = h_lambda
    if h_lambda > EXPLICIT_TRIGGER:
        rc[RC_NONSTIFF_RUN] = 0.0
        rc[RC_STIFF_HITS] += 1.0
        if rc[RC_STIFF_HITS] >= max(rc[RC_HITS_NEEDED], STIFF_HITS):
            to_implicit(rc, ist)
            return True
    else:
        rc[RC_NONSTIFF_RUN] += 1.0
        if rc[RC_NONSTIFF_RUN] >= NONSTIFF_RESET:
            rc[RC_STIFF_HITS] = 0.0
    return False


@njit(cache=True, nogil=True)
def implicit_test(rc, ist, h_next, cost):
    """After an accepted Radau step of the automatic method: is the explicit method cheaper?

    The explicit pair could take steps up to EXPLICIT_STEP / rho (rho: the spectral radius of
    the last Jacobian) at ``RC_COST_EXPLICIT`` evaluations per step (measured in its last
    phase; 16 before any: 12 stages and a third of the steps rejected); the implicit method
    takes ``h_next`` at ``RC_COST_IMPLICIT`` evaluation-equivalents per step (its Jacobians'
    evaluations and LU decompositions included). Where even the stability-bound explicit step
    is cheaper per unit time for EXPLICIT_RUN steps in a row, the implicit step is bounded by
    accuracy, not stability, i.e. the problem is not stiff on this scale (Hairer & Wanner 1996,
    Sec. IV.2), and the automatic method switches back (the cost comparison per unit time of
    Petzold's (1983) LSODA). ``cost``: evaluation-equivalents of the step just taken. Returns
    whether it switched."""
    rc[RC_COST_IMPLICIT] = average(rc[RC_COST_IMPLICIT], cost)
    rc[RC_PHASE_STEPS] += 1.0
    c_exp = rc[RC_COST_EXPLICIT] if rc[RC_COST_EXPLICIT] > 0.0 else 16.0
    cheaper = rc[RC_RHO] * h_next * c_exp < EXPLICIT_STEP * rc[RC_COST_IMPLICIT]
    if cheaper:
        rc[RC_EXPLICIT_OK] += 1.0
        if rc[RC_EXPLICIT_OK] >= EXPLICIT_RUN:
            to_explicit(rc, ist)
            return True
    else:
        rc[RC_EXPLICIT_OK] = 0.0
    return False


@njit(cache=True, nogil=True)
def implicit_cost(ist, rhs_before, lu_before, n):
    """Evaluation-equivalents of the implicit method since the counters read ``rhs_before`` and
    ``lu_before``."""
    return (ist[IS_RHS] - rhs_before) + (ist[IS_LU] - lu_before) * lu_cost(n)
