"""Hook-free linear algebra of the tangent system
(:mod:`workbench.solver._templates.tangent_hooks`), compiled once for all models: the tangent
directions' sizes, their re-orthonormalisation, the volume they span and its rate.

The directions are the columns ``u_c = Y[b_c : b_c + nx]`` of the tangent-system state (``b_c =
n + c nx``, ``nx = n + na``: state then discrete-state components). Sizes and angles are taken
in the inner product ``<u, v> = sum_j w_j u_j v_j`` with weights ``w = [1 / s^2 (n), 1 / s_a^2
(na)]`` from the state scales ``s`` and the discrete-state scales ``s_a`` (0 for a discrete
state the flow does not depend on). Algorithms: modified Gram-Schmidt and the Cholesky
factorisation (Golub & Van Loan 2013, Algorithms 5.2.6 and 4.2.1); the volume spanned by m
columns is ``sqrt(det G)`` for their Gram matrix ``G``, and the rate of its logarithm under
``du/dt = D`` is ``tr(G^-1 U^T W D)`` (W = diag(w)).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


def scratch_size(n: int, na: int, m: int, ne: int) -> int:
    """Floats of scratch the tangent system's hooks take from ``work`` (see :func:`scratch`)."""
    return 3 * n + n * na + n * n + 5 * m * n + m * (n + na) + 2 * m * m + 2 * na + 2 * ne


@njit(cache=True, nogil=True, inline="always")
def scratch(work, o, n, na, m, ne):
    """Views of ``work[o:]`` (:func:`scratch_size` floats), allocated once per run so that the
    hooks called at every evaluation and step allocate nothing; flat, matrices by rows: a
    displaced state ``yd`` and two derivatives ``fp``, ``fm`` (n each), ``J_a`` (n x na) and
    ``J_y`` (n x n); the vectors' rates ``D``, their discrete state's share ``Dm``, the two
    transformed by the directions' triangular factor (``DR``, ``DmR``) and the linear rates
    ``L`` at a step's end (m x n each, a row per vector: its state components); the directions'
    orthonormalised copy ``Q`` (m x nx, a row per vector), a triangular factor ``R`` and a Gram
    matrix ``G`` (m x m each); per discrete state its value ``a0`` and a flag ``carried`` (1.0
    or 0.0; na each); the event functions at the state and at a displaced one, ``g0`` and
    ``gd`` (ne each)."""
    yd = work[o : o + n]
    fp = work[o + n : o + 2 * n]
    fm = work[o + 2 * n : o + 3 * n]
    o += 3 * n
    ja = work[o : o + n * na]
    o += n * na
    jy = work[o : o + n * n]
    o += n * n
    mn = m * n
    D = work[o : o + mn]
    Dm = work[o + mn : o + 2 * mn]
    DR = work[o + 2 * mn : o + 3 * mn]
    DmR = work[o + 3 * mn : o + 4 * mn]
    L = work[o + 4 * mn : o + 5 * mn]
    o += 5 * mn
    Q = work[o : o + m * (n + na)]
    o += m * (n + na)
    R = work[o : o + m * m]
    G = work[o + m * m : o + 2 * m * m]
    o += 2 * m * m
    a0 = work[o : o + na]
    carried = work[o + na : o + 2 * na]
    o += 2 * na
    g0 = work[o : o + ne]
    gd = work[o + ne : o + 2 * ne]
    return yd, fp, fm, ja, jy, D, Dm, DR, DmR, L, Q, R, G, a0, carried, g0, gd


@njit(cache=True, nogil=True, inline="always")
def column_dot(Y, b1, b2, nx, w):
    """``<u, v>`` of the columns starting at ``Y[b1]`` and ``Y[b2]``."""
    acc = 0.0
    for j in range(nx):
        acc += w[j] * Y[b1 + j] * Y[b2 + j]
    return acc


@njit(cache=True, nogil=True)
def normalise(Y, b, nx, w, il):
    """Scale the column at ``Y[b]`` to unit size and add the log of its size to ``Y[il]`` (a
    column of zero size is left as it is)."""
    size = math.sqrt(column_dot(Y, b, b, nx, w))
    if size > 0.0 and math.isfinite(size):
        for j in range(nx):
            Y[b + j] /= size
        Y[il] += math.log(size)


@njit(cache=True, nogil=True)
def gram(Y, n, nx, m, w, G):
    """The Gram matrix ``G[a, c] = <u_a, u_c>`` of the m columns (m x m by rows, flat, written
    into G)."""
    for a in range(m):
        for c in range(a, m):
            G[a * m + c] = column_dot(Y, n + a * nx, n + c * nx, nx, w)
            G[c * m + a] = G[a * m + c]


@njit(cache=True, nogil=True)
def log_volume(G, m):
    """``ln sqrt(det G)`` of a Gram matrix (m x m by rows, flat) by its Cholesky factorisation
    (G is overwritten); -inf where G is not positive definite (dependent columns)."""
    total = 0.0
    for j in range(m):
        d = G[j * m + j]
        for q in range(j):
            d -= G[j * m + q] * G[j * m + q]
        if not d > 0.0:
            return -math.inf
        d = math.sqrt(d)
        G[j * m + j] = d
        total += math.log(d)
        for i in range(j + 1, m):
            acc = G[i * m + j]
            for q in range(j):
                acc -= G[i * m + q] * G[j * m + q]
            G[i * m + j] = acc / d
    return total


