"""Dense LU decomposition with partial pivoting and its solves, real or complex, in place and
without allocation (the implicit method's Newton matrices are small: a mechanism's handful of
states). Golub & Van Loan (2013), Algorithms 3.4.1 (Gaussian elimination with partial
pivoting) and 3.1.1-3.1.2 (triangular solves); one source serves float64 and complex128
arrays (numba compiles one version per type).
"""

from __future__ import annotations

from numba import njit


@njit(cache=True, nogil=True)
def lu_factor(A, piv):
    """Overwrite ``A`` (n x n) by its LU factors (unit lower triangle below the diagonal), row
    interchanges in ``piv``. Returns 0, or 1 + the index of the first zero pivot (singular)."""
    n = A.shape[0]
    for k in range(n):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            v = abs(A[i, k])
            if v > big:
                big = v
                p = i
        piv[k] = p
        if big == 0.0:
            return k + 1
        if p != k:
            for j in range(n):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
        inv = 1.0 / A[k, k]
        for i in range(k + 1, n):
            A[i, k] *= inv
            lik = A[i, k]
            if lik != 0.0:
                for j in range(k + 1, n):
                    A[i, j] -= lik * A[k, j]
    return 0


@njit(cache=True, nogil=True)
def lu_solve(LU, piv, b):
    """Overwrite ``b`` by the solution x of A x = b, with A's factors from :func:`lu_factor`."""
    n = LU.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(1, n):
        acc = b[i]
        for j in range(i):
            acc -= LU[i, j] * b[j]
        b[i] = acc
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, n):
            acc -= LU[i, j] * b[j]
        b[i] = acc / LU[i, i]
