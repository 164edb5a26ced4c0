"""Riccati backward pass of FDDP, compiled with numba over the stacked node derivatives.

Crocoddyl's sign inside (δu = −k − K δx); :class:`wbmpc.ocp.solvers.fddp.SolverFDDP` exposes the
library sign. The Cholesky factor L of Quu is written out (nu is small) and inverted, so the gains
come from one product [K | k] = L⁻ᵀ L⁻¹ [Qxuᵀ | Qu]; every product goes to BLAS through
``np.dot`` into preallocated buffers.
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
    FxT = np.empty((ndx, ndx))
    FuT = np.empty((nu, ndx))
    FxTVxx = np.empty((ndx, ndx))
    FuTVxx = np.empty((nu, ndx))
    Qxx = np.empty((ndx, ndx))
    Qxu = np.empty((ndx, nu))
    Qx = np.empty(ndx)
    QuuInv = np.empty((nu, nu))
    Kk = np.empty((nu, ndx + 1))
    QxuK = np.empty((ndx, ndx))
    product_x = np.empty(ndx)  # matrix-vector products, written in place (no allocation per node)
    product_u = np.empty(nu)
    Vx_t = np.empty(ndx)
    for t in range(N - 1, -1, -1):
        FxT[:, :] = Fx[t].T
        FuT[:, :] = Fu[t].T
        np.dot(FxT, Vxx[t + 1], FxTVxx)
        np.dot(FuT, Vxx[t + 1], FuTVxx)
        np.dot(FxT, Vx[t + 1], product_x)
        for i in range(ndx):
            Qx[i] = Lx[t, i] + product_x[i]
        np.dot(FxTVxx, Fx[t], Qxx)
        Qxx += Lxx[t]
        np.dot(FuT, Vx[t + 1], product_u)
        for i in range(nu):
            Qu[t, i] = Lu[t, i] + product_u[i]
        np.dot(FuTVxx, Fu[t], Quu[t])
        Quu[t] += Luu[t]
        np.dot(FxTVxx, Fu[t], Qxu)
        Qxu += Lxu[t]
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
