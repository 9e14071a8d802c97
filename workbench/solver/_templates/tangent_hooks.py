"""Compiled tangent (variational) system of a model, with saltation at events (a template,
specialised per model by :func:`workbench.solver._compile.tangent_for`).

The state of the tangent system is ``Y = [y (n), U (m columns of nx = n + na), L, l (m), W, M,
K, W0, M0]``: the model's state ``y``; ``m`` tangent vectors of the *extended* state ``x = (y,
aux)`` (the discrete state ``aux`` is part of the state the future depends on: a contact's held
onset velocity sets its damping), each stored as a direction ``u`` of unit size and its log
size ``l`` (``v = e^l u``); ``L``, the sum of ``log |det S_yy|`` over the events so far
(the state block of each saltation matrix); with re-orthonormalisation (below) the log volume
``W`` the vectors span and the part ``M`` of it that the discrete state fed back between events,
and the count ``K`` of re-orthonormalisations (with ``normalisation="step"`` ``W`` and ``M``
are integrated from 0 in every step, their values taken out into ``W0`` and ``M0`` at its end, so
that the solver controls the error of each step's increment, not of the whole accumulated
volume: the volume is ``W0 + W``). Sizes, angles and volumes are those of the state
divided by its scales ``s`` and the discrete state by its scales ``s_a`` (a discrete state that
the flow does not depend on, such as a counter, has none and is left out: see
:mod:`workbench.solver._tangent_numerics`).

Between events ``dy/dt = f(t, y, aux)`` and for each column ``v = (v_y, v_a)``

    dv_y/dt = J_y v_y + J_a v_a,        dv_a/dt = 0,

with ``J_y = df/dy`` and ``J_a = df/daux``. Each column's rate ``J_y v_y + J_a v_a`` is a
directional derivative: from the model's analytic ``jacobian`` hook (``J_a`` by central
differences over the discrete states that a column carries and that are active: ``aux_k != 0``,
a zero discrete state means "inactive", e.g. no contact), else one central difference of ``rhs``
along ``(v_y, v_a)`` (the state and the carried active discrete states displaced together: two
evaluations per column, with the step DIRECTION_STEP, shortened near event surfaces).

Each vector is stored as a direction ``u`` and its log size ``l`` (``v = e^l u``). By default
(``normalisation="step"``) ``u`` follows the linear equations above between the ends of the
solver's steps, and at the end of every accepted step (the loop's ``step_end`` hook) its size is
taken out into ``l`` (``u`` scaled to unit size, its derivative likewise: a change of basis of a
linear system, no evaluation and no restart). The solver then controls the error of every
component relative to the vector's size (``atol s_i`` is ``atol`` times it), which is what the
accuracy of a direction means: a vector that grows by e^20 between re-orthonormalisations (the
nine-bar's chaos does so within a fraction of a second) would otherwise hold components far
below the rounding of its derivative, and the step size would collapse. The tangent system's
own rates are then those of the model's Jacobian, and the steps those the model takes to the
same tolerance. With ``normalisation="continuous"`` (for a system integrated without the
``step_end`` hook, such as copies of it side by side) the size is taken out by a rate instead:

    du/dt = (J_y u_y + J_a u_a, 0) - a u,        dl/dt = a,

with ``a = <u, du/dt + a u> / <u, u>`` (continuous normalisation, e.g. Geist, Parlitz &
Lauterborn 1990, Prog. Theor. Phys. 83, 875), which keeps the size of ``u`` but shifts the
rates of its other components by ``-a``: up to twice the spectral radius of the Jacobian, and
steps to match.

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
(the directions have unit size after). An event located in time (as this system did
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
``ip = [model ip, n, na, m, ne, len(model p), len(model ip), model work size, flags]`` (flags:
1 re-orthonormalise, 2 normalise at steps' ends); ``work = [model work, scratch]`` (the scratch
laid out by :func:`workbench.solver._tangent_numerics.scratch`, so that the hooks called at
every evaluation allocate nothing); the kernel's ``aux`` is the model's.
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
    scratch,
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
#: (190 515 steps over 0.2 s where the model takes 2 073; 3 396 at 1e-4). A forward difference
#: (one evaluation) is no substitute: its truncation error is first order in the step, which
#: near a contact (Hertz: delta^1.5) biased the free journal's tangent map by 7.6e-4 at 1e-4,
#: and a shorter step's noise took 100 times the model's steps at rtol 1e-10.
DIRECTION_STEP = 1e-4
#: Near an event surface the step is shortened so that the stencil changes no event function by
#: more than SURFACE_FRACTION of its value: at a contact's onset and end the rhs varies on the
#: scale of the penetration itself (Hertz: delta^1.5, relative truncation error
#: (step / delta)^2 / 24), and the long step biased the nine-bar's tangent map over four
#: contacts by 8.6e-3 (7.0e-5 with the shortening; 1.3e-4 with the cube-root step). Not below
#: MIN_STEP_FACTOR times the step, whose rounding noise would return.
SURFACE_FRACTION = 0.02
MIN_STEP_FACTOR = 1e-3
#: largest change of an active discrete state across the stencil, relative to its value (the
#: stencil shortens where a direction's discrete-state component would move it further: a
#: grazing contact's onset velocity)
AUX_FRACTION = 1e-3


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
    return (ip[ip.size - 1] & 1) != 0


@njit(cache=True, nogil=True, inline="always")
def _linear(ip):
    """Whether the vectors follow their linear equations, their sizes taken out at every
    step's end (else: continuously normalised)."""
    return (ip[ip.size - 1] & 2) != 0


