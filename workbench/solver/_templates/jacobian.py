"""Compiled Jacobian of a model's right-hand side (a template, specialised per model).

A model may define the optional hook

``jacobian(t, y, p, ip, aux, work, J) -> int``
    Writes ``J[i, j] = d f_i / d y_j`` (state units: (unit of y_i) s-1 / (unit of y_j)) at the
    discrete state ``aux``; returns 0 or a positive model failure code.

Where it does not, :func:`jacobian` is :func:`fd_jacobian`: central differences of the model's
compiled ``rhs`` with steps ``h_j = eps^(1/3) max(|y_j|, s_j)`` for the state scales ``s``
(the model's ``Problem.atol_scale``), whose truncation and rounding errors balance at a relative
error of ~eps^(2/3) ~ 4e-11 for a smooth right-hand side (Dennis & Schnabel 1996, Sec. 5.6).
Across a kink of the right-hand side (a contact onset, a friction-law corner) the difference
quotient mixes the two one-sided derivatives, as any Jacobian there must. :func:`fd_jacobian` is
always compiled, so that an analytic Jacobian is checked against it.

The line marked ``@@HOOKS@@`` and the one marked ``@@JACOBIAN@@`` are rewritten by
:func:`workbench.solver._compile.jacobian_for` to import the model's hooks; ``HAS_ANALYTIC`` says
whether the model has a ``jacobian`` of its own.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from workbench.solver._templates.placeholder_hooks import jacobian as model_jacobian  # @@JACOBIAN@@
from workbench.solver._templates.placeholder_hooks import rhs  # @@HOOKS@@

HAS_ANALYTIC = True  # @@FLAG@@

#: cube root of the machine epsilon: the central-difference step relative to a state's size
EPS3 = 2.220446049250313e-16 ** (1.0 / 3.0)


@njit(cache=True, nogil=True)
def step(y_j, s_j):
    """Central-difference step for a state of value ``y_j`` and scale ``s_j`` (state units),
    rounded so that ``y_j + h`` and ``y_j - h`` are exact machine numbers apart by 2 h."""
    size = abs(y_j)
    if math.isfinite(s_j) and s_j > size:
        size = s_j
    if size == 0.0:
        size = 1.0
    h = EPS3 * size
    return (y_j + h) - y_j


@njit(cache=True, nogil=True)
def fd_jacobian(t, y, p, ip, aux, work, scale, J):
    """``J[i, j] = d f_i / d y_j`` by central differences of ``rhs`` (steps: :func:`step`).

    Returns 0 or the first positive model failure code met at a displaced state.
    """
    n = y.size
    yd = y.copy()
    fp = np.empty(n)
    fm = np.empty(n)
    for j in range(n):
        h = step(y[j], scale[j])
        yd[j] = y[j] + h
        code = rhs(t, yd, p, ip, aux, work, fp)
        if code > 0:
            return code
        yd[j] = y[j] - h
        code = rhs(t, yd, p, ip, aux, work, fm)
        if code > 0:
            return code
        yd[j] = y[j]
        for i in range(n):
            J[i, j] = (fp[i] - fm[i]) / (2.0 * h)
    return 0


@njit(cache=True, nogil=True)
def fd_aux_jacobian(t, y, p, ip, aux, work, need, yd, fp, fm, Ja):
    """``Ja[i, k] = d f_i / d aux_k`` by central differences of ``rhs`` for the discrete states
    with ``need[k]`` that are active (``aux_k`` finite and nonzero: a zero discrete state means
    "inactive", e.g. no contact, and is not differenced); 0 for the others. ``aux`` is displaced
    in place and restored exactly; ``yd``, ``fp``, ``fm`` (n) are scratch. Returns 0 or a
    positive model failure code.
    """
    n = y.size
    for k in range(aux.size):
        for i in range(n):
            Ja[i, k] = 0.0
        a0 = aux[k]
        if not need[k] or a0 == 0.0 or not math.isfinite(a0):
            continue
        h = step(a0, 0.0)
        for i in range(n):  # a loop, not a slice copy: callable without reference counting
            yd[i] = y[i]
        aux[k] = a0 + h
        c1 = rhs(t, yd, p, ip, aux, work, fp)
        for i in range(n):
            yd[i] = y[i]
        aux[k] = a0 - h
        c2 = rhs(t, yd, p, ip, aux, work, fm)
        aux[k] = a0
        if c1 > 0:
            return c1
        if c2 > 0:
            return c2
        for i in range(n):
            Ja[i, k] = (fp[i] - fm[i]) / (2.0 * h)
    return 0


@njit(cache=True, nogil=True)
def jacobian(t, y, p, ip, aux, work, scale, J):
    """The model's Jacobian ``J[i, j] = d f_i / d y_j``: its analytic hook where it has one,
    else :func:`fd_jacobian`. ``scale`` (state units) sizes the difference steps."""
    if HAS_ANALYTIC:
        return model_jacobian(t, y, p, ip, aux, work, J)
    return fd_jacobian(t, y, p, ip, aux, work, scale, J)


@njit(cache=True, nogil=True)
def jacobians_along(t, Y, AUX, p, ip, work, scale, Js, Jas):
    """:func:`jacobian` (into ``Js[k]``) and :func:`fd_aux_jacobian` (every active discrete
    state, into ``Jas[k]``) at every record (rows of ``Y`` and ``AUX``); returns the model
    failure code per record (0 where fine)."""
    codes = np.zeros(t.size, np.int64)
    n = Y.shape[1]
    need = np.ones(AUX.shape[1], np.bool_)
    yd = np.empty(n)
    fp = np.empty(n)
    fm = np.empty(n)
    for k in range(t.size):
        codes[k] = jacobian(t[k], Y[k], p, ip, AUX[k], work, scale, Js[k])
        if codes[k] == 0:
            aux = AUX[k].copy()
            codes[k] = fd_aux_jacobian(t[k], Y[k], p, ip, aux, work, need, yd, fp, fm, Jas[k])
    return codes
