"""Route (a): the parametric sensitivity of a shooting problem by one extra linear-quadratic sweep.

The LQ problem of :mod:`sensitivity.ocp_parametric` has the Hessian and the dynamics of the
Riccati recursion that factorises the solver's Newton step: P_N = H_N and, backwards,

    Quu = Huu + Fuᵀ P Fu,  Qux = Hxuᵀ + Fuᵀ P Fx,  K = Quu⁻¹ Qux,  P_k = Hxx + Fxᵀ P Fx − Kᵀ Quu K

(:func:`wbmpc.ocp.solvers.riccati.riccati_backward` with zero gradients and no regularisation:
that is the factorisation, computed once whatever the number of parameters). The sensitivity
sweep then carries only the linear terms, all m parameter columns at once (matrix-vector work per
node against the factorisation's matrix-matrix work):

    backward: s_N = q_N;  w = s_{k+1} + P_{k+1} c_k,  Qx = q_k + Fxᵀ w,  Qu = r_k + Fuᵀ w,
              k_k = Quu⁻¹ Qu,  s_k = Qx − Kᵀ Qu
    forward:  δx_0 = 0,  δu_k = −k_k − K δx_k,  δx_{k+1} = Fx δx_k + Fu δu_k + c_k

giving dx_k*/dp (tangent at x_k) and du_k*/dp. With the Gauss-Newton Hessian the factorisation is
exactly FDDP's backward pass at the solution (the solver's own factorisation can be passed).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from sensitivity.ocp_parametric import LinearQuadratic
from wbmpc.errors import ParameterError, SolverError
from wbmpc.ocp.kernels.linalg import cholesky_in_place
from wbmpc.ocp.solvers.riccati import riccati_backward


@dataclass(frozen=True)
class RiccatiFactorisation:
    """P (N + 1, ndx, ndx) value Hessians, K (N, nu, ndx) (Crocoddyl's sign, δu = −K δx), Quu (N, nu, nu)."""

    P: np.ndarray
    K: np.ndarray
    Quu: np.ndarray


@dataclass(frozen=True)
class OcpSensitivity:
    """Derivatives of a shooting problem's solution with respect to its m parameters.

    Attributes:
        dxs: (N + 1, ndx, m), dx_k*/dp in the tangent space at x_k* (row 0 is zero: x0 is fixed).
        dus: (N, nu, m), du_k*/dp.
        method: the route ("riccati", "kkt", "finite_differences") and Hessian.
        seconds: wall times of the route's parts [s].
    """

    dxs: np.ndarray
    dus: np.ndarray
    method: str
    seconds: dict


def factorise(lq: LinearQuadratic, regularization: float = 0.0) -> RiccatiFactorisation:
    """The Riccati factorisation of the LQ problem's Hessian (one backward pass); ``regularization``
    ρ >= 0 is added to the diagonals of Quu and of P as FDDP's backward pass adds its ``preg`` (0: the
    factorisation of the Hessian itself).

    Raises:
        SolverError: Quu is not positive definite at some node (no strict local minimum: the
            second-order sufficient conditions fail and the solution map has no derivative).
    """
    N, ndx = lq.Fx.shape[0], lq.Fx.shape[1]
    nu = lq.Fu.shape[2]
    P = np.zeros((N + 1, ndx, ndx))
    Vx = np.zeros((N + 1, ndx))
    K = np.zeros((N, nu, ndx))
    Quu = np.zeros((N, nu, nu))
    if not (np.isfinite(regularization) and regularization >= 0):
        raise ParameterError(f"regularization={regularization} must be finite and >= 0")
    failed = riccati_backward(lq.Fx, lq.Fu, np.zeros((N + 1, ndx)), np.zeros((N, nu)), lq.Hxx, lq.Hxu, lq.Huu,
                              np.zeros((N + 1, ndx)), float(regularization), True, Vx, P, np.zeros((N, nu)), Quu,
                              np.zeros((N, nu)), np.zeros((N, nu)), K)
    if failed >= 0:
        raise SolverError(f"the {lq.hessian} Hessian's Quu is not positive definite at node {failed}: no strict "
                          "local minimum, the solution has no parametric derivative")
    return RiccatiFactorisation(P, K, Quu)


@njit(cache=True)
def _cholesky_solve(A, B, X):
    """X = A⁻¹ B for A (n, n) positive definite (checked by the factorisation), B (n, m); the
    Cholesky factor is the solver's (:func:`wbmpc.ocp.kernels.linalg.cholesky_in_place`, lower
    triangle only)."""
    n = A.shape[0]
    L = A.copy()
    cholesky_in_place(L)
    for c in range(B.shape[1]):
        for i in range(n):  # L y = b
            s = B[i, c]
            for p in range(i):
                s -= L[i, p] * X[p, c]
            X[i, c] = s / L[i, i]
        for i in range(n - 1, -1, -1):  # Lᵀ x = y
            s = X[i, c]
            for p in range(i + 1, n):
                s -= L[p, i] * X[p, c]
            X[i, c] = s / L[i, i]


@njit(cache=True)
def _sensitivity_sweep(Fx, Fu, P, K, Quu, q, r, c, dxs, dus):
    """The backward and forward sweeps of the module docstring for the m columns of q, r, c."""
    N = Fx.shape[0]
    nu = Fu.shape[2]
    m = q.shape[2]
    kff = np.empty((N, nu, m))
    s = q[N].copy()
    for t in range(N - 1, -1, -1):
        w = s + np.dot(P[t + 1], c[t])
        Qx = q[t] + np.dot(np.ascontiguousarray(Fx[t].T), w)
        Qu = r[t] + np.dot(np.ascontiguousarray(Fu[t].T), w)
        _cholesky_solve(Quu[t], Qu, kff[t])
        s = Qx - np.dot(np.ascontiguousarray(K[t].T), Qu)
    dxs[0] = 0.0
    for t in range(N):
        dus[t] = -kff[t] - np.dot(K[t], dxs[t])
        dxs[t + 1] = np.dot(Fx[t], dxs[t]) + np.dot(Fu[t], dus[t]) + c[t]


def sweep(lq: LinearQuadratic, factorisation: RiccatiFactorisation) -> tuple[np.ndarray, np.ndarray]:
    """(dxs (N + 1, ndx, m), dus (N, nu, m)) from the factorisation: the sensitivity sweep."""
    N, ndx = lq.Fx.shape[0], lq.Fx.shape[1]
    nu, m = lq.Fu.shape[2], lq.q.shape[2]
    dxs = np.zeros((N + 1, ndx, m))
    dus = np.zeros((N, nu, m))
    _sensitivity_sweep(lq.Fx, lq.Fu, factorisation.P, factorisation.K, factorisation.Quu,
                       np.ascontiguousarray(lq.q), np.ascontiguousarray(lq.r), np.ascontiguousarray(lq.c), dxs, dus)
    return dxs, dus


def riccati_sensitivity(lq: LinearQuadratic, factorisation: RiccatiFactorisation | None = None) -> OcpSensitivity:
    """Route (a): factorise (unless given) and sweep; ``seconds`` has "factorisation" and "sweep"."""
    seconds = {}
    if factorisation is None:
        tic = time.perf_counter()
        factorisation = factorise(lq)
        seconds["factorisation"] = time.perf_counter() - tic
    tic = time.perf_counter()
    dxs, dus = sweep(lq, factorisation)
    seconds["sweep"] = time.perf_counter() - tic
    return OcpSensitivity(dxs, dus, f"riccati ({lq.hessian} Hessian)", seconds)


def time_sweep_against_riccati(lq: LinearQuadratic, repeats: int = 20) -> dict:
    """Median wall times [s] of one Riccati factorisation and of one sensitivity sweep on ``lq``
    (compiled code warmed up first), and their ratio sweep / factorisation."""
    factorisation = factorise(lq)
    sweep(lq, factorisation)
    riccati_times, sweep_times = [], []
    for _ in range(repeats):
        tic = time.perf_counter()
        factorise(lq)
        riccati_times.append(time.perf_counter() - tic)
        tic = time.perf_counter()
        sweep(lq, factorisation)
        sweep_times.append(time.perf_counter() - tic)
    riccati_s, sweep_s = float(np.median(riccati_times)), float(np.median(sweep_times))
    return {"riccati_pass_s": riccati_s, "sensitivity_sweep_s": sweep_s, "sweep_over_riccati": sweep_s / riccati_s,
            "n_parameters": int(lq.q.shape[2]), "repeats": int(repeats)}
