"""The horizon-batched problem evaluates the same function as the node-wise pipeline."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pinocchio as pin
import pytest
from robot_extras import needs_h1_extra
from wbmpc_fixtures import alternating_schedule, random_state, standing_state

from robots import load_robot
from wbmpc.errors import ParameterError
from wbmpc.ocp.batched_problem import BatchedShootingProblem, batched_evaluation_support
from wbmpc.ocp.problem import ShootingProblem
from wbmpc.ocp.solvers import SolverFDDP
from wbmpc.walking.ocp import SlowPathWarning, WalkingOCP, WalkingOCPConfig
from wbmpc.walking.preset import load_walking_preset

# every running term of a point-foot walking OCP the batched pass supports (contact-force
# regularisation and friction cones included), a Baumgarte position gain (moving contact references)
BATCHED_TERMS = WalkingOCPConfig(foothold_weight=100.0, touchdown_height_weight=1e5, baumgarte_gains=(20.0, 40.0),
                                 contact_force_weight=1e-2, friction_cone_weight=10.0)
STACKED = ("xnext", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu")


@pytest.fixture(scope="module")
def bolt():
    return load_robot("bolt")


def _twin_problems(ocp: WalkingOCP) -> tuple[ShootingProblem, BatchedShootingProblem]:
    """A node-wise and a batched problem over the same node models (the OCP's own batched one,
    synced with the models)."""
    p = ocp.problem
    assert isinstance(p, BatchedShootingProblem)
    p.sync()
    return ShootingProblem(p.x0, p.running_models, p.terminal_model), p


def _random_trajectory(robot, n_nodes: int, nu: int, seed: int):
    rng = np.random.default_rng(seed)
    xs = np.array([random_state(robot, rng) for _ in range(n_nodes + 1)])
    us = 2.0 * rng.standard_normal((n_nodes, nu))  # some beyond Bolt's 2.7 N·m: the bound barrier acts
    return xs, us


def _batched_walking_ocp(robot, config: WalkingOCPConfig, n_nodes: int) -> WalkingOCP:
    """A WalkingOCP of 20 ms nodes that evaluates batched (a SlowPathWarning is an error)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", SlowPathWarning)
        ocp = WalkingOCP(robot, config, n_nodes=n_nodes, dt=0.02)
    assert ocp.evaluation == "batched"
    return ocp


def _small_random_trajectory(robot, n_nodes: int, nu: int, seed: int, q_scale: float, v_scale: float):
    """States near the standing posture (random_state's scales) and unit-normal torques [N·m]."""
    rng = np.random.default_rng(seed)
    xs = np.array([random_state(robot, rng, q_scale, v_scale) for _ in range(n_nodes + 1)])
    return xs, rng.standard_normal((n_nodes, nu))


def _assert_same(nodes: ShootingProblem, batched: BatchedShootingProblem, names=STACKED) -> None:
    for name in names:
        expected, actual = getattr(nodes, name), getattr(batched, name)
        scale = max(1.0, float(np.max(np.abs(expected))))
        assert np.max(np.abs(actual - expected)) <= 1e-12 * scale, name


def _assert_same_half_step_rollout(nodes: ShootingProblem, batched: BatchedShootingProblem, xs, us) -> None:
    """The FDDP rollout with α = 0.5 from the Riccati gains at (xs, us) costs the same on both problems."""
    solver = SolverFDDP(nodes)
    solver._set_candidate(xs, us, False)
    solver._calc_diff()
    solver._backward_pass()
    rollouts = []
    for problem in (nodes, batched):
        xs_try, us_try, dx = np.zeros_like(xs), np.zeros_like(us), np.zeros((problem.T, problem.ndx))
        rollouts.append(problem.forward_rollout(solver.xs, solver.us, solver._k, solver._K, solver.fs, 0.5, xs_try,
                                                us_try, dx))
    assert rollouts[1] == pytest.approx(rollouts[0], rel=1e-12)


def test_walking_ocp_uses_the_batched_problem_when_it_can(bolt):
    assert WalkingOCP(bolt, WalkingOCPConfig(), 5, 0.01).evaluation == "batched"
    nodes = WalkingOCP(bolt, WalkingOCPConfig(evaluation="nodes"), 5, 0.01)
    assert nodes.evaluation == "nodes" and type(nodes.problem) is ShootingProblem
    # the touchdown velocity (ResidualFrameVelocity) has no batched evaluation
    with pytest.warns(SlowPathWarning, match="node-wise evaluation.*ResidualFrameVelocity"):  # said, not silent
        fallback = WalkingOCP(bolt, WalkingOCPConfig(touchdown_velocity_weight=1.0), 5, 0.01)
    assert fallback.evaluation == "nodes"
    assert "ResidualFrameVelocity" in fallback.evaluation_note
    with pytest.raises(ParameterError, match="evaluation='batched'.*ResidualFrameVelocity"):
        WalkingOCP(bolt, WalkingOCPConfig(touchdown_velocity_weight=1.0, evaluation="batched"), 5, 0.01)
    with pytest.raises(ParameterError, match="evaluation='fast'"):
        WalkingOCPConfig(evaluation="fast")
    assert batched_evaluation_support(fallback.problem) is not None


@pytest.mark.parametrize("t0", [0.0, 0.27])
def test_values_and_derivatives_match_the_node_pipeline(bolt, t0):
    """Costs, next states and every derivative at random states, to rounding (1e-12)."""
    ocp = WalkingOCP(bolt, BATCHED_TERMS, n_nodes=40, dt=0.01)
    ocp.update(standing_state(bolt), alternating_schedule(t0, 0.01, 40), np.array([0.1, 0.0, 0.3]))
    nodes, batched = _twin_problems(ocp)
    xs, us = _random_trajectory(bolt, 40, ocp.nu, seed=3)
    cost = nodes.calc(xs, us)
    nodes.calcDiff(xs, us)
    assert batched.calc(xs, us) == pytest.approx(cost, rel=1e-13)
    _assert_same(nodes, batched, names=("xnext",))
    assert batched.calcDiff(xs, us) == pytest.approx(cost, rel=1e-13)
    _assert_same(nodes, batched)
    assert batched.term_costs() == pytest.approx(nodes.term_costs(), rel=1e-12, abs=1e-14)
    running = [d.cost for d in nodes.running_datas]
    np.testing.assert_allclose(batched.node_costs(), running, rtol=1e-12, atol=1e-15)
    active = {name for name, value in batched.term_costs().items() if value > 0}
    assert {"control_bounds", "state_regularization", "terminal_com_position"} <= active
    assert any(name.endswith("_foothold") for name in active)
    assert any(name.endswith("_touchdown_height") for name in active)
    assert any(name.endswith("_contact_force") for name in active)
    assert any(name.endswith("_friction_cone") for name in active)


def test_a_node_without_contacts_uses_aba(bolt):
    ocp = WalkingOCP(bolt, BATCHED_TERMS, n_nodes=6, dt=0.01)
    ocp.update(standing_state(bolt), alternating_schedule(0.0, 0.01, 6), np.array([0.1, 0.0, 0.3]))
    ocp.problem.running_models[2].differential.set_active_contacts([])  # a flight node
    for foot in ocp.feet:
        costs = ocp.problem.running_models[2].differential.costs.costs
        costs[f"{foot}_height"].active = True
        costs[f"{foot}_contact_force"].active = costs[f"{foot}_friction_cone"].active = False  # no contact to read
    nodes, batched = _twin_problems(ocp)
    xs, us = _random_trajectory(bolt, 6, ocp.nu, seed=4)
    assert batched.calcDiff(xs, us) == pytest.approx(nodes.calc_and_diff(xs, us), rel=1e-13)
    _assert_same(nodes, batched)