@njit(cache=True, nogil=True, inline="always")
def _linear_rates(n, nx, m, D, il, dY):
    """The directions' rates under the linear flow, from ``D`` (m x n by rows, flat: a row per
    vector, its state components; the discrete state's are zero), and their log sizes' (zero:
    the sizes are taken out at steps' ends and events)."""
    for c in range(m):
        b = n + c * nx
        for i in range(n):
            dY[b + i] = D[c * n + i]
        for k in range(n, nx):
            dY[b + k] = 0.0
        dY[il + c] = 0.0


@njit(cache=True, nogil=True, inline="always")
def _carried(Y, n, nx, m, w, aux, k):
    """Whether discrete state k enters the vectors' rates: weighted (the flow depends on it),
    active (nonzero and finite: a zero discrete state means "inactive", e.g. no contact) and
    nonzero in some direction."""
    if not (w[n + k] > 0.0 and aux[k] != 0.0 and math.isfinite(aux[k])):
        return False
    for c in range(m):
        if Y[n + c * nx + n + k] != 0.0:
            return True
    return False


@njit(cache=True, nogil=True, inline="always")
def _normalised_rates(Y, n, nx, m, w, D, il, dY):
    """Continuous normalisation: from the rates ``D`` of the vectors' state blocks (m x n by
    rows, flat: a row per vector), the rates of the normalised directions u (their
    discrete-state blocks included) and of their log sizes l (at ``il``): l takes the growth
    rate a of u, and u loses it."""
    for c in range(m):
        b = n + c * nx
        size = column_dot(Y, b, b, nx, w)
        rate = 0.0
        for i in range(n):
            rate += w[i] * Y[b + i] * D[c * n + i]
        a = rate / size if size > 0.0 else 0.0
        for i in range(n):
            dY[b + i] = D[c * n + i] - a * Y[b + i]
        for k in range(n, nx):
            dY[b + k] = -a * Y[b + k]
        dY[il + c] = a


@njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def rhs(t, Y, p, ip, aux, work, dY):
    n, na, m, ne, pm, ipm, wm, scale, w, _, _ = _layout(p, ip, work)
    nx = n + na
    y = Y[:n]
    f0 = dY[:n]
    code = model_rhs(t, y, pm, ipm, aux, wm, f0)
    if code > 0:
        return code
    yd, fp, fm, ja, jy, D, Dm, DR, DmR, _, Q, R, _, a0, carried, g0, gd = scratch(
        work, wm.size, n, na, m, ne
    )
    volume = _reorthonormalising(ip)
    memory = volume and m == n  # the discrete state's share of the volume: all n vectors only
    any_carried = False
    for k in range(na):
        a0[k] = aux[k]
        carried[k] = 1.0 if _carried(Y, n, nx, m, w, aux, k) else 0.0
        any_carried = any_carried or carried[k] > 0.0
    if any_carried and (HAS_ANALYTIC or memory):  # J_a's columns of the carried states
        c1 = fd_aux_jacobian(t, y, pm, ipm, aux, wm, carried, yd, fp, fm, ja.reshape((n, na)))
        if c1 > 0:
            return c1
    if ne > 0 and not HAS_ANALYTIC:
        model_event_values(t, y, pm, ipm, aux, wm, g0)
    if HAS_ANALYTIC:
        c1 = jacobian(t, y, pm, ipm, aux, wm, scale, jy.reshape((n, n)))
        if c1 > 0:
            return c1
        for c in range(m):
            b = n + c * nx
            for i in range(n):
                acc = 0.0
                for j in range(n):
                    acc += jy[i * n + j] * Y[b + j]
                for k in range(na):
                    if carried[k] > 0.0:
                        acc += ja[i * na + k] * Y[b + n + k]
                D[c * n + i] = acc
    else:
        # one central difference per vector along (u_y, u_a): J_y u_y + J_a u_a in two
        # evaluations
        for c in range(m):
            b = n + c * nx
            acc = 0.0
            for j in range(n):
                acc += (Y[b + j] / scale[j]) ** 2
            for k in range(na):
                if carried[k] > 0.0:
                    acc += w[n + k] * Y[b + n + k] * Y[b + n + k]
            size = math.sqrt(acc)
            if not size > 0.0:
                for i in range(n):
                    D[c * n + i] = 0.0
                continue
            eps = DIRECTION_STEP / size
            for k in range(na):
                if carried[k] > 0.0:
                    change = eps * abs(Y[b + n + k])
                    allowed = AUX_FRACTION * abs(a0[k])
                    if change > allowed:
                        eps *= allowed / change
            if ne > 0:
                eps = _near_surface_step(t, y, Y, b, eps, carried, a0, pm, ipm, aux, wm, g0, gd, yd)
            _displace(y, Y, b, eps, carried, a0, aux, yd)
            c1 = model_rhs(t, yd, pm, ipm, aux, wm, fp)
            _displace(y, Y, b, -eps, carried, a0, aux, yd)
            c2 = model_rhs(t, yd, pm, ipm, aux, wm, fm)
            for k in range(na):
                aux[k] = a0[k]
            if c1 > 0:
                return c1
            if c2 > 0:
                return c2
            inv = 0.5 / eps
            for i in range(n):
                D[c * n + i] = (fp[i] - fm[i]) * inv
    if memory:
        for c in range(m):
            b = n + c * nx
            for i in range(n):
                acc = 0.0
                for k in range(na):
                    if carried[k] > 0.0:
                        acc += ja[i * na + k] * Y[b + n + k]
                Dm[c * n + i] = acc
    iv = n + m * nx + 1 + m  # W, M, K and the parts of W and M taken out at steps' ends
    dY[n + m * nx] = 0.0
    for i in range(iv, iv + 5):
        dY[i] = 0.0
    if volume:
        dY[iv], dY[iv + 1] = volume_rates(Y, n, nx, m, w, D, Dm, memory, Q, R, DR, DmR)
    if _linear(ip):
        _linear_rates(n, nx, m, D, n + m * nx + 1, dY)
    else:
        _normalised_rates(Y, n, nx, m, w, D, n + m * nx + 1, dY)
    return code


@njit(cache=True, nogil=True, inline="always")
def _displace(y, Y, b, h, carried, a0, aux, yd):
    """``yd = y + h u_y`` and the carried discrete states ``aux = a0 + h u_a`` for the column
    ``u`` at ``Y[b]``."""
    n = y.size
    for j in range(n):
        yd[j] = y[j] + h * Y[b + j]
    for k in range(a0.size):
        if carried[k] > 0.0:
            aux[k] = a0[k] + h * Y[b + n + k]


