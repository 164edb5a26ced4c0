"""Contact timing as a continuous OCP parameter (issue 16): the timed OCP equals the fixed-spacing one
on the grid, its analytic parameter derivatives match differences of the model, and the three routes
to d(u, x, forces, CoM)/dτ agree (Riccati sweep = full KKT = re-solved finite differences), on Bolt
(point feet, no double support) and on the G1 (6D soles, wrench cone, 0.1 s of double support after
each touchdown)."""

import dataclasses
import json

import numpy as np
import pytest

from sensitivity.ocp_finite_differences import check_fd_step
from sensitivity.ocp_parametric import check_converged, linear_quadratic
from sensitivity.ocp_riccati import time_sweep_against_riccati
from sequencer import contact_schedule, timed_contact_schedule
from wbmpc.errors import ParameterError
from wbmpc.ocp.solvers import SolverFDDP
from wbmpc.walking.ocp import WalkingOCP, quasi_static_controls
from wbmpc.walking.timing import (
    ContactTimingOCP,
    contact_timing_sensitivity,
    dcm_sensitivity,
    standing_start_timing_ocp,
)

N_NODES = 50  # Bolt, 0.5 s: two touchdowns inside the horizon, a re-solve in ~0.1 s
#: robot -> (N, dt [s]): Bolt's two touchdowns in 0.5 s; the G1's first touchdown (0.3 s), its double
#: support (to 0.4 s) and the next swing (to t_end = 0.5 s), a re-solve in ~0.2 s
CASES = {"bolt": (N_NODES, 0.01), "g1": (25, 0.02)}


@pytest.fixture(scope="module", params=list(CASES))
def solved(request):
    n_nodes, dt = CASES[request.param]
    timed = standing_start_timing_ocp(request.param, n_nodes=n_nodes, dt=dt)
    solver = timed.solve(th_stop=1e-17)
    return timed, solver


@pytest.fixture(scope="module")
def report(solved):
    timed, solver = solved
    return contact_timing_sensitivity(timed, solver, fd_step=2e-5)  # KKT: dense LU on Bolt, sparse on the G1


@pytest.fixture(scope="module")
def bolt():
    return standing_start_timing_ocp("bolt", n_nodes=N_NODES)


def on_grid(plan, dt):
    """The plan with its touchdowns moved to multiples of dt (phase durations multiples of dt when the
    double support is one too)."""
    steps = tuple(dataclasses.replace(step, touchdown_time=round(step.touchdown_time / dt) * dt) for step in plan.steps)
    return dataclasses.replace(plan, steps=steps)


def test_timed_schedule_on_the_grid_equals_the_fixed_spacing_schedule(solved):
    timed, _ = solved
    dt, n_nodes = timed.ocp.dt, timed.ocp.n_nodes
    plan = on_grid(timed.plan, dt)
    fixed = contact_schedule(plan, 0.0, dt, n_nodes, rounding="nearest")
    scaled = timed_contact_schedule(plan, 0.0, dt, n_nodes)
    np.testing.assert_array_equal(scaled.in_contact, fixed.in_contact)
    np.testing.assert_allclose(scaled.swing_phase, fixed.swing_phase, atol=1e-12)
    np.testing.assert_allclose(scaled.swing_duration, fixed.swing_duration, atol=1e-12)
    np.testing.assert_allclose(scaled.node_spacing, dt, atol=1e-14)
    np.testing.assert_allclose(scaled.times, fixed.times, atol=1e-12)
    if plan.double_support > 0:  # the G1: both feet down from the touchdown to the lift-off
        assert np.any(fixed.in_contact.all(axis=1)[1:-1]), "no double-support phase in the horizon"