@pytest.mark.parametrize("n_nodes", [10, 50])
def test_g1_preset_flat_feet_match_the_node_pipeline(n_nodes):
    """The G1 preset's OCP (wrench cones on the 6D sole contacts, swing-sole orientation) with the
    contact-wrench regularisation too and a Baumgarte position gain: batched (no SlowPathWarning),
    and equal to the node-wise pipeline, values, derivatives and the rollout."""
    g1 = load_robot("g1")
    config = dataclasses.replace(load_walking_preset("g1").ocp, contact_force_weight=1e-4, baumgarte_gains=(10.0, 30.0))
    ocp = _batched_walking_ocp(g1, config, n_nodes)
    ocp.update(standing_state(g1), alternating_schedule(0.0, 0.02, n_nodes, step_duration=0.4, foot_y=(0.12, -0.12)),
               np.array([0.05, 0.0, 0.7]))
    nodes, batched = _twin_problems(ocp)
    xs, us = _small_random_trajectory(g1, n_nodes, ocp.nu, seed=2, q_scale=0.05, v_scale=0.2)
    cost = nodes.calc(xs, us)
    assert batched.calc(xs, us) == pytest.approx(cost, rel=1e-13)
    assert batched.calcDiff(xs, us) == pytest.approx(nodes.calc_and_diff(xs, us), rel=1e-13)
    _assert_same(nodes, batched)
    assert batched.term_costs() == pytest.approx(nodes.term_costs(), rel=1e-12, abs=1e-14)
    active = {name for name, value in batched.term_costs().items() if value > 0}
    assert {"left_wrench_cone", "left_contact_force", "right_orientation"} <= active
    _assert_same_half_step_rollout(nodes, batched, xs, us)


def test_a_force_term_active_where_its_contact_is_not_is_an_error_naming_it(bolt):
    ocp = WalkingOCP(bolt, BATCHED_TERMS, n_nodes=6, dt=0.01)
    ocp.update(standing_state(bolt), alternating_schedule(0.0, 0.01, 6), np.array([0.1, 0.0, 0.3]))
    batched = ocp.problem
    costs = batched.running_models[2].differential.costs.costs
    swing = next(foot for foot in ocp.feet if not costs[f"{foot}_friction_cone"].active)
    costs[f"{swing}_friction_cone"].active = True
    xs, us = _random_trajectory(bolt, 6, ocp.nu, seed=4)
    with pytest.raises(ParameterError, match=rf"cost on contact '{swing}' \(ResidualFrictionCone\) is active at "
                                             "running node 2, whose contact set"):
        batched.calc(xs, us)


@pytest.mark.parametrize("alpha", [1.0, 0.25])
def test_forward_rollout_matches_the_node_pipeline(bolt, alpha):
    """The FDDP rollout with feedback, closing the gaps by 1 − α."""
    ocp = WalkingOCP(bolt, BATCHED_TERMS, n_nodes=30, dt=0.01)
    ocp.update(standing_state(bolt), alternating_schedule(0.1, 0.01, 30), np.array([0.1, 0.0, 0.3]))
    nodes, batched = _twin_problems(ocp)
    solver = SolverFDDP(nodes)
    xs, us = _random_trajectory(bolt, 30, ocp.nu, seed=5)
    solver._set_candidate(xs, us, False)
    solver._calc_diff()
    solver._backward_pass()
    outputs = []
    for problem in (nodes, batched):
        xs_try, us_try, dx = np.zeros_like(xs), np.zeros_like(us), np.zeros((30, problem.ndx))
        cost = problem.forward_rollout(solver.xs, solver.us, solver._k, solver._K, solver.fs, alpha, xs_try, us_try,
                                       dx)
        outputs.append((cost, xs_try, us_try, dx))
    (c0, x0, u0, d0), (c1, x1, u1, d1) = outputs
    assert c1 == pytest.approx(c0, rel=1e-12)
    for a, b in ((x0, x1), (u0, u1), (d0, d1)):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-12 * max(1.0, np.max(np.abs(a))))


def test_solves_take_the_same_iterates(bolt):
    """A 20-iteration solve from the same guess: same iterations, cost and trajectory."""
    results = []
    for evaluation in ("nodes", "batched"):
        ocp = WalkingOCP(bolt, dataclasses.replace(BATCHED_TERMS, evaluation=evaluation), n_nodes=30, dt=0.01)
        x0 = standing_state(bolt)
        ocp.update(x0, alternating_schedule(0.0, 0.01, 30), np.array([0.1, 0.0, 0.3]))
        solver = SolverFDDP(ocp.problem)
        converged = solver.solve([x0] * 31, [np.zeros(ocp.nu)] * 30, maxiter=20)
        results.append((converged, solver.iter, solver.cost, solver.xs.copy(), solver.us.copy(), solver.K.copy()))
    (c0, i0, cost0, xs0, us0, K0), (c1, i1, cost1, xs1, us1, K1) = results
    assert (c1, i1) == (c0, i0)
    assert cost1 == pytest.approx(cost0, rel=1e-10)
    np.testing.assert_allclose(xs1, xs0, atol=1e-8)
    np.testing.assert_allclose(us1, us0, atol=1e-8)
    np.testing.assert_allclose(K1, K0, atol=1e-6 * np.max(np.abs(K0)))


@pytest.mark.parametrize("config", [BATCHED_TERMS, WalkingOCPConfig(foothold_weight=1e5, touchdown_height_weight=1e5)])
def test_updates_are_read_from_the_node_models(bolt, config):
    """After every WalkingOCP.update (contact sets, activity, references moving with the
    schedule) the batched problem evaluates what the node-wise pipeline evaluates on its models."""
    ocp = WalkingOCP(bolt, config, n_nodes=40, dt=0.01)
    nodes, batched = ShootingProblem(ocp.problem.x0, ocp.problem.running_models, ocp.problem.terminal_model), \
        ocp.problem
    xs, us = _random_trajectory(bolt, 40, ocp.nu, seed=8)
    for t0, step_duration in ((0.0, 0.3), (0.01, 0.3), (0.13, 0.27), (0.29, 0.3)):
        ocp.update(standing_state(bolt), alternating_schedule(t0, 0.01, 40, step_duration=step_duration),
                   np.array([0.1, 0.0, 0.3]))
        assert batched.calcDiff(xs, us) == pytest.approx(nodes.calc_and_diff(xs, us), rel=1e-13)
        _assert_same(nodes, batched)
        assert batched.term_costs() == pytest.approx(nodes.term_costs(), rel=1e-12, abs=1e-14)
    assert batched.term_costs()["left_foothold"] > 0 or batched.term_costs()["right_foothold"] > 0
    # a reference written into a node residual is seen without sync (the batched rows are its storage)
    item = ocp.problem.running_models[3].differential.costs.costs["state_regularization"]
    item.cost.residual.reference[7] += 0.1
    assert batched.calc(xs, us) == pytest.approx(nodes.calc(xs, us), rel=1e-13)
    with pytest.raises(ParameterError, match="no running cost term 'nose_height'"):
        batched.term_index("nose_height")


