"""Route (c): the parametric sensitivity of a shooting problem from its full KKT system.

The LQ problem of :mod:`sensitivity.ocp_parametric` written as one linear system in all the
unknowns z = (δx_0 … δx_N, δu_0 … δu_{N−1}) and the multipliers μ_0 … μ_N of the initial condition
and the dynamics,

    [ H   Aᵀ ] [ z ]   [ −g ]        A z = b:  δx_0 = 0,  δx_{k+1} − Fx_k δx_k − Fu_k δu_k = c_k,
    [ A   0  ] [ μ ] = [  b ]        g = (q_0 … q_N, r_0 … r_{N−1}),

assembled and solved at once (dense LU for small horizons, sparse LU otherwise): no recursion, no
factorisation shared with route (a), the same Hessian H.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from sensitivity.ocp_parametric import LinearQuadratic
from sensitivity.ocp_riccati import OcpSensitivity
from wbmpc.errors import ParameterError

KKT_SOLVERS = ("auto", "dense", "sparse")


def kkt_system(lq: LinearQuadratic) -> tuple[sp.csc_matrix, np.ndarray]:
    """The KKT matrix (sparse, size n = (N + 1) ndx + N nu + (N + 1) ndx) and right-hand sides (n, m)."""
    N, ndx = lq.Fx.shape[0], lq.Fx.shape[1]
    nu, m = lq.Fu.shape[2], lq.q.shape[2]
    nx_all = (N + 1) * ndx
    nz = nx_all + N * nu
    n = nz + (N + 1) * ndx
    xi = lambda k: slice(k * ndx, (k + 1) * ndx)
    ui = lambda k: slice(nx_all + k * nu, nx_all + (k + 1) * nu)
    mi = lambda k: slice(nz + k * ndx, nz + (k + 1) * ndx)
    M = sp.lil_matrix((n, n))
    rhs = np.zeros((n, m))
    eye = np.eye(ndx)
    for k in range(N + 1):
        M[xi(k), xi(k)] = lq.Hxx[k]
        rhs[xi(k)] = -lq.q[k]
        if k < N:
            M[xi(k), ui(k)] = lq.Hxu[k]
            M[ui(k), xi(k)] = lq.Hxu[k].T
            M[ui(k), ui(k)] = lq.Huu[k]
            rhs[ui(k)] = -lq.r[k]
    M[mi(0), xi(0)] = eye
    M[xi(0), mi(0)] = eye
    for k in range(N):
        rows = mi(k + 1)
        M[rows, xi(k + 1)] = eye
        M[rows, xi(k)] = -lq.Fx[k]
        M[rows, ui(k)] = -lq.Fu[k]
        M[xi(k + 1), rows] = eye
        M[xi(k), rows] = -lq.Fx[k].T
        M[ui(k), rows] = -lq.Fu[k].T
        rhs[rows] = lq.c[k]
    return M.tocsc(), rhs


def kkt_sensitivity(lq: LinearQuadratic, solver: str = "auto", dense_limit: int = 3000) -> OcpSensitivity:
    """Route (c): solve the full KKT system; ``solver`` "dense" (numpy LU), "sparse" (SuperLU) or
    "auto" (dense up to ``dense_limit`` unknowns)."""
    if solver not in KKT_SOLVERS:
        raise ParameterError(f"solver={solver!r} must be one of {KKT_SOLVERS}")
    N, ndx = lq.Fx.shape[0], lq.Fx.shape[1]
    nu = lq.Fu.shape[2]
    tic = time.perf_counter()
    M, rhs = kkt_system(lq)
    assembled = time.perf_counter()
    if solver == "dense" or (solver == "auto" and M.shape[0] <= dense_limit):
        solution = np.linalg.solve(M.toarray(), rhs)
        used = "dense"
    else:
        solution = spla.splu(M).solve(rhs)
        used = "sparse"
    solved = time.perf_counter()
    nx_all = (N + 1) * ndx
    dxs = solution[:nx_all].reshape(N + 1, ndx, -1)
    dus = solution[nx_all:nx_all + N * nu].reshape(N, nu, -1)
    return OcpSensitivity(dxs, dus, f"kkt ({used}, {lq.hessian} Hessian, {M.shape[0]} unknowns)",
                          {"assembly": assembled - tic, "solve": solved - assembled})