def test_timed_ocp_on_the_grid_has_the_solution_of_the_fixed_spacing_ocp(solved):
    timed, _ = solved
    dt, n_nodes = timed.ocp.dt, timed.ocp.n_nodes
    plan = on_grid(timed.plan, dt)
    x0, com = timed.x0, timed.com_terminal_reference
    config = timed.ocp.config
    fixed = WalkingOCP(timed.ocp.robot, config, n_nodes=n_nodes, dt=dt)
    fixed.update(x0, contact_schedule(plan, 0.0, dt, n_nodes, rounding="nearest"), com)
    scaled = ContactTimingOCP(WalkingOCP(timed.ocp.robot, config, n_nodes=n_nodes, dt=dt), plan, 0.0, x0, com)
    guess_u = [quasi_static_controls(fixed, x0)] * n_nodes
    solutions = []
    for problem in (fixed.problem, scaled.problem):
        solver = SolverFDDP(problem)
        solver.solve([x0] * (n_nodes + 1), guess_u, maxiter=15)
        solutions.append((solver.xs.copy(), solver.us.copy(), solver.cost))
    # the same nodes: at one trajectory the same transitions, costs and derivatives ...
    xs, us = solutions[0][0], solutions[0][1]
    evaluated = []
    for problem in (fixed.problem, scaled.problem):
        cost = problem.calc_and_diff(xs, us)
        evaluated.append([cost] + [getattr(problem, name).copy() for name in ("xnext", "Fx", "Fu", "Lx", "Lu", "Luu")])
    for a, b in zip(*evaluated):
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(a).max()))
    # ... so the same FDDP iterates (up to the spacings' rounding, 1e-17 s, grown by 15 iterations)
    np.testing.assert_allclose(solutions[1][0], solutions[0][0], atol=1e-7)
    np.testing.assert_allclose(solutions[1][1], solutions[0][1], atol=1e-7 * max(1.0, np.abs(solutions[0][1]).max()))
    assert abs(solutions[1][2] - solutions[0][2]) < 1e-9


def test_double_support_moves_with_its_touchdown():
    """The G1's first touchdown 5 ms late: the double support after it keeps its 0.1 s (its nodes shift by
    5 ms, its spacing stays), the single support before it stretches, the one after shrinks."""
    timed = standing_start_timing_ocp("g1", n_nodes=25, dt=0.02)
    plan, tau = timed.plan, timed.touchdown_times
    base = timed_contact_schedule(plan, 0.0, 0.02, 25)
    late = timed_contact_schedule(plan, 0.0, 0.02, 25, tau + 0.005)
    both = base.in_contact.all(axis=1)[:-1]
    double = np.flatnonzero(both & (np.arange(25) >= 10))  # after the first touchdown (t = 0.3 s, node 15)
    assert double.tolist() == [15, 16, 17, 18, 19]
    np.testing.assert_allclose(late.node_spacing[double], 0.02, atol=1e-15)
    np.testing.assert_allclose(late.times[double] - base.times[double], 0.005, atol=1e-15)
    np.testing.assert_allclose(base.node_spacing_jacobian[double], 0.0)
    np.testing.assert_allclose(late.node_spacing[5:15], 0.205 / 10)  # lift-off 0.1 s (fixed) to the touchdown
    np.testing.assert_allclose(late.node_spacing[20:], 0.095 / 5)  # lift-off 0.405 s to t_end = 0.5 s
    assert base.swing_phase_jacobian[20, 0, 0] == 0 and np.all(base.swing_phase_jacobian[21:, 0, 0] < 0)  # lags


def test_contact_events_just_past_the_horizon_or_moved_across_it_are_refused():
    timed = standing_start_timing_ocp("g1", n_nodes=25, dt=0.02)
    plan = timed.plan
    with pytest.raises(ParameterError, match="within half a node after the horizon's end"):
        timed_contact_schedule(plan, -0.005, 0.02, 20)  # the lift-off at 0.4 s, t_end = 0.395 s
    timed_contact_schedule(plan, 0.0, 0.02, 19)  # t_end = 0.38 s: the lift-off at 0.4 s is past the horizon
    with pytest.raises(ParameterError, match="touchdown_times=.*across t0 or t_end"):
        timed_contact_schedule(plan, 0.0, 0.02, 19, [0.27])  # ... and would come at 0.37 s


def test_node_spacing_and_swing_phase_jacobians_match_differences(solved):
    timed, _ = solved
    tau = timed.touchdown_times
    grid = (0.0, timed.ocp.dt, timed.ocp.n_nodes)
    base = timed_contact_schedule(timed.plan, *grid, tau)
    h = 1e-7
    for j in range(tau.size):
        step = np.zeros(tau.size)
        step[j] = h
        plus = timed_contact_schedule(timed.plan, *grid, tau + step)
        minus = timed_contact_schedule(timed.plan, *grid, tau - step)
        np.testing.assert_allclose((plus.node_spacing - minus.node_spacing) / (2 * h), base.node_spacing_jacobian[:, j],
                                   atol=1e-7)
        fd = np.nan_to_num(plus.swing_phase - minus.swing_phase) / (2 * h)
        np.testing.assert_allclose(fd, base.swing_phase_jacobian[:, :, j], atol=1e-6)
    assert np.abs(base.swing_phase_jacobian).max() > 0.1  # the swings at both ends of the horizon move


