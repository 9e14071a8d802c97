"""Compiled system of several copies of a model integrated side by side (a template,
specialised per model by :func:`workbench.solver._compile.copies_for`).

The state is ``Y = [y_0, y_1, ..., y_K]`` (K + 1 copies of the model's n states), the discrete
state ``aux = [aux_0, ..., aux_K, (L_c, N_c, P_c) for c = 1..K]`` and the event functions are
those of every copy, so event ``k < (K + 1) ne`` is event ``k % ne`` of copy ``k // ne``. One
step-size sequence serves every copy: nearby copies then make nearly the same integration error
in every step, and their *difference* is integrated far more accurately than the tolerance
(two separate runs would each make their own error of the size of the tolerance, which impacts
amplify).

With renormalisation on, copies 1..K follow the fiducial copy 0 at scaled separations ``d0_c``
(each state divided by its size ``s``) for the two-trajectory Lyapunov exponent (Benettin et al.
1976, 1980). Each copy has two events on its log separation ``x_c = log(d_c / d0_c)``: growth,
event ``(K + 1) ne + c - 1``, fires where ``x_c`` rises to ``G_c + P_c``; shrinkage, event
``(K + 1) ne + K + c - 1``, where it falls to ``-(G_c + P_c)``. Either way (one update, whatever
the sign of ``x_c``: Benettin et al. 1980 rescale whatever the change) copy c is moved along its
separation back to ``d0_c`` (its discrete state linearised about the fiducial's the same way),
``L_c`` adds ``x_c`` (negative on shrinkage), ``N_c`` counts (``S_c`` counts the shrinkages) and
``P_c`` returns to 0. Renormalising on the separation's change, not on a clock, keeps every copy
in the linear range through the bursts of stretching at impacts, whatever their rate, and, on
shrinkage, above the integration's noise on a contracting orbit, where a copy renormalised only
on growth shrinks onto the fiducial trajectory until its separation is noise, and the noise's
growth is then measured. The band ``|x_c| < G_c`` is symmetric about ``d0_c`` in the log:
``d0`` balances the round-off error (relative size eps / d) against the curvature (relative size
d), so both stay within the same factor ``exp(G_c)`` of their balance. A copy is renormalised
only where it and the fiducial copy lie on the same side of every event surface and agree on
which discrete states are active (zero or not): pulled back across a contact surface it would
sit in a contact with no held onset velocity, or hold one out of contact. Elsewhere the
renormalisation waits (``P_c`` grows by G_c / 4, widening the band both ways) until they agree
again. A copy at zero separation has no direction to be rescaled along: neither of its events
fires (the caller reports it).

Separations are measured and renormalised in the first ``nm`` states of each copy (all of them
for a model; the model's own states when the copies are of a tangent system, whose fiducial
copy alone carries a tangent vector, so that the two-trajectory and the variational exponents
follow one fiducial trajectory).

Layout: ``p = [model p, s (n), (d0_c, G_c) for c = 1..K]``; ``ip = [model ip, n, na, ne,
copies, len(model p), renormalise (0/1), nm]``; ``aux = [aux_0 .. aux_K, (L_c, N_c, P_c, S_c) for
c = 1..K]`` (``SLOTS`` per copy, also without renormalisation); the copies share the model's
scratch ``work``, which the hooks use only within a call.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from workbench.solver._templates.placeholder_hooks import (
    apply_event as model_apply_event,  # @@HOOKS@@
)
from workbench.solver._templates.placeholder_hooks import (
    event_values as model_event_values,  # @@HOOKS@@
)
from workbench.solver._templates.placeholder_hooks import rhs as model_rhs  # @@HOOKS@@

N_META = 7
#: discrete states per copy after the first: log growth L, renormalisations N, wait P, shrinkages S
SLOTS = 4


@njit(cache=True, nogil=True)
def _meta(ip):
    """(n, na, ne, copies, len(model p), renormalise) from the tail of ``ip``."""
    k = ip.size - N_META
    return ip[k], ip[k + 1], ip[k + 2], ip[k + 3], ip[k + 4], ip[k + 5]


@njit(cache=True, nogil=True)
def _measured(ip):
    """How many leading states of a copy its separation is measured and renormalised in."""
    return ip[ip.size - 1]


@njit(cache=True, nogil=True)
def rhs(t, Y, p, ip, aux, work, dY):
    n, na, ne, copies, npm, renorm = _meta(ip)
    pm = p[:npm]
    ipm = ip[: ip.size - N_META]
    result = 0
    for c in range(copies):
        code = model_rhs(
            t, Y[c * n : (c + 1) * n], pm, ipm, aux[c * na : (c + 1) * na], work,
            dY[c * n : (c + 1) * n],
        )  # fmt: skip
        if code > 0:
            return code
        if code != 0:
            result = code
    return result


@njit(cache=True, nogil=True)
def separation(Y, p, n, npm, c, nm):
    """Scaled distance between copy c and the fiducial copy 0 in their first ``nm`` states."""
    acc = 0.0
    for i in range(nm):
        d = (Y[c * n + i] - Y[i]) / p[npm + i]
        acc += d * d
    return math.sqrt(acc)


@njit(cache=True, nogil=True)
def event_values(t, Y, p, ip, aux, work, g):
    n, na, ne, copies, npm, renorm = _meta(ip)
    pm = p[:npm]
    ipm = ip[: ip.size - N_META]
    for c in range(copies):
        model_event_values(
            t, Y[c * n : (c + 1) * n], pm, ipm, aux[c * na : (c + 1) * na], work,
            g[c * ne : (c + 1) * ne],
        )  # fmt: skip
    if renorm:
        renormalised = copies - 1
        for c in range(1, copies):
            d0 = p[npm + n + 2 * (c - 1)]
            growth = p[npm + n + 2 * (c - 1) + 1]
            wait = aux[copies * na + SLOTS * (c - 1) + 2]
            d = separation(Y, p, n, npm, c, _measured(ip))
            if d > 0.0:
                x = math.log(d / d0)
                g[copies * ne + c - 1] = x - growth - wait
                g[copies * ne + renormalised + c - 1] = -x - growth - wait
            else:
                g[copies * ne + c - 1] = -math.inf
                g[copies * ne + renormalised + c - 1] = -math.inf


@njit(cache=True, nogil=True)
def apply_event(k, t, Y, p, ip, aux, work):
    n, na, ne, copies, npm, renorm = _meta(ip)
    if k < copies * ne:
        c = k // ne
        return model_apply_event(
            k % ne, t, Y[c * n : (c + 1) * n], p[:npm], ip[: ip.size - N_META],
            aux[c * na : (c + 1) * na], work,
        )  # fmt: skip
    c = k - copies * ne + 1  # growth events first, then the shrinkage events
    shrink = c >= copies
    if shrink:
        c -= copies - 1
    d0 = p[npm + n + 2 * (c - 1)]
    base = copies * na + SLOTS * (c - 1)
    if not _same_mode(t, Y, p, ip, aux, work, c):
        aux[base + 2] += 0.25 * p[npm + n + 2 * (c - 1) + 1]
        return 0
    nm = _measured(ip)
    d = separation(Y, p, n, npm, c, nm)
    f = d0 / d
    for i in range(nm):
        Y[c * n + i] = Y[i] + (Y[c * n + i] - Y[i]) * f
    for i in range(na):
        aux[c * na + i] = aux[i] + (aux[c * na + i] - aux[i]) * f
    aux[base] += math.log(d / d0)
    aux[base + 1] += 1.0
    aux[base + 2] = 0.0
    if shrink:
        aux[base + 3] += 1.0
    return 0


@njit(cache=True, nogil=True)
def _same_mode(t, Y, p, ip, aux, work, c):
    """Whether copy c and copy 0 lie on the same side of every event surface (g <= 0 or
    g > 0) and agree on which discrete states are active (nonzero)."""
    n, na, ne, copies, npm, renorm = _meta(ip)
    pm = p[:npm]
    ipm = ip[: ip.size - N_META]
    for i in range(na):
        if (aux[i] == 0.0) != (aux[c * na + i] == 0.0):
            return False
    if ne == 0:
        return True
    g0 = np.empty(ne)
    gc = np.empty(ne)
    model_event_values(t, Y[:n], pm, ipm, aux[:na], work, g0)
    model_event_values(t, Y[c * n : (c + 1) * n], pm, ipm, aux[c * na : (c + 1) * na], work, gc)
    for k in range(ne):
        if (g0[k] > 0.0) != (gc[k] > 0.0):
            return False
    return True
