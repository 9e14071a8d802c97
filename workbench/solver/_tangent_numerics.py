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


@njit(cache=True, nogil=True)
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
    """The Gram matrix ``G[a, c] = <u_a, u_c>`` of the m columns (m x m, written into G)."""
    for a in range(m):
        for c in range(a, m):
            G[a, c] = column_dot(Y, n + a * nx, n + c * nx, nx, w)
            G[c, a] = G[a, c]


@njit(cache=True, nogil=True)
def log_volume(G):
    """``ln sqrt(det G)`` of a Gram matrix by its Cholesky factorisation (G is overwritten);
    -inf where G is not positive definite (dependent columns)."""
    m = G.shape[0]
    total = 0.0
    for j in range(m):
        d = G[j, j]
        for q in range(j):
            d -= G[j, q] * G[j, q]
        if not d > 0.0:
            return -math.inf
        d = math.sqrt(d)
        G[j, j] = d
        total += math.log(d)
        for i in range(j + 1, m):
            acc = G[i, j]
            for q in range(j):
                acc -= G[i, q] * G[j, q]
            G[i, j] = acc / d
    return total


@njit(cache=True, nogil=True)
def columns_log_volume(Y, n, nx, m, w):
    """``ln`` of the volume spanned by the m columns."""
    G = np.empty((m, m))
    gram(Y, n, nx, m, w, G)
    return log_volume(G)


@njit(cache=True, nogil=True)
def defect(Y, n, nx, m, w):
    """Orthogonality defect of the columns: the sum of their log sizes minus the log of the
    volume they span (Hadamard: >= 0, 0 for orthogonal columns, +inf for dependent ones)."""
    if m == 1:
        return 0.0
    G = np.empty((m, m))
    gram(Y, n, nx, m, w, G)
    sizes = 0.0
    for a in range(m):
        if not G[a, a] > 0.0:
            return math.inf
        sizes += 0.5 * math.log(G[a, a])
    return sizes - log_volume(G)


@njit(cache=True, nogil=True)
def gram_schmidt(Y, n, nx, m, w, il, R):
    """Re-orthonormalise the m columns in place (modified Gram-Schmidt: ``U = Q R``, ``U <- Q =
    U R^-1``) and add ``log R_kk`` to the log sizes ``Y[il + k]``: the vectors ``V = U
    diag(e^l)`` then hold Benettin's accumulators in ``l``, span the same nested subspaces and
    the same volume. ``R`` (m x m, written): the upper triangular factor (a column of zero size
    is left as it is, with ``R_kk = 1`` and no projection on it)."""
    for k in range(m):
        for c in range(m):
            R[k, c] = 1.0 if c == k else 0.0
    for k in range(m):
        bk = n + k * nx
        r = math.sqrt(column_dot(Y, bk, bk, nx, w))
        if not (r > 0.0 and math.isfinite(r)):
            continue
        R[k, k] = r
        for j in range(nx):
            Y[bk + j] /= r
        Y[il + k] += math.log(r)
        for c in range(k + 1, m):
            bc = n + c * nx
            d = column_dot(Y, bk, bc, nx, w)
            R[k, c] = d
            for j in range(nx):
                Y[bc + j] -= d * Y[bk + j]


@njit(cache=True, nogil=True)
def transform_rates(L, R):
    """``L <- L R^-1`` in place for the factor ``R`` of :func:`gram_schmidt` (nx x m, upper
    triangular m x m): the rates of a linear system's columns after the change of basis ``U <-
    U R^-1`` (column c of the result: ``(L_c - sum_{k<c} L_k R_kc) / R_cc``)."""
    nx, m = L.shape
    for c in range(m):
        for i in range(nx):
            acc = L[i, c]
            for k in range(c):
                acc -= L[i, k] * R[k, c]
            L[i, c] = acc / R[c, c]


@njit(cache=True, nogil=True)
def volume_rates(Y, n, nx, m, w, D, Dm):
    """``(tr(G^-1 U^T W D), tr(G^-1 U^T W Dm))``: the rate of the log volume of the m columns
    under ``du_c/dt = D[:, c]`` (nx x m) and the part of it from ``Dm`` (n x m, the rate's
    share in the state components). NaN where the columns are dependent.

    Computed as ``sum_k <q_k, (D R^-1)_k>`` from the columns' Gram-Schmidt factors ``U = Q R``
    (the same trace: ``G^-1 U^T W = R^-1 Q^T W``), whose rounding grows with the columns'
    condition number e^D, where solving with the Gram matrix would grow with its square e^2D
    (at the defect of 10 and beyond, until a step's end re-orthonormalises them, the volume
    rate of Duffing's two vectors drifted by 1.6e-9 of the trace so)."""
    Q = np.empty((nx, m))
    for c in range(m):
        for j in range(nx):
            Q[j, c] = Y[n + c * nx + j]
    R = np.empty((m, m))
    for k in range(m):
        r = 0.0
        for j in range(nx):
            r += w[j] * Q[j, k] * Q[j, k]
        r = math.sqrt(r)
        if not (r > 0.0 and math.isfinite(r)):
            return math.nan, math.nan
        R[k, k] = r
        for j in range(nx):
            Q[j, k] /= r
        for c in range(k + 1, m):
            d = 0.0
            for j in range(nx):
                d += w[j] * Q[j, k] * Q[j, c]
            R[k, c] = d
            for j in range(nx):
                Q[j, c] -= d * Q[j, k]
    DR = D[:n, :].copy()
    DmR = Dm.copy()
    transform_rates(DR, R)
    transform_rates(DmR, R)
    total = 0.0
    memory = 0.0
    for k in range(m):
        for j in range(n):
            total += w[j] * Q[j, k] * DR[j, k]
            memory += w[j] * Q[j, k] * DmR[j, k]
    return total, memory