def test_parameter_derivatives_match_differences_of_the_model(solved):
    timed, solver = solved
    xs, us = solver.xs.copy(), solver.us.copy()
    problem = timed.problem
    analytic = timed.parameter_derivatives(xs, us, com_reference=True)
    tau, com = timed.touchdown_times, timed.com_terminal_reference.copy()
    h = 1e-6
    try:
        for j in range(tau.size + 3):
            values = []
            for sign in (1.0, -1.0):
                p = np.concatenate([tau, com])
                p[j] += sign * h
                timed.set_parameters(p[: tau.size], p[tau.size:])
                problem.calc_and_diff(xs, us)
                values.append((problem.xnext.copy(), problem.Lx.copy(), problem.Lu.copy()))
            dxnext = np.array([problem.state.diff(a, b) for a, b in zip(values[1][0], values[0][0])]) / (2 * h)
            for fd, exact in ((dxnext, analytic.dxnext[..., j]), ((values[0][1] - values[1][1]) / (2 * h),
                              analytic.dLx[..., j]), ((values[0][2] - values[1][2]) / (2 * h), analytic.dLu[..., j])):
                scale = max(np.abs(exact).max(), 1.0)
                assert np.abs(fd - exact).max() < 1e-6 * scale
    finally:
        timed.set_parameters(tau, com)


def test_riccati_sweep_equals_the_full_kkt_solution(report):
    gaps = report.disagreement["kkt vs riccati"]
    assert max(gaps.values()) < 1e-8, gaps


def test_riccati_sweep_agrees_with_re_solved_finite_differences(solved, report):
    gaps = report.disagreement["finite_differences vs riccati"]
    assert max(gaps.values()) < 1e-4, gaps
    assert report.max_relative_disagreement < 1e-4
    assert np.abs(report.routes["riccati"]["u0"]).max() > 0.1  # not trivially zero [N·m/s]
    assert report.routes["riccati"]["forces0"].shape[0] == (3 if solved[0].ocp.contact_type == "point3d" else 12)


def test_gains_derivative_agrees_with_re_solved_gains(solved, report):
    """dK/dτ of the solver's gains (the backward pass's recursion differentiated along the solution's
    derivative) against central differences of the gains of re-solved OCPs."""
    timed, solver = solved
    gaps = report.disagreement["finite_differences vs riccati"]
    assert gaps["K0"] < 1e-4 and gaps["K"] < 1e-4, gaps
    dK = report.dK_dtouchdown
    assert dK.shape == (timed.ocp.nu, timed.problem.ndx, timed.touchdown_times.size)
    assert np.abs(dK).max() > 1.0  # [N·m/(state unit)/s], not trivially zero
    assert report.gains["solver_K0_gap"] < 1e-6  # K0 is the solver's own first gains
    np.testing.assert_allclose(report.gains["K0"], solver.K[0], atol=1e-6 * np.abs(solver.K[0]).max())
    with pytest.raises(ParameterError, match="gains=False"):
        _ = dataclasses.replace(report, gains=None).dK_dtouchdown


