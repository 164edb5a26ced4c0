"""The joint-limit barrier of the walking OCP (``joint_limits``: ResidualJointPosition under a quadratic barrier at the
model's position limits narrowed by ``joint_limit_margin``)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from robot_extras import needs_h1_extra
from wbmpc_fixtures import alternating_schedule, random_state, standing_state

from robots import load_robot
from wbmpc.errors import ParameterError
from wbmpc.ocp.numdiff import tangent_jacobian
from wbmpc.ocp.problem import ShootingProblem
from wbmpc.ocp.residuals import ResidualJointPosition
from wbmpc.ocp.solvers import SolverFDDP
from wbmpc.ocp.state import StateMultibody
from wbmpc.walking.ocp import WalkingOCP, WalkingOCPConfig
from wbmpc.walking.preset import load_walking_preset

N_NODES = 12
LIMITS = {"joint_limit_weight": 1e5, "joint_limit_margin": 0.05}


def _h1_ocp(evaluation: str = "batched", **overrides) -> tuple:
    """The H1 preset's OCP over an alternating walk of 0.2 s steps (the right foot swings first): (robot, ocp)."""
    h1 = load_robot("h1")
    preset = load_walking_preset("h1").ocp
    config = preset.node_wise(**overrides) if evaluation == "nodes" else dataclasses.replace(preset, evaluation=evaluation,
                                                                                              **overrides)
    ocp = WalkingOCP(h1, config, n_nodes=N_NODES, dt=0.02)
    schedule = alternating_schedule(0.0, 0.02, N_NODES, step_duration=0.2, foot_y=(0.2, -0.2), step_length=0.1)
    ocp.update(standing_state(h1), schedule, np.array([0.05, 0.0, 0.97]))
    return h1, ocp


def _joint_q_index(robot, name: str) -> int:
    model = robot.pinocchio_model
    return model.joints[model.getJointId(name)].idx_q


@needs_h1_extra
def test_the_residual_is_the_joint_angles_with_a_constant_selection_jacobian():
    h1 = load_robot("h1")
    state = StateMultibody(h1.pinocchio_model)
    residual = ResidualJointPosition(state, 19)
    assert residual.nr == 19 and residual.joint_names[3] == "left_knee"
    rng = np.random.default_rng(3)
    x = random_state(h1, rng)
    data = residual.createData()
    residual.calc(data, x, None, None)
    residual.calcDiff(data, x, None, None)
    np.testing.assert_array_equal(data.r, x[7:26])

    def r_of_x(xx):
        d = residual.createData()
        residual.calc(d, xx, None, None)
        return d.r.copy()

    np.testing.assert_allclose(data.Rx, tangent_jacobian(state, r_of_x, x), atol=1e-7)
    assert not data.Ru.any()
    with pytest.raises(ParameterError, match="q_reference of shape"):
        ResidualJointPosition(state, 19, np.zeros(3))


@needs_h1_extra
def test_the_barrier_is_zero_inside_the_narrowed_limits_and_quadratic_beyond():
    """The running term's value at one node: zero with every joint inside [lower + margin, upper − margin], and
    w · ½ e² with the left knee e below it (the cost rate; the Euler node integrates it over dt)."""
    h1, ocp = _h1_ocp(**LIMITS)
    model = ocp.problem.running_models[0]
    x = standing_state(h1)
    u = np.zeros(ocp.nu)

    def term_cost(xx):
        data = model.createData()
        model.calc(data, xx, u)
        return model.differential.costs.term_costs(data.differential.costs)["joint_limits"]

    assert term_cost(x) == 0.0
    knee = _joint_q_index(h1, "left_knee")
    lower = h1.pinocchio_model.lowerPositionLimit[knee] + LIMITS["joint_limit_margin"]
    x[knee] = lower - 0.1
    assert term_cost(x) == pytest.approx(1e5 * 0.5 * 0.1**2, rel=1e-12)
    x[knee] = lower + 0.01
    assert term_cost(x) == 0.0


@needs_h1_extra
@pytest.mark.parametrize("overrides", [LIMITS, {"joint_limit_weight": 1e5, "joint_limit_joints": ["knee"]}],
                         ids=["every joint", "the knees"])
def test_the_batched_barrier_matches_the_node_pipeline_beyond_the_limits(overrides):
    h1, ocp = _h1_ocp(**overrides)
    assert ocp.evaluation == "batched"
    p = ocp.problem
    p.sync()
    nodes = ShootingProblem(p.x0, p.running_models, p.terminal_model)
    rng = np.random.default_rng(5)
    xs = np.array([random_state(h1, rng, 0.02, 0.1) for _ in range(N_NODES + 1)])
    us = rng.standard_normal((N_NODES, ocp.nu))
    knee, hip_roll = _joint_q_index(h1, "right_knee"), _joint_q_index(h1, "left_hip_roll")
    xs[2:6, knee] = -0.4  # past the extension stop (-0.26 rad)
    xs[7, hip_roll] = 0.5  # past +0.43 rad
    cost = nodes.calc_and_diff(xs, us)
    assert p.calcDiff(xs, us) == pytest.approx(cost, rel=1e-13)
    for name in ("Lx", "Lxx"):
        expected, actual = getattr(nodes, name), getattr(p, name)
        assert np.max(np.abs(actual - expected)) <= 1e-12 * max(1.0, float(np.max(np.abs(expected)))), name
    assert p.term_costs()["joint_limits"] == pytest.approx(nodes.term_costs()["joint_limits"], rel=1e-12)
    assert p.term_costs()["joint_limits"] > 0


