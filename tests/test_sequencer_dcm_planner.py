"""DcmFootstepPlanner: the FootstepPlanner interface over Algorithm 1, heading frame, command and corrections per call."""

import dataclasses
import math

import numpy as np
import pytest

from sequencer import (
    DcmFootstepPlanner,
    FootstepPlanner,
    FootstepSequencer,
    InfeasibleStep,
    LipmCorrections,
    ReducedState,
    SequencerParams,
    StanceState,
    VelocityCommand,
)
from wbmpc.errors import ParameterError

TABLE_I_STANCE = StanceState("left", [-0.12, 0.10], 0.0, 0.0)
TABLE_I_MEASURED = ReducedState(com=[-0.11, -0.01, 0.31], com_velocity=[0.2, -0.3, 0.0], dcm=[-0.12, -0.07])


def rotation(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array(((c, -s), (s, c)))


def assert_plans_identical(a, b):
    """Every field of both plans equal bit for bit."""
    assert (a.t0, a.stance_foot, a.omega, a.t_stance_start, a.horizon) == (b.t0, b.stance_foot, b.omega,
                                                                            b.t_stance_start, b.horizon)
    assert np.array_equal(a.stance_position, b.stance_position) and np.array_equal(a.dcm_measured, b.dcm_measured)
    assert len(a.steps) == len(b.steps)
    for x, y in zip(a.steps, b.steps):
        assert (x.foot, x.touchdown_time, x.stance_start_time, x.active, x.yaw) == (
            y.foot, y.touchdown_time, y.stance_start_time, y.active, y.yaw)
        for name in ("position", "dcm_offset", "dcm_at_touchdown"):
            assert np.array_equal(getattr(x, name), getattr(y, name)), name


def random_states(params, count, seed):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        foot = "left" if rng.random() < 0.5 else "right"
        p0 = rng.uniform(-1.0, 1.0, 2)
        t_start = rng.uniform(0.0, 5.0)
        t = t_start + rng.uniform(0.0, params.t_max)
        yield t, StanceState(foot, p0, 0.0, t_start), ReducedState([0, 0, 0.3], [0, 0, 0], p0 + rng.normal(0, 0.2, 2))


# ---------------------------------------------------------------------------- the interface
def test_planner_implements_the_interface_with_the_lipm_model():
    params = dataclasses.replace(SequencerParams.bolt_walking(), double_support=0.04)
    planner = DcmFootstepPlanner(params)
    assert isinstance(planner, FootstepPlanner)
    assert planner.feet == ("left", "right")
    assert planner.omega == params.omega and planner.com_height == params.z_c == 0.295
    assert planner.double_support == 0.04 and planner.backend == "exact"
    assert planner.nominal_command == VelocityCommand(params.v_x, params.v_y, 0.0)
    plan = planner.plan(0.229, TABLE_I_STANCE, TABLE_I_MEASURED, planner.nominal_command)
    assert plan.double_support == 0.04 and plan.com_height == 0.295 and plan.feet == ("left", "right")


@pytest.mark.parametrize("preset", ["table_i", "bolt_walking"])
def test_straight_walking_is_algorithm_1_bit_for_bit(preset):
    params = SequencerParams.preset(preset)
    planner = DcmFootstepPlanner(params)
    sequencer = FootstepSequencer(params)
    command = VelocityCommand(params.v_x, params.v_y, 0.0)
    for t, stance, measured in random_states(params, 50, seed=3):
        expected = sequencer.plan(t, stance.foot, stance.position, measured.dcm, stance.t_start, clamp_elapsed=True)
        assert_plans_identical(planner.plan(t, stance, measured, command), expected)
        assert all(step.yaw == 0.0 for step in expected.steps)


@pytest.mark.parametrize("backend", ["osqp", "proxqp"])
def test_straight_walking_with_a_solver_backend_is_algorithm_1_bit_for_bit(backend):
    params = SequencerParams.table_i()
    plan = DcmFootstepPlanner(params, backend=backend).plan(0.229, TABLE_I_STANCE, TABLE_I_MEASURED,
                                                            VelocityCommand(params.v_x))
    expected = FootstepSequencer(params, backend=backend).plan(0.229, "left", [-0.12, 0.10], [-0.12, -0.07], 0.0)
    assert_plans_identical(plan, expected)


def test_command_per_call_equals_a_sequencer_built_with_that_velocity():
    params = SequencerParams.table_i()
    planner = DcmFootstepPlanner(params)
    for v_x, v_y in [(0.2, 0.0), (-0.3, 0.1), (0.2, 0.0), (0.5, -0.2)]:  # no rebuild between commands
        plan = planner.plan(0.229, TABLE_I_STANCE, TABLE_I_MEASURED, VelocityCommand(v_x, v_y))
        rebuilt = FootstepSequencer(dataclasses.replace(params, v_x=v_x, v_y=v_y))
        assert_plans_identical(plan, rebuilt.plan(0.229, "left", [-0.12, 0.10], [-0.12, -0.07], 0.0))
    assert planner.params is params  # the frozen parameters are not replaced


def test_corrections_are_read_live_and_equal_a_sequencer_built_with_them():
    params = SequencerParams.bolt_walking()
    corrections = LipmCorrections.from_params(params)
    planner = DcmFootstepPlanner(params, corrections=corrections)
    assert planner.corrections is corrections
    command = VelocityCommand(0.3)
    before = planner.plan(0.1, TABLE_I_STANCE, TABLE_I_MEASURED, command)
    corrections.swing_drift = 0.2
    corrections.dcm_offset_bias = 0.01
    after = planner.plan(0.1, TABLE_I_STANCE, TABLE_I_MEASURED, command)
    assert not np.array_equal(after.steps[0].dcm_offset, before.steps[0].dcm_offset)
    rebuilt = FootstepSequencer(dataclasses.replace(params, v_x=0.3, swing_drift=0.2, dcm_offset_bias=0.01))
    assert_plans_identical(after, rebuilt.plan(0.1, "left", [-0.12, 0.10], [-0.12, -0.07], 0.0))
    # the nominal sagittal offset aimed at is (1 - kappa) l_nom / (E - 1) - bias
    gait = planner.sequencer.nominal_gait((0.3, 0.0), corrections)
    growth = math.exp(params.omega * params.t_nom)
    assert gait.dcm_offset("left")[0] == pytest.approx(0.8 * 0.3 * params.t_nom / (growth - 1.0) - 0.01, rel=1e-14)


def test_lipm_corrections_are_validated_on_assignment():
    corrections = LipmCorrections()
    assert corrections.as_tuple() == (0.0, 0.0, 0.0)
    with pytest.raises(ParameterError, match=r"swing_drift=0.95 must be in \[0, 0.9\]"):
        corrections.swing_drift = 0.95
    with pytest.raises(ParameterError, match=r"dcm_offset_bias=-0.06 m must be in \[-0.05, 0.05\] m"):
        corrections.dcm_offset_bias = -0.06
    with pytest.raises(ParameterError, match=r"swing_drift='high' must be a real number"):
        LipmCorrections(swing_drift="high")
    with pytest.raises(ParameterError, match=r"dcm_offset_bias=nan must be finite"):
        LipmCorrections(dcm_offset_bias=float("nan"))
    assert corrections.as_tuple() == (0.0, 0.0, 0.0)  # a refused value leaves the old one
    with pytest.raises(ParameterError, match=r"corrections must be a LipmCorrections or None, got dict"):
        DcmFootstepPlanner(SequencerParams.table_i(), corrections={"swing_drift": 0.1})


# ---------------------------------------------------------------------------- heading frame
def check_steps_in_heading_frames(plan, params, yaw_rate):
    """Each step: bounds of eqs. 15a-15f in its stance's heading frame, heading increments yaw_rate T_k, eq. (1b)."""
    previous, stance, yaw, dcm, t_from = plan.stance_position, plan.stance_foot, plan.stance_yaw, plan.dcm_measured, plan.t0
    tol = 1e-9
    for step in plan.steps:
        length, width = rotation(yaw).T @ (step.position - previous)
        w_lo, w_hi = params.width_bounds(stance)
        assert params.l_min - tol <= length <= params.l_max + tol
        assert w_lo - tol <= width <= w_hi + tol
        assert step.yaw == pytest.approx(yaw + yaw_rate * step.duration, abs=1e-14)
        expected = previous + (dcm - previous) * math.exp(params.omega * (step.touchdown_time - t_from))
        assert step.dcm_at_touchdown == pytest.approx(expected, abs=1e-9, rel=1e-12)
        previous, stance, yaw, dcm, t_from = step.position, step.foot, step.yaw, step.dcm_at_touchdown, step.touchdown_time


def fit_circle(points: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Least-squares circle (centre (2,), radius, largest radial residual) through points (n, 2)."""
    A = np.column_stack([2.0 * points, np.ones(len(points))])
    solution, *_ = np.linalg.lstsq(A, np.sum(points**2, axis=1), rcond=None)
    centre = solution[:2]
    radius = math.sqrt(solution[2] + centre @ centre)
    return centre, radius, float(np.max(np.abs(np.linalg.norm(points - centre, axis=1) - radius)))


@pytest.mark.parametrize("yaw_rate", [0.4, -0.7])
def test_constant_yaw_rate_walks_the_footholds_around_a_circle(yaw_rate):
    params = dataclasses.replace(SequencerParams.table_i(), horizon=15.0)
    v_x = 0.3
    stance = StanceState("left", [-0.12, 0.10], 0.3, 0.0)
    plan = DcmFootstepPlanner(params).plan(0.229, stance, TABLE_I_MEASURED, VelocityCommand(v_x, 0.0, yaw_rate))
    check_steps_in_heading_frames(plan, params, yaw_rate)
    # heading increments: yaw_rate times each planned duration, from the stance yaw
    durations = np.array([step.duration for step in plan.steps])
    assert np.diff(np.concatenate([[stance.yaw], plan.yaws])) == pytest.approx(yaw_rate * durations, abs=1e-14)
    # once the gait has settled each foot's footholds lie on a circle, both circles concentric, the
    # inner one on the side of the turn, and the mean radius is v_x / yaw_rate (to 1 %: the settled
    # steps of a turning gait differ slightly from the nominal ones, whose offsets are the straight gait's)
    fits = {}
    for foot in ("left", "right"):
        points = np.array([step.position for step in plan.steps if step.foot == foot])
        fits[foot] = fit_circle(points[len(points) // 2:])
        assert fits[foot][2] < 1e-9
    assert fits["left"][0] == pytest.approx(fits["right"][0], abs=1e-9)
    inner, outer = ("left", "right") if yaw_rate > 0 else ("right", "left")
    assert fits[inner][1] < fits[outer][1]
    assert 0.5 * (fits["left"][1] + fits["right"][1]) == pytest.approx(v_x / abs(yaw_rate), rel=1e-2)


@pytest.mark.parametrize("backend", ["exact", "osqp"])
@pytest.mark.parametrize("yaw_rate", [0.0, 0.6])
def test_a_plan_in_a_rotated_world_is_the_rotated_plan(backend, yaw_rate):
    params = SequencerParams.table_i()
    planner = DcmFootstepPlanner(params, backend=backend)
    command = VelocityCommand(0.25, 0.1, yaw_rate)
    tol = 1e-12 if backend == "exact" else 1e-6
    rng = np.random.default_rng(11)
    for _ in range(10):
        foot = "left" if rng.random() < 0.5 else "right"
        p0 = rng.uniform(-1.0, 1.0, 2)
        t = rng.uniform(0.0, 0.3)
        stance = StanceState(foot, p0, float(rng.uniform(-math.pi, math.pi)), 0.0)
        measured = ReducedState([0, 0, 0.3], [0, 0, 0], p0 + rng.normal(0, 0.05, 2))
        angle = float(rng.uniform(-2 * math.pi, 2 * math.pi))
        turn = rotation(angle)
        plan = planner.plan(t, stance, measured, command)
        rotated = planner.plan(
            t, dataclasses.replace(stance, position=turn @ stance.position, yaw=stance.yaw + angle),
            dataclasses.replace(measured, dcm=turn @ measured.dcm), command,
        )
        assert len(rotated.steps) == len(plan.steps)
        for a, b in zip(plan.steps, rotated.steps):
            assert b.foot == a.foot
            if backend == "exact":
                assert b.active == a.active
            assert b.touchdown_time == pytest.approx(a.touchdown_time, abs=tol)
            assert b.yaw == pytest.approx(a.yaw + angle, abs=tol)
            assert b.position == pytest.approx(turn @ a.position, abs=tol)
            assert b.dcm_offset == pytest.approx(turn @ a.dcm_offset, abs=tol)


def test_turning_plans_of_the_solver_backends_match_the_exact_one():
    params = SequencerParams.table_i()
    stance = StanceState("right", [0.3, -0.2], 1.1, 0.0)
    command = VelocityCommand(0.3, -0.1, 0.5)
    exact = DcmFootstepPlanner(params).plan(0.1, stance, TABLE_I_MEASURED, command)
    for backend in ("osqp", "proxqp"):
        other = DcmFootstepPlanner(params, backend=backend).plan(0.1, stance, TABLE_I_MEASURED, command)
        assert len(other.steps) == len(exact.steps)
        for a, b in zip(exact.steps, other.steps):
            assert (b.foot, b.active) == (a.foot, a.active)
            assert b.position == pytest.approx(a.position, abs=1e-6)
            assert b.touchdown_time == pytest.approx(a.touchdown_time, abs=1e-6)
            assert b.yaw == pytest.approx(a.yaw, abs=1e-6)


@pytest.mark.parametrize("stance_yaw", [0.0, math.pi / 2, -2.5])
def test_lateral_command_walks_left_of_the_heading(stance_yaw):
    params = dataclasses.replace(SequencerParams.table_i(), horizon=6.0)
    planner = DcmFootstepPlanner(params)
    stance = dataclasses.replace(TABLE_I_STANCE, yaw=stance_yaw)
    # the Table I DCM, relative to the stance foot, turned with the heading
    dcm = stance.position + rotation(stance_yaw) @ (TABLE_I_MEASURED.dcm - stance.position)
    plan = planner.plan(0.229, stance, dataclasses.replace(TABLE_I_MEASURED, dcm=dcm), VelocityCommand(0.1, 0.2, 0.0))
    check_steps_in_heading_frames(plan, params, 0.0)
    velocity_heading = rotation(stance_yaw).T @ plan.mean_velocity()
    assert velocity_heading == pytest.approx([0.1, 0.2], abs=2e-3)
    assert all(step.yaw == stance_yaw for step in plan.steps)


# ---------------------------------------------------------------------------- commands
def test_command_range_follows_from_the_bounds():
    planner = DcmFootstepPlanner(SequencerParams.table_i())
    ranges = planner.command_range()
    assert ranges["v_x"] == pytest.approx((-1.0, 1.0))  # [l_min, l_max] / t_nom
    assert ranges["v_y"] == pytest.approx((-0.5, 0.5))  # ([-0.40, -0.10] + 0.25) / 0.3 and ([0.10, 0.40] - 0.25) / 0.3
    assert ranges["yaw_rate"] == (-math.inf, math.inf)
    bolt = DcmFootstepPlanner(SequencerParams.bolt_walking()).command_range()
    assert bolt["v_x"] == pytest.approx((-0.2 / 0.3, 0.2 / 0.3))
    assert bolt["v_y"] == pytest.approx((-0.2, 0.2))  # left stance ([-0.20, -0.04] + 0.10) / 0.3 = [-1/3, 0.2]
    # the corners of the range pass and plan
    for v_x in ranges["v_x"]:
        for v_y in ranges["v_y"]:
            command = VelocityCommand(v_x, v_y, 3.0)
            planner.check_command(command)
            planner.plan(0.229, TABLE_I_STANCE, TABLE_I_MEASURED, command)


@pytest.mark.parametrize(
    "command, message",
    [
        (VelocityCommand(1.2, 0.0, 0.0), r"v_x=1.2 m/s gives a nominal step length v_x\*t_nom=0.36 m outside "
                                         r"\[l_min, l_max\] = \[-0.3, 0.3\] m: v_x must lie within \[-1, 1\] m/s"),
        (VelocityCommand(0.1, 0.6, 0.0), r"v_y=0.6 m/s give a nominal left-stance width -0.07 m outside "
                                         r"\[w_left_min, w_left_max\] = \[-0.4, -0.1\] m: v_y must lie within \[-0.5, 0.5\] m/s"),
        (VelocityCommand(0.1, -0.6, 0.0), r"v_y=-0.6 m/s give a nominal left-stance width -0.43 m outside"),
    ],
)
def test_commands_outside_the_range_are_refused_with_component_value_and_range(command, message):
    planner = DcmFootstepPlanner(SequencerParams.table_i())
    with pytest.raises(ParameterError, match=message):
        planner.check_command(command)
    with pytest.raises(ParameterError, match=message):  # plan refuses it too: clip to command_range()
        planner.plan(0.229, TABLE_I_STANCE, TABLE_I_MEASURED, command)
    planner.check_command(VelocityCommand(0.3, 0.0, 10.0))  # no bound on the yaw rate


def test_a_pelvis_width_no_lateral_command_fits_is_named():
    with pytest.raises(ParameterError, match=r"pelvis_width=0.5 m and v_y=0.0 m/s give a nominal left-stance width "
                                             r"-0.5 m outside .*: no v_y fits the width bounds of both stances"):
        dataclasses.replace(SequencerParams.table_i(), pelvis_width=0.5)


def test_plan_input_errors_and_late_touchdowns():
    params = SequencerParams.table_i()
    planner = DcmFootstepPlanner(params)
    command = VelocityCommand(0.2)
    with pytest.raises(ParameterError, match=r"stance must be a StanceState, got tuple"):
        planner.plan(0.229, ("left", [0, 0], 0.0, 0.0), TABLE_I_MEASURED, command)
    with pytest.raises(ParameterError, match=r"measured must be a ReducedState, got ndarray"):
        planner.plan(0.229, TABLE_I_STANCE, np.zeros(2), command)
    with pytest.raises(ParameterError, match=r"stance foot='front_left' must be one of \('left', 'right'\)"):
        planner.plan(0.229, StanceState("front_left", [0, 0], 0.0, 0.0), TABLE_I_MEASURED, command)
    with pytest.raises(ParameterError, match=r"command must be a VelocityCommand or \(v_x, v_y, yaw_rate\), got str"):
        planner.plan(0.229, TABLE_I_STANCE, TABLE_I_MEASURED, "fast")
    with pytest.raises(ParameterError, match=r"clamp_elapsed=1 must be True or False"):
        DcmFootstepPlanner(params, clamp_elapsed=1)
    assert planner.plan(0.229, TABLE_I_STANCE, TABLE_I_MEASURED, (0.2, 0.0, 0.1)).steps  # a tuple is a command
    late = planner.plan(1.5, TABLE_I_STANCE, TABLE_I_MEASURED, command)  # stance older than t_max: touchdown now
    assert late.steps[0].touchdown_time == pytest.approx(late.t0)
    with pytest.raises(InfeasibleStep, match=r"exceeds T_max=1.0 s"):
        DcmFootstepPlanner(params, clamp_elapsed=False).plan(1.5, TABLE_I_STANCE, TABLE_I_MEASURED, command)


def test_com_reference_is_the_lipm_com_at_the_model_height():
    planner = DcmFootstepPlanner(SequencerParams.table_i())
    plan = planner.plan(0.229, TABLE_I_STANCE, TABLE_I_MEASURED, VelocityCommand(0.3, 0.0, 0.4))
    com_xy = TABLE_I_MEASURED.com[:2]
    reference = plan.com_reference(1.2, com_xy)
    assert reference.shape == (3,)
    assert reference[:2] == pytest.approx(plan.lipm_com_at(1.2, com_xy), abs=0.0)
    assert reference[2] == 0.31
    times = np.linspace(plan.t0, 2.5, 7)
    references = plan.com_reference(times, com_xy)
    assert references.shape == (7, 3)
    assert references[:, :2] == pytest.approx(plan.lipm_com_at(times, com_xy), abs=0.0)
    assert np.all(references[:, 2] == 0.31)
    with pytest.raises(ParameterError, match=r"must be >= the plan's t0=0.229 s"):
        plan.com_reference(0.0, com_xy)


def test_a_stance_not_begun_is_planned_from_its_start_and_the_nominal_dcm():
    """A start from standing: before the stance begins the plan is the one made at its start from
    the DCM the nominal gait has there, whatever the measured DCM; that first step is nominal."""
    params = SequencerParams.table_i()
    planner = DcmFootstepPlanner(params)
    command = VelocityCommand(0.2, 0.0, 0.1)
    stance = StanceState("left", [0.3, 0.1], 0.4, 1.0)
    standing = ReducedState(np.array([0.3, -0.02, 0.3]), np.zeros(3), np.array([0.3, -0.02]))
    early = planner.plan(0.5, stance, standing, command)
    dcm = planner.stance_start_dcm(stance, command)
    at_start = planner.plan(1.0, stance, dataclasses.replace(standing, dcm=dcm), command)
    assert early.t0 == 1.0
    np.testing.assert_array_equal(early.positions, at_start.positions)
    np.testing.assert_array_equal(early.touchdown_times, at_start.touchdown_times)
    gait = planner.sequencer.nominal_gait((0.2, 0.0), planner.corrections)
    heading = np.array([[np.cos(0.4), -np.sin(0.4)], [np.sin(0.4), np.cos(0.4)]])
    first = heading.T @ (early.steps[0].position - stance.position)
    np.testing.assert_allclose(first, (gait.step_length, gait.step_width("left")), atol=1e-6)
    assert early.steps[0].touchdown_time == pytest.approx(1.0 + params.t_nom, abs=1e-6)


# ---------------------------------------------------------------------------- the committed swing foothold
@pytest.mark.parametrize("yaw", [0.0, 0.6])
def test_a_committed_swing_foothold_moves_across_the_heading_at_its_rate_near_touchdown(yaw):
    """``swing_commit_time``: in the last T_c of a swing the foothold's lateral component (across the stance's heading)
    moves at most ``swing_commit_rate`` times the time since the previous plan; earlier in the swing, with another
    stance or with T_c = 0 it follows the measured DCM as Algorithm 1 does (the DCM pushed 6 cm sideways per replan)."""
    params = dataclasses.replace(SequencerParams.bolt_walking(), t_nom=0.3, t_min=0.1, t_max=0.6, w_left_min=-0.8,
                                 w_right_max=0.8)
    committed = dataclasses.replace(params, swing_commit_time=0.15, swing_commit_rate=0.1)
    stance = StanceState("left", [0.2, 0.1], yaw, 1.0)
    across = rotation(yaw) @ np.array([0.0, 1.0])

    def lateral(plan):
        return float(across @ (plan.steps[0].position - stance.position))

    command = VelocityCommand(0.2, 0.0)
    start = DcmFootstepPlanner(params).stance_start_dcm(stance, command)

    def dcm_at(t, k):  # the nominal gait's DCM, pushed sideways by 6 cm per replan
        nominal = stance.position + (start - stance.position) * math.exp(params.omega * (t - stance.t_start))
        return nominal - 0.06 * k * across

    def plans(p, times):
        planner = DcmFootstepPlanner(p)
        return [planner.plan(t, stance, ReducedState([0, 0, 0.3], [0, 0, 0], dcm_at(t, k)), command)
                for k, t in enumerate(times)]

    times = [1.10, 1.18, 1.20, 1.22, 1.24]
    free, held = plans(params, times), plans(committed, times)
    touchdown = held[0].steps[0].touchdown_time
    assert touchdown - times[1] < 0.15 < touchdown - times[0]  # the commitment begins at the second replan
    assert lateral(held[0]) == lateral(free[0])  # before it, the same plan
    for k in range(1, len(times)):
        assert abs(lateral(free[k]) - lateral(free[k - 1])) > 0.005  # Algorithm 1 moves it (0.6-3 cm per replan)
        reach = 0.1 * (times[k] - times[k - 1])
        assert abs(lateral(held[k]) - lateral(held[k - 1])) <= reach + 1e-12, k
    measured = ReducedState([0, 0, 0.3], [0, 0, 0], dcm_at(times[-1], 4))  # a planner new to the stance: nothing
    assert lateral(DcmFootstepPlanner(committed).plan(times[-1], stance, measured, command)) == \
        lateral(free[-1])  # to commit to


def test_the_committed_swing_foothold_is_checked_and_needs_the_exact_backend():
    with pytest.raises(ParameterError, match=r"swing_commit_time=-0.1 s must be in \[0 \(off\), t_max="):
        dataclasses.replace(SequencerParams.bolt_walking(), swing_commit_time=-0.1)
    with pytest.raises(ParameterError, match=r"swing_commit_rate=-1.0 m/s must be in \[0, 10\] m/s"):
        dataclasses.replace(SequencerParams.bolt_walking(), swing_commit_rate=-1.0)
    params = dataclasses.replace(SequencerParams.bolt_walking(), swing_commit_time=0.1)
    with pytest.raises(ParameterError, match="swing_commit_time=0.1 s .* 'exact' backend only, not 'osqp'"):
        DcmFootstepPlanner(params, backend="osqp").plan(0.5, TABLE_I_STANCE, TABLE_I_MEASURED, VelocityCommand(0.3, 0))
