"""CasADi route to the DCM sensitivity: symbolic KKT residual F(z, theta) + implicit function theorem.

Independent of :mod:`sensitivity.kkt`: the QP is written symbolically from eqs. (3a), (4), (7)
and (8), solved with IPOPT (an interior-point method) through ``casadi.nlpsol``, and the KKT
residual of eq. (9) (stationarity, complementarity ``u_i g_i``, disturbed equalities) is
differentiated by CasADi's automatic differentiation.

Interior-point multipliers of inactive constraints are tiny but not zero (about tol / g_i), so an
active set read from ``u > 0`` marks every constraint active. ``clip_inactive_lam`` sets the
multipliers below that threshold to exactly zero before the derivative and the active set are
computed; without it the complementarity rows still give nearly the right derivative (errors of
order u_i / g_i) but the reported active set is meaningless.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from sensitivity.kkt import DcmSensitivity
from sequencer.step_qp import StepProblem, StepSolution
from wbmpc.errors import SolverError


def _symbolic_problem(problem: StepProblem):
    """Symbols x (5), theta (2) and expressions f, g (6), h_theta (2) of eqs. (3a), (4), (6)-(8)."""
    x = ca.SX.sym("x", 5)
    theta = ca.SX.sym("theta", 2)
    a1, a2, a3 = (float(v) for v in problem.alpha)
    p0 = [float(v) for v in problem.p0]
    zeta = [float(v) for v in problem.dcm_measured]
    n = [float(v) for v in problem.step_nominal]
    bn = [float(v) for v in problem.b_nominal]
    gamma_nom = problem.gamma_nominal
    g_lo, g_hi = problem.gamma_bounds
    decay = problem.decay
    f = (
        a1 * ((x[0] - p0[0] - n[0]) ** 2 + (x[1] - p0[1] - n[1]) ** 2)
        + a2 * (x[2] - gamma_nom) ** 2
        + a3 * ((x[3] - bn[0]) ** 2 + (x[4] - bn[1]) ** 2)
    )
    (l_min, l_max), (w_min, w_max) = problem.length_bounds, problem.width_bounds
    g = ca.vertcat(
        x[0] - p0[0] - l_min,
        l_max - x[0] + p0[0],
        x[1] - p0[1] - w_min,
        w_max - x[1] + p0[1],
        x[2] - g_lo,
        g_hi - x[2],
    )
    h = ca.vertcat(
        x[0] + x[3] - p0[0] - (zeta[0] - p0[0]) * decay * x[2],
        x[1] + x[4] - p0[1] - (zeta[1] - p0[1]) * decay * x[2],
    )
    c = ca.vertcat(-decay * x[2], -decay * x[2])
    return x, theta, f, g, h + theta * c


def solve_ipopt(problem: StepProblem, tol: float = 1e-10) -> StepSolution:
    """Solve the footstep QP with IPOPT; multipliers converted to the eq. (9) convention (u >= 0)."""
    x, theta, f, g, h = _symbolic_problem(problem)
    nlp = {"x": x, "p": theta, "f": f, "g": ca.vertcat(g, h)}
    options = {"print_time": False, "ipopt": {"print_level": 0, "tol": tol, "sb": "yes"}}
    solver = ca.nlpsol("footstep_qp", "ipopt", nlp, options)
    lbg = np.concatenate([np.zeros(6), np.zeros(2)])
    ubg = np.concatenate([np.full(6, np.inf), np.zeros(2)])
    x0 = np.concatenate([problem.p0 + problem.step_nominal, [problem.gamma_nominal], problem.b_nominal])
    result = solver(x0=x0, p=np.zeros(2), lbg=lbg, ubg=ubg)
    status = solver.stats()["return_status"]
    if not solver.stats()["success"]:
        raise SolverError(f"IPOPT failed on the footstep QP (status {status!r})\n{problem.describe()}")
    x_opt = np.asarray(result["x"]).ravel()
    lam = np.asarray(result["lam_g"]).ravel()
    # CasADi: grad f + J_g' lam_g = 0, lam_g < 0 on an active lower bound g >= 0 -> u = -lam_g.
    u = np.maximum(-lam[:6], 0.0)
    w = lam[6:]
    g_val = problem.inequalities(x_opt)
    active = u > 0.0
    return StepSolution(
        x=x_opt, u=u, w=w, active=active, duration=float(np.log(x_opt[2]) / problem.omega),
        objective=problem.objective(x_opt), backend="ipopt", status=status,
        iterations=int(solver.stats()["iter_count"]), extra={"slack": g_val},
    )


def casadi_sensitivity(
    problem: StepProblem, solution: StepSolution | None = None, clip_inactive_lam: float | None = None
) -> DcmSensitivity:
    """d(x*, u*, w*)/d theta from CasADi's derivatives of the KKT residual F(z, theta) (eq. 9).

    Args:
        problem: the undisturbed footstep QP.
        solution: primal-dual point; solved with IPOPT when omitted.
        clip_inactive_lam: multipliers u_i below this value are set to 0 (inactive) first.
    """
    if solution is None:
        solution = solve_ipopt(problem)
    x, theta, f, g, h = _symbolic_problem(problem)
    u = ca.SX.sym("u", 6)
    w = ca.SX.sym("w", 2)
    lagrangian_gradient = ca.gradient(f - ca.dot(u, g) + ca.dot(w, h), x)
    residual = ca.vertcat(lagrangian_gradient, u * g, h)
    z = ca.vertcat(x, u, w)
    jacobians = ca.Function("kkt_jacobians", [z, theta], [ca.jacobian(residual, z), ca.jacobian(residual, theta)])
    u_val = solution.u.copy()
    if clip_inactive_lam is not None:
        u_val[u_val < clip_inactive_lam] = 0.0
    z_val = np.concatenate([solution.x, u_val, solution.w])
    J_z, J_theta = (np.asarray(m) for m in jacobians(z_val, np.zeros(2)))
    derivative = -np.linalg.solve(J_z, J_theta)
    return DcmSensitivity(
        x=solution.x.copy(), dx_dtheta=derivative[:5], du_dtheta=derivative[5:11], dw_dtheta=derivative[11:],
        active=u_val > 0.0, method="casadi",
    )
