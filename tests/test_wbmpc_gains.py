"""Sign convention of the Riccati gains: K = ∂u*/∂x (plus sign), checked by finite differences.

FDDP's K is the feedback of the Gauss-Newton (LQ) model of the problem, so it is the exact
derivative of the LQ solution and a close, not exact, estimate of the derivative of the true
optimal control; the test checks direction and sign on random initial-state perturbations.
"""

from __future__ import annotations

import numpy as np
import pytest
from wbmpc_fixtures import alternating_schedule, standing_state

from robots import load_robot
from wbmpc.ocp.solvers import SolverFDDP
from wbmpc.walking.ocp import WalkingOCP, WalkingOCPConfig, quasi_static_controls


@pytest.fixture(scope="module")
def converged():
    robot = load_robot("bolt")
    n_nodes = 20
    ocp = WalkingOCP(robot, WalkingOCPConfig(), n_nodes=n_nodes, dt=0.01)
    x0 = standing_state(robot)
    ocp.update(x0, alternating_schedule(0.0, 0.01, n_nodes), np.array([0.05, 0.0, 0.3]))
    solver = SolverFDDP(ocp.problem)
    solver.th_stop = 1e-18  # iterate to machine precision so finite differences are meaningful
    u0 = quasi_static_controls(ocp, x0)
    assert solver.solve([x0] * (n_nodes + 1), [u0] * n_nodes, maxiter=200)
    return ocp, solver, x0, solver.xs.copy(), solver.us.copy(), solver.K.copy()


def test_gain_is_the_derivative_of_the_optimal_control(converged):
    ocp, solver, x0, xs, us, K = converged
    state = ocp.state
    rng = np.random.default_rng(0)
    eps = 1e-3
    cosines, flipped = [], []
    for _ in range(4):
        direction = rng.standard_normal(state.ndx)
        direction /= np.linalg.norm(direction)
        x_perturbed = state.integrate(x0, eps * direction)
        ocp.problem.set_x0(x_perturbed)
        guess = xs.copy()
        guess[0] = x_perturbed
        assert solver.solve(guess, us, maxiter=200)
        response = (solver.us[0] - us[0]) / eps
        predicted = K[0] @ direction
        cosines.append(response @ predicted / np.linalg.norm(response) / np.linalg.norm(predicted))
        flipped.append(response @ -predicted / np.linalg.norm(response) / np.linalg.norm(predicted))
    ocp.problem.set_x0(x0)
    assert min(cosines) > 0.6, cosines
    assert np.mean(cosines) > 0.85, cosines
    assert max(flipped) < -0.6  # Crocoddyl's sign would point the other way
