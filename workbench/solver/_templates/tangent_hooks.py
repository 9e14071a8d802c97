"""Compiled tangent (variational) system of a model, with saltation at events (a template,
specialised per model by :func:`workbench.solver._compile.tangent_for`).

The state of the tangent system is ``Y = [y (n), U (m columns of nx = n + na), L, l (m), W, M,
K]``: the model's state ``y``; ``m`` tangent vectors of the *extended* state ``x = (y, aux)``
(the discrete state ``aux`` is part of the state the future depends on: a contact's held onset
velocity sets its damping), each stored as a direction ``u`` of unit size and its log size ``l``
(the tangent vector is ``v = e^l u``); ``L``, the sum of ``log |det S_yy|`` over the events so far
(the state block of each saltation matrix); with re-orthonormalisation (below) the log volume
``W`` the vectors span and the part ``M`` of it that the discrete state fed back between events,
and the count ``K`` of re-orthonormalisations. Sizes, angles and volumes are those of the state
divided by its scales ``s`` and the discrete state by its scales ``s_a`` (a discrete state that
the flow does not depend on, such as a counter, has none and is left out: see
:mod:`workbench.solver._tangent_numerics`).

Between events ``dy/dt = f(t, y, aux)`` and for each column ``v = (v_y, v_a)``

    dv_y/dt = J_y v_y + J_a v_a,        dv_a/dt = 0,

with ``J_y = df/dy`` from the model's Jacobian (its analytic ``jacobian`` hook, or a central
difference of ``rhs`` along ``v_y``: two evaluations per column, with the step DIRECTION_STEP,
shortened near event surfaces) and ``J_a = df/daux`` by central differences over the discrete
states that a column carries and that are active (``aux_k != 0``; a zero discrete state means
"inactive", e.g. no contact, and is not differenced). Written for ``v = e^l u`` with any rate
``a(t)`` of the log size this is

    du/dt = (J_y u_y + J_a u_a, 0) - a u,        dl/dt = a,

and the system takes ``a = <u, du/dt + a u> / <u, u>``, the rate at which the size of ``u`` would
change: ``u`` keeps its size (1 from the start and after every event) while ``l`` carries the
growth (continuous normalisation, e.g. Geist, Parlitz & Lauterborn 1990, Prog. Theor. Phys. 83,
875). Why: the solver controls the error of every component relative to its own size, with the
absolute floor ``atol s_i``. A tangent vector that grows by e^20 between re-orthonormalisations
(the nine-bar's chaos does so within a fraction of a second) holds components some 1e9 smaller
than its size, whose tolerance lies far below the rounding of its derivative (which scales with
the vector's size): the step size then collapsed to the smallest step where the model's own run
integrates fine. With the size split off every component is measured against the vector's size
(``atol s_i`` is ``atol`` times the size), which is what the accuracy of a direction means.

At an event with event function ``g`` and reset ``x+ = R(t, x-)`` every column jumps by the
saltation matrix (Müller 1995, Chaos Solitons Fractals 5, 1671; Dellago, Posch & Hoover 1996,
Phys. Rev. E 53, 1485; Leine & Nijmeijer 2004, Sec. 3.5):

    S = DR + (F+ - DR F- - dR/dt) grad(g)^T / (grad(g) . F- + dg/dt),

where ``F-`` and ``F+`` are the extended vector fields ``(f, 0)`` before and after the reset,
and is normalised again (its log size added to ``l``). ``DR``, ``dR/dt``, ``grad g`` and
``dg/dt`` are central differences of the model's ``apply_event`` and ``event_values`` (steps:
:func:`workbench.solver._templates.jacobian.step`).

Re-orthonormalisation (optional, for Lyapunov exponents): the directions tend to the most
expanding one, and a direction whose part orthogonal to the others has shrunk by e^-D relative
to its size is known to rtol e^D of that part only. At the end of every accepted step where the
orthogonality defect ``D`` (the columns' log sizes minus the log of the volume they span,
Hadamard) exceeds ``D_max`` (the loop's ``step_end`` hook), and after an event whose saltation
left it there, the directions are re-orthonormalised by Gram-Schmidt (``U <- U R^-1``, ``l_k +=
log R_kk``: Benettin's accumulators; the nested subspaces and the volume stay). Benettin et al.
(1980, Meccanica 15, 9 and 21) re-orthonormalise at any times frequent enough that the vectors stay
numerically independent, and the exponents do not depend on which (the Gram-Schmidt/QR method,
Geist, Parlitz & Lauterborn 1990, Prog. Theor. Phys. 83, 875): the defect's crossing needs no
location in time. Nor is the change of basis a discontinuity of the flow: the tangent equations
are linear, so the linear part of the directions' derivative at the step's end transforms by the
same ``R^-1`` (:func:`step_end`), the next step starts from it (first-same-as-last, no
evaluation) with the step size the controller chose, and every component keeps its error scale
(the directions have unit size before and after). An event located in time (as this system did
before) cost the dense output's three stages, the evaluation after it and the rest of the step
at every re-orthonormalisation. Without re-orthonormalisation the vectors stay ``Phi V`` (a
monodromy matrix).

The volume: the log volume ``W`` of the m vectors grows at ``tr(G^-1 U^T S^-2 A U)`` (``G`` the
Gram matrix of the directions, ``A = [[J_y, J_a], [0, 0]]`` the generator of the extended
tangent flow: the trace of the generator on the vectors' span, the feedback of the held onset
velocity ``J_a`` included, whose share is ``M``) and jumps at an event by the log of the volume
ratio of the columns after and before the saltation. The sum of the m largest exponents is the
mean rate of ``W`` (``sum log R_kk = W`` after any re-orthonormalisation): ``W`` integrated with
the solver's error control and the accumulators from the integrated directions are an exact
check of the spectrum's sum.

Layout (set by :func:`workbench.solver._tangent.tangent_problem`): ``p = [model p, s (n), w
(nx), time scale, D_max]`` with the state scales ``s`` (state units), the weights ``w`` of the
inner product (``1 / s^2``, ``1 / s_a^2`` or 0) and a time scale (s) for the difference steps;
``ip = [model ip, n, na, m, ne, len(model p), len(model ip), model work size, re-orthonormalise
(0/1)]``; ``work = [model work, scratch]``; the kernel's ``aux`` is the model's.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from workbench.solver._tangent_numerics import (
    column_dot,
    columns_log_volume,
    defect,
    gram_schmidt,
    normalise,
    transform_rates,
    volume_rates,
)
from workbench.solver._templates.jacobian import (  # @@MODEL_JACOBIAN@@
    HAS_ANALYTIC,
    fd_aux_jacobian,
    jacobian,
    step,
)
from workbench.solver._templates.placeholder_hooks import (
    apply_event as model_apply_event,  # @@HOOKS@@
)
from workbench.solver._templates.placeholder_hooks import (
    event_values as model_event_values,  # @@HOOKS@@
)
from workbench.solver._templates.placeholder_hooks import rhs as model_rhs  # @@HOOKS@@

N_META = 8

#: central-difference step along a direction of unit scaled size (a model without an analytic
#: Jacobian): 1e-4 of each state's size. The difference's rounding error, eps |f| / step, enters
#: the tangent's rate as noise that no step size integrates away; at the cube-root step
#: eps^(1/3) ~ 6e-6 it held the nine-bar's tangent run in contact to ~1e-6 s steps at rtol 1e-10
#: (190 515 steps over 0.2 s where the model takes 2 073; 3 396 now).
DIRECTION_STEP = 1e-4
#: Near an event surface the step is shortened so that the stencil changes no event function by
#: more than SURFACE_FRACTION of its value: at a contact's onset and end the rhs varies on the
#: scale of the penetration itself (Hertz: delta^1.5, relative truncation error
#: (step / delta)^2 / 24), and the long step biased the nine-bar's tangent map over four
#: contacts by 8.6e-3 (7.0e-5 with the shortening; 1.3e-4 with the cube-root step). Not below
#: MIN_STEP_FACTOR times the step, whose rounding noise would return.
SURFACE_FRACTION = 0.02
MIN_STEP_FACTOR = 1e-3


@njit(cache=True, nogil=True, inline="always")
def _layout(p, ip, work):
    """The parts of the layout (see the module's docstring): ``(n, na, m, ne, pm, ipm, wm, s,
    w, time_scale, d_max)``, the model's sizes (states, discrete states; tangent vectors; the
    model's events), its own ``p``, ``ip`` and ``work`` (views; the tangent system's scratch
    is ``work[len(wm):]``), the state scales, the weights of the inner product, the time scale
    (s) and the defect at which the vectors are re-orthonormalised."""
    k = ip.size - N_META
    n, na, m, ne = ip[k], ip[k + 1], ip[k + 2], ip[k + 3]
    npm, nip, ws = ip[k + 4], ip[k + 5], ip[k + 6]
    nx = n + na
    s = p[npm : npm + n]
    w = p[npm + n : npm + n + nx]
    return n, na, m, ne, p[:npm], ip[:nip], work[:ws], s, w, p[npm + n + nx], p[npm + n + nx + 1]


@njit(cache=True, nogil=True, inline="always")
def _reorthonormalising(ip):
    """Whether the system re-orthonormalises its vectors (and integrates their volume)."""
    return ip[ip.size - 1] != 0


@njit(cache=True, nogil=True, inline="always")
def _normalised_rates(Y, n, nx, na, m, w, D, il, dY):
    """Continuous normalisation: from the rates ``D`` (n x m) of the vectors' state blocks, the
    rates of the normalised vectors u (their memory blocks included) and of their log sizes l
    (at ``il``): l takes the growth rate a of u, and u loses it."""
    for c in range(m):
        b = n + c * nx
        size = column_dot(Y, b, b, nx, w)
        rate = 0.0
        for i in range(n):
            rate += w[i] * Y[b + i] * D[i, c]
        a = rate / size if size > 0.0 else 0.0
        for i in range(n):
            dY[b + i] = D[i, c] - a * Y[b + i]
        for k in range(na):
            dY[b + n + k] = -a * Y[b + n + k]
        dY[il + c] = a


@njit(cache=True, nogil=True)
def rhs(t, Y, p, ip, aux, work, dY):
    n, na, m, ne, pm, ipm, wm, scale, w, _, _ = _layout(p, ip, work)
    nx = n + na
    y = Y[:n]
    code = model_rhs(t, y, pm, ipm, aux, wm, dY[:n])
    if code > 0:
        return code
    o = wm.size
    yd = work[o : o + n]
    fp = work[o + n : o + 2 * n]
    fm = work[o + 2 * n : o + 3 * n]
    ja = work[o + 3 * n : o + 3 * n + n * na]
    jy = work[o + 3 * n + n * na : o + 3 * n + n * na + n * n]
    ge = o + 3 * n + n * na + n * n
    g0 = work[ge : ge + ne]  # event functions at y, and at a point of a difference stencil
    gd = work[ge + ne : ge + 2 * ne]
    if ne > 0 and not HAS_ANALYTIC:
        model_event_values(t, y, pm, ipm, aux, wm, g0)
    volume = _reorthonormalising(ip)
    D = np.zeros((nx, m))  # the directions' rates before the normalisation (state rows)
    Dm = np.zeros((n, m))  # their discrete state's share
    # J_a: columns of the active discrete states that some tangent vector carries
    need = np.zeros(na, np.bool_)
    for k in range(na):
        for c in range(m):
            if Y[n + c * nx + n + k] != 0.0:
                need[k] = True
    jam = ja.reshape((n, na))
    c1 = fd_aux_jacobian(t, y, pm, ipm, aux, wm, need, yd, fp, fm, jam)
    if c1 > 0:
        return c1
    if HAS_ANALYTIC:
        jm = jy.reshape((n, n))
        c1 = jacobian(t, y, pm, ipm, aux, wm, scale, jm)
        if c1 > 0:
            return c1
    for c in range(m):
        b = n + c * nx
        if HAS_ANALYTIC:
            for i in range(n):
                acc = 0.0
                for j in range(n):
                    acc += jy[i * n + j] * Y[b + j]
                D[i, c] = acc
        else:
            nv = 0.0
            for j in range(n):
                nv += (Y[b + j] / scale[j]) ** 2
            nv = math.sqrt(nv)
            if nv > 0.0:
                eps = DIRECTION_STEP / nv
                if ne > 0:
                    eps = _near_surface_step(t, y, Y[b : b + n], eps, pm, ipm, aux, wm, g0, gd, yd)
                for j in range(n):
                    yd[j] = y[j] + eps * Y[b + j]
                c1 = model_rhs(t, yd, pm, ipm, aux, wm, fp)
                for j in range(n):
                    yd[j] = y[j] - eps * Y[b + j]
                c2 = model_rhs(t, yd, pm, ipm, aux, wm, fm)
                if c1 > 0:
                    return c1
                if c2 > 0:
                    return c2
                for i in range(n):
                    D[i, c] = (fp[i] - fm[i]) / (2.0 * eps)
        for k in range(na):
            va = Y[b + n + k]
            if va != 0.0:
                for i in range(n):
                    D[i, c] += ja[i * na + k] * va
                    Dm[i, c] += ja[i * na + k] * va
    iv = n + m * nx + 1 + m  # W, M, K
    dY[n + m * nx] = 0.0
    dY[iv] = 0.0
    dY[iv + 1] = 0.0
    dY[iv + 2] = 0.0
    if volume:
        dY[iv], dY[iv + 1] = volume_rates(Y, n, nx, m, w, D, Dm)
    _normalised_rates(Y, n, nx, na, m, w, D, n + m * nx + 1, dY)
    return code


@njit(cache=True, nogil=True)
def _near_surface_step(t, y, v, eps, pm, ipm, aux, wm, g0, gd, yd):
    """The difference step along ``v`` (a multiple of it), shortened so that no event function
    changes by more than SURFACE_FRACTION of its value at ``y`` (``g0``) across the stencil:
    near a contact's onset and end the rhs varies on the scale of the penetration itself
    (Hertz: delta^1.5), and a longer stencil would bias the derivative. ``gd``, ``yd``:
    scratch."""
    for _ in range(2):  # g is close to linear across the stencil: one correction suffices
        for j in range(y.size):
            yd[j] = y[j] + eps * v[j]
        model_event_values(t, yd, pm, ipm, aux, wm, gd)
        factor = 1.0
        for k in range(g0.size):
            change = abs(gd[k] - g0[k])
            allowed = SURFACE_FRACTION * abs(g0[k])
            if change > allowed:
                factor = min(factor, max(allowed / change, MIN_STEP_FACTOR))
        if factor == 1.0:
            break
        eps *= factor
    return eps


@njit(cache=True, nogil=True)
def event_values(t, Y, p, ip, aux, work, g):
    n, _, _, _, pm, ipm, wm, _, _, _, _ = _layout(p, ip, work)
    model_event_values(t, Y[:n], pm, ipm, aux, wm, g)


@njit(cache=True, nogil=True)
def _reset(k, t, y, a, pm, ipm, wm, out):
    """``out = R(t, (y, a))``: the model's event update applied to copies."""
    n = y.size
    yc = y.copy()
    ac = a.copy()
    model_apply_event(k, t, yc, pm, ipm, ac, wm)
    out[:n] = yc
    out[n:] = ac