def test_weights_and_activity_set_on_the_node_items_are_seen_without_sync(bolt):
    """A cost item's weight or activity set after the last sync (sync reads only the contact sets)
    is what the batched evaluation uses, a frame term switched on included (its frame's
    kinematics are then computed at that node)."""
    ocp = WalkingOCP(bolt, BATCHED_TERMS, n_nodes=12, dt=0.01)
    ocp.update(standing_state(bolt), alternating_schedule(0.0, 0.01, 12), np.array([0.1, 0.0, 0.3]))
    nodes, batched = _twin_problems(ocp)
    xs, us = _random_trajectory(bolt, 12, ocp.nu, seed=10)
    costs = [model.differential.costs.costs for model in batched.running_models]
    frame_term = next(name for name in ("left_height", "right_height") if not costs[4][name].active)
    costs[3]["state_regularization"].weight *= 3.0
    costs[5]["control_regularization"].active = False
    costs[6]["control_bounds"].weight = 0.0
    costs[4][frame_term].active = True
    costs[4][frame_term].cost.residual.reference = 0.2
    batched.running_models[7].differential.costs.changeCostStatus("state_regularization", False)
    assert batched.calcDiff(xs, us) == pytest.approx(nodes.calc_and_diff(xs, us), rel=1e-13)
    _assert_same(nodes, batched)
    assert batched.term_costs() == pytest.approx(nodes.term_costs(), rel=1e-12, abs=1e-14)
    assert batched.node_costs()[4] == pytest.approx(nodes.running_datas[4].cost, rel=1e-12)
    costs[4][frame_term].active = False  # and back off
    assert batched.calc(xs, us) == pytest.approx(nodes.calc(xs, us), rel=1e-13)
    with pytest.raises(ParameterError, match="weight=-1.0 of cost 'control_bounds' must be finite and >= 0"):
        costs[6]["control_bounds"].weight = -1.0


@pytest.mark.parametrize(("nr", "ndx", "nu"), [(1, 3, 2), (7, 50, 19), (300, 12, 0), (0, 4, 3)])
def test_the_dense_patterns_hessian_entries_are_those_of_its_rows(nr, ndx, nu):
    """A node's cost data lists the Hessian entries of its dense Jacobian pattern without building the rows' incidence:
    the same arrays, in the same order, as :func:`hessian_entries` of the pattern (none without rows)."""
    from wbmpc.ocp.kernels.costs import dense_hessian_entries, hessian_entries

    n = ndx + nu
    pattern = hessian_entries(np.arange(0, nr * n + 1, n, dtype=np.int64), np.tile(np.arange(n, dtype=np.int64), nr),
                              ndx)
    dense = dense_hessian_entries(n if nr else 0, ndx)
    for expected, got in zip(pattern, dense, strict=True):
        assert got.dtype == np.int64 and got.flags.c_contiguous and np.array_equal(got, expected)


@pytest.mark.parametrize("density", [0.3, 1.0])
def test_sparse_gauss_newton_writes_exactly_the_dense_result_on_its_hessian_entries(density):
    """The batched pass's Hessian over the entries of its Jacobian pattern equals the dense
    Gauss-Newton Hessian, and reads and writes no other entry (NaN elsewhere stays NaN); a dense
    pattern (every entry listed: the lists' row-by-row branch) too."""
    from wbmpc.ocp.kernels.costs import (
        add_gauss_newton_rows,
        clear_hessian_entries,
        cost_rows_derivatives,
        hessian_entries,
        scale_cost_derivatives,
    )
    rng = np.random.default_rng(1)
    ndx, nu, nr = 8, 3, 9
    n = ndx + nu
    mask = rng.random((nr, n)) < density
    mask[0, [1, ndx + 1]] = True  # an Lxu entry
    mask[1, [ndx, ndx + 2]] = True  # an off-diagonal Luu entry
    R = np.where(mask, rng.standard_normal((nr, n)), 0.0)
    rows, cols = np.nonzero(mask)
    row_start = np.searchsorted(rows, np.arange(nr + 1)).astype(np.int64)
    r, w = rng.standard_normal(nr), rng.random(nr) + 0.1
    lb, ub = -0.3 * np.ones(nr), 0.3 * np.ones(nr)  # some rows in the dead zone
    row_term = (np.arange(nr) % 2).astype(np.int64)
    term_scale = np.array([2.0, 0.5])
    gradient, hessian = np.zeros(n), np.zeros((n, n))
    cost_rows_derivatives(r, R.reshape(-1), np.arange(0, nr * n + 1, n, dtype=np.int64),
                          np.tile(np.arange(n, dtype=np.int64), nr), row_term, term_scale, w, lb, ub, gradient, hessian)
    entries = hessian_entries(row_start, cols, ndx)
    assert sum(e.shape[0] for e in entries) == np.count_nonzero(np.triu(mask.T.astype(float) @ mask))
    sparse_gradient, sparse_hessian = np.zeros(n), np.full((n, n), np.nan)
    clear_hessian_entries(sparse_hessian, *entries)
    add_gauss_newton_rows(r, R[rows, cols], row_start, cols, row_term, term_scale, w, lb, ub, sparse_gradient,
                          sparse_hessian)
    blocks = [np.full(shape, np.nan) for shape in ((ndx,), (nu,), (ndx, ndx), (ndx, nu), (nu, nu))]
    scale_cost_derivatives(0.01, sparse_gradient, sparse_hessian, *entries, *blocks)
    Lx, Lu, Lxx, Lxu, Luu = blocks
    dense = 0.01 * hessian
    for block, expected in ((Lxx, dense[:ndx, :ndx]), (Lxu, dense[:ndx, ndx:]), (Luu, dense[ndx:, ndx:])):
        written = ~np.isnan(block)
        assert np.array_equal(block[written], expected[written])
        assert not np.any(expected[~written])  # what is not written is structurally zero
    assert np.array_equal(Lx, 0.01 * gradient[:ndx]) and np.array_equal(Lu, 0.01 * gradient[ndx:])
    assert not np.isnan(Lxu).all() and np.isnan(Luu).any() == (density < 1.0)
    assert np.isnan(sparse_hessian[np.tril_indices(n, -1)]).all()  # the lower triangle neither read nor written


def test_a_term_without_batched_evaluation_is_an_error_naming_it(bolt):
    ocp = WalkingOCP(bolt, WalkingOCPConfig(touchdown_velocity_weight=1.0, evaluation="nodes"), 5, 0.01)
    p = ocp.problem
    with pytest.raises(ParameterError, match=r"cost 'left_touchdown_velocity' \(ResidualFrameVelocity\) cannot be "
                                             "batched: the compiled horizon kinematics"):
        BatchedShootingProblem(p.x0, p.running_models, p.terminal_model)


class _PlainControlResidual:
    """A residual written by a user without a batched evaluation (r = u, node-wise only)."""

    def __init__(self, state, nu):
        self.state, self.nu, self.nr = state, nu, nu

    def calc(self, data, x, u, shared):
        data.r[:] = u

    def calcDiff(self, data, x, u, shared):
        data.Ru[:] = np.eye(self.nu)

    def createData(self):
        from wbmpc.ocp.residuals import ResidualData

        return ResidualData(self.nr, self.state.ndx, self.nu)