@njit(cache=True, nogil=True)
def columns_log_volume(Y, n, nx, m, w):
    """``ln`` of the volume spanned by the m columns."""
    G = np.empty(m * m)
    gram(Y, n, nx, m, w, G)
    return log_volume(G, m)


@njit(cache=True, nogil=True)
def defect(Y, n, nx, m, w, G):
    """Orthogonality defect of the columns: the sum of their log sizes minus the log of the
    volume they span (Hadamard: >= 0, 0 for orthogonal columns, +inf for dependent ones).
    ``G``: m x m scratch."""
    if m == 1:
        return 0.0
    gram(Y, n, nx, m, w, G)
    sizes = 0.0
    for a in range(m):
        if not G[a * m + a] > 0.0:
            return math.inf
        sizes += 0.5 * math.log(G[a * m + a])
    return sizes - log_volume(G, m)


@njit(cache=True, nogil=True)
def gram_schmidt(Y, n, nx, m, w, il, R):
    """Re-orthonormalise the m columns in place (modified Gram-Schmidt: ``U = Q R``, ``U <- Q =
    U R^-1``) and add ``log R_kk`` to the log sizes ``Y[il + k]``: the vectors ``V = U
    diag(e^l)`` then hold Benettin's accumulators in ``l``, span the same nested subspaces and
    the same volume. ``R`` (m x m by rows, flat, written): the upper triangular factor (a
    column of zero size is left as it is, with ``R_kk = 1`` and no projection on it)."""
    for k in range(m):
        for c in range(m):
            R[k * m + c] = 1.0 if c == k else 0.0
    for k in range(m):
        bk = n + k * nx
        r = math.sqrt(column_dot(Y, bk, bk, nx, w))
        if not (r > 0.0 and math.isfinite(r)):
            continue
        R[k * m + k] = r
        for j in range(nx):
            Y[bk + j] /= r
        Y[il + k] += math.log(r)
        for c in range(k + 1, m):
            bc = n + c * nx
            d = column_dot(Y, bk, bc, nx, w)
            R[k * m + c] = d
            for j in range(nx):
                Y[bc + j] -= d * Y[bk + j]


@njit(cache=True, nogil=True, inline="always")
def transform_rates(L, R, m, n):
    """``L <- L R^-1`` in place for the factor ``R`` of :func:`gram_schmidt` (m x m, upper
    triangular) and the rates ``L`` of the columns (m x n, a row per column: its state
    components), both by rows and flat: the rates of a linear system's columns after the change
    of basis ``U <- U R^-1`` (row c of the result: ``(L_c - sum_{k<c} R_kc L_k) / R_cc``)."""
    for c in range(m):
        for k in range(c):
            rkc = R[k * m + c]
            for i in range(n):
                L[c * n + i] -= rkc * L[k * n + i]
        inv = 1.0 / R[c * m + c]
        for i in range(n):
            L[c * n + i] *= inv


@njit(cache=True, nogil=True, inline="always")
def volume_rates(Y, n, nx, m, w, D, Dm, memory, Q, R, DR, DmR):
    """``(tr(G^-1 U^T W D), tr(G^-1 U^T W Dm))``: the rate of the log volume of the m columns
    under ``du_c/dt = D_c`` (m x n by rows, flat: each column's state components; the discrete
    state's are zero) and the part of it from ``Dm`` (0 without ``memory``). NaN where the
    columns are dependent. ``Q`` (m x nx), ``R`` (m x m), ``DR``, ``DmR`` (m x n): scratch.

    Computed as ``sum_k <q_k, (D R^-1)_k>`` from the columns' Gram-Schmidt factors ``U = Q R``
    (the same trace: ``G^-1 U^T W = R^-1 Q^T W``), whose rounding grows with the columns'
    condition number, where solving with the Gram matrix would grow with its square."""
    for c in range(m):
        for j in range(nx):
            Q[c * nx + j] = Y[n + c * nx + j]
        for i in range(n):
            DR[c * n + i] = D[c * n + i]
            DmR[c * n + i] = Dm[c * n + i] if memory else 0.0
    for k in range(m):
        r = 0.0
        for j in range(nx):
            r += w[j] * Q[k * nx + j] * Q[k * nx + j]
        r = math.sqrt(r)
        if not (r > 0.0 and math.isfinite(r)):
            return math.nan, math.nan
        R[k * m + k] = r
        inv = 1.0 / r
        for j in range(nx):
            Q[k * nx + j] *= inv
        for c in range(k + 1, m):
            d = 0.0
            for j in range(nx):
                d += w[j] * Q[k * nx + j] * Q[c * nx + j]
            R[k * m + c] = d
            for j in range(nx):
                Q[c * nx + j] -= d * Q[k * nx + j]
    transform_rates(DR, R, m, n)
    if memory:
        transform_rates(DmR, R, m, n)
    total = 0.0
    share = 0.0
    for k in range(m):
        for i in range(n):
            total += w[i] * Q[k * nx + i] * DR[k * n + i]
            share += w[i] * Q[k * nx + i] * DmR[k * n + i]
    return total, share