@njit(cache=True, nogil=True)
def _reorthonormalise(Y, n, nx, m, w, R):
    """Gram-Schmidt on the directions (``U <- U R^-1``, ``R`` written), their log sizes taking
    log R_kk; counted."""
    gram_schmidt(Y, n, nx, m, w, n + m * nx + 1, R)
    Y[n + m * nx + 1 + m + 2] += 1.0


@njit(cache=True, nogil=True)
def step_end(t, Y, p, ip, aux, work, dY):
    """At the end of an accepted step (the loop's ``step_end`` hook), with the state ``Y`` and
    its derivative ``dY`` there: where the directions' orthogonality defect exceeds D_max,
    re-orthonormalise them and transform ``dY`` alike, without an evaluation. Returns 1 where
    it did, else 0.

    ``U <- U R^-1`` is a change of basis of the span of a linear system: the linear part of
    each direction's rate, ``L(u_c) = du_c/dt + a_c u_c = (J_y u_y + J_a u_a, 0)``, transforms
    by the same ``R^-1``, the new directions' rates ``a`` follow from it, and the rates of the
    volume ``W`` and of its memory part ``M`` (traces on the span) do not change."""
    n, na, m, _, _, _, _, _, w, _, d_max = _layout(p, ip, work)
    if not _reorthonormalising(ip):
        return 0
    nx = n + na
    if not defect(Y, n, nx, m, w) > d_max:
        return 0
    il = n + m * nx + 1
    L = np.empty((n, m))  # the state rows; the discrete state's are zero
    for c in range(m):
        b = n + c * nx
        for i in range(n):
            L[i, c] = dY[b + i] + dY[il + c] * Y[b + i]
    R = np.empty((m, m))
    _reorthonormalise(Y, n, nx, m, w, R)
    transform_rates(L, R)
    _normalised_rates(Y, n, nx, na, m, w, L, il, dY)
    return 1


