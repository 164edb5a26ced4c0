"""Analytic Fiacco sensitivity of the footstep QP to a disturbance on the measured DCM (eqs. 6-12).

The measured DCM is zeta_hat = zeta + theta (theta (2,) [m]); the QP's equality becomes
``h_j(x) + theta_j c_j(x) = 0`` with ``c_j(x) = -exp(-omega t) Gamma`` (eq. 8). At the solution
(x*, u*, w*) of the undisturbed problem, the implicit function theorem applied to the KKT system
F (eq. 9: stationarity, complementarity u_i g_i = 0, equalities) gives (eq. 10)::

    d(x*, u*, w*)/d theta = -J_F*^{-1} J_F(theta)

with J_F* (13, 13) of eq. (11) and J_F(theta) (13, 2) of eq. (12). The cost here is eq. (3a) as
written, so the Hessian block is 2 diag(a1, a1, a2, a3, a3) (eq. 11 prints diag(a1, ...); the
factor scales the multipliers only and leaves dx*/dtheta unchanged).

The theorem needs strict complementarity and linearly independent active constraint gradients.
When either fails the solution map has a kink at theta = 0 and no derivative exists;
:func:`fiacco_sensitivity` then raises :class:`DegenerateSensitivity` saying which constraint is
to blame instead of returning a number.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sequencer.step_qp import CONSTRAINT_NAMES, ExactBackend, StepProblem, StepSolution
from wbmpc.errors import WbmpcError


class DegenerateSensitivity(WbmpcError):
    """The solution is not differentiable in theta (weakly active constraint or dependent gradients)."""


@dataclass(frozen=True)
class DcmSensitivity:
    """Derivatives of the footstep QP's primal-dual solution with respect to the DCM disturbance.

    Attributes:
        x: primal solution (p_T,x, p_T,y, Gamma, b_T,x, b_T,y), shape (5,).
        dx_dtheta: shape (5, 2); column j is d x* / d theta_j ([m/m] or [1/m] for Gamma).
        du_dtheta: shape (6, 2), inequality multipliers.
        dw_dtheta: shape (2, 2), equality multipliers.
        active: shape (6,) bool, the active set used.
        method: which route produced it ("analytic", "casadi", ...).
    """

    x: np.ndarray
    dx_dtheta: np.ndarray
    du_dtheta: np.ndarray
    dw_dtheta: np.ndarray
    active: np.ndarray
    method: str

    @property
    def active_names(self) -> list[str]:
        return [name for name, on in zip(CONSTRAINT_NAMES, self.active) if on]


def kkt_jacobians(problem: StepProblem, solution: StepSolution) -> tuple[np.ndarray, np.ndarray]:
    """J_F* (13, 13) of eq. (11) and J_F(theta) (13, 2) of eq. (12), unknowns ordered (x, u, w)."""
    a1, a2, a3 = problem.alpha
    x, u, w = solution.x, solution.u, solution.w
    G = problem.inequality_jacobian()  # (5, 6)
    H = problem.equality_jacobian()  # (5, 2)
    g = problem.inequalities(x)
    c = -problem.decay * x[2]
    C = np.zeros((5, 2))
    C[2, :] = -problem.decay  # grad_x c_j
    J = np.zeros((13, 13))
    J[:5, :5] = 2.0 * np.diag([a1, a1, a2, a3, a3])
    J[:5, 5:11] = -G
    J[:5, 11:] = H
    J[5:11, :5] = np.diag(u) @ G.T
    J[5:11, 5:11] = np.diag(g)
    J[11:, :5] = H.T
    J_theta = np.zeros((13, 2))
    J_theta[:5] = C @ np.diag(w)
    J_theta[11:] = np.diag([c, c])
    return J, J_theta


def check_regularity(
    problem: StepProblem, solution: StepSolution, multiplier_tol: float = 1e-9, slack_tol: float = 1e-9
) -> None:
    """Raise DegenerateSensitivity unless strict complementarity and LICQ hold at ``solution``.

    Args:
        multiplier_tol: an active constraint needs u_i > multiplier_tol * scale, where scale is the
            largest multiplier magnitude (or 1).
        slack_tol: an inactive constraint needs g_i > slack_tol (in the constraint's units).
    """
    u, w = solution.u, solution.w
    scale = max(1.0, float(np.max(np.abs(np.concatenate([u, w])))))
    g = problem.inequalities(solution.x)
    for i, name in enumerate(CONSTRAINT_NAMES):
        if solution.active[i] and u[i] <= multiplier_tol * scale:
            raise DegenerateSensitivity(
                f"constraint {name!r} is active with a zero multiplier (u={u[i]:.3g}): strict complementarity "
                "fails, the solution map has a kink at theta = 0 and only one-sided derivatives exist"
            )
        if not solution.active[i] and g[i] <= slack_tol:
            raise DegenerateSensitivity(
                f"constraint {name!r} is at its bound (g={g[i]:.3g}) but reported inactive: weakly active, "
                "the solution is not differentiable in theta"
            )
    gradients = np.hstack([problem.inequality_jacobian()[:, solution.active], problem.equality_jacobian()])
    if np.linalg.matrix_rank(gradients) < gradients.shape[1]:
        raise DegenerateSensitivity(
            f"active constraint gradients {solution.active_names} + the 2 equalities are linearly dependent "
            "(e.g. both bounds of one variable active, min == max): LICQ fails"
        )


def fiacco_sensitivity(
    problem: StepProblem, solution: StepSolution | None = None, multiplier_tol: float = 1e-9
) -> DcmSensitivity:
    """Analytic d(x*, u*, w*)/d theta of eq. (10).

    Args:
        problem: the undisturbed footstep QP (theta = 0).
        solution: its primal-dual solution; solved exactly when omitted.
        multiplier_tol: relative threshold for strict complementarity (see check_regularity).

    Raises:
        DegenerateSensitivity: strict complementarity or LICQ fails.
    """
    if solution is None:
        solution = ExactBackend().solve(problem)
    check_regularity(problem, solution, multiplier_tol=multiplier_tol)
    J, J_theta = kkt_jacobians(problem, solution)
    derivative = -np.linalg.solve(J, J_theta)
    return DcmSensitivity(
        x=solution.x.copy(), dx_dtheta=derivative[:5], du_dtheta=derivative[5:11], dw_dtheta=derivative[11:],
        active=solution.active.copy(), method="analytic",
    )