@needs_h1_extra
def test_a_swing_knee_asked_past_its_extension_stop_is_held_inside_by_the_barrier():
    """The right (swing) knee's posture reference at −0.8 rad, weighted 100: without the barrier the solved plan
    extends the knee past the model's stop (−0.26 rad), with it the knee stays within 2 cm·rad of the narrowed
    bound at every node."""
    knee_index = None
    minima = {}
    for name, overrides in (("free", {"joint_limit_weight": 0.0}), ("barrier", LIMITS)):
        weights = dataclasses.replace(load_walking_preset("h1").ocp.state_weights,
                                      joint_position_by_name=(("torso", 10.0), ("shoulder", 3.0), ("elbow", 3.0),
                                                              ("right_knee", 100.0)))
        h1, ocp = _h1_ocp(state_weights=weights, **overrides)
        knee_index = _joint_q_index(h1, "right_knee")
        for model in [*ocp.problem.running_models, ocp.problem.terminal_model]:
            ocp_reference = model.differential.costs.costs["state_regularization"].cost.residual.reference
            ocp_reference[knee_index] = -0.8
        solver = SolverFDDP(ocp.problem)
        solver.solve(maxiter=40)
        minima[name] = float(np.min(np.array(solver.xs)[:, knee_index]))
    stop = load_robot("h1").pinocchio_model.lowerPositionLimit[knee_index]
    assert minima["free"] < stop - 0.1, minima
    assert minima["barrier"] > stop + LIMITS["joint_limit_margin"] - 0.02, minima


@needs_h1_extra
def test_a_margin_by_joint_name_narrows_only_the_joints_it_names():
    h1, ocp = _h1_ocp(joint_limit_weight=1e5, joint_limit_margin=0.0, joint_limit_margin_by_name=[["knee", 0.05]])
    activation = ocp.problem.running_models[0].differential.costs.costs["joint_limits"].cost.activation
    model = h1.pinocchio_model
    knees = [i for i, name in enumerate(ocp.problem.running_models[0].differential.costs.costs["joint_limits"]
                                        .cost.residual.joint_names) if "knee" in name]
    assert len(knees) == 2
    margin = np.zeros(19)
    margin[knees] = 0.05
    np.testing.assert_allclose(activation.lower, model.lowerPositionLimit[7:] + margin)
    np.testing.assert_allclose(activation.upper, model.upperPositionLimit[7:] - margin)
    with pytest.raises(ParameterError, match="joint_limit_margin_by_name: 'wrist' matches no joint"):
        _h1_ocp(joint_limit_weight=1e5, joint_limit_margin_by_name=(("wrist", 0.1),))


@needs_h1_extra
def test_the_barrier_covers_only_the_joints_it_names():
    """``joint_limit_joints = ["knee"]``: bounds at the knees' limits, none on the other joints (a hip far past its
    stop costs nothing, a knee past its extension stop does)."""
    h1, ocp = _h1_ocp(joint_limit_weight=1e5, joint_limit_joints=["knee"])
    model = ocp.problem.running_models[0]
    term = model.differential.costs.costs["joint_limits"].cost
    limits = h1.pinocchio_model
    knees = [i for i, name in enumerate(term.residual.joint_names) if "knee" in name]
    others = [i for i in range(19) if i not in knees]
    assert len(knees) == 2
    np.testing.assert_allclose(term.activation.lower[knees], limits.lowerPositionLimit[7:][knees])
    np.testing.assert_allclose(term.activation.upper[knees], limits.upperPositionLimit[7:][knees])
    assert np.all(term.activation.lower[others] == -np.inf) and np.all(term.activation.upper[others] == np.inf)

    def term_cost(xx):
        data = model.createData()
        model.calc(data, xx, np.zeros(ocp.nu))
        return model.differential.costs.term_costs(data.differential.costs)["joint_limits"]

    x = standing_state(h1)
    hip, knee = _joint_q_index(h1, "left_hip_roll"), _joint_q_index(h1, "left_knee")
    x[hip] = limits.upperPositionLimit[hip] + 0.3
    assert term_cost(x) == 0.0
    x[knee] = limits.lowerPositionLimit[knee] - 0.1
    assert term_cost(x) == pytest.approx(1e5 * 0.5 * 0.1**2, rel=1e-12)
    with pytest.raises(ParameterError, match="joint_limit_joints: 'wrist' matches no joint"):
        _h1_ocp(joint_limit_weight=1e5, joint_limit_joints=["wrist"])


def test_bad_joint_limit_settings_are_one_line_errors_naming_them():
    with pytest.raises(ParameterError, match="joint_limit_weight=-1.0 must be finite and >= 0"):
        WalkingOCPConfig(joint_limit_weight=-1.0)
    with pytest.raises(ParameterError, match="joint_limit_margin=-0.1 rad must be finite and >= 0"):
        WalkingOCPConfig(joint_limit_margin=-0.1)
    with pytest.raises(ParameterError, match="joint_limit_margin_by_name: 'knee' has margin=-0.1 rad"):
        WalkingOCPConfig(joint_limit_margin_by_name=(("knee", -0.1),))
    with pytest.raises(ParameterError, match="joint_limit_margin_by_name=.* must be .joint name part, margin"):
        WalkingOCPConfig(joint_limit_margin_by_name=("knee",))
    with pytest.raises(ParameterError, match="joint_limit_joints='knee' must be a list of joint name parts"):
        WalkingOCPConfig(joint_limit_joints="knee")
    bolt = load_robot("bolt")  # placeholder limits of +-10 rad
    with pytest.raises(ParameterError, match="joint_limit_margin=11.0 rad leaves no range for joint 'FL_HAA'"):
        WalkingOCP(bolt, WalkingOCPConfig(joint_limit_weight=1.0, joint_limit_margin=11.0), 4, 0.01)