def test_a_custom_residual_without_batched_evaluation_keeps_the_problem_node_wise(bolt):
    """The reason names the custom class; the problems stay node-wise and equal to themselves."""
    from wbmpc.ocp.costs import CostModelResidual

    ocp = WalkingOCP(bolt, WalkingOCPConfig(evaluation="nodes"), 5, 0.01)
    p = ocp.problem
    assert batched_evaluation_support(p) is None
    for model in p.running_models:
        model.differential.costs.add("plain", CostModelResidual(_PlainControlResidual(ocp.state, ocp.nu)), 1.0)
    assert batched_evaluation_support(p) == ("cost 'plain' (_PlainControlResidual) cannot be batched: it declares "
                                             "no batched evaluation")
    with pytest.raises(ParameterError, match=r"cannot be evaluated batched: cost 'plain' \(_PlainControlResidual\)"):
        BatchedShootingProblem(p.x0, p.running_models, p.terminal_model)


def test_a_second_batched_problem_over_the_same_models_detaches_the_first(bolt):
    ocp = WalkingOCP(bolt, BATCHED_TERMS, 5, 0.01)
    ocp.update(standing_state(bolt), alternating_schedule(0.0, 0.01, 5), np.array([0.1, 0.0, 0.3]))
    first = ocp.problem
    p = first
    second = BatchedShootingProblem(p.x0, p.running_models, p.terminal_model)
    xs, us = _random_trajectory(bolt, 5, ocp.nu, seed=9)
    second.calc(xs, us)
    with pytest.raises(ParameterError, match="bound by a newer BatchedShootingProblem"):
        first.calc(xs, us)


def test_the_base_yaw_reference_follows_the_planned_footholds(bolt):
    """base_yaw_reference="footholds": each node's state reference turns the base by the mean
    yaw of the feet's footholds (both evaluations see it); "fixed" keeps the reference posture's."""
    from wbmpc.walking.ocp import foothold_heading

    schedule = alternating_schedule(0.0, 0.01, 40)
    contact = np.asarray(schedule.in_contact)
    turning = dataclasses.replace(  # the left foothold at 0.2 rad, the right one at 0.4, landings at 0.6
        schedule, contact_yaw=np.where(contact, np.array([0.2, 0.4]), np.nan),
        touchdown_yaw=np.where(contact, np.nan, 0.6))
    heading = foothold_heading(contact, turning.contact_yaw, turning.touchdown_yaw)
    assert set(np.round(heading, 12)) == {0.4, 0.5}  # left swinging: (0.6 + 0.4) / 2; right swinging: (0.2 + 0.6) / 2
    xs, us = _random_trajectory(bolt, 40, 6, seed=3)
    costs = {}
    for reference in ("fixed", "footholds"):
        ocp = WalkingOCP(bolt, WalkingOCPConfig(base_yaw_reference=reference), n_nodes=40, dt=0.01)
        ocp.update(standing_state(bolt), turning, np.array([0.1, 0.0, 0.3]))
        nodes, batched = _twin_problems(ocp)
        costs[reference] = batched.calc(xs, us)
        assert costs[reference] == pytest.approx(nodes.calc(xs, us), rel=1e-13)
        models = [*ocp.problem.running_models, ocp.problem.terminal_model]
        yaws = [pin.rpy.matrixToRpy(pin.Quaternion(m.differential.costs.costs["state_regularization"]
                                                   .cost.residual.reference[3:7]).toRotationMatrix())[2] for m in models]
        np.testing.assert_allclose(yaws, heading if reference == "footholds" else 0.0, atol=1e-12)
    assert costs["footholds"] != pytest.approx(costs["fixed"], rel=1e-6)
    with pytest.raises(ParameterError, match="base_yaw_reference='heading' must be one of"):
        WalkingOCPConfig(base_yaw_reference="heading")
    with pytest.raises(ParameterError, match="a node has no foot with a planned yaw"):
        foothold_heading(contact[:2], np.full((2, 2), np.nan), np.full((2, 2), np.nan))


@needs_h1_extra
def test_contact_damping_reaches_the_batched_constraint_dynamics():
    """The batched problem's per-node constraintDynamics calls use the node dynamics' proximal
    settings: with contact_damping on the H1 (double support, then a step) it evaluates what the
    node pipeline evaluates, and not what the rigid contacts give."""
    h1 = load_robot("h1")
    schedule = alternating_schedule(0.0, 0.02, 10, step_duration=0.4, foot_y=(0.2, -0.2), t_start=0.07)
    stacked = {}
    for damping in (1e-3, 0.0):
        config = WalkingOCPConfig(swing_apex_height=0.08, baumgarte_gains=(0.0, 30.0), contact_damping=damping)
        ocp = WalkingOCP(h1, config, n_nodes=10, dt=0.02)
        ocp.update(standing_state(h1), schedule, np.array([0.0, 0.0, 0.97]))
        assert ocp.evaluation == "batched"
        nodes, batched = _twin_problems(ocp)
        rng = np.random.default_rng(2)
        xs = np.array([random_state(h1, rng, 0.02, 0.1) for _ in range(11)])
        us = rng.standard_normal((10, ocp.nu))
        assert batched.calcDiff(xs, us) == pytest.approx(nodes.calc_and_diff(xs, us), rel=1e-13)
        _assert_same(nodes, batched)
        stacked[damping] = batched.Fx.copy()
    assert np.max(np.abs(stacked[1e-3] - stacked[0.0])) > 1e-3 * np.max(np.abs(stacked[0.0]))


