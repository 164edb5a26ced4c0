"""How the feedback gains of a solved shooting problem move with its parameters: dK/dp.

The gains the whole-body MPC hands to the robot are those of FDDP's backward pass at its converged
solution (xs*, us*)(p): with the dynamics Jacobians (Fx, Fu), the **Gauss-Newton** cost blocks
(Lxx, Lxu, Luu: no residual curvature, no λᵀ∇²f) and the solver's regularisation ρ (``preg``, added
to the diagonals of Quu and of P; reg_min = 1e-9 at convergence),

    P_N = Lxx_N + ρ I,   Quu = Luu + Fuᵀ P' Fu + ρ I,   Qux = Lxuᵀ + Fuᵀ P' Fx,   Qxx = Lxx + Fxᵀ P' Fx,
    K = Quu⁻¹ Qux,   P = sym(Qxx − Quxᵀ K) + ρ I                       (P' = P_{k+1})

(:func:`wbmpc.ocp.solvers.riccati.riccati_backward`, Crocoddyl's sign: δu = −K δx). The library hands
out −K (``SolverFDDP.K``, ∂u*/∂x: u = u* + K_lib (x ⊖ x*)), and so do :class:`GainSensitivity` and
:func:`solver_gains`. That K is what is differentiated: the solver's own gains, Gauss-Newton as the
solver's are (the exact-Hessian factorisation, which the solution's derivative needs, has other
gains, which no controller uses). Its total derivative in p_j is the derivative of the recursion along

    Ḃ_j = d/dε B(x* ⊕ ε dx*/dp_j, u* + ε du*/dp_j; p + ε e_j) |_{ε=0}

for every block B ∈ {Fx, Fu, Lxx, Lxu, Luu} of every node: the blocks move with the parameter itself
(a node's spacing, a reference) and with the solution (dx*/dp, du*/dp: the exact-Hessian sensitivity
of :mod:`sensitivity.ocp_riccati`). Ḃ holds second derivatives of the contact dynamics and third
derivatives of the costs, which the model does not give: :func:`block_derivatives` takes central
differences of its analytic first derivatives along that direction (two evaluations of the whole
problem per parameter; the step is cut so that no dead-zone row, e.g. a saturated torque's barrier,
crosses its kink, where the Gauss-Newton curvature jumps). The recursion is then differentiated
exactly (:func:`gain_derivatives`), backwards from dP_N = dLxx_N:

    dQuu = dLuu + dFuᵀ P' Fu + Fuᵀ P' dFu + Fuᵀ dP' Fu,   dQux = dLxuᵀ + dFuᵀ P' Fx + Fuᵀ P' dFx + Fuᵀ dP' Fx,
    dQxx = dLxx + dFxᵀ P' Fx + Fxᵀ P' dFx + Fxᵀ dP' Fx,   dK = Quu⁻¹ (dQux − dQuu K),
    dP = sym(dQxx − dQuxᵀ K − Quxᵀ dK).

All blocks are in the problem's charts (tangent at x_k for the input, at f_k for the output), which
move with the solution as they do when the problem is re-solved at p + ε e_j: dK/dp is the derivative
of the numbers the solver returns, what central differences of re-solved gains measure.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numba import njit

from sensitivity.ocp_parametric import LinearQuadratic, dead_zone_step
from sensitivity.ocp_riccati import RiccatiFactorisation, _cholesky_solve, factorise
from wbmpc.errors import ParameterError


@dataclass(frozen=True)
class BlockDerivatives:
    """Ḃ of the module docstring, the parameter axis last: dFx (N, ndx, ndx, m), dFu (N, ndx, nu, m),
    dLxx (N + 1, ndx, ndx, m) (row N: the terminal node), dLxu (N, ndx, nu, m), dLuu (N, nu, nu, m);
    ``steps`` (m,): the central-difference step ε used for each parameter (in its unit)."""

    dFx: np.ndarray
    dFu: np.ndarray
    dLxx: np.ndarray
    dLxu: np.ndarray
    dLuu: np.ndarray
    steps: np.ndarray


@dataclass(frozen=True)
class GainSensitivity:
    """The solver's gains and their derivative, the library's sign (``SolverFDDP.K``, ∂u*/∂x = −Quu⁻¹ Qux):
    K (N, nu, ndx) [N·m per unit of the state component], dK (N, nu, ndx, m) [that per parameter unit],
    the factorisation they come from (Crocoddyl's sign there) and the wall times [s] of the parts."""

    K: np.ndarray
    dK: np.ndarray
    factorisation: RiccatiFactorisation
    seconds: dict


def gauss_newton_lq(problem) -> LinearQuadratic:
    """The problem's Riccati blocks after calcDiff (Fx, Fu, Gauss-Newton Lxx, Lxu, Luu), as an LQ
    problem without linear terms (m = 0): what :func:`sensitivity.ocp_riccati.factorise` reads."""
    N, ndx, nu = problem.T, problem.ndx, problem.nu
    return LinearQuadratic(problem.Fx.copy(), problem.Fu.copy(), problem.Lxx.copy(), problem.Lxu.copy(),
                           problem.Luu.copy(), np.zeros((N + 1, ndx, 0)), np.zeros((N, nu, 0)), np.zeros((N, ndx, 0)),
                           "gauss-newton")


def solver_gains(problem, xs, us, regularization: float) -> np.ndarray:
    """K (N, nu, ndx) of FDDP's backward pass at (xs, us) with regularisation ρ, the library's sign
    (``SolverFDDP.K``); evaluates the problem."""
    problem.calc_and_diff(xs, us)
    return -factorise(gauss_newton_lq(problem), regularization).K


def block_derivatives(problem, set_parameters, parameters, xs, us, dxs: np.ndarray, dus: np.ndarray,
                      step: float = 1e-6) -> BlockDerivatives:
    """Ḃ_j (module docstring) by central differences along (dx*/dp_j, du*/dp_j, e_j).

    Args:
        problem: the shooting problem, at the parameters ``parameters``.
        set_parameters: p (m,) -> None, re-parameterises the problem in place.
        parameters: the base p (m,).
        xs, us: the converged solution (N + 1, nx), (N, nu).
        dxs, dus: its derivative (N + 1, ndx, m) (tangent at x_k), (N, nu, m).
        step: the largest ε [parameter unit], > 0; cut per parameter to a quarter of the ε at which
            a dead-zone row of some node would reach its bound (that row's residual moves with x and u
            only, not with p directly, in this library's OCPs).

    Leaves the problem at ``parameters``, evaluated at (xs, us).
    """
    if not (np.isfinite(step) and step > 0):
        raise ParameterError(f"step={step} must be finite and > 0")
    p0 = np.asarray(parameters, dtype=float)
    state = problem.state
    N, m = problem.T, p0.size
    problem.calc_and_diff(xs, us)
    datas = problem.running_datas + [problem.terminal_data]
    steps = np.full(m, float(step))
    for j in range(m):
        for k, data in enumerate(datas):
            direction = np.concatenate([dxs[k, :, j], dus[k, :, j] if k < N else np.zeros(problem.nu)])
            steps[j] = min(steps[j], 0.25 * dead_zone_step(data.differential.costs, direction))
    names = ("Fx", "Fu", "Lxx", "Lxu", "Luu")
    out = {name: np.zeros(getattr(problem, name).shape + (m,)) for name in names}
    try:
        for j in range(m):
            eps = steps[j]
            for sign in (1.0, -1.0):
                p = p0.copy()
                p[j] += sign * eps
                set_parameters(p)
                moved = np.array([state.integrate(x, sign * eps * dx) for x, dx in zip(xs, dxs[..., j])])
                problem.calc_and_diff(moved, us + sign * eps * dus[..., j])
                for name in names:
                    out[name][..., j] += sign * getattr(problem, name) / (2.0 * eps)
    finally:
        set_parameters(p0)
        problem.calc_and_diff(xs, us)
    return BlockDerivatives(out["Fx"], out["Fu"], out["Lxx"], out["Lxu"], out["Luu"], steps)


@njit(cache=True)
def _gain_derivative_sweep(Fx, Fu, P, K, Quu, dFx, dFu, dLxx, dLxu, dLuu, dK, dP):
    """The backward recursion of the module docstring; derivative arrays parameter-first (m, N, ...)."""
    m = dFx.shape[0]
    N = Fx.shape[0]
    nu, ndx = K.shape[1], K.shape[2]
    for j in range(m):
        dP[j, N] = dLxx[j, N]
    rhs = np.empty((nu, m * ndx))
    solution = np.empty((nu, m * ndx))
    for t in range(N - 1, -1, -1):
        FxT = np.ascontiguousarray(Fx[t].T)
        FuT = np.ascontiguousarray(Fu[t].T)
        PFx = np.dot(P[t + 1], Fx[t])
        PFu = np.dot(P[t + 1], Fu[t])
        PFuT = np.ascontiguousarray(PFu.T)
        PFxT = np.ascontiguousarray(PFx.T)
        Qux = np.dot(Quu[t], K[t])  # = Lxuᵀ + Fuᵀ P' Fx (K = Quu⁻¹ Qux, Quu with ρ)
        dQxx_all = np.empty((m, ndx, ndx))
        dQux_all = np.empty((m, nu, ndx))
        for j in range(m):
            dFuT = np.ascontiguousarray(dFu[j, t].T)
            dFxT = np.ascontiguousarray(dFx[j, t].T)
            dPn = dP[j, t + 1]
            dQuu = dLuu[j, t] + np.dot(dFuT, PFu) + np.dot(PFuT, dFu[j, t]) + np.dot(FuT, np.dot(dPn, Fu[t]))
            dQux = (np.ascontiguousarray(dLxu[j, t].T) + np.dot(dFuT, PFx) + np.dot(PFuT, dFx[j, t])
                    + np.dot(FuT, np.dot(dPn, Fx[t])))
            dQxx_all[j] = dLxx[j, t] + np.dot(dFxT, PFx) + np.dot(PFxT, dFx[j, t]) + np.dot(FxT, np.dot(dPn, Fx[t]))
            dQux_all[j] = dQux
            rhs[:, j * ndx:(j + 1) * ndx] = dQux - np.dot(dQuu, K[t])
        _cholesky_solve(Quu[t], rhs, solution)
        QuxT = np.ascontiguousarray(Qux.T)
        for j in range(m):
            dK[j, t] = solution[:, j * ndx:(j + 1) * ndx]
            dPt = dQxx_all[j] - np.dot(np.ascontiguousarray(dQux_all[j].T), K[t]) - np.dot(QuxT, dK[j, t])
            dP[j, t] = 0.5 * (dPt + dPt.T)


def gain_derivatives(lq: LinearQuadratic, blocks: BlockDerivatives, regularization: float,
                     factorisation: RiccatiFactorisation | None = None) -> GainSensitivity:
    """K and dK/dp (module docstring) from the Gauss-Newton LQ blocks (:func:`gauss_newton_lq`, or the
    "gauss-newton" :func:`sensitivity.ocp_parametric.linear_quadratic`), their derivatives and the
    solver's regularisation ρ; ``factorisation``: that LQ's factorisation with ρ, if already made."""
    if lq.hessian != "gauss-newton":
        raise ParameterError(f"lq.hessian={lq.hessian!r}: the solver's gains come from the Gauss-Newton blocks")
    seconds = {}
    if factorisation is None:
        tic = time.perf_counter()
        factorisation = factorise(lq, regularization)
        seconds["factorisation"] = time.perf_counter() - tic
    first = lambda a: np.ascontiguousarray(np.moveaxis(a, -1, 0))
    m = blocks.dFx.shape[-1]
    N, nu, ndx = factorisation.K.shape
    dK = np.zeros((m, N, nu, ndx))
    dP = np.zeros((m, N + 1, ndx, ndx))
    tic = time.perf_counter()
    _gain_derivative_sweep(lq.Fx, lq.Fu, factorisation.P, factorisation.K, factorisation.Quu, first(blocks.dFx),
                           first(blocks.dFu), first(blocks.dLxx), first(blocks.dLxu), first(blocks.dLuu), dK, dP)
    seconds["recursion"] = time.perf_counter() - tic
    return GainSensitivity(-factorisation.K, -np.moveaxis(dK, 0, -1), factorisation, seconds)


def time_gain_recursion(lq: LinearQuadratic, blocks: BlockDerivatives, regularization: float,
                        repeats: int = 10) -> dict:
    """Median wall times [s] of the gains' derivative recursion and of one Riccati factorisation of the
    same LQ (compiled code warmed up first), and their ratio."""
    factorisation = factorise(lq, regularization)
    gain_derivatives(lq, blocks, regularization, factorisation)
    recursion, riccati = [], []
    for _ in range(repeats):
        tic = time.perf_counter()
        factorise(lq, regularization)
        riccati.append(time.perf_counter() - tic)
        recursion.append(gain_derivatives(lq, blocks, regularization, factorisation).seconds["recursion"])
    recursion_s, riccati_s = float(np.median(recursion)), float(np.median(riccati))
    return {"gain_recursion_s": recursion_s, "gain_recursion_over_riccati": recursion_s / riccati_s}
