"""Riccati backward pass of FDDP, compiled with numba over the stacked node derivatives.

Crocoddyl's sign inside (δu = −k − K δx); :class:`wbmpc.solvers.fddp.SolverFDDP` exposes the
library sign. The Cholesky factorisation of Quu and its solves are written out (nu is small);
the products go to BLAS through ``np.dot``.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _cholesky_in_place(A):
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
def _cholesky_solve(L, B):
    """Solve (L Lᵀ) X = B in place for B (n, m)."""
    n, m = B.shape
    for c in range(m):
        for i in range(n):
            s = B[i, c]
            for p in range(i):
                s -= L[i, p] * B[p, c]
            B[i, c] = s / L[i, i]
        for i in range(n - 1, -1, -1):
            s = B[i, c]
            for p in range(i + 1, n):
                s -= L[p, i] * B[p, c]
            B[i, c] = s / L[i, i]


@njit(cache=True)
def riccati_backward(Fx, Fu, Lx, Lu, Lxx, Lxu, Luu, fs, preg, is_feasible, Vx, Vxx, Qu, Quu, Quuk, k, K):
    """Fill Vx (N+1, ndx), Vxx (N+1, ndx, ndx), Qu, Quu, Quuk, k (N, nu), K (N, nu, ndx).

    Returns -1 on success, else the node index where Quu was not positive definite or the
    value function was not finite.
    """
    N = Fx.shape[0]
    ndx = Fx.shape[1]
    nu = Fu.shape[2]
    Vxx[N] = Lxx[N]
    for i in range(ndx):
        Vxx[N, i, i] += preg
    Vx[N] = Lx[N]
    if not is_feasible:
        Vx[N] += np.dot(Vxx[N], fs[N])
    L = np.empty((nu, nu))
    rhs = np.empty((nu, ndx + 1))
    for t in range(N - 1, -1, -1):
        FxT = np.ascontiguousarray(Fx[t].T)
        FuT = np.ascontiguousarray(Fu[t].T)
        FxTVxx = np.dot(FxT, Vxx[t + 1])
        Qx = Lx[t] + np.dot(FxT, Vx[t + 1])
        Qxx = Lxx[t] + np.dot(FxTVxx, Fx[t])
        Qu[t] = Lu[t] + np.dot(FuT, Vx[t + 1])
        Quu[t] = Luu[t] + np.dot(np.dot(FuT, Vxx[t + 1]), Fu[t])
        Qxu = Lxu[t] + np.dot(FxTVxx, Fu[t])
        for i in range(nu):
            Quu[t, i, i] += preg
        L[:, :] = Quu[t]
        if not _cholesky_in_place(L):
            return t
        for i in range(nu):
            for j in range(ndx):
                rhs[i, j] = Qxu[j, i]
            rhs[i, ndx] = Qu[t, i]
        _cholesky_solve(L, rhs)
        for i in range(nu):
            for j in range(ndx):
                K[t, i, j] = rhs[i, j]
            k[t, i] = rhs[i, ndx]
        Quuk[t] = np.dot(Quu[t], k[t])
        Kt = K[t]
        Vx_t = Qx - np.dot(np.ascontiguousarray(Kt.T), Qu[t])
        Vxx_t = Qxx - np.dot(Qxu, Kt)
        for i in range(ndx):
            for j in range(i, ndx):
                s = 0.5 * (Vxx_t[i, j] + Vxx_t[j, i])
                Vxx[t, i, j] = s
                Vxx[t, j, i] = s
            Vxx[t, i, i] += preg
        if not is_feasible:
            Vx_t = Vx_t + np.dot(Vxx[t], fs[t])
        Vx[t] = Vx_t
        if not (np.all(np.isfinite(Vx_t)) and np.all(np.isfinite(Vxx[t]))):
            return t
    return -1