@needs_h1_extra
@pytest.mark.parametrize("moments", ["sole", "corners"])
def test_h1_soles_with_the_obstacle_clearance_are_batched_and_match_the_node_pipelines(moments):
    """The H1 preset over a swing that crosses a box (the clearance terms on the toe, heel and knee and the smooth
    swing path's tracking active), with
    its "sole" contact damping (the KKT backend: the batched problem calls each node's own dynamics) or
    "corners" (each sole's four corner contacts, Pinocchio's constraintDynamics): batched without a
    SlowPathWarning and equal to the node-wise pipeline (values, derivatives, a rollout, the prepared dynamics);
    "corners" also to the KKT backend's node-wise pipeline (the scaled 6D soles with the corners' drift)."""
    from wbmpc_fixtures import crossing_schedule

    h1 = load_robot("h1")
    backend = "kkt" if moments == "sole" else "pinocchio"
    config = dataclasses.replace(_h1_preset_on_pinocchio_paths(), contact_damping_moments=moments,
                                 dynamics_backend=backend, evaluation="auto", obstacle_swing_path_timing="smooth",
                                 obstacle_swing_path_weight=1e4, obstacle_clearance_gating="path",
                                 obstacle_com_weight=0.0)  # (the "profile" clearance and the CoM path: below)
    n_nodes = 12
    schedule, crossings = crossing_schedule(n_nodes)
    ocp = _batched_walking_ocp(h1, config, n_nodes)
    ocp.update(standing_state(h1), schedule, np.array([0.1, 0.0, 0.97]), crossings=crossings)
    nodes, batched = _twin_problems(ocp)
    xs, us = _small_random_trajectory(h1, n_nodes, ocp.nu, seed=3, q_scale=0.02, v_scale=0.1)
    cost = nodes.calc_and_diff(xs, us)
    assert batched.calcDiff(xs, us) == pytest.approx(cost, rel=1e-13)
    _assert_same(nodes, batched)
    keys = [model.differential.active_key for model in batched.running_models]
    assert batched.prepare_dynamics(xs[:n_nodes], us, keys) == n_nodes
    assert batched.calcDiff(xs, us) == pytest.approx(cost, rel=1e-13)
    assert batched.prepared_used == n_nodes
    _assert_same(nodes, batched)
    if moments == "corners":
        kkt_ocp = WalkingOCP(h1, dataclasses.replace(config, dynamics_backend="kkt", evaluation="nodes"),
                             n_nodes=n_nodes, dt=0.02)
        kkt_ocp.update(standing_state(h1), schedule, np.array([0.1, 0.0, 0.97]), crossings=crossings)
        kkt = kkt_ocp.problem
        assert kkt.calc_and_diff(xs, us) == pytest.approx(cost, rel=1e-11)
        for name in STACKED:
            for k in range(n_nodes):
                ours, theirs = getattr(kkt.running_datas[k], name), getattr(nodes.running_datas[k], name)
                assert np.max(np.abs(ours - theirs)) <= 1e-9 * max(1.0, np.max(np.abs(theirs))), (name, k)
    for name in ("right_clearance_sole0", "right_clearance_sole1", "right_clearance_shank", "right_swing_path",
                 "left_wrench_cone"):
        assert any(model.differential.costs.costs[name].active for model in nodes.running_models), name
    assert batched.term_costs()["right_clearance_sole0"] > 0  # the random states put the toe below the clearance
    _assert_same_half_step_rollout(nodes, batched, xs, us)


def _h1_crossing_ocp(n_nodes: int, com_weight: float) -> tuple:
    """The H1 preset's OCP (KKT backend, "profile" clearance of the sole points, the smooth crossing path's
    tracking), batched, with ``obstacle_com_weight`` = com_weight, updated over crossing_schedule's swings over a
    10 cm box with a CoM path: (robot, ocp, schedule)."""
    from wbmpc_fixtures import crossing_schedule

    h1 = load_robot("h1")
    config = dataclasses.replace(load_walking_preset("h1").ocp, evaluation="batched", obstacle_com_weight=com_weight)
    assert config.obstacle_clearance_gating == "profile"
    ocp = _batched_walking_ocp(h1, config, n_nodes)
    schedule, crossings = crossing_schedule(n_nodes)
    com_path = np.column_stack([np.linspace(0.0, 0.3, n_nodes + 1), np.full(n_nodes + 1, 0.01),
                                np.full(n_nodes + 1, 0.97)])
    ocp.update(standing_state(h1), schedule, np.array([0.1, 0.0, 0.97]), crossings=crossings, com_path=com_path)
    return h1, ocp, schedule


def _sole_point(robot, residual, x: np.ndarray) -> np.ndarray:
    """World position (3,) [m] of a ResidualFramePointAboveBox's point at the state x."""
    model = robot.pinocchio_model
    data = model.createData()
    pin.framesForwardKinematics(model, data, x[:model.nq])
    placement = data.oMf[residual.frame_id]
    return placement.translation + placement.rotation @ residual.point_local


def _box_beside(residual, point: np.ndarray, yaw: float, along: float, across: float) -> None:
    """Set residual's box (5 x 10 cm half extents, 15 cm top) so that ``point`` (3,) [m] is ``along`` and
    ``across`` [m] beyond its grown footprint's edges (its axis at ``yaw`` [rad]): negative inside,
    0 < along < transition on the profile's slope."""
    axis = np.array([np.cos(yaw), np.sin(yaw)])
    normal = np.array([-axis[1], axis[0]])
    half = np.array([0.05, 0.1]) + residual.margin
    centre = point[:2] - (half[0] + along) * axis - (half[1] + across) * normal
    residual.set_box(centre, axis, 0.05, 0.1, 0.15)


def _term_rows(batched: BatchedShootingProblem, name: str, k: int) -> tuple[np.ndarray, np.ndarray]:
    """(r (nr,), [Rx Ru] (nr, ndx + nu)) of the running term ``name`` at node k after the batched problem's
    last evaluation (the Jacobian from its pattern's nonzeros, after a calcDiff)."""
    j = batched.term_index(name)
    r = batched._r[k, batched._term_rows[j]].copy()
    rows, cols = batched._terms[j].jacobian_pattern()
    jacobian = np.zeros((r.size, batched.ndx + batched.nu))
    jacobian[rows, cols] = batched._values[k, batched._term_values[j]]
    return r, jacobian


@needs_h1_extra
def test_h1_box_profile_clearance_batched_jacobian_matches_finite_differences():
    """The batched rows of the "profile" clearance (ResidualFramePointAboveBox) at swing nodes whose box puts the
    toe on the profile's slope (one edge, then a corner: both windows falling) and inside the grown footprint:
    their Jacobian against central differences of the batched rows, through the frame rotation and ∇h."""
    from wbmpc.ocp.numdiff import tangent_jacobian

    n_nodes = 12
    h1, ocp, schedule = _h1_crossing_ocp(n_nodes, com_weight=0.0)
    batched = ocp.problem
    swing = np.flatnonzero(~np.asarray(schedule.in_contact)[:n_nodes, 1])
    name = "right_clearance_sole0"
    xs, us = _small_random_trajectory(h1, n_nodes, ocp.nu, seed=8, q_scale=0.05, v_scale=0.1)
    cases = [(swing[0], 0.3, 0.02, -0.05), (swing[1], -0.4, 0.03, 0.015), (swing[2], 0.0, -0.01, -0.05)]
    for k, yaw, along, across in cases:
        residual = batched.running_models[k].differential.costs.costs[name].cost.residual
        _box_beside(residual, _sole_point(h1, residual, xs[k]), yaw, along, across)
    batched.calcDiff(xs, us)
    for k, _, along, _ in cases:
        residual = batched.running_models[k].differential.costs.costs[name].cost.residual
        r, jacobian = _term_rows(batched, name, k)
        height, gradient = residual.profile(_sole_point(h1, residual, xs[k])[:2])
        assert r[0] == pytest.approx(_sole_point(h1, residual, xs[k])[2] - height, abs=1e-14)
        if along > 0:  # on the slope
            assert 0.0 < height < 0.15 and np.linalg.norm(gradient) > 1.0
        else:
            assert height == 0.15 and not gradient.any()

        def r_of_x(x, k=k):
            trial = xs.copy()
            trial[k] = x
            batched.calc(trial, us)
            return batched._r[k, batched._term_rows[batched.term_index(name)]].copy()

        expected = tangent_jacobian(batched.state, r_of_x, xs[k])
        error = np.max(np.abs(jacobian[:, :batched.ndx] - expected))
        assert error <= 1e-6 * np.max(np.abs(expected)), (k, error)
        assert not jacobian[:, batched.ndx:].any()


