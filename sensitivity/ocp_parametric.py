"""The optimality conditions of a shooting problem and their derivatives with respect to parameters p.

For a shooting problem (:class:`wbmpc.ocp.problem.ShootingProblem`) whose nodes depend on
parameters p (m,), written in the local coordinates δx_k (tangent at x_k), δu_k of a converged
solution, with the dynamics δx_{k+1} = g_k(δx_k, δu_k; p) = f_k(x_k ⊕ δx_k, u_k + δu_k; p) ⊖ x_{k+1}
(linear in δx_{k+1}, so the only curvature is f's) and the Lagrangian

    ℒ = Σ_k ℓ_k(x_k ⊕ δx_k, u_k + δu_k; p) + ℓ_N + Σ_k λ_{k+1}ᵀ (g_k − δx_{k+1}) + λ_0ᵀ (x0 ⊖ x_0 − δx_0),

the first-order conditions at δ = 0 are the costate recursion λ_N = ∇ℓ_N, λ_k = Lx_k + Fx_kᵀ λ_{k+1},
Lu_k + Fu_kᵀ λ_{k+1} = 0 and the dynamics (λ estimated by the Riccati pass's value gradient,
:func:`costates`). The implicit-function theorem gives d(δx, δu, δλ)/dp from
the linear-quadratic problem

    min Σ_k ½ [δx; δu]ᵀ H_k [δx; δu] + [q_k; r_k]ᵀ [δx; δu] + ½ δx_Nᵀ H_N δx_N + q_Nᵀ δx_N
    s.t. δx_0 = 0, δx_{k+1} = Fx_k δx_k + Fu_k δu_k + c_k

(one column of q, r, c per parameter) with

- H_k = ∇²ℒ_k, the Hessian of ℓ_k + λ_{k+1}ᵀ g_k (:func:`lagrangian_hessians`, "exact"), or the
  Gauss-Newton blocks (Lxx, Lxu, Luu) FDDP uses ("gauss-newton": no residual curvature, no
  λᵀ∇²f term); the first gives the derivative of the true solution map, the second an
  approximation of it (quantified against re-solved OCPs in docs/sensitivity.md);
- q_k = ∂_p[Lx_k + Fx_kᵀ J_diffᵀ λ_{k+1}], r_k = ∂_p[Lu_k + Fu_kᵀ J_diffᵀ λ_{k+1}] at fixed
  (x, u, λ), c_k = ∂f_k/∂p and q_N = ∂Lx_N/∂p (:func:`linear_terms`), J_diff = ∂(y ⊖ x_{k+1})/∂y
  at y = f_k (identity at p, but moving with f_k). The parameters of this library enter f only
  through the node spacing (time scaling), so ∂(Fxᵀ λ)/∂p = ∂(Fxᵀ λ)/∂dt · ∂dt/∂p.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbmpc.errors import ParameterError, SolverError
from wbmpc.ocp.solvers.riccati import riccati_backward

HESSIANS = ("exact", "gauss-newton")


@dataclass(frozen=True)
class ParameterDerivatives:
    """First-order derivatives of the nodes with respect to p (m,) at fixed (x, u).

    Attributes:
        dxnext: (N, ndx, m), ∂f_k/∂p in the tangent space at f_k(x_k, u_k).
        dLx: (N + 1, ndx, m), ∂Lx_k/∂p (row N: the terminal node).
        dLu: (N, nu, m), ∂Lu_k/∂p.
        ddt: (N, m), ∂dt_k/∂p of the node spacings (None: p does not scale time), which brings the
            costate term ∂(Fxᵀ λ)/∂dt of :func:`linear_terms`.
    """

    dxnext: np.ndarray
    dLx: np.ndarray
    dLu: np.ndarray
    ddt: np.ndarray | None = None

    @property
    def n_parameters(self) -> int:
        return self.dxnext.shape[2]


@dataclass(frozen=True)
class LinearQuadratic:
    """The sensitivity LQ problem (module docstring): Fx (N, ndx, ndx), Fu (N, ndx, nu), Hxx
    (N + 1, ndx, ndx), Hxu (N, ndx, nu), Huu (N, nu, nu), q (N + 1, ndx, m) (row N: q_N),
    r (N, nu, m), c (N, ndx, m); ``hessian`` says which Hessian H is."""

    Fx: np.ndarray
    Fu: np.ndarray
    Hxx: np.ndarray
    Hxu: np.ndarray
    Huu: np.ndarray
    q: np.ndarray
    r: np.ndarray
    c: np.ndarray
    hessian: str


def check_converged(stop: float, th_stop: float, is_feasible: bool = True) -> None:
    """Refuse a base solution that is not a converged, feasible FDDP solution.

    Args:
        stop: the solver's stopping value (|d1 + d2/2| of its last iteration).
        th_stop: the largest stop accepted, > 0.
        is_feasible: the solution has no gaps.

    Raises:
        ParameterError: stop >= th_stop, stop not finite, or the solution is infeasible.
    """
    if not (np.isfinite(th_stop) and th_stop > 0):
        raise ParameterError(f"th_stop={th_stop} must be finite and > 0")
    if not (np.isfinite(stop) and stop < th_stop):
        raise ParameterError(f"solver stop={stop:.3g} must be < th_stop={th_stop:.3g}: the base solution is not "
                             "converged (solve it further)")
    if not is_feasible:
        raise ParameterError("solver is_feasible=False: the base solution has gaps (solve it further)")


COSTATE_METHODS = ("value-gradient", "open-loop")


def costates(problem, method: str = "value-gradient") -> np.ndarray:
    """λ (N + 1, ndx), the dynamics' multipliers at a converged solution (needs calcDiff there).

    At an exact optimum λ_N = Lx_N, λ_k = Lx_k + Fx_kᵀ λ_{k+1} and Lu_k + Fu_kᵀ λ_{k+1} = 0. A solver's
    solution is optimal to Qu ≠ 0 only, and ``method`` says which estimate of λ is returned:

    - "value-gradient" (default): the value gradient Vx_k of the Riccati pass at the solution (the
      problem's gradients, Gauss-Newton blocks, no regularisation): Vx_k = Qx_k − K_kᵀ Qu_k, which is
      λ at an exact optimum and whose error stays of the order of the solution's (P δx): the closed
      loop carries it;
    - "open-loop": the recursion above, which carries the residual's consequences with the open-loop
      Fxᵀ: on the G1's walking OCP (N = 50, 20 ms) it grew the solver's |Qu| ~ 3e-11 into
      |Lu + Fuᵀ λ| = 4e-4 at node 0 (the open-loop dynamics amplify ~1.4x per node there), and the
      sensitivity built on it disagreed with re-solved OCPs by 1.1 %.

    Raises:
        ParameterError: an unknown method. SolverError: the Gauss-Newton Quu is not positive definite.
    """
    if method not in COSTATE_METHODS:
        raise ParameterError(f"method={method!r} must be one of {COSTATE_METHODS}")
    N, ndx, nu = problem.T, problem.ndx, problem.nu
    lam = np.zeros((N + 1, ndx))
    if method == "open-loop":
        lam[N] = problem.Lx[N]
        for k in range(N - 1, -1, -1):
            lam[k] = problem.Lx[k] + problem.Fx[k].T @ lam[k + 1]
        return lam
    failed = riccati_backward(problem.Fx, problem.Fu, problem.Lx, problem.Lu, problem.Lxx, problem.Lxu, problem.Luu,
                              np.zeros((N + 1, ndx)), 0.0, True, lam, np.zeros((N + 1, ndx, ndx)), np.zeros((N, nu)),
                              np.zeros((N, nu, nu)), np.zeros((N, nu)), np.zeros((N, nu)), np.zeros((N, nu, ndx)))
    if failed >= 0:
        raise SolverError(f"the Gauss-Newton Quu is not positive definite at node {failed}: not a converged solution")
    return lam


def stationarity_residual(problem, lam: np.ndarray) -> float:
    """max_k ‖Lu_k + Fu_kᵀ λ_{k+1}‖_∞: how far the solution is from the first-order conditions."""
    return float(np.max(np.abs(problem.Lu + np.einsum("kij,ki->kj", problem.Fu, lam[1:]))))


def linear_terms(problem, xs, derivatives: ParameterDerivatives, lam: np.ndarray,
                 chart_step: float = 1e-6) -> tuple[np.ndarray, ...]:
    """(q (N + 1, ndx, m), r (N, nu, m), c (N, ndx, m)) of the module docstring. Needs calcDiff at the solution.

    Besides ∂Lx/∂p, ∂Lu/∂p and the time-scaling term ∂(Fxᵀ λ)/∂dt ∂dt/∂p, the gradient of
    λᵀ (f_k ⊖ x_{k+1}) holds J_diff = ∂(y ⊖ x_{k+1})/∂y at y = f_k, which moves with p as f_k does
    (the chart of δx_{k+1} stays at x_{k+1}): q_k += Fxᵀ w, r_k += Fuᵀ w with
    w = d/dε J_diff(x_{k+1}, x_{k+1} ⊕ ε ∂f_k/∂p)ᵀ λ_{k+1}, a second derivative of the Lie-group
    difference (no closed form in Pinocchio: central differences of its analytic Jacobian, step
    ``chart_step`` relative to the largest entry of ∂f_k/∂p). Zero on a vector space.
    """
    q = derivatives.dLx.copy()
    r = derivatives.dLu.copy()
    state = problem.state
    for k in range(problem.T):  # the chart term: J_diff(x_{k+1}, f_k(p))ᵀ λ_{k+1} moves as f_k does
        for j in np.flatnonzero(np.any(derivatives.dxnext[k] != 0.0, axis=0)):
            direction = derivatives.dxnext[k][:, j]
            eps = chart_step / float(np.max(np.abs(direction)))
            w = np.zeros(problem.ndx)
            for sign in (1.0, -1.0):
                moved = state.integrate(xs[k + 1], sign * eps * direction)
                w += sign * (state.Jdiff(xs[k + 1], moved)[1].T @ lam[k + 1])
            w /= 2.0 * eps
            q[k][:, j] += problem.Fx[k].T @ w
            r[k][:, j] += problem.Fu[k].T @ w
    if derivatives.ddt is not None:
        for k, (model, data) in enumerate(zip(problem.running_models, problem.running_datas)):
            column = derivatives.ddt[k]
            if not np.any(column):
                continue
            gx, gu = model.transitionJacobiansTransposeDt(data, xs[k], lam[k + 1])
            q[k] += np.outer(gx, column)
            r[k] += np.outer(gu, column)
    return q, r, derivatives.dxnext.copy()


def lagrangian_hessians(problem, xs, us, lam: np.ndarray, step: float = 1e-6) -> tuple[np.ndarray, ...]:
    """Exact Hessians of ℒ_k = ℓ_k(x_k ⊕ δx, u_k + δu) + λ_{k+1}ᵀ (f_k(x_k ⊕ δx, u_k + δu) ⊖ x_{k+1})
    in (δx, δu) at 0, and of ℓ_N(x_N ⊕ δx): central differences with ``step`` of the analytic gradient

        ∇_δx ℒ_k = J_intᵀ (Lx + Fxᵀ J_diffᵀ λ_{k+1}),   ∇_δu ℒ_k = Lu + Fuᵀ J_diffᵀ λ_{k+1}

    (J_int = ∂(x_k ⊕ δx)/∂δx, J_diff = ∂(y ⊖ x_{k+1})/∂y at y = f_k), symmetrised. Fresh node data
    are used, the problem's data keep the solution's values. A dead-zone activation (the control
    bounds' barrier) has a curvature jump at its bounds, and the soft barrier keeps a saturated
    torque within ~1e-5 N·m of its limit: a node's step is cut to a quarter of the distance
    (:func:`dead_zone_margin`) of its nearest such row from its bound, so the differences stay on
    one side of every kink.

    Returns:
        (Hxx (N + 1, ndx, ndx), Hxu (N, ndx, nu), Huu (N, nu, nu)).
    """
    state = problem.state
    N, ndx, nu = problem.T, problem.ndx, problem.nu
    n = ndx + nu
    Hxx = np.zeros((N + 1, ndx, ndx))
    Hxu = np.zeros((N, ndx, nu))
    Huu = np.zeros((N, nu, nu))

    def gradient(model, data, x, u, dz, lam_next, x_next):
        x_pert = state.integrate(x, dz[:ndx])
        J_int = state.Jintegrate(x, dz[:ndx])[1]
        if u is None:
            model.calc(data, x_pert)
            model.calcDiff(data, x_pert)
            return J_int.T @ data.Lx
        u_pert = u + dz[ndx:]
        model.calc(data, x_pert, u_pert)
        model.calcDiff(data, x_pert, u_pert)
        mu = state.Jdiff(x_next, data.xnext)[1].T @ lam_next
        return np.concatenate([J_int.T @ (data.Lx + data.Fx.T @ mu), data.Lu + data.Fu.T @ mu])

    datas = problem.running_datas + [problem.terminal_data]
    for k, model in enumerate(problem.running_models + [problem.terminal_model]):
        terminal = k == N
        size = ndx if terminal else n
        h = min(step, 0.25 * dead_zone_margin(datas[k].differential.costs))
        data = model.createData()
        H = np.zeros((size, size))
        for i in range(size):
            dz = np.zeros(n)
            dz[i] = h
            args = (None if terminal else us[k], None if terminal else lam[k + 1], None if terminal else xs[k + 1])
            plus = gradient(model, data, xs[k], args[0], dz, args[1], args[2])
            minus = gradient(model, data, xs[k], args[0], -dz, args[1], args[2])
            H[:, i] = (plus - minus) / (2.0 * h)
        H = 0.5 * (H + H.T)
        Hxx[k] = H[:ndx, :ndx]
        if not terminal:
            Hxu[k] = H[:ndx, ndx:]
            Huu[k] = H[ndx:, ndx:]
    return Hxx, Hxu, Huu


def _dead_zone_rows(cost_data):
    """(r, R, distance to the nearest bound) of a node's active dead-zone cost rows (lb < ub)."""
    rows = cost_data.lb < cost_data.ub
    rows &= cost_data.term_scale[cost_data.row_term] > 0  # active terms only
    r, lb, ub = cost_data.r[rows], cost_data.lb[rows], cost_data.ub[rows]
    return r, cost_data.R[rows], np.minimum(np.abs(r - lb), np.abs(r - ub))


def dead_zone_margin(cost_data) -> float:
    """Smallest distance, in the tangent/control coordinates, of a node's dead-zone cost rows
    (lb < ub) from their bounds: min |r − bound| / max |∂r/∂(x, u)| over those rows (inf: none).
    Needs calcDiff at the point (the problem's node data: ``data.differential.costs``)."""
    r, R, distance = _dead_zone_rows(cost_data)
    if r.size == 0:
        return np.inf
    slope = np.max(np.abs(R), axis=1)
    return float(np.min(distance / np.maximum(slope, 1e-300)))


def dead_zone_step(cost_data, direction: np.ndarray) -> float:
    """The largest ε for which no dead-zone row of a node crosses its bound along (δx, δu) = ε
    ``direction`` (ndx + nu,), to first order: min |r − bound| / |∂r/∂(x, u) · direction| (inf: no
    such row moves). Needs calcDiff at the point."""
    r, R, distance = _dead_zone_rows(cost_data)
    rate = np.abs(R @ direction)
    moving = rate > 0
    return float(np.min(distance[moving] / rate[moving])) if np.any(moving) else np.inf


def linear_quadratic(problem, xs, us, derivatives: ParameterDerivatives, hessian: str = "exact",
                     hessian_step: float = 1e-6) -> LinearQuadratic:
    """The sensitivity LQ problem at a converged solution (xs, us): evaluates the problem's
    derivatives there (calc and calcDiff), the costates, the linear terms and the Hessians
    (``hessian`` "exact" or "gauss-newton", see the module docstring)."""
    if hessian not in HESSIANS:
        raise ParameterError(f"hessian={hessian!r} must be one of {HESSIANS}")
    problem.calc_and_diff(xs, us)
    lam = costates(problem)
    q, r, c = linear_terms(problem, xs, derivatives, lam)
    if hessian == "exact":
        Hxx, Hxu, Huu = lagrangian_hessians(problem, xs, us, lam, hessian_step)
    else:
        Hxx, Hxu, Huu = problem.Lxx.copy(), problem.Lxu.copy(), problem.Luu.copy()
    return LinearQuadratic(problem.Fx.copy(), problem.Fu.copy(), Hxx, Hxu, Huu, q, r, c, hessian)
