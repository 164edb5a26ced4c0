"""Riccati backward pass of FDDP, compiled with numba over the stacked node derivatives.

Crocoddyl's sign inside (δu = −k − K δx); :class:`wbmpc.ocp.solvers.fddp.SolverFDDP` exposes the
library sign. Per node the Q blocks come from two products with [Fx Fu] (Vxx' [Fx Fu], then
[Fx Fu]ᵀ of it: Qxx, Qxu and Quu at once, 13 % faster on the H1's ndx = 50, nu = 19 than five
separate products); the Cholesky factor L of Quu is written out (nu is small) and inverted, so the
gains come from one product [K | k] = L⁻ᵀ L⁻¹ [Qxuᵀ | Qu]; every product goes to BLAS through
``np.dot`` into preallocated buffers. (numba caches a kernel with the kernels it inlines, L⁻¹ among
them, by this file's stamp: a change to those invalidates nothing here unless this file changes too.)
"""

from __future__ import annotations

import numpy as np
from numba import njit

from wbmpc.ocp.kernels.linalg import cholesky_in_place, lower_triangular_inverse


@njit(cache=True)
def _all_finite(v, M):
    """True if every entry of v (n,) and M (n, n) is finite."""
    for i in range(v.size):
        if not np.isfinite(v[i]):
            return False
    for i in range(M.shape[0]):
        for j in range(M.shape[1]):
            if not np.isfinite(M[i, j]):
                return False
    return True


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
    Linv = np.empty((nu, nu))
    rhs = np.empty((nu, ndx + 1))  # [Qxuᵀ | Qu]
    m = ndx + nu
    Fxu = np.empty((ndx, m))  # [Fx | Fu] of the node: one pair of products gives Qxx, Qxu and Quu
    VFxu = np.empty((ndx, m))
    Q = np.empty((m, m))
    Qv = np.empty(m)
    Qxx = np.empty((ndx, ndx))
    Qxu = np.empty((ndx, nu))
    Qx = np.empty(ndx)
    QuuInv = np.empty((nu, nu))
    Kk = np.empty((nu, ndx + 1))
    QxuK = np.empty((ndx, ndx))
    product_x = np.empty(ndx)  # matrix-vector products, written in place (no allocation per node)
    Vx_t = np.empty(ndx)
    for t in range(N - 1, -1, -1):
        Fxu[:, :ndx] = Fx[t]
        Fxu[:, ndx:] = Fu[t]
        np.dot(Vxx[t + 1], Fxu, VFxu)
        np.dot(Fxu.T, VFxu, Q)  # [Fx Fu]ᵀ Vxx' [Fx Fu]
        np.dot(Fxu.T, Vx[t + 1], Qv)
        for i in range(ndx):
            Qx[i] = Lx[t, i] + Qv[i]
            for j in range(ndx):
                Qxx[i, j] = Q[i, j] + Lxx[t, i, j]
            for j in range(nu):
                Qxu[i, j] = Q[i, ndx + j] + Lxu[t, i, j]
        for i in range(nu):
            Qu[t, i] = Lu[t, i] + Qv[ndx + i]
            for j in range(nu):
                Quu[t, i, j] = Q[ndx + i, ndx + j] + Luu[t, i, j]
        for i in range(nu):
            Quu[t, i, i] += preg
        L[:, :] = Quu[t]
        if not cholesky_in_place(L):
            return t
        # Quu⁻¹ = L⁻ᵀ L⁻¹, then [K | k] = Quu⁻¹ [Qxuᵀ | Qu] in one BLAS product
        lower_triangular_inverse(L, Linv)
        np.dot(Linv.T, Linv, QuuInv)
        rhs[:, :ndx] = Qxu.T
        rhs[:, ndx] = Qu[t]
        np.dot(QuuInv, rhs, Kk)
        K[t] = Kk[:, :ndx]
        k[t] = Kk[:, ndx]
        np.dot(Quu[t], k[t], Quuk[t])
        Kt = K[t]
        np.dot(Kt.T, Qu[t], product_x)
        for i in range(ndx):
            Vx_t[i] = Qx[i] - product_x[i]
        np.dot(Qxu, Kt, QxuK)
        for i in range(ndx):
            for j in range(i, ndx):
                s = 0.5 * (Qxx[i, j] - QxuK[i, j] + Qxx[j, i] - QxuK[j, i])
                Vxx[t, i, j] = s
                Vxx[t, j, i] = s
            Vxx[t, i, i] += preg
        if not is_feasible:
            np.dot(Vxx[t], fs[t], product_x)
            for i in range(ndx):
                Vx_t[i] += product_x[i]
        Vx[t] = Vx_t
        if not _all_finite(Vx_t, Vxx[t]):
            return t
    return -1