@needs_h1_extra
def test_h1_preset_with_a_crossing_is_batched_and_matches_the_node_pipeline():
    """The H1 preset's OCP as it is (KKT backend, "profile" clearance of the sole points, the smooth crossing path's
    tracking, ``com_path`` tracking the plan's CoM) over swings that cross a box: batched (the box profile's and the
    CoM's batched evaluations) and equal to the node-wise pipeline, values, derivatives and a rollout, with a toe on
    the profile's slope, a heel at a corner of its transition, and nodes where the box is cleared (h = ground)."""
    n_nodes = 20
    h1, ocp, schedule = _h1_crossing_ocp(n_nodes, com_weight=load_walking_preset("h1").ocp.obstacle_com_weight)
    nodes, batched = _twin_problems(ocp)
    xs, us = _small_random_trajectory(h1, n_nodes, ocp.nu, seed=5, q_scale=0.02, v_scale=0.1)
    costs = [model.differential.costs.costs for model in batched.running_models]
    right, left = (np.flatnonzero(~np.asarray(schedule.in_contact)[:n_nodes, j]) for j in (1, 0))
    for k, name, yaw, along, across in ((right[1], "right_clearance_sole0", 0.2, 0.02, -0.05),
                                        (right[3], "right_clearance_sole1", -0.3, 0.01, 0.02),
                                        (left[2], "left_clearance_sole0", 0.0, 0.035, -0.05)):
        residual = costs[k][name].cost.residual
        _box_beside(residual, _sole_point(h1, residual, xs[k]), yaw, along, across)
        height, gradient = residual.profile(_sole_point(h1, residual, xs[k])[:2])
        assert 0.0 < height < 0.15 and np.linalg.norm(gradient) > 1.0
    for k in (right[5], left[4]):
        costs[k]["right_clearance_sole1" if k == right[5] else "left_clearance_sole1"].cost.residual.clear()
    assert all(node["com_path"].active for node in costs)
    for name in ("right_clearance_sole0", "left_clearance_sole1", "right_swing_path"):
        assert any(node[name].active for node in costs), name
    cost = nodes.calc(xs, us)
    assert batched.calc(xs, us) == pytest.approx(cost, rel=1e-13)
    _assert_same(nodes, batched, names=("xnext",))
    cost = nodes.calc_and_diff(xs, us)
    assert batched.calcDiff(xs, us) == pytest.approx(cost, rel=1e-13)
    _assert_same(nodes, batched)
    assert batched.term_costs() == pytest.approx(nodes.term_costs(), rel=1e-12, abs=1e-14)
    np.testing.assert_allclose(batched.node_costs(), [d.cost for d in nodes.running_datas], rtol=1e-12, atol=1e-15)
    terms = batched.term_costs()
    assert terms["com_path"] > 0 and terms["right_clearance_sole0"] > 0 and terms["left_clearance_sole0"] > 0
    _assert_same_half_step_rollout(nodes, batched, xs, us)


def test_rollout_dynamics_is_checked_naming_the_choices(bolt):
    """rollout_dynamics: a one-line ParameterError naming the field, its value and what is allowed (the
    config, the problem, calc_dynamics); "compiled" needs the "kkt" backend and the batched evaluation."""
    with pytest.raises(ParameterError, match=r"^rollout_dynamics='fast' must be 'pinocchio' or 'compiled'$"):
        WalkingOCPConfig(rollout_dynamics="fast")
    with pytest.raises(ParameterError, match=r"^rollout_dynamics='compiled' needs dynamics_backend='kkt'.*got "
                                             r"'pinocchio'$"):
        WalkingOCPConfig(rollout_dynamics="compiled")
    with pytest.raises(ParameterError, match=r"^rollout_dynamics='compiled' needs the batched evaluation.*got "
                                             r"evaluation='nodes'$"):
        WalkingOCPConfig(rollout_dynamics="compiled", dynamics_backend="kkt", evaluation="nodes")
    assert WalkingOCPConfig().rollout_dynamics == "pinocchio"
    config = WalkingOCPConfig(dynamics_backend="kkt", rollout_dynamics="compiled")
    with pytest.raises(ParameterError, match=r"^rollout_dynamics='compiled' needs the batched evaluation, not "
                                             r"possible for this problem: .*ResidualFrameVelocity"):
        WalkingOCP(bolt, dataclasses.replace(config, touchdown_velocity_weight=1.0), 5, 0.01)
    ocp = WalkingOCP(bolt, config, 5, 0.01)
    assert ocp.problem.rollout_dynamics == "compiled"
    p = ocp.problem
    with pytest.raises(ParameterError, match=r"^rollout_dynamics='Compiled' must be one of \('pinocchio', "
                                             r"'compiled'\)$"):
        BatchedShootingProblem(p.x0, p.running_models, p.terminal_model, rollout_dynamics="Compiled")
    assert BatchedShootingProblem(p.x0, p.running_models, p.terminal_model).rollout_dynamics == "pinocchio"
    dam, data = p.running_models[0].differential, p.running_datas[0].differential
    with pytest.raises(ParameterError, match=r"^rollout_dynamics=None must be one of"):
        dam.calc_dynamics(data, p.x0, np.zeros(ocp.nu), None)


def _h1_rollouts(ocp: WalkingOCP, n_nodes: int, seed: int, python_node: int | None = None):
    """The H1 OCP's batched problem after an update, its node-wise twin, and an FDDP step's
    (solver, xs, us) from the twin's Riccati gains at a small random trajectory."""
    h1 = ocp.robot
    ocp.update(standing_state(h1), alternating_schedule(0.0, 0.02, n_nodes, step_duration=0.1, foot_y=(0.2, -0.2),
                                                        t_start=0.07), np.array([0.1, 0.0, 0.97]))
    nodes, batched = _twin_problems(ocp)
    xs, us = _small_random_trajectory(h1, n_nodes, ocp.nu, seed=seed, q_scale=0.02, v_scale=0.1)
    solver = SolverFDDP(nodes)
    solver._set_candidate(xs, us, False)
    solver._calc_diff()
    solver._backward_pass()
    return nodes, batched, solver


def _rollout(problem, solver, alpha: float, calls: list | None = None) -> tuple:
    """(cost, xs_try, us_try, dx, the batched problem's kept forces) of ``problem``'s rollout; ``calls``:
    the rollout_dynamics of each node a batched problem runs from Python."""
    xs_try, us_try = np.zeros_like(solver.xs), np.zeros_like(solver.us)
    dx = np.zeros((problem.T, problem.ndx))
    if calls is not None:
        problem._kkt_dynamics = lambda *args, seen=calls: (seen.append(args[-1]) or
                                                          BatchedShootingProblem._kkt_dynamics(*args))
    cost = problem.forward_rollout(solver.xs, solver.us, solver._k, solver._K, solver.fs, alpha, xs_try, us_try, dx)
    forces = problem._forces.copy() if isinstance(problem, BatchedShootingProblem) else None
    return cost, xs_try, us_try, dx, forces


def _h1_preset_on_pinocchio_paths():
    """The H1 preset's OCP with both dynamics paths "pinocchio" (the reference the compiled ones are checked
    against, and its obstacle runs' paths; its walking runs are compiled since session 33)."""
    return dataclasses.replace(load_walking_preset("h1").ocp, rollout_dynamics="pinocchio",
                               derivative_dynamics="pinocchio")


