"""DCM sensitivity (eqs. 9-12): analytic = CasADi = finite differences = ProxQP compute_backward."""

import dataclasses

import numpy as np
import pytest
from sequencer_instances import random_problems

from sensitivity import DegenerateSensitivity, crosscheck, fiacco_sensitivity
from sensitivity.casadi_ import casadi_sensitivity, solve_ipopt
from sensitivity.crosscheck import finite_difference_jacobian, proxqp_backward_jacobian
from sequencer import SequencerParams, StepProblem
from sequencer.step_qp import ExactBackend


def table_i_problem(**overrides):
    params = dataclasses.replace(SequencerParams.table_i(), **overrides)
    return StepProblem.from_params(params, "left", [-0.12, 0.10], [-0.12, -0.07], 0.229)


def regular(problems):
    """Instances where the derivative exists (almost all random ones)."""
    kept = []
    for problem in problems:
        try:
            fiacco_sensitivity(problem)
        except DegenerateSensitivity:
            continue
        kept.append(problem)
    return kept


@pytest.mark.parametrize("tight", [False, True])
def test_four_routes_agree_on_random_instances(tight):
    problems = regular(random_problems(25, seed=11, tight=tight))
    assert len(problems) >= 20
    n_active = 0
    for problem in problems:
        check = crosscheck(problem)
        scale = 1.0 + np.max(np.abs(check.jacobians["analytic"]))
        assert check.max_disagreement < 1e-5 * scale, (check.worst_route, problem.describe())
        n_active += int(check.active.any())
    if tight:
        assert n_active >= 8


def test_variables_on_an_active_bound_have_zero_sensitivity():
    found = 0
    for problem in regular(random_problems(60, seed=12, tight=True)):
        sens = fiacco_sensitivity(problem)
        for k in range(3):  # p_T,x, p_T,y, Gamma
            if sens.active[2 * k] or sens.active[2 * k + 1]:
                found += 1
                assert np.all(sens.dx_dtheta[k] == pytest.approx(0.0, abs=1e-12))
                assert np.all(finite_difference_jacobian(problem)[k] == pytest.approx(0.0, abs=1e-9))
        inactive = ~sens.active
        assert np.all(sens.du_dtheta[inactive] == pytest.approx(0.0, abs=1e-9))
    assert found >= 10


def test_table_i_sensitivity_structure():
    problem = table_i_problem()
    sens = fiacco_sensitivity(problem)
    assert not sens.active.any()  # as stated for Fig. 2
    J = sens.dx_dtheta
    # no active step bound: stationarity in p and b gives a1 dp = a3 db, so db/dtheta = (a1/a3) dp/dtheta
    assert J[3:] == pytest.approx(1e-3 * J[:2], rel=1e-9)
    # the step takes the disturbance, the DCM offset barely moves (alpha3 >> alpha1)
    assert J[1, 1] > 0 and abs(J[4, 1]) < 1e-2 * abs(J[1, 1])
    # with the timing frozen (alpha2 huge), dp_y/dtheta_y = e^{-omega t} Gamma a3/(a1+a3)
    frozen = table_i_problem(alpha2=1e12)
    sens_frozen = fiacco_sensitivity(frozen)
    gamma = sens_frozen.x[2]
    assert sens_frozen.dx_dtheta[1, 1] == pytest.approx(frozen.decay * gamma * 1e6 / (1e6 + 1e3), rel=1e-4)


def test_kkt_matrix_solves_match_casadi_multiplier_derivatives():
    problem = random_problems(1, seed=5, tight=True)[0]
    analytic = fiacco_sensitivity(problem)
    via_casadi = casadi_sensitivity(problem, solution=ExactBackend().solve(problem))
    assert via_casadi.dx_dtheta == pytest.approx(analytic.dx_dtheta, abs=1e-9)
    assert via_casadi.du_dtheta == pytest.approx(analytic.du_dtheta, rel=1e-7, abs=1e-6)
    assert via_casadi.dw_dtheta == pytest.approx(analytic.dw_dtheta, rel=1e-7, abs=1e-6)


def test_ipopt_multipliers_need_clipping_to_give_the_active_set():
    problem = table_i_problem()
    solution = solve_ipopt(problem)
    assert solution.x == pytest.approx(ExactBackend().solve(problem).x, abs=1e-7)
    unclipped = casadi_sensitivity(problem, solution=solution)
    clipped = casadi_sensitivity(problem, solution=solution, clip_inactive_lam=1e-6)
    assert unclipped.active.all()  # interior point: every multiplier is tiny but positive
    assert not clipped.active.any()
    assert clipped.dx_dtheta == pytest.approx(fiacco_sensitivity(problem).dx_dtheta, abs=1e-6)


def test_proxqp_backward_matches_analytic_on_table_i():
    problem = table_i_problem()
    assert proxqp_backward_jacobian(problem) == pytest.approx(fiacco_sensitivity(problem).dx_dtheta, abs=1e-6)


def test_weakly_active_constraint_is_reported_not_differentiated():
    # put the unconstrained optimum of the step length exactly on l_max: active with zero multiplier
    problem = table_i_problem()
    free = ExactBackend().solve(problem)
    step = free.x[0] - problem.p0[0]
    weak = dataclasses.replace(problem, length_bounds=(-0.3, step))
    solution = ExactBackend().solve(weak)
    assert solution.active[1]
    with pytest.raises(DegenerateSensitivity, match=r"'step_length_max' is active with a zero multiplier"):
        fiacco_sensitivity(weak, solution)


def test_dependent_active_gradients_are_reported():
    # T_min == T_max: both time bounds active, their gradients are opposite (LICQ fails)
    problem = table_i_problem(t_min=0.3, t_nom=0.3, t_max=0.3)
    solution = ExactBackend().solve(problem)
    forced = dataclasses.replace(solution, active=np.array([False, False, False, False, True, True]),
                                 u=np.array([0, 0, 0, 0, 1.0, 1.0]))
    with pytest.raises(DegenerateSensitivity, match="linearly dependent"):
        fiacco_sensitivity(problem, forced)
