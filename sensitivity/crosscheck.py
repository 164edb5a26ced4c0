"""Four independent routes to dx*/dtheta and their largest disagreement.

Routes:
    analytic: eq. (10) from the exact active-set solution (:mod:`sensitivity.kkt`).
    casadi: CasADi AD of the KKT residual at an IPOPT solution (:mod:`sensitivity.casadi_`).
    finite_differences: central differences of exactly re-solved QPs, step ``fd_step`` [m].
    proxqp_backward: ProxSuite's ``compute_backward`` (implicit differentiation inside ProxQP):
        theta enters the equality matrix A through its Gamma column, A[j, 2] = -(zeta_j - p0_j) e^{-omega t},
        so dx_i/dtheta_j = dL/dA[j, 2] * (-e^{-omega t}) with the loss L = x_i.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import proxsuite

from sensitivity.casadi_ import casadi_sensitivity
from sensitivity.kkt import fiacco_sensitivity
from sequencer.step_qp import ExactBackend, StepProblem

ROUTES = ("analytic", "casadi", "finite_differences", "proxqp_backward")


def finite_difference_jacobian(problem: StepProblem, fd_step: float = 1e-6) -> np.ndarray:
    """Central finite differences of exactly re-solved QPs, dx*/dtheta shape (5, 2)."""
    solver = ExactBackend()
    jacobian = np.zeros((5, 2))
    for j in range(2):
        step = np.zeros(2)
        step[j] = fd_step
        plus = solver.solve(problem.with_dcm_disturbance(step)).x
        minus = solver.solve(problem.with_dcm_disturbance(-step)).x
        jacobian[:, j] = (plus - minus) / (2.0 * fd_step)
    return jacobian


def proxqp_backward_jacobian(problem: StepProblem, eps: float = 1e-10, regularization: float = 1e-14) -> np.ndarray:
    """dx*/dtheta (5, 2) through ProxQP's compute_backward (one backward pass per x_i).

    Args:
        eps: ProxQP's forward solve tolerance.
        regularization: eps, rho_backward and mu_backward of compute_backward. Its defaults
            (1e-4, 1e-6, 1e-6) regularise the KKT system and bias the derivative by up to 0.8
            (37% of the largest entry) on this badly scaled QP (alpha3/alpha2 = 1e6); 1e-14 brings it to ~1e-8.
    """
    data = problem.qp_matrices()
    dense = proxsuite.proxqp.dense
    qp = dense.QP(5, 2, 3)
    qp.settings.eps_abs = eps
    qp.settings.eps_rel = 0.0
    qp.settings.verbose = False
    qp.init(data["P"], data["q"], data["A"], data["b"], data["C"], data["lower"], data["upper"])
    qp.solve()
    jacobian = np.zeros((5, 2))
    for i in range(5):
        loss_derivative = np.zeros(5 + 2 + 3)
        loss_derivative[i] = 1.0
        dense.compute_backward(qp, loss_derivative, regularization, regularization, regularization)
        jacobian[i] = np.asarray(qp.model.backward_data.dL_dA)[:, 2] * (-problem.decay)
    return jacobian


@dataclass(frozen=True)
class Crosscheck:
    """dx*/dtheta by every route and their disagreement.

    Attributes:
        x: primal solution, shape (5,).
        active: active set of the exact solution, shape (6,).
        jacobians: route name -> dx*/dtheta, shape (5, 2).
        max_disagreement: largest |J_route - J_analytic| over routes and entries.
        worst_route: the route reaching it.
    """

    x: np.ndarray
    active: np.ndarray
    jacobians: dict
    max_disagreement: float
    worst_route: str


def crosscheck(problem: StepProblem, fd_step: float = 1e-6, clip_inactive_lam: float = 1e-6) -> Crosscheck:
    """Compute dx*/dtheta by the four routes; raises DegenerateSensitivity if no derivative exists."""
    analytic = fiacco_sensitivity(problem)
    jacobians = {
        "analytic": analytic.dx_dtheta,
        "casadi": casadi_sensitivity(problem, clip_inactive_lam=clip_inactive_lam).dx_dtheta,
        "finite_differences": finite_difference_jacobian(problem, fd_step),
        "proxqp_backward": proxqp_backward_jacobian(problem),
    }
    gaps = {name: float(np.max(np.abs(j - analytic.dx_dtheta))) for name, j in jacobians.items() if name != "analytic"}
    worst = max(gaps, key=gaps.get)
    return Crosscheck(
        x=analytic.x, active=analytic.active, jacobians=jacobians, max_disagreement=gaps[worst], worst_route=worst
    )