@needs_h1_extra
def test_h1_rollout_dynamics_pinocchio_is_mains_node_by_node_rollout():
    """rollout_dynamics="pinocchio" (the default; the H1 preset's obstacle runs'): every "kkt" node of the rollout is
    its own calc_dynamics as before the option (Pinocchio's crba and nonLinearEffects, the explicit-inverse KKT
    solve, node by node from Python), so each transition is, to the last bit, the default calc_dynamics and
    Euler step at the rollout's (x, u); the compiled rollout is not built."""
    from wbmpc.ocp.kernels.integration import free_flyer_euler_step

    h1 = load_robot("h1")
    n_nodes = 12
    preset = _h1_preset_on_pinocchio_paths()
    ocp = _batched_walking_ocp(h1, preset, n_nodes)
    nodes, batched, solver = _h1_rollouts(ocp, n_nodes, seed=6)
    assert batched.rollout_dynamics == "pinocchio" and batched._kkt_rollout is None and batched._keep_forces
    for alpha in (1.0, 0.5):
        calls = []
        cost, xs_try, us_try, _, forces = _rollout(batched, solver, alpha, calls)
        assert calls == ["pinocchio"] * n_nodes
        for t, (model, entry) in enumerate(zip(batched.running_models, batched._node_dynamics)):
            dam, data = entry[-1]
            assert dam is model.differential and not data.kinematics_for_costs
            fresh = dam.createData()
            fresh.kinematics_for_costs = False
            dam.calc_dynamics(fresh, xs_try[t], us_try[t])
            xnext, euler_dx = np.zeros(batched.state.nx), np.zeros(batched.ndx)
            free_flyer_euler_step(xs_try[t], fresh.xout, model.dt, euler_dx, xnext)
            assert np.array_equal(xnext, batched.xnext[t])
            assert np.array_equal(forces[t, :dam.nc], fresh.force_all[:dam.nc])
        reference = _rollout(nodes, solver, alpha)
        assert cost == pytest.approx(reference[0], rel=1e-12)


@needs_h1_extra
@pytest.mark.parametrize("python_node", [None, 5])
def test_h1_rollout_dynamics_compiled_agrees_with_pinocchio(python_node):
    """rollout_dynamics="compiled" on the H1 preset ("kkt" soles): the rollout's nodes in one compiled call
    (kernels/rollout.py) give the node-by-node rollout's states, controls, forces and cost to the last bit
    (the same kernels), and the "pinocchio" rollout's (Pinocchio's M and b, the explicit-inverse KKT solve)
    and the node-wise pipeline's to 1e-12 relative; a node handed back to Python in the middle (as one the
    compiled call cannot run) is run there, the compiled call resuming after it."""
    h1 = load_robot("h1")
    n_nodes = 12
    preset = load_walking_preset("h1").ocp
    ocp = _batched_walking_ocp(h1, dataclasses.replace(preset, rollout_dynamics="compiled"), n_nodes)
    nodes, batched, solver = _h1_rollouts(ocp, n_nodes, seed=6)
    assert batched.rollout_dynamics == "compiled"
    assert all(batched._kkt_rollout.compiled(k) for k in range(n_nodes)) and batched._keep_forces
    if python_node is not None:
        batched._horizon_contacts.contacts[python_node] = -1
    default = _batched_walking_ocp(h1, dataclasses.replace(preset, rollout_dynamics="pinocchio"), n_nodes)
    _, default_problem, _ = _h1_rollouts(default, n_nodes, seed=6)
    for alpha in (1.0, 0.5):
        outputs = []
        for use_compiled in (False, True):
            batched.use_compiled_rollout = use_compiled
            calls = []
            outputs.append(_rollout(batched, solver, alpha, calls))
            assert calls == ["compiled"] * (n_nodes if not use_compiled else python_node is not None)
        python, (c2, x2, u2, d2, f2) = outputs
        assert c2 == python[0] and all(np.array_equal(a, b) for a, b in zip((x2, u2, d2, f2), python[1:]))
        for reference in (_rollout(default_problem, solver, alpha), _rollout(nodes, solver, alpha)):
            c0, x0, u0 = reference[:3]
            assert c2 == pytest.approx(c0, rel=1e-12)
            for ours, theirs in ((x2, x0), (u2, u0)):
                assert np.max(np.abs(ours - theirs)) <= 1e-12 * np.max(np.abs(theirs))
            if reference[4] is not None:
                assert np.max(np.abs(f2 - reference[4])) <= 1e-12 * np.max(np.abs(reference[4]))
            assert not np.array_equal(x2, x0) or reference[4] is None  # not the same path: rounding differs


def test_derivative_dynamics_is_checked_naming_the_choices(bolt):
    """derivative_dynamics: a one-line ParameterError naming the field, its value and what is allowed (the
    config, the problem, calc_dynamics, calc_diff_dynamics); "compiled" needs the "kkt" backend and the batched
    evaluation, as rollout_dynamics."""
    with pytest.raises(ParameterError, match=r"^derivative_dynamics='fast' must be 'pinocchio' or 'compiled'$"):
        WalkingOCPConfig(derivative_dynamics="fast")
    with pytest.raises(ParameterError, match=r"^derivative_dynamics='compiled' needs dynamics_backend='kkt'.*got "
                                             r"'pinocchio'$"):
        WalkingOCPConfig(derivative_dynamics="compiled")
    with pytest.raises(ParameterError, match=r"^derivative_dynamics='compiled' needs the batched evaluation.*got "
                                             r"evaluation='nodes'$"):
        WalkingOCPConfig(derivative_dynamics="compiled", dynamics_backend="kkt", evaluation="nodes")
    assert WalkingOCPConfig().derivative_dynamics == "pinocchio"
    config = WalkingOCPConfig(dynamics_backend="kkt", derivative_dynamics="compiled")
    with pytest.raises(ParameterError, match=r"^derivative_dynamics='compiled' needs the batched evaluation, not "
                                             r"possible for this problem: .*ResidualFrameVelocity"):
        WalkingOCP(bolt, dataclasses.replace(config, touchdown_velocity_weight=1.0), 5, 0.01)
    ocp = WalkingOCP(bolt, config, 5, 0.01)
    p = ocp.problem
    assert p.derivative_dynamics == "compiled" and p.rollout_dynamics == "pinocchio"
    with pytest.raises(ParameterError, match=r"^derivative_dynamics='Compiled' must be one of \('pinocchio', "
                                             r"'compiled'\)$"):
        BatchedShootingProblem(p.x0, p.running_models, p.terminal_model, derivative_dynamics="Compiled")
    assert BatchedShootingProblem(p.x0, p.running_models, p.terminal_model).derivative_dynamics == "pinocchio"
    dam, data = p.running_models[0].differential, p.running_datas[0].differential
    with pytest.raises(ParameterError, match=r"^derivative_dynamics=None must be one of"):
        dam.calc_dynamics(data, p.x0, np.zeros(ocp.nu), "pinocchio", None)
    dam.calc_dynamics(data, p.x0, np.zeros(ocp.nu))
    with pytest.raises(ParameterError, match=r"^derivative_dynamics='rnea' must be one of"):
        dam.calc_diff_dynamics(data, p.x0, np.zeros(ocp.nu), "rnea")


