"""Small dense linear algebra for the numba kernels: 3x3 products written out (inside a compiled
loop ``np.dot`` on 3x3 blocks calls BLAS and allocates its result, ~180 ns, where these take
~13 ns; they write into ``out``, which must not alias the inputs, and are inlined into their
callers), the cross-product matrix, a sum of quadratic forms over a horizon, and the Cholesky
factor and triangular inverse the Riccati pass and the KKT dynamics use."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def mat3_mul(A, B, out):
    """out = A B, all (3, 3)."""
    for i in range(3):
        a0, a1, a2 = A[i, 0], A[i, 1], A[i, 2]
        for j in range(3):
            out[i, j] = a0 * B[0, j] + a1 * B[1, j] + a2 * B[2, j]


@njit(cache=True, inline="always")
def mat3_tmul(A, B, out):
    """out = Aᵀ B, all (3, 3)."""
    for i in range(3):
        a0, a1, a2 = A[0, i], A[1, i], A[2, i]
        for j in range(3):
            out[i, j] = a0 * B[0, j] + a1 * B[1, j] + a2 * B[2, j]


@njit(cache=True, inline="always")
def mat3_vec(A, x, out):
    """out = A x, A (3, 3), x and out (3,)."""
    x0, x1, x2 = x[0], x[1], x[2]
    for i in range(3):
        out[i] = A[i, 0] * x0 + A[i, 1] * x1 + A[i, 2] * x2


@njit(cache=True, inline="always")
def mat3_tvec(A, x, out):
    """out = Aᵀ x, A (3, 3), x and out (3,)."""
    x0, x1, x2 = x[0], x[1], x[2]
    for i in range(3):
        out[i] = A[0, i] * x0 + A[1, i] * x1 + A[2, i] * x2


@njit(cache=True, inline="always")
def skew_into(w, out):
    """out (3, 3) = [w]×, the cross-product matrix of w (3,)."""
    out[0, 0] = 0.0
    out[1, 1] = 0.0
    out[2, 2] = 0.0
    out[0, 1] = -w[2]
    out[0, 2] = w[1]
    out[1, 0] = w[2]
    out[1, 2] = -w[0]
    out[2, 0] = -w[1]
    out[2, 1] = w[0]


@njit(cache=True)
def skew3(w):
    """[w]×, shape (3, 3)."""
    S = np.empty((3, 3))
    skew_into(w, S)
    return S


@njit(cache=True)
def sum_quadratic_forms(a, M, b):
    """Σ_t a[t]ᵀ M[t] b[t] for a, b (T, n) and M (T, n, n)."""
    total = 0.0
    T, n = a.shape
    for t in range(T):
        for i in range(n):
            ai = a[t, i]
            if ai == 0.0:
                continue
            s = 0.0
            for j in range(n):
                s += M[t, i, j] * b[t, j]
            total += ai * s
    return total


@njit(cache=True)
def cholesky_in_place(A):
    """Lower Cholesky factor of A (n, n) written in its lower triangle; False if not PD."""
    n = A.shape[0]
    for j in range(n):
        s = A[j, j]
        for p in range(j):
            s -= A[j, p] * A[j, p]
        if not (s > 0.0):
            return False
        d = np.sqrt(s)
        A[j, j] = d
        for i in range(j + 1, n):
            s = A[i, j]
            for p in range(j):
                s -= A[i, p] * A[j, p]
            A[i, j] = s / d
    return True


@njit(cache=True)
def lower_triangular_inverse(L, Linv):
    """Linv = L⁻¹ for a lower-triangular L (n, n) with a positive diagonal (lower triangle only).

    Linv[i, j] = (−Σ_{p=j}^{i−1} L[i, p] Linv[p, j]) / L[i, i], each sum taken in increasing p (the
    textbook order, to the last bit), the products of one p applied to row i of Linv at once (row p
    of Linv is contiguous: the compiler vectorises it).
    """
    n = L.shape[0]
    Linv[:, :] = 0.0
    for i in range(n):
        Linv[i, i] = 1.0 / L[i, i]
        for p in range(i):
            lip = L[i, p]
            for j in range(p + 1):
                Linv[i, j] -= lip * Linv[p, j]
        for j in range(i):
            Linv[i, j] = Linv[i, j] / L[i, i]