def test_gain_recursion_derivative_matches_differences_of_the_factorisation():
    """The differentiated backward pass against central differences of the factorisation itself, on a
    random LQ problem (blocks moving along random directions, regularisation 1e-3)."""
    from sensitivity.ocp_gains import BlockDerivatives, gain_derivatives
    from sensitivity.ocp_parametric import LinearQuadratic
    from sensitivity.ocp_riccati import factorise

    rng = np.random.default_rng(0)
    N, ndx, nu, m, rho = 6, 5, 3, 2, 1e-3

    def blocks():
        A = rng.standard_normal((N + 1, ndx + nu, ndx + nu))
        H = np.einsum("kij,klj->kil", A, A)
        return (np.eye(ndx) + 0.1 * rng.standard_normal((N, ndx, ndx)), rng.standard_normal((N, ndx, nu)),
                H[:, :ndx, :ndx], H[:N, :ndx, ndx:], H[:N, ndx:, ndx:])

    def lq(b):
        return LinearQuadratic(*b, np.zeros((N + 1, ndx, 0)), np.zeros((N, nu, 0)), np.zeros((N, ndx, 0)), "gauss-newton")

    base = blocks()
    directions = [np.stack([d, 0.5 * d], axis=-1) for d in blocks()]
    sens = gain_derivatives(lq(base), BlockDerivatives(*directions, np.ones(m)), rho)
    np.testing.assert_allclose(sens.K, -factorise(lq(base), rho).K)  # the library's sign
    h = 1e-6
    for j in range(m):
        plus = -factorise(lq(tuple(b + h * d[..., j] for b, d in zip(base, directions))), rho).K
        minus = -factorise(lq(tuple(b - h * d[..., j] for b, d in zip(base, directions))), rho).K
        np.testing.assert_allclose(sens.dK[..., j], (plus - minus) / (2 * h), atol=1e-7 * np.abs(sens.dK).max())
    with pytest.raises(ParameterError, match="regularization"):
        factorise(lq(base), -1.0)
    with pytest.raises(ParameterError, match="hessian"):
        gain_derivatives(dataclasses.replace(lq(base), hessian="exact"), BlockDerivatives(*directions, np.ones(m)), rho)


def test_gain_block_step_is_cut_before_a_dead_zone_kink_and_checked(bolt):
    from types import SimpleNamespace

    from sensitivity.ocp_gains import block_derivatives
    from sensitivity.ocp_parametric import dead_zone_step

    rows = SimpleNamespace(lb=np.array([0.0, -1.0, -1.0]), ub=np.array([0.0, 1.0, 1.0]), term_scale=np.array([1.0, 1.0]),
                           row_term=np.array([0, 1, 1]), r=np.array([5.0, 1.001, 0.5]),
                           R=np.array([[1.0, 0.0], [2.0, 0.0], [0.0, 1.0]]))
    # the quadratic row (lb = ub) has no kink; the saturated row is 1e-3 past its bound, moving at 2 per unit
    assert dead_zone_step(rows, np.array([1.0, 0.0])) == pytest.approx(5e-4)
    assert dead_zone_step(rows, np.array([0.0, 1.0])) == pytest.approx(0.5)
    with pytest.raises(ParameterError, match="step=0"):
        block_derivatives(bolt.problem, bolt.set_parameters, bolt.touchdown_times, None, None, None, None, step=0.0)


def test_gauss_newton_hessian_misses_the_true_derivative(report):
    """FDDP's Gauss-Newton factorisation gives a derivative, but not the derivative of the solution map."""
    gap = report.gauss_newton["gap_to_finite_differences"]
    assert gap["u0"] > 1e-3


def test_sweep_timing_reports_both_passes_measured_in_one_run(solved):
    """The cost figure (sweep / Riccati pass, measured in the same run) is reported, not asserted:
    speed targets are checked by the CLI's report and docs/benchmarks.md, never by timed tests."""
    timed, solver = solved
    derivatives = timed.parameter_derivatives(solver.xs, solver.us)
    lq = linear_quadratic(timed.problem, solver.xs, solver.us, derivatives, "gauss-newton")
    timing = time_sweep_against_riccati(lq, repeats=3)
    assert set(timing) >= {"sweep_over_riccati"}, timing
    assert all(np.isfinite(v) and v > 0 for v in timing.values() if isinstance(v, float)), timing


def test_dcm_end_to_end_matches_finite_differences_of_the_whole_chain():
    result = dcm_sensitivity("bolt", n_nodes=N_NODES, fd_step=1e-4)
    assert result["max_relative_disagreement"] < 1e-3, result["disagreement"]
    assert np.abs(result["du0_dtheta"]).max() > 0.1


@pytest.mark.parametrize("times, match", [
    ([0.3, 0.2], "strictly increasing"),
    ([0.17, 0.7], "inside the horizon"),
    ([-0.1, 0.4], "inside the horizon"),
    ([0.17], "shape"),
    ([np.nan, 0.4], "finite"),
])
def test_bad_touchdown_times_are_refused(bolt, times, match):
    timed = bolt
    with pytest.raises(ParameterError, match=f"touchdown_times.*{match}|{match}.*touchdown_times|touchdown_times has shape"):
        timed_contact_schedule(timed.plan, 0.0, 0.01, N_NODES, times)