@njit(cache=True, nogil=True, inline="always")
def _near_surface_step(t, y, Y, b, eps, carried, a0, pm, ipm, aux, wm, g0, gd, yd):
    """The difference step along the column at ``Y[b]`` (a multiple of ``eps``), shortened so
    that no event function changes by more than SURFACE_FRACTION of its value at ``y``
    (``g0``) across the stencil: near a contact's onset and end the rhs varies on the scale
    of the penetration itself (Hertz: delta^1.5), and a longer stencil would bias the
    derivative. ``gd``, ``yd``: scratch; ``aux`` is restored to ``a0``."""
    for _ in range(2):  # g is close to linear across the stencil: one correction suffices
        _displace(y, Y, b, eps, carried, a0, aux, yd)
        model_event_values(t, yd, pm, ipm, aux, wm, gd)
        for k in range(a0.size):
            aux[k] = a0[k]
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


@njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def step_end(t, Y, p, ip, aux, work, dY):
    """At the end of an accepted step (the loop's ``step_end`` hook), with the state ``Y`` and
    its derivative ``dY`` there: where the directions' orthogonality defect exceeds D_max,
    re-orthonormalise them (``U <- U R^-1``, ``l_k += log R_kk``); else, for vectors on the
    model's steps, take their sizes out into their log sizes (``R`` diagonal). ``dY``
    transforms alike, without an evaluation. Returns 1 where the representation changed, else
    0.

    Both are changes of basis of the span of a linear system: the linear part of each
    direction's rate, ``L(u_c) = du_c/dt + a_c u_c = (J_y u_y + J_a u_a, 0)`` (``a_c = 0`` on
    the model's steps), transforms by the same ``R^-1``, the new directions' rates follow from
    it, and the rates of the volume ``W`` and of its memory part ``M`` (traces on the span) do
    not change."""
    n, na, m, ne, _, _, wm, _, w, _, d_max = _layout(p, ip, work)
    nx = n + na
    linear = _linear(ip)
    _, _, _, _, _, _, _, _, _, L, _, R, G, _, _, _, _ = scratch(work, wm.size, n, na, m, ne)
    orthonormalise = m > 1 and _reorthonormalising(ip) and defect(Y, n, nx, m, w, G) > d_max
    if not (orthonormalise or linear):
        return 0
    il = n + m * nx + 1
    for c in range(m):  # the state rows; the discrete state's are zero
        b = n + c * nx
        for i in range(n):
            L[c * n + i] = dY[b + i] + dY[il + c] * Y[b + i]
    if orthonormalise:
        gram_schmidt(Y, n, nx, m, w, il, R)
        Y[il + m + 2] += 1.0
        transform_rates(L, R, m, n)
    else:
        for c in range(m):
            b = n + c * nx
            size = math.sqrt(column_dot(Y, b, b, nx, w))
            if size > 0.0 and math.isfinite(size):
                inv = 1.0 / size
                for j in range(nx):
                    Y[b + j] *= inv
                for i in range(n):
                    L[c * n + i] *= inv
                Y[il + c] += math.log(size)
    if linear:
        _linear_rates(n, nx, m, L, il, dY)
        iv = il + m  # W and M start every step from 0 (their error then scales with the step's
        # increment, not with the whole accumulated volume)
        Y[iv + 3] += Y[iv]
        Y[iv + 4] += Y[iv + 1]
        Y[iv] = 0.0
        Y[iv + 1] = 0.0
    else:
        _normalised_rates(Y, n, nx, m, w, L, il, dY)
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
    if volume and defect(Y, n, nx, m, w, np.empty(m * m)) > d_max:
        gram_schmidt(Y, n, nx, m, w, n + m * nx + 1, np.empty(m * m))
        Y[n + m * nx + 1 + m + 2] += 1.0
    return stop