@njit(cache=True, nogil=True)
def apply_event(k, t, Y, p, ip, aux, work):
    n, na, m, ne, pm, ipm, wm, scale, w, time_scale, d_max = _layout(p, ip, work)
    nx = n + na
    h_t = step(t, time_scale)
    volume = _reorthonormalising(ip)
    y = Y[:n]
    carried = False
    for i in range(n, n + m * nx):
        if Y[i] != 0.0:
            carried = True
    if not carried:  # no tangent vector to carry over the event (a copy without one)
        return model_apply_event(k, t, y, pm, ipm, aux, wm)
    y0 = y.copy()
    a0 = aux.copy()
    # vector field before the reset
    f_minus = np.empty(n)
    model_rhs(t, y0.copy(), pm, ipm, a0.copy(), wm, f_minus)
    # gradient and time derivative of event function k
    gp = np.empty(ne)
    gm = np.empty(ne)
    grad = np.empty(n)
    yd = y0.copy()
    for j in range(n):
        h = step(y0[j], scale[j])
        yd[j] = y0[j] + h
        model_event_values(t, yd, pm, ipm, a0, wm, gp)
        yd[j] = y0[j] - h
        model_event_values(t, yd, pm, ipm, a0, wm, gm)
        yd[j] = y0[j]
        grad[j] = (gp[k] - gm[k]) / (2.0 * h)
    model_event_values(t + h_t, y0, pm, ipm, a0, wm, gp)
    model_event_values(t - h_t, y0, pm, ipm, a0, wm, gm)
    g_dot = (gp[k] - gm[k]) / (2.0 * h_t)
    for j in range(n):
        g_dot += grad[j] * f_minus[j]
    if g_dot == 0.0:
        g_dot = 1e-300  # an exactly tangent crossing: the saltation is unbounded there
    # the update itself, and the vector field after it
    stop = model_apply_event(k, t, y, pm, ipm, aux, wm)
    f_plus = np.empty(n)
    model_rhs(t, y.copy(), pm, ipm, aux.copy(), wm, f_plus)
    # DR (extended state) and dR/dt by central differences of the update
    DR = np.zeros((nx, nx))
    rp = np.empty(nx)
    rm = np.empty(nx)
    ad = a0.copy()
    for j in range(nx):
        if j < n:
            h = step(y0[j], scale[j])
            yd[j] = y0[j] + h
            _reset(k, t, yd, a0, pm, ipm, wm, rp)
            yd[j] = y0[j] - h
            _reset(k, t, yd, a0, pm, ipm, wm, rm)
            yd[j] = y0[j]
        else:
            a = a0[j - n]
            if not math.isfinite(a):
                continue
            h = step(a, 0.0)
            ad[j - n] = a + h
            _reset(k, t, y0, ad, pm, ipm, wm, rp)
            ad[j - n] = a - h
            _reset(k, t, y0, ad, pm, ipm, wm, rm)
            ad[j - n] = a
        for i in range(nx):
            d = (rp[i] - rm[i]) / (2.0 * h)
            DR[i, j] = d if math.isfinite(d) else 0.0
    _reset(k, t + h_t, y0, a0, pm, ipm, wm, rp)
    _reset(k, t - h_t, y0, a0, pm, ipm, wm, rm)
    # jump direction per unit event-time shift: DR F- + dR/dt - F+
    jump = np.empty(nx)
    for i in range(nx):
        acc = (rp[i] - rm[i]) / (2.0 * h_t)
        if not math.isfinite(acc):
            acc = 0.0
        for j in range(n):
            acc += DR[i, j] * f_minus[j]
        if i < n:
            acc -= f_plus[i]
        jump[i] = acc
    # state block of S, for the volume change
    S = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            S[i, j] = DR[i, j] - jump[i] * grad[j] / g_dot
    det = abs(np.linalg.det(S))
    Y[n + m * nx] += math.log(det) if det > 0.0 else -math.inf
    before = columns_log_volume(Y, n, nx, m, w) if volume else 0.0
    # every column: v <- DR v - jump * dt, dt = -(grad . v_y) / g_dot the event-time shift
    v = np.empty(nx)
    for c in range(m):
        b = n + c * nx
        shift = 0.0
        for j in range(n):
            shift += grad[j] * Y[b + j]
        shift /= g_dot
        for i in range(nx):
            v[i] = Y[b + i]
        for i in range(nx):
            acc = -jump[i] * shift
            for j in range(nx):
                acc += DR[i, j] * v[j]
            Y[b + i] = acc
    if volume:  # the jump of the log volume the columns span
        Y[n + m * nx + 1 + m] += columns_log_volume(Y, n, nx, m, w) - before
    for c in range(m):
        normalise(Y, n + c * nx, nx, w, n + m * nx + 1 + c)
    # a saltation can leave the defect beyond D_max (the loop evaluates the derivative after an
    # event: nothing to transform)
    if volume and defect(Y, n, nx, m, w) > d_max:
        _reorthonormalise(Y, n, nx, m, w, np.empty((m, m)))
    return stop