def test_costates_are_the_value_gradient_at_the_solution(solved):
    """The multipliers from the Riccati pass satisfy stationarity to the solver's |Qu|, the open-loop
    recursion's agree with them at a well-converged solution; an unknown method is refused."""
    from sensitivity.ocp_parametric import costates, stationarity_residual

    timed, solver = solved
    timed.set_parameters()
    timed.problem.calc_and_diff(solver.xs, solver.us)
    lam = costates(timed.problem)
    assert stationarity_residual(timed.problem, lam) < 1e-8
    np.testing.assert_allclose(costates(timed.problem, "open-loop"), lam, atol=1e-5 * np.abs(lam).max())
    with pytest.raises(ParameterError, match="method='adjoint'"):
        costates(timed.problem, "adjoint")


def test_non_converged_base_solution_is_refused(solved):
    timed, _ = solved
    timed.set_parameters()
    solver = timed.solve(th_stop=1e-9)
    with pytest.raises(ParameterError, match=r"stop=.* must be < th_stop"):
        contact_timing_sensitivity(timed, solver, th_stop=1e-30)
    with pytest.raises(ParameterError, match="stop=nan"):
        check_converged(float("nan"), 1e-12)


@pytest.mark.parametrize("step", [0.0, -1e-4, float("nan"), float("inf"), "a"])
def test_bad_finite_difference_step_is_refused(step):
    with pytest.raises(ParameterError, match="fd_step"):
        check_fd_step(step)


def test_cli_contact_timing_prints_every_route_and_their_disagreement(capsys, tmp_path):
    from wbmpc.cli import main

    plot = tmp_path / "timing.png"
    assert main(["sensitivity", "--wrt", "contact-timing", "--nodes", str(N_NODES), "--json", "--plot", str(plot)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert set(report["routes"]) == {"riccati", "kkt", "finite_differences"}
    assert np.asarray(report["routes"]["riccati"]["du0_dtau"]).shape == (6, 2)
    assert np.asarray(report["routes"]["kkt"]["dforces0_dtau"]).shape == (3, 2)
    assert np.asarray(report["routes"]["finite_differences"]["dcom_terminal_dtau"]).shape == (3, 2)
    assert np.asarray(report["routes"]["riccati"]["dK0_dtau"]).shape == (6, 24, 2)
    assert np.asarray(report["routes"]["finite_differences"]["dK0_dtau"]).shape == (6, 24, 2)
    assert "dK0_dtau" not in report["routes"]["kkt"]
    assert report["disagreement"]["finite_differences vs riccati"]["K0"] < 1e-4
    assert len(report["state_tangent"]) == 24 and report["gains"]["by_joint"][0]["joint"] in report["joints"]
    assert report["max_relative_disagreement"] < 1e-4
    assert report["cost"]["sweep_over_riccati"] > 0
    assert plot.stat().st_size > 0


def test_cli_contact_timing_on_the_g1(capsys):
    from wbmpc.cli import main

    assert main(["sensitivity", "--wrt", "contact-timing", "--robot", "g1", "--nodes", "25", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["robot"] == "g1" and report["dt_s"] == 0.02 and report["double_support_s"] == 0.1
    assert np.asarray(report["routes"]["riccati"]["dK0_dtau"]).shape == (29, 70, 1)
    assert np.asarray(report["routes"]["kkt"]["dforces0_dtau"]).shape == (12, 1)  # two 6D soles at node 0
    assert report["max_relative_disagreement"] < 1e-4


def test_cli_dcm_prints_the_end_to_end_derivative(capsys):
    from wbmpc.cli import main

    assert main(["sensitivity", "--wrt", "dcm", "--nodes", str(N_NODES), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert np.asarray(report["du0_dtheta"]).shape == (6, 2)
    assert report["max_relative_disagreement"] < 1e-3


def test_cli_dcm_refuses_another_robot(capsys):
    from wbmpc.cli import main

    assert main(["sensitivity", "--wrt", "dcm", "--robot", "g1"]) == 2
    err = capsys.readouterr().err
    assert "--robot g1" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("value", ["0", "-1e-4", "nan", "inf"])
def test_cli_refuses_a_bad_fd_step(capsys, value):
    from wbmpc.cli import main

    assert main(["sensitivity", "--wrt", "contact-timing", "--fd-step", value]) == 2
    err = capsys.readouterr().err
    assert "--fd-step" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