@needs_h1_extra
def test_h1_derivative_dynamics_compiled_agrees_with_pinocchio(monkeypatch):
    """derivative_dynamics="compiled" on the H1 preset ("kkt" soles, single and double support): calcDiff's
    next states, Fx, Fu, cost derivatives and kept contact forces and their derivatives equal the default's
    (Pinocchio's crba, nonLinearEffects and computeRNEADerivatives) to 1e-10 relative (~1e-15 measured), not to
    the bit, without any of those binding calls; prepare_dynamics too; the rollouts are the default's."""
    h1 = load_robot("h1")
    n_nodes = 12
    preset = _h1_preset_on_pinocchio_paths()
    default = _batched_walking_ocp(h1, preset, n_nodes)
    compiled = _batched_walking_ocp(h1, dataclasses.replace(preset, derivative_dynamics="compiled"), n_nodes)
    problems = []
    for ocp in (default, compiled):
        _, batched, solver = _h1_rollouts(ocp, n_nodes, seed=6)
        problems.append(batched)
    reference, batched = problems
    assert batched.derivative_dynamics == "compiled" and reference.derivative_dynamics == "pinocchio"
    assert {len(key) for key in batched._node_contact_keys} == {1, 2}  # single and double support
    xs, us = solver.xs, solver.us
    reference.calcDiff(xs, us)

    def refused(*args, **kwargs):
        raise AssertionError("a Pinocchio dynamics call under derivative_dynamics='compiled'")

    for name in ("crba", "nonLinearEffects", "computeRNEADerivatives"):  # (the terminal node: computeAllTerms)
        monkeypatch.setattr(pin, name, refused)
    batched.calcDiff(xs, us)
    assert batched.cost == pytest.approx(reference.cost, rel=1e-12)
    names = STACKED + ("_forces", "_force_jacobians")
    for name in names:
        expected, actual = getattr(reference, name), getattr(batched, name)
        assert np.max(np.abs(actual - expected)) <= 1e-10 * np.max(np.abs(expected)), name
    assert not np.array_equal(batched.Fx, reference.Fx)  # the compiled path: rounding differs
    # prepared ahead (every node but the first), then taken by calcDiff: the same numbers
    keys = list(batched._node_contact_keys)
    assert batched.prepare_dynamics(xs[:-1], us, [None] + keys[1:]) == n_nodes - 1
    Fx = batched.Fx.copy()
    batched.calcDiff(xs, us)
    assert batched.prepared_used == n_nodes - 1 and np.array_equal(batched.Fx, Fx)


def _derivative_pass(problem: BatchedShootingProblem, xs, us, compiled: bool, prepare: list | None = None) -> tuple:
    """The stacked arrays, kept forces and force derivatives of ``problem.calcDiff(xs, us)``, its derivative pass in
    one compiled call or node by node; with ``prepare`` (the keys) the nodes prepared ahead first (at the same xs, us,
    so calcDiff takes them), and the prepared arrays too."""
    problem.use_compiled_derivatives = compiled
    if prepare is not None:
        assert problem.prepare_dynamics(xs[:-1], us, prepare) == sum(key is not None for key in prepare)
        prepared = tuple(getattr(problem, f"_prepared_{name}").copy()
                         for name in ("xnext", "euler_dx", "da_dx", "da_du", "forces", "force_jacobians"))
    cost = problem.calcDiff(xs, us)  # takes the prepared nodes whose contact set is the node's
    assert problem.prepared_used == (0 if prepare is None else
                                     sum(key == own for key, own in zip(prepare, problem._node_contact_keys)))
    arrays = tuple(getattr(problem, name).copy() for name in STACKED + ("_euler_dx", "_forces", "_force_jacobians"))
    return (cost, *arrays) + (() if prepare is None else prepared)


@needs_h1_extra
@pytest.mark.parametrize("python_node", [None, 4])
def test_h1_derivative_pass_in_one_compiled_call_is_the_node_by_node_pass(python_node):
    """derivative_dynamics="compiled" on the H1 preset (single and double support, the costs reading the contact
    forces): calcDiff's derivative pass in one compiled call (kernels/derivative_pass.py) gives the node-by-node
    pass's next states, Euler steps, Fx, Fu, cost derivatives, kept forces and force derivatives to the last bit
    (the same kernels in the same order), and so does prepare_dynamics (each node with the contact set of another
    node: the horizon shifted), which calcDiff then takes; a node left to Python (as one the compiled call cannot
    run) is computed there."""
    h1 = load_robot("h1")
    n_nodes = 12
    preset = _h1_preset_on_pinocchio_paths()
    ocp = _batched_walking_ocp(h1, dataclasses.replace(preset, derivative_dynamics="compiled"), n_nodes)
    _, batched, solver = _h1_rollouts(ocp, n_nodes, seed=6)
    assert batched._kkt_derivatives is not None and batched._kkt_rollout is None and batched._keep_forces
    assert all(batched._horizon_contacts.compiled(k) for k in range(n_nodes))
    assert {len(key) for key in batched._node_contact_keys} == {1, 2}  # single and double support
    if python_node is not None:
        batched._horizon_contacts.contacts[python_node] = -1
    xs, us = solver.xs, solver.us
    python, compiled = (_derivative_pass(batched, xs, us, use) for use in (False, True))
    assert compiled[0] == python[0]
    for name, ours, theirs in zip(STACKED + ("_euler_dx", "_forces", "_force_jacobians"), compiled[1:], python[1:]):
        assert np.array_equal(ours, theirs), name
    # prepared ahead with the next horizon's contact sets (node k the set of node k + 1), then taken
    keys = list(batched._node_contact_keys)
    shifted = [None] + keys[2:] + [keys[-1]]
    assert 0 < sum(key == own for key, own in zip(shifted, keys)) < n_nodes - 1  # some taken, some not
    python, compiled = (_derivative_pass(batched, xs, us, use, shifted) for use in (False, True))
    assert compiled[0] == python[0]
    for ours, theirs in zip(compiled[1:], python[1:]):
        assert np.array_equal(ours, theirs)


def test_bolt_derivative_pass_in_one_compiled_call_with_moving_references(bolt):
    """The same on Bolt's point contacts with a Baumgarte position gain (their references move: read before the
    compiled call) and a flight node (no contacts: left to the node-by-node path): to the last bit."""
    config = dataclasses.replace(BATCHED_TERMS, dynamics_backend="kkt", derivative_dynamics="compiled")
    ocp = WalkingOCP(bolt, config, n_nodes=40, dt=0.01)
    ocp.update(standing_state(bolt), alternating_schedule(0.27, 0.01, 40), np.array([0.1, 0.0, 0.3]))
    ocp.problem.running_models[7].differential.set_active_contacts([])  # a flight node
    costs = ocp.problem.running_models[7].differential.costs.costs
    for foot in ocp.feet:
        costs[f"{foot}_contact_force"].active = costs[f"{foot}_friction_cone"].active = False  # no contact to read
    _, batched = _twin_problems(ocp)
    sets = batched._horizon_contacts
    assert sets._moving and batched._keep_forces
    assert [k for k in range(40) if not sets.compiled(k)] == [7]
    xs, us = _random_trajectory(bolt, 40, ocp.nu, seed=3)
    python, compiled = (_derivative_pass(batched, xs, us, use) for use in (False, True))
    assert compiled[0] == python[0]
    for name, ours, theirs in zip(STACKED + ("_euler_dx", "_forces", "_force_jacobians"), compiled[1:], python[1:]):
        assert np.array_equal(ours, theirs), name
