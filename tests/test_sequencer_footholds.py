"""Footholds outside obstacles (sequencer.footholds): the DCM planner's before/beyond choice per step, the
crossing step's bounds, the crossing marks, and the plan without obstacles unchanged."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sequencer.dcm_planner import DcmFootstepPlanner
from sequencer.footholds import crossing_of, forbidden_box, rectangles_overlap, sole_corners
from sequencer.obstacles import Obstacle
from sequencer.params import SequencerParams
from sequencer.planner import ReducedState, StanceState, VelocityCommand
from wbmpc.errors import ParameterError, SolverError

# the H1's walking geometry (wbmpc/walking/presets/h1.toml [planner]) with a long horizon
H1 = SequencerParams(alpha1=1e3, alpha2=1.0, alpha3=1e6, z_c=0.97, v_x=0.0, l_min=-0.3, l_max=0.3, pelvis_width=0.406,
                     w_left_min=-0.6, w_left_max=-0.3, w_right_min=0.3, w_right_max=0.6, t_min=0.3, t_nom=0.4,
                     t_max=0.8, double_support=0.1, horizon=4.0, obstacle_margin=0.04, obstacle_step_length_max=0.6,
                     obstacle_step_duration_min=0.5, sole_front=0.1025, sole_rear=0.1375, sole_half_width=0.04)
COMMAND = VelocityCommand(0.3, 0.0, 0.0)


def _start(planner: DcmFootstepPlanner, yaw: float = 0.0):
    """A left stance at the origin with the nominal gait's DCM, the right foot lifted off beside it."""
    position = np.array([-0.203 * np.sin(yaw), 0.203 * np.cos(yaw)])
    stance = StanceState("left", position, yaw, 0.0, swing_liftoff=-position)
    dcm = planner.stance_start_dcm(stance, COMMAND)
    return stance, ReducedState(np.array([*dcm, 0.97]), np.zeros(3), dcm)


def _sole_overlaps(plan, obstacle: Obstacle, geometry) -> list[int]:
    """Indices of the planned footholds whose sole rectangle overlaps the obstacle grown by the margin."""
    grown = obstacle.grown(geometry.margin).footprint_corners()
    return [k for k, step in enumerate(plan.steps)
            if rectangles_overlap(sole_corners(step.position, step.yaw, geometry), grown)]


def _assert_plans_equal(a, b) -> None:
    """Every field of two plans and of their steps equal, bit for bit."""
    for field in dataclasses.fields(a):
        if field.name != "steps":
            assert np.array_equal(getattr(a, field.name), getattr(b, field.name)), field.name
    assert len(a.steps) == len(b.steps)
    for x, y in zip(a.steps, b.steps):
        for field in dataclasses.fields(x):
            u, v = getattr(x, field.name), getattr(y, field.name)
            assert (u is None and v is None) or np.array_equal(u, v), field.name


def _along(plan, yaw: float) -> np.ndarray:
    return plan.positions @ np.array([np.cos(yaw), np.sin(yaw)])


@pytest.mark.parametrize("seed", range(12))
def test_random_obstacles_ahead_are_stepped_over_with_every_sole_outside(seed):
    rng = np.random.default_rng(seed)
    yaw = rng.uniform(-0.5, 0.5)  # the walking heading
    planner = DcmFootstepPlanner(H1)
    stance, measured = _start(planner, yaw)
    distance, depth = rng.uniform(0.3, 1.0), rng.uniform(0.05, 0.15)
    heading = np.array([np.cos(yaw), np.sin(yaw)])
    obstacle = Obstacle((distance + 0.5 * depth) * heading + rng.uniform(-0.05, 0.05, 2), yaw + rng.uniform(-0.1, 0.1),
                        depth, rng.uniform(0.8, 1.5), rng.uniform(0.1, 0.4))
    plan = planner.plan(0.0, stance, measured, COMMAND, obstacles=(obstacle,))
    geometry = H1.foothold_geometry()
    assert _sole_overlaps(plan, obstacle, geometry) == []
    # the plan gets beyond: some foothold past the far side, both feet eventually
    corners_along = obstacle.footprint_corners() @ heading
    along = _along(plan, yaw)
    beyond = np.flatnonzero(along > corners_along.max())
    assert beyond.size >= 2
    first = beyond[0]
    previous = along[first - 1] if first > 0 else stance.position @ heading
    # the crossing step: within its own length bound, as long as the crossing duration, marked
    crossing = plan.steps[first]
    assert along[first] - previous <= geometry.step_length_max + 1e-9
    assert crossing.duration >= geometry.step_duration_min - 1e-9
    assert crossing.crossing is not None and crossing.crossing.obstacle is obstacle
    trailing = plan.steps[first + 1]  # the other foot crosses next, marked and slow too
    assert trailing.crossing is not None and trailing.duration >= geometry.step_duration_min - 1e-9
    # the last step before it lands before the near side, within the step length bounds
    assert previous <= corners_along.min()
    steps = np.diff(np.concatenate([[stance.position @ heading], along]))
    assert np.all(steps >= H1.l_min - 1e-9) and np.all(steps <= geometry.step_length_max + 1e-9)
    # after the crossing, walking steps again (within the walking bounds)
    assert np.all(np.abs(steps[first + 2:]) <= H1.l_max + 1e-9)


def test_the_plan_without_obstacles_or_past_them_is_bit_identical():
    planner = DcmFootstepPlanner(H1)
    stance, measured = _start(planner, 0.3)
    plain = planner.plan(0.1, stance, measured, COMMAND)
    _assert_plans_equal(planner.plan(0.1, stance, measured, COMMAND, obstacles=()), plain)
    behind = Obstacle(np.array([-1.0, 0.0]), 0.0, 0.2, 1.0, 0.2)  # behind the robot: no foothold moves
    beside = Obstacle(np.array([1.0, 3.0]), 0.0, 0.2, 1.0, 0.2)
    _assert_plans_equal(planner.plan(0.1, stance, measured, COMMAND, obstacles=(behind, beside)), plain)


@pytest.mark.parametrize("lateral_aim", [0.0, 0.7])
def test_the_osqp_backend_chooses_the_same_footholds_as_the_exact_one(lateral_aim):
    pytest.importorskip("osqp")
    obstacle = Obstacle(np.array([0.85, 0.0]), 0.0, 0.15, 1.2, 0.2)
    plans = []
    for backend in ("exact", "osqp"):
        planner = DcmFootstepPlanner(dataclasses.replace(H1, obstacle_lateral_aim_duration=lateral_aim), backend=backend)
        stance, measured = _start(planner)
        plans.append(planner.plan(0.0, stance, measured, COMMAND, obstacles=(obstacle,)))
    assert np.allclose(plans[0].positions, plans[1].positions, atol=2e-4)
    assert [s.crossing is None for s in plans[0].steps] == [s.crossing is None for s in plans[1].steps]


def test_an_obstacle_too_deep_to_cross_stops_the_robot_before_it():
    deep = Obstacle(np.array([0.9, 0.0]), 0.0, 0.5, 1.2, 0.2)  # 0.5 + 0.08 + 0.24 m > 0.6 m crossing steps
    planner = DcmFootstepPlanner(H1)
    stance, measured = _start(planner)
    plan = planner.plan(0.0, stance, measured, COMMAND, obstacles=(deep,))
    assert np.all(_along(plan, 0.0) + H1.sole_front <= 0.65 - H1.obstacle_margin + 1e-9)  # toes before the margin
    assert all(step.crossing is None for step in plan.steps)


def test_a_narrow_post_is_stepped_beside_not_over():
    post = Obstacle(np.array([0.55, -0.203]), 0.0, 0.05, 0.05, 0.3)  # on the right foot's line
    planner = DcmFootstepPlanner(H1)
    stance, measured = _start(planner)
    plan = planner.plan(0.0, stance, measured, COMMAND, obstacles=(post,))
    assert _sole_overlaps(plan, post, H1.foothold_geometry()) == []


def test_crossing_marks_follow_the_sole_along_the_swing():
    geometry = H1.foothold_geometry()
    box = Obstacle(np.array([0.5, 0.0]), 0.0, 0.1, 1.0, 0.1)
    over = crossing_of((box,), (0.1, 0.1), (0.9, 0.1), 0.0, geometry)
    assert over is not None and over.obstacle is box
    s_in, s_out = over.phase_interval
    # the toe reaches the grown near side (0.41 m) at 0.41 - 0.1025 m, the heel leaves the far side at 0.59 + 0.1375
    assert s_in == pytest.approx((0.41 - 0.1025 - 0.1) / 0.8, abs=0.026)
    assert s_out == pytest.approx((0.59 + 0.1375 - 0.1) / 0.8, abs=0.026)
    assert crossing_of((box,), (0.1, 0.1), (0.2, 0.1), 0.0, geometry) is None  # a step that stays before it
    assert crossing_of((box,), None, (0.9, 0.1), 0.0, geometry) is None  # lift-off unknown
    # a foot that landed 1 cm short of the far bound (its heel within the margin) and steps away does not cross it;
    # one lifting off within the near margin and stepping over it does
    bound = 0.55 + geometry.margin + geometry.sole_rear
    assert crossing_of((box,), (bound - 0.01, 0.1), (bound + 0.3, 0.1), 0.0, geometry) is None
    assert crossing_of((box,), (bound - 0.01, 0.1), (bound - 0.005, 0.1), 0.0, geometry) is not None  # stays in it
    assert crossing_of((box,), (0.45 - geometry.margin - geometry.sole_front + 0.01, 0.1), (0.9, 0.1), 0.0,
                       geometry) is not None


def test_obstacle_helpers_and_bad_input():
    box = Obstacle(np.array([1.0, 0.0]), 0.0, 0.2, 1.0, 0.1)
    grown = box.grown(0.05)
    assert (grown.depth, grown.width, grown.height) == pytest.approx((0.3, 1.1, 0.1))
    assert grown.contains((0.86, 0.54)) and not box.contains((0.86, 0.54))
    with pytest.raises(ParameterError, match="margin=-0.1 m must be >= 0"):
        box.grown(-0.1)
    with pytest.raises(ParameterError, match="obstacle_step_length_max=0.0 m must be > 0"):
        dataclasses.replace(H1, obstacle_step_length_max=0.0)
    with pytest.raises(ParameterError, match=r"obstacle_step_duration_min=0.9 s must be in "
                                             r"\[0, the crossing's duration bound 0.8 s"):
        dataclasses.replace(H1, obstacle_step_duration_min=0.9)
    # a crossing longer than any walking step (its own upper bound beyond t_max)
    assert dataclasses.replace(H1, obstacle_step_duration_min=0.9, obstacle_step_duration_max=1.0).foothold_geometry() \
        .step_duration_min == 0.9
    with pytest.raises(ParameterError, match="sole_front=-0.01 m must be >= 0"):
        dataclasses.replace(H1, sole_front=-0.01)
    planner = DcmFootstepPlanner(H1)
    stance, measured = _start(planner)
    with pytest.raises(ParameterError, match="obstacles must be sequencer.obstacles.Obstacle"):
        planner.plan(0.0, stance, measured, COMMAND, obstacles=("box",))


def test_a_stance_inside_the_margin_with_no_way_out_is_a_solver_error():
    """The stance sole in the grown footprint of a box that no step within the bounds leaves: a SolverError
    (a control loop keeps its last plan), never a foothold on the box."""
    tight = dataclasses.replace(H1, l_min=-0.05, l_max=0.05, obstacle_step_length_max=0.05)
    planner = DcmFootstepPlanner(tight)
    stance = StanceState("left", np.array([0.0, 0.203]), 0.0, 0.0, swing_liftoff=np.array([0.0, -0.203]))
    measured = ReducedState(np.array([0.0, 0.0, 0.97]), np.zeros(3), np.array([0.02, 0.1]))
    around = Obstacle(np.array([0.0, 0.0]), 0.0, 0.3, 3.0, 0.1)  # under both feet
    with pytest.raises(SolverError, match="no foothold outside the obstacle box"):
        planner.plan(0.0, stance, measured, VelocityCommand(0.1), obstacles=(around,))


def test_the_alip_planner_refuses_obstacles():
    from sequencer.alip import AlipParams
    from sequencer.alip.planner import AlipFootstepPlanner

    planner = AlipFootstepPlanner(AlipParams.preset("g1"))
    assert not planner.avoids_obstacles and DcmFootstepPlanner(H1).avoids_obstacles
    stance = StanceState("left", np.array([0.0, 0.1]), 0.0, 0.0)
    measured = ReducedState(np.array([0.0, 0.0, 0.7]), np.zeros(3), np.zeros(2))
    with pytest.raises(ParameterError, match="the ALIP planner cannot avoid obstacles"):
        planner.plan(0.0, stance, measured, VelocityCommand(0.2), obstacles=(Obstacle(np.ones(2), 0.0, 0.1, 1, 0.1),))


def test_a_planned_crossing_is_kept_and_the_swing_keeps_its_decision():
    """A crossing once planned for the step of a stance is kept, in the double support and in the swing, when the
    measured DCM falls back; a step before the obstacle becomes the crossing while still in the double support when
    the DCM runs on far enough, and the swing in progress keeps the decision it lifted off with (no flip from
    before the obstacle to beyond it mid-swing)."""
    box = Obstacle(np.array([0.7425, 0.0]), 0.0, 0.1, 1.2, 0.1)  # near side 0.6925 m: ℓ <= 0.1 m stays before
    stance = StanceState("left", np.array([0.45, 0.203]), 0.0, 0.0, swing_liftoff=np.array([0.33, -0.203]))

    def first_step(planner, t, dcm_ahead):
        dcm = stance.position + np.array([dcm_ahead, -0.09])
        plan = planner.plan(t, stance, ReducedState(np.array([*dcm, 0.97]), np.zeros(3), dcm), COMMAND,
                            obstacles=(box,))
        return plan.steps[0]

    planner = DcmFootstepPlanner(H1)  # (a fresh planner stays before the box up to a DCM 8 cm ahead, crosses at 10)
    late = first_step(planner, 0.0, 0.06)  # the touchdown: the crossing is late, one more step before the box
    assert late.crossing is None and late.position[0] + H1.sole_front <= 0.6925 - H1.obstacle_margin + 1e-9
    assert first_step(planner, 0.05, 0.3).crossing is not None  # the DCM ran on in the double support: it crosses
    assert first_step(planner, 0.08, 0.06).crossing is not None  # and keeps crossing when the DCM falls back
    # ... also behind the stance foot, where the step's own foothold (a step back) stops short of the box: the
    # decision is about the box ahead, not about where that foothold is (seed 33 at 10 cm: stepped in place, fell)
    assert DcmFootstepPlanner(H1).plan(0.0, stance, ReducedState(np.array([*(stance.position + [-0.05, -0.09]), 0.97]),
                                                                 np.zeros(3), stance.position + [-0.05, -0.09]),
                                       COMMAND, obstacles=(box,)).steps[0].position[0] < stance.position[0]
    fallen = first_step(planner, 0.09, -0.05)
    assert fallen.crossing is not None and fallen.position[0] - H1.sole_rear >= 0.7925 + H1.obstacle_margin - 1e-9
    assert first_step(planner, 0.2, 0.06).crossing is not None  # in the swing too
    planner = DcmFootstepPlanner(H1)
    assert first_step(planner, 0.12, 0.06).crossing is None  # lifted off before the box
    assert first_step(planner, 0.2, 0.3).crossing is None  # the DCM far ahead now: the swing keeps its decision
    next_stance = StanceState("left", np.array([0.45, 0.203]), 0.0, 1.0, swing_liftoff=np.array([0.33, -0.203]))
    dcm = next_stance.position + np.array([0.3, -0.09])  # a new stance decides afresh
    assert planner.plan(1.0, next_stance, ReducedState(np.array([*dcm, 0.97]), np.zeros(3), dcm), COMMAND,
                        obstacles=(box,)).steps[0].crossing is not None


def test_a_quasi_static_crossing_settles_the_dcm_before_each_crossing_swing():
    """obstacle_double_support > 0: both crossing swings (the lead foot's from the last foot before the box, the
    trailing foot's from the lead foot beyond it) and the step resuming the walk lift off after that long a double
    support, in which the plan's DCM rests on the settle point (the stance foothold before a crossing swing); the
    contact schedule keeps both feet down for it; the steps before and after walk as without it."""
    from sequencer.schedule import contact_schedule, timed_contact_schedule

    quasi = dataclasses.replace(H1, obstacle_double_support=0.8, horizon=8.0)
    box = Obstacle(np.array([1.05, 0.0]), 0.0, 0.1, 1.2, 0.1)
    planner = DcmFootstepPlanner(quasi)
    stance, measured = _start(planner)
    plan = planner.plan(0.0, stance, measured, COMMAND, obstacles=(box,))
    geometry = quasi.foothold_geometry()
    assert _sole_overlaps(plan, box, geometry) == []
    crossing = [k for k, step in enumerate(plan.steps) if step.crossing is not None]
    assert len(crossing) == 2 and crossing[1] == crossing[0] + 1  # the lead foot, then the trailing foot
    lead, trailing = crossing
    for k, step in enumerate(plan.steps):
        settled = lead <= k <= trailing + 1
        assert (step.double_support == 0.8 and step.settle_dcm is not None) if settled else \
            (step.double_support is None and step.settle_dcm is None), k
    before = plan.steps[lead - 1].position
    assert before[0] + quasi.sole_front <= 1.0 - quasi.obstacle_margin + 1e-9  # the last foot before the box
    # the lead swing from a halt on it (along the heading; across it the walk's sway), the trailing swing with the
    # weight on the lead foot
    np.testing.assert_allclose(plan.steps[lead].settle_dcm[0], before[0], atol=1e-12)
    inward = plan.steps[lead].settle_dcm[1] - before[1]  # towards the landing side, less than the walk's sway
    sway = planner.stance_start_dcm(StanceState(plan.steps[lead - 1].foot, before, 0.0, 0.0), COMMAND) - before
    assert np.sign(inward) == np.sign(sway[1]) and abs(inward) < abs(sway[1])
    # which carries the DCM to the nominal width: the lead foot lands a pelvis width aside, not at the bound
    np.testing.assert_allclose(abs(plan.steps[lead].position[1] - before[1]), quasi.pelvis_width, atol=1e-9)
    np.testing.assert_allclose(plan.steps[trailing].settle_dcm[0], plan.steps[lead].position[0], atol=1e-12)
    np.testing.assert_allclose(plan.steps[lead].dcm_at_touchdown[0], before[0], atol=1e-12)  # it stayed there
    assert plan.steps[lead].position[0] > 1.1 and plan.steps[trailing].position[0] > 1.1
    for k in (lead, trailing):  # the swing after the double support lasts the crossing duration
        step = plan.steps[k]
        swing = step.touchdown_time - step.stance_start_time - 0.8
        assert swing >= geometry.step_duration_min - quasi.double_support - 1e-9
        start = step.stance_start_time
        settle_end = start + 0.8 - quasi.double_support
        held = plan.dcm_at(np.linspace(start, 0.5 * (start + settle_end) - 1e-3, 5))  # where the touchdown left it
        np.testing.assert_allclose(held, np.tile(held[0], (5, 1)), atol=1e-12)
        np.testing.assert_allclose(plan.dcm_at(np.linspace(0.5 * (start + settle_end), settle_end - 1e-3, 5)),
                                   np.tile(step.settle_dcm, (5, 1)), atol=1e-12)  # then at the settle point
        grid_t0 = start + 0.01
        schedule = contact_schedule(plan, grid_t0, 0.02, 50, rounding="nearest")
        rows = schedule.times < start + 0.8 - 0.011
        assert schedule.in_contact[rows].all()  # both feet on the ground through the long double support
        j = schedule.feet.index(step.foot)
        assert not schedule.in_contact[(schedule.times > start + 0.81) & (schedule.times < step.touchdown_time - 0.011),
                                       j].any()
    with pytest.raises(ParameterError, match="use contact_schedule"):
        timed_contact_schedule(plan, 0.0, 0.02, 50)
    # the walk resumes: the steps after the resuming one are walking steps
    steps = np.diff(_along(plan, 0.0))
    assert np.all(np.abs(steps[trailing + 2:]) <= quasi.l_max + 1e-9) and plan.steps[-1].position[0] > 1.5
    # the plan without obstacles does not change
    _assert_plans_equal(DcmFootstepPlanner(quasi).plan(0.0, stance, measured, COMMAND),
                        DcmFootstepPlanner(dataclasses.replace(quasi, obstacle_double_support=0.0)).plan(
                            0.0, stance, measured, COMMAND))


def test_quasi_static_crossing_bad_input():
    with pytest.raises(ParameterError, match="obstacle_double_support"):
        dataclasses.replace(H1, obstacle_double_support=0.05)  # shorter than the walking double support
    with pytest.raises(ParameterError, match="obstacle_double_support"):
        dataclasses.replace(H1, obstacle_double_support=6.0)


def test_a_trailing_settle_halts_the_trailing_crossing_swing_once_the_lead_foot_is_down():
    """obstacle_trailing_double_support > 0 (the lead crossing dynamic): the plans before the lead touchdown are the
    dynamic crossing's, bit for bit; from the lead foot beyond the box, the trailing crossing swing and the step
    resuming the walk lift off after that long a double support, in which the plan's DCM rests on the lead
    foothold (along the heading), with both feet on the ground; the trailing foot lands beyond the box."""
    from sequencer.schedule import contact_schedule

    settled = dataclasses.replace(H1, obstacle_trailing_double_support=0.6, horizon=6.0)
    dynamic = dataclasses.replace(settled, obstacle_trailing_double_support=0.0)
    box = Obstacle(np.array([1.05, 0.0]), 0.0, 0.1, 1.2, 0.1)
    stance, measured = _start(DcmFootstepPlanner(dynamic))
    plan = DcmFootstepPlanner(dynamic).plan(0.0, stance, measured, COMMAND, obstacles=(box,))
    same = DcmFootstepPlanner(settled).plan(0.0, stance, measured, COMMAND, obstacles=(box,))
    assert np.array_equal(same.positions, plan.positions) and np.array_equal(same.touchdown_times, plan.touchdown_times)
    for x, y in zip(same.steps, plan.steps, strict=True):
        assert np.array_equal(x.dcm_offset, y.dcm_offset) and x.double_support is None and x.settle_dcm is None
        assert (x.crossing is None) == (y.crossing is None)
        assert x.crossing is None or x.crossing.phase_interval == y.crossing.phase_interval
    lead = next(k for k, step in enumerate(plan.steps) if step.crossing is not None)
    assert plan.steps[lead + 1].crossing is not None and plan.steps[lead + 1].double_support is None
    down = plan.steps[lead]  # the lead foot beyond the box, the trailing one lifting off before it
    lead_stance = StanceState(down.foot, down.position, 0.0, down.touchdown_time,
                              swing_liftoff=plan.steps[lead - 1].position)
    at_touchdown = ReducedState(np.array([*down.dcm_at_touchdown, 0.97]), np.zeros(3), down.dcm_at_touchdown)
    after = DcmFootstepPlanner(settled).plan(down.touchdown_time, lead_stance, at_touchdown, COMMAND,
                                             obstacles=(box,))
    trailing, resume = after.steps[0], after.steps[1]
    assert trailing.crossing is not None and resume.crossing is None
    assert trailing.double_support == 0.6 and resume.double_support == 0.6
    assert all(step.double_support is None and step.settle_dcm is None for step in after.steps[2:])
    np.testing.assert_allclose(trailing.settle_dcm[0], down.position[0], atol=1e-12)
    assert _sole_overlaps(after, box, settled.foothold_geometry()) == []
    assert trailing.position[0] > 1.1 + settled.sole_rear  # beyond the grown box
    swing = trailing.touchdown_time - trailing.stance_start_time - 0.6
    assert swing >= settled.obstacle_step_duration_min - settled.double_support - 1e-9
    start, settle_end = trailing.stance_start_time, trailing.stance_start_time + 0.6 - settled.double_support
    np.testing.assert_allclose(after.dcm_at(np.linspace(0.5 * (start + settle_end), settle_end - 1e-3, 5)),
                               np.tile(trailing.settle_dcm, (5, 1)), atol=1e-12)
    schedule = contact_schedule(after, start + 0.01, 0.02, 50, rounding="nearest")
    assert schedule.in_contact[schedule.times < start + 0.6 - 0.011].all()
    # a stance sole within the margin before the box is no lead foot, nor is a lift-off there a trailing swing: no
    # settle (closed loop, the H1's preset margin: a lead swing set down short at 0.843 m, the other foot at 0.821 m)
    short = StanceState("left", np.array([0.843, 0.215]), 0.0, 4.48, swing_liftoff=np.array([0.821, -0.091]))
    at_short = ReducedState(np.array([0.925, 0.1, 0.97]), np.zeros(3), np.array([0.925, 0.1]))
    assert all(step.settle_dcm is None for step in DcmFootstepPlanner(dataclasses.replace(
        settled, obstacle_margin=0.08)).plan(4.48, short, at_short, COMMAND, obstacles=(box,)).steps)
    # without the settle the same stance asks the trailing foot to swing on at the walking double support
    unsettled = DcmFootstepPlanner(dynamic).plan(down.touchdown_time, lead_stance, at_touchdown, COMMAND,
                                                 obstacles=(box,))
    assert unsettled.steps[0].double_support is None and unsettled.steps[0].crossing is not None


def test_a_resuming_settle_halts_only_the_step_after_the_trailing_crossing():
    """obstacle_resume_double_support > 0: every plan until the trailing foot is down is the dynamic crossing's, bit
    for bit (the lead and the trailing crossing swings at the walking double support, no settle planned after them:
    planned early, a settle holds the OCP's CoM reference back, docs/ocp.md); from the trailing foot beyond the box
    the step resuming the walk lifts off after that long a double support, both feet on the ground, the plan's DCM
    settling on the walk's stance-start DCM; the steps after it walk."""
    from sequencer.schedule import contact_schedule

    resuming = dataclasses.replace(H1, obstacle_resume_double_support=0.5, horizon=6.0)
    dynamic = dataclasses.replace(resuming, obstacle_resume_double_support=0.0)
    box = Obstacle(np.array([1.05, 0.0]), 0.0, 0.1, 1.2, 0.1)
    stance, measured = _start(DcmFootstepPlanner(dynamic))
    plan = DcmFootstepPlanner(dynamic).plan(0.0, stance, measured, COMMAND, obstacles=(box,))
    lead = next(k for k, step in enumerate(plan.steps) if step.crossing is not None)
    planners = {"dynamic": DcmFootstepPlanner(dynamic), "resuming": DcmFootstepPlanner(resuming)}
    plans = {name: planner.plan(0.0, stance, measured, COMMAND, obstacles=(box,)) for name, planner in planners.items()}
    # the first plan: the dynamic crossing's
    assert plans["resuming"].steps[lead + 1].crossing is not None
    np.testing.assert_array_equal(plans["resuming"].positions, plan.positions)
    np.testing.assert_array_equal(plans["resuming"].touchdown_times, plan.touchdown_times)
    assert all(step.settle_dcm is None and step.double_support is None for step in plans["resuming"].steps)
    # the stance of the lead foot (the trailing swing next): still dynamic, bit for bit
    down = plan.steps[lead]
    lead_stance = StanceState(down.foot, down.position, 0.0, down.touchdown_time,
                              swing_liftoff=plan.steps[lead - 1].position)
    at_lead = ReducedState(np.array([*down.dcm_at_touchdown, 0.97]), np.zeros(3), down.dcm_at_touchdown)
    after_lead = {name: planner.plan(down.touchdown_time, lead_stance, at_lead, COMMAND, obstacles=(box,))
                  for name, planner in planners.items()}
    assert after_lead["resuming"].steps[0].crossing is not None
    np.testing.assert_array_equal(after_lead["resuming"].positions, after_lead["dynamic"].positions)
    np.testing.assert_array_equal(after_lead["resuming"].touchdown_times, after_lead["dynamic"].touchdown_times)
    assert all(step.settle_dcm is None for step in after_lead["resuming"].steps)
    # the trailing foot down beyond the box (the planner saw it land): the resuming step settles
    swing = after_lead["resuming"].steps[0]
    trailing_stance = StanceState(swing.foot, swing.position, 0.0, swing.touchdown_time, swing_liftoff=lead_stance.position)
    at_trailing = ReducedState(np.array([*swing.dcm_at_touchdown, 0.97]), np.zeros(3), swing.dcm_at_touchdown)
    after = planners["resuming"].plan(swing.touchdown_time, trailing_stance, at_trailing, COMMAND, obstacles=(box,))
    first = after.steps[0]
    assert first.crossing is None and first.double_support == 0.5 and first.settle_dcm is not None
    assert all(step.double_support is None and step.settle_dcm is None for step in after.steps[1:])
    assert _sole_overlaps(after, box, resuming.foothold_geometry()) == []
    start, settle_end = first.stance_start_time, first.stance_start_time + 0.5 - resuming.double_support
    np.testing.assert_allclose(after.dcm_at(np.linspace(0.5 * (start + settle_end), settle_end - 1e-3, 5)),
                               np.tile(first.settle_dcm, (5, 1)), atol=1e-12)
    schedule = contact_schedule(after, start + 0.01, 0.02, 50, rounding="nearest")
    assert schedule.in_contact[schedule.times < start + 0.5 - 0.011].all()
    # without the option the same stance steps on at the walking double support
    unsettled = planners["dynamic"].plan(swing.touchdown_time, trailing_stance, at_trailing, COMMAND, obstacles=(box,))
    assert unsettled.steps[0].double_support is None and unsettled.steps[0].settle_dcm is None
    for value in (0.05, 6.0, float("nan")):
        with pytest.raises(ParameterError, match="obstacle_resume_double_support"):
            dataclasses.replace(H1, obstacle_resume_double_support=value)
    with pytest.raises(ParameterError, match="obstacle_resume_double_support=0.5 s needs obstacle_double_support"):
        dataclasses.replace(resuming, obstacle_trailing_double_support=0.6)


def _plans_towards_a_box(field: str, values: tuple[float, float]):
    """(box, {value: plan}, the lead crossing's index) of the H1 geometry walking towards a 10 cm box with the planner
    parameter ``field`` at each of ``values``: both plans cross with the same step and keep every step before the
    last one before the box."""
    box = Obstacle(np.array([1.09, 0.0]), 0.0, 0.1, 1.2, 0.1)
    plans = {}
    for value in values:
        planner = DcmFootstepPlanner(dataclasses.replace(H1, obstacle_offset_tolerance=0.1, **{field: value}))
        stance, measured = _start(planner)
        plans[value] = planner.plan(0.0, stance, measured, COMMAND, obstacles=(box,))
    leads = {next(k for k, step in enumerate(plan.steps) if step.crossing is not None) for plan in plans.values()}
    assert len(leads) == 1, leads
    lead = leads.pop()
    first, second = (plans[value] for value in values)
    np.testing.assert_array_equal(first.positions[:lead - 1], second.positions[:lead - 1])
    return box, plans, lead


def test_the_last_step_before_an_obstacle_aims_further_ahead_with_a_shorter_aim_duration():
    """obstacle_aim_duration: the last step before the box aims at (ℓ_c + b_nom) exp(-ω T_aim), at least the nominal
    offset (0, the default: T_aim = the crossing's longest duration); a shorter T_aim leans that step further
    ahead (the same foothold along the heading, a larger DCM offset at its touchdown); the steps before are kept."""
    box, plans, lead = _plans_towards_a_box("obstacle_aim_duration", (0.0, 0.5))
    last = lead - 1
    assert plans[0.0].positions[last, 0] == plans[0.5].positions[last, 0]  # along the heading (aside: the QP's)
    assert plans[0.5].steps[last].dcm_offset[0] > plans[0.0].steps[last].dcm_offset[0] + 0.02
    assert _sole_overlaps(plans[0.5], box, H1.foothold_geometry()) == []


def test_the_last_step_before_an_obstacle_aims_at_the_lateral_offset_of_a_long_crossing():
    """obstacle_lateral_aim_duration T_lat: the last step before the box aims at the lateral DCM offset
    b_y,nom exp(-ω (T_lat - t_nom)), the one a crossing lasting T_lat carries to the nominal lateral offset: that step
    lands nearer its DCM (a smaller lateral offset at its touchdown) and the crossing after it is narrower; the
    steps before are kept (the iterative backends: with the osqp backend's test)."""
    box, plans, lead = _plans_towards_a_box("obstacle_lateral_aim_duration", (0.0, 0.7))
    last = lead - 1
    before, after = plans[0.0].steps[last].dcm_offset[1], plans[0.7].steps[last].dcm_offset[1]
    fraction = np.exp(-H1.omega * (0.7 - H1.t_nom))
    assert abs(after) < abs(before) - 0.02 and abs(after - fraction * before) < 0.02, (before, after, fraction)
    width = {lateral: abs(plan.positions[lead, 1] - plan.positions[last, 1]) for lateral, plan in plans.items()}
    assert width[0.7] < width[0.0] - 0.02, width
    # the lead crossing aims at the trailing crossing's lateral offset too (the last step's, without the aim, is the
    # nominal one)
    assert abs(plans[0.7].steps[lead].dcm_offset[1]) == pytest.approx(fraction * abs(before), abs=0.005)
    assert _sole_overlaps(plans[0.7], box, H1.foothold_geometry()) == []


def test_a_crossing_swing_pivots_on_the_centre_of_pressure_its_qp_chooses():
    """obstacle_crossing_cop δ: a swing over the box pivots on a point within δ of its stance foothold along the
    heading, the one its QP does best with: from a DCM 6 cm ahead of the stance foot the point-foot plan takes one
    more step before the box, with δ = 5 cm the lead crosses at once on its heel side, landing at the nominal offset;
    the plan's DCM prediction pivots there too (the stance's ``cop_offset``: continuous at every touchdown), and
    only the stances of crossing swings have one."""
    box = Obstacle(np.array([0.7425, 0.0]), 0.0, 0.1, 1.2, 0.1)  # near side 0.6925 m
    stance = StanceState("left", np.array([0.45, 0.203]), 0.0, 0.0, swing_liftoff=np.array([0.33, -0.203]))
    dcm = stance.position + np.array([0.06, -0.09])
    measured = ReducedState(np.array([*dcm, 0.97]), np.zeros(3), dcm)
    plans = {cop: DcmFootstepPlanner(dataclasses.replace(H1, obstacle_crossing_cop=cop)).plan(
        0.0, stance, measured, COMMAND, obstacles=(box,)) for cop in (0.0, 0.05)}
    assert plans[0.0].steps[0].crossing is None and plans[0.0].stance_cop_offset is None
    lead = plans[0.05].steps[0]
    assert lead.crossing is not None and lead.position[0] - H1.sole_rear >= 0.7925 + H1.obstacle_margin - 1e-9
    np.testing.assert_allclose(plans[0.05].stance_cop_offset, [-0.05, 0.0])
    # eq. 1b about the pivot: the DCM at the lead touchdown is the plan's, at the nominal offset ahead of the foothold
    pivot = stance.position + plans[0.05].stance_cop_offset
    np.testing.assert_allclose(pivot + (dcm - pivot) * np.exp(H1.omega * lead.duration), lead.dcm_at_touchdown,
                               atol=1e-9)
    nominal = DcmFootstepPlanner(H1).stance_start_dcm(StanceState("right", np.zeros(2), 0.0, 0.0), COMMAND)
    assert lead.dcm_offset[0] == pytest.approx(nominal[0], abs=1e-3)  # the walk's offset, from the far bound
    for plan in plans.values():
        for step in plan.steps:
            np.testing.assert_allclose(plan.dcm_at(step.touchdown_time - 1e-9), step.dcm_at_touchdown, atol=1e-6)
    steps = plans[0.05].steps
    assert all(step.cop_offset is None or (steps[k + 1].crossing is not None and abs(step.cop_offset[0]) <= 0.05)
               for k, step in enumerate(steps[:-1]))  # a pivot off the foothold: the stance of a crossing swing
    with pytest.raises(ParameterError, match=r"obstacle_crossing_cop=0.3 m must be in \[0, 0.2\) m"):
        dataclasses.replace(H1, obstacle_crossing_cop=0.3)
    with pytest.raises(ParameterError, match="obstacle_crossing_cop=0.05 m .* 'exact' backend only"):
        DcmFootstepPlanner(dataclasses.replace(H1, obstacle_crossing_cop=0.05), backend="osqp").plan(
            0.0, stance, measured, COMMAND, obstacles=(box,))


def test_a_step_pinned_beyond_a_crossed_box_pivots_on_its_heel_side_and_walks_on():
    """obstacle_passed_cop δ_p: after the trailing touchdown both feet stand on the box's far bound with the DCM 8 cm
    behind the stance foot; the point-foot plan pins every next foothold at the bound and has the DCM fall back (the
    H1 fell back over the box there), with δ_p = 12 cm the step pivots behind the foot (within δ_p, chosen by its QP)
    and the plan carries the DCM forwards and walks on, every sole outside the box; a DCM ahead of the feet plans as
    without it, bit for bit."""
    box = Obstacle(np.array([0.7425, 0.0]), 0.0, 0.1, 1.2, 0.1)  # far side 0.7925 m
    bound = 0.7925 + H1.obstacle_margin + H1.sole_rear  # a foothold's far bound along x [m]
    params = dataclasses.replace(H1, obstacle_crossing_cop=0.05)
    stance = StanceState("right", np.array([bound, -0.203]), 0.0, 0.0, swing_liftoff=np.array([bound, 0.203]))

    def plans(lag):
        dcm = stance.position + np.array([-lag, 0.09])
        measured = ReducedState(np.array([*dcm, 0.97]), np.zeros(3), dcm)
        return dcm, {cop: DcmFootstepPlanner(dataclasses.replace(params, obstacle_passed_cop=cop)).plan(
            0.0, stance, measured, COMMAND, obstacles=(box,)) for cop in (0.0, 0.12)}

    dcm, lagging = plans(0.08)
    pinned, pivoted = lagging[0.0], lagging[0.12]
    assert pinned.stance_cop_offset is None
    assert all(step.position[0] == pytest.approx(bound, abs=1e-9) for step in pinned.steps[:3])
    assert pinned.steps[0].dcm_at_touchdown[0] < dcm[0] - 0.05  # the point-foot plan: falling back over the box
    assert -0.12 - 1e-9 <= pivoted.stance_cop_offset[0] < -0.08 and pivoted.stance_cop_offset[1] == 0.0
    pivot = stance.position + pivoted.stance_cop_offset
    first = pivoted.steps[0]
    np.testing.assert_allclose(pivot + (dcm - pivot) * np.exp(H1.omega * first.duration), first.dcm_at_touchdown,
                               atol=1e-9)  # eq. 1b about the pivot
    assert first.dcm_at_touchdown[0] > dcm[0] + 0.05 and first.position[0] >= bound - 1e-9
    assert pivoted.steps[2].position[0] > bound + 0.1  # walking on
    for step in pivoted.steps:
        np.testing.assert_allclose(pivoted.dcm_at(step.touchdown_time - 1e-9), step.dcm_at_touchdown, atol=1e-6)
    assert _sole_overlaps(pivoted, box, params.foothold_geometry()) == []
    _, ahead = plans(-0.06)  # the DCM 6 cm ahead of the feet: nominal footholds free of the box
    assert ahead[0.12].stance_cop_offset is None
    _assert_plans_equal(ahead[0.0], ahead[0.12])
    with pytest.raises(ParameterError, match=r"obstacle_passed_cop=0.2 m must be in \[0, 0.2\) m"):
        dataclasses.replace(H1, obstacle_passed_cop=0.2)


def test_the_trailing_crossing_swing_pivots_within_the_passed_bound():
    """The trailing crossing swing (its stance, the lead foot, on the far bound; the DCM 4 cm behind it) pivots
    within max(δ, δ_p): with δ = 5 cm alone it lands beside the lead foot on the bound, with δ_p = 12 cm it pivots
    further back and lands a step beyond the lead foot, the DCM ahead of it."""
    box = Obstacle(np.array([0.7425, 0.0]), 0.0, 0.1, 1.2, 0.1)
    bound = 0.7925 + H1.obstacle_margin + H1.sole_rear
    params = dataclasses.replace(H1, obstacle_crossing_cop=0.05)
    stance = StanceState("left", np.array([bound, 0.203]), 0.0, 0.0, swing_liftoff=np.array([0.6, -0.203]))
    dcm = stance.position + np.array([-0.04, -0.09])
    measured = ReducedState(np.array([*dcm, 0.97]), np.zeros(3), dcm)
    plans = {cop: DcmFootstepPlanner(dataclasses.replace(params, obstacle_passed_cop=cop)).plan(
        0.0, stance, measured, COMMAND, obstacles=(box,)) for cop in (0.0, 0.12)}
    trailing = {cop: plan.steps[0] for cop, plan in plans.items()}
    assert all(step.crossing is not None for step in trailing.values())
    assert plans[0.0].stance_cop_offset[0] >= -0.05 - 1e-9
    assert trailing[0.0].position[0] == pytest.approx(bound, abs=1e-9)
    assert -0.12 - 1e-9 <= plans[0.12].stance_cop_offset[0] < -0.05
    assert trailing[0.12].position[0] > bound + 0.05 and trailing[0.12].dcm_at_touchdown[0] > trailing[0.12].position[0]
    assert _sole_overlaps(plans[0.12], box, params.foothold_geometry()) == []


def test_the_lead_crossing_aims_at_its_momentum_beyond_the_nominal_offset():
    """obstacle_crossing_offset Δb: the lead crossing lands on the same foothold along the heading (its bound
    beyond the box) with the DCM further ahead, towards Δb beyond the nominal offset, its swing lasting longer for
    the DCM to get there; the DCM check still compares with the nominal aim (the lead still crosses at once)."""
    box = Obstacle(np.array([0.7425, 0.0]), 0.0, 0.1, 1.2, 0.1)  # near side 0.6925 m
    stance = StanceState("left", np.array([0.45, 0.203]), 0.0, 0.0, swing_liftoff=np.array([0.33, -0.203]))
    dcm = stance.position + np.array([0.06, -0.09])
    measured = ReducedState(np.array([*dcm, 0.97]), np.zeros(3), dcm)
    params = dataclasses.replace(H1, obstacle_crossing_cop=0.05)
    plans = {extra: DcmFootstepPlanner(dataclasses.replace(params, obstacle_crossing_offset=extra)).plan(
        0.0, stance, measured, COMMAND, obstacles=(box,)) for extra in (0.0, 0.06)}
    lead = {extra: plan.steps[0] for extra, plan in plans.items()}
    assert all(step.crossing is not None for step in lead.values())
    assert lead[0.06].position[0] == pytest.approx(lead[0.0].position[0], abs=1e-9)  # along: on its bound
    # the QP trades it against the lateral offset (the crossing's width on its bound: the longer swing lands with
    # the lateral DCM nearer the foot): 0.039 m of the 0.06 m here
    gain = lead[0.06].dcm_offset[0] - lead[0.0].dcm_offset[0]
    assert 0.03 < gain <= 0.06 + 1e-9, gain
    assert lead[0.06].duration > lead[0.0].duration + 0.015
    for step in plans[0.06].steps:
        np.testing.assert_allclose(plans[0.06].dcm_at(step.touchdown_time - 1e-9), step.dcm_at_touchdown, atol=1e-6)
    with pytest.raises(ParameterError, match=r"obstacle_crossing_offset=0.3 m must be in \[0, 0.3\) m"):
        dataclasses.replace(H1, obstacle_crossing_offset=0.3)


def test_the_lead_crossing_lands_with_room_beyond_the_far_bound_within_its_length_bound():
    """obstacle_landing_room r: the lead crossing lands r beyond the box's far bound (b = far side + margin + heel),
    at most its length bound from the stance, and never short of b; the rest of the crossing is planned as before
    (the trailing swing still passes over the box, every sole outside it), and r = 0 is the plan on the bound, bit
    for bit."""
    box = Obstacle(np.array([0.7425, 0.0]), 0.0, 0.1, 1.2, 0.1)  # far side 0.7925 m
    stance = StanceState("left", np.array([0.45, 0.203]), 0.0, 0.0, swing_liftoff=np.array([0.33, -0.203]))
    dcm = stance.position + np.array([0.06, -0.09])
    measured = ReducedState(np.array([*dcm, 0.97]), np.zeros(3), dcm)
    params = dataclasses.replace(H1, obstacle_crossing_cop=0.05)
    bound = 0.7925 + H1.obstacle_margin + H1.sole_rear  # the lead foothold's far bound along x [m]
    reach = stance.position[0] + max(H1.l_max, H1.obstacle_step_length_max)
    plans = {room: DcmFootstepPlanner(dataclasses.replace(params, obstacle_landing_room=room)).plan(
        0.0, stance, measured, COMMAND, obstacles=(box,)) for room in (0.0, 0.08, 0.3)}
    lead = {room: plan.steps[0] for room, plan in plans.items()}
    assert all(step.crossing is not None for step in lead.values())
    assert lead[0.0].position[0] == pytest.approx(bound, abs=1e-9)
    assert lead[0.08].position[0] == pytest.approx(bound + 0.08, abs=1e-9)
    assert lead[0.3].position[0] == pytest.approx(reach, abs=1e-9) and reach < bound + 0.3
    for plan in plans.values():
        assert plan.steps[1].crossing is not None  # the trailing swing passes over the box
        assert _sole_overlaps(plan, box, H1.foothold_geometry()) == []
    default = DcmFootstepPlanner(params).plan(0.0, stance, measured, COMMAND, obstacles=(box,))
    for step, other in zip(default.steps, plans[0.0].steps):
        np.testing.assert_array_equal(step.position, other.position)
        assert step.touchdown_time == other.touchdown_time
    with pytest.raises(ParameterError, match=r"obstacle_landing_room=0.5 m must be in \[0, 0.5\) m"):
        dataclasses.replace(H1, obstacle_landing_room=0.5)


def test_the_far_margin_brings_both_crossing_feet_nearer_the_box():
    """obstacle_far_margin_reduction: the box's far side (further along the heading) grown by obstacle_margin minus
    it: the lead crossing lands that much nearer the box (on the new bound), the side facing the stance keeps its
    margin (the last step before the box is unchanged), and every sole stays outside the box grown by the far margin
    on that side; a turned box's bound moves back by the same amount."""
    box = Obstacle(np.array([0.7425, 0.0]), 0.0, 0.1, 1.2, 0.1)  # far side 0.7925 m
    stance = StanceState("left", np.array([0.45, 0.203]), 0.0, 0.0, swing_liftoff=np.array([0.33, -0.203]))
    dcm = stance.position + np.array([0.06, -0.09])
    measured = ReducedState(np.array([*dcm, 0.97]), np.zeros(3), dcm)
    params = dataclasses.replace(H1, obstacle_crossing_cop=0.05, obstacle_margin=0.08)
    plans = {cut: DcmFootstepPlanner(dataclasses.replace(params, obstacle_far_margin_reduction=cut)).plan(
        0.0, stance, measured, COMMAND, obstacles=(box,)) for cut in (0.0, 0.04)}
    lead = {cut: plan.steps[0] for cut, plan in plans.items()}
    assert all(step.crossing is not None for step in lead.values())
    assert lead[0.0].position[0] == pytest.approx(0.7925 + 0.08 + H1.sole_rear, abs=1e-9)
    assert lead[0.04].position[0] == pytest.approx(0.7925 + 0.04 + H1.sole_rear, abs=1e-9)
    far_only = dataclasses.replace(params.foothold_geometry(), margin=0.04)  # the whole box grown by the far margin
    assert _sole_overlaps(plans[0.04], box, far_only) == []
    geometry = dataclasses.replace(params, obstacle_far_margin_reduction=0.04).foothold_geometry()
    for yaw in (0.0, 0.3):
        turned = Obstacle(box.center, yaw, box.depth, box.width, box.height)
        a0, b0, c0, d0 = forbidden_box(turned, stance.position, 0.0, params.foothold_geometry(), (-0.6, -0.22))
        a, b, c, d = forbidden_box(turned, stance.position, 0.0, geometry, (-0.6, -0.22))
        assert (a, c, d) == (a0, c0, d0) and b == pytest.approx(b0 - 0.04)
    with pytest.raises(ParameterError, match=r"obstacle_far_margin_reduction=0.09 m must be in \[0, obstacle_margin"):
        dataclasses.replace(params, obstacle_far_margin_reduction=0.09)


def test_the_last_step_before_the_box_aims_for_the_crossing_with_its_landing_room():
    """The last step before the box aims at the DCM offset from which the longer crossing (to the far bound plus the
    landing room) reaches its aim: further ahead than without room, as a crossing that much longer asks."""
    geometry = H1.foothold_geometry()
    with_room = dataclasses.replace(geometry, landing_room=0.1)
    from sequencer.footholds import FootholdConstraints
    plain, roomy = (FootholdConstraints((), g, H1.omega) for g in (geometry, with_room))
    nominal = 0.05
    assert roomy.last_step_aim(0.5, 1.0, 0.12, nominal) == pytest.approx(plain.last_step_aim(0.6, 1.0, 0.12, nominal))
    assert roomy.last_step_aim(0.5, 1.0, 0.12, nominal) > plain.last_step_aim(0.5, 1.0, 0.12, nominal)
    top = geometry.step_length_max  # the room ends at the crossing's length bound
    assert roomy.last_step_aim(top - 0.02, 1.0, 0.12, nominal) == pytest.approx(
        plain.last_step_aim(top, 1.0, 0.12, nominal))


def test_a_negotiation_narrows_the_inner_width_bound_so_the_last_step_reaches_its_lateral_aim():
    """obstacle_width_min: with the DCM far across the heading from the left stance, the last step before the box is
    held by the walk's 0.30 m inner width bound 2.4 cm off the lateral aim of a 0.7 s crossing (a lateral DCM offset of
    5.8 cm at its touchdown against 3.4 cm aimed); with the bound at 0.22 m during the negotiation it lands on the aim,
    nearer its DCM, and the lead crossing after it lands narrower. The steps before it, and every plan without
    obstacles, are the walk's, bit for bit."""
    box = Obstacle(np.array([1.0, 0.0]), 0.0, 0.2, 1.2, 0.1)  # near side 0.9 m
    base = dataclasses.replace(H1, obstacle_offset_tolerance=0.1, obstacle_lateral_aim_duration=0.7,
                               obstacle_margin=0.08)
    stance = StanceState("left", np.array([0.45, 0.203]), 0.0, 0.0, swing_liftoff=np.array([0.33, -0.203]))
    dcm = stance.position + np.array([0.08, -0.16])
    measured = ReducedState(np.array([*dcm, 0.97]), np.zeros(3), dcm)
    plans, plain = {}, {}
    for width in (0.0, 0.22):
        planner = DcmFootstepPlanner(dataclasses.replace(base, obstacle_width_min=width))
        plans[width] = planner.plan(0.1, stance, measured, COMMAND, obstacles=(box,))
        plain[width] = planner.plan(0.1, stance, measured, COMMAND)
    _assert_plans_equal(plain[0.22], plain[0.0])
    lead = next(k for k, step in enumerate(plans[0.0].steps) if step.crossing is not None)
    assert lead == next(k for k, step in enumerate(plans[0.22].steps) if step.crossing is not None)
    last = lead - 1
    np.testing.assert_array_equal(plans[0.22].positions[:last], plans[0.0].positions[:last])
    aim = abs(base.b_nom("left")[1]) * np.exp(-base.omega * (0.7 - base.t_nom))
    width = {w: plans[w].positions[last - 1, 1] - plans[w].positions[last, 1] for w in plans}
    assert width[0.0] == pytest.approx(0.30) and 0.22 <= width[0.22] < 0.30 - 0.02, width
    assert plans[0.0].steps[last].dcm_offset[1] > aim + 0.02, plans[0.0].steps[last].dcm_offset[1]
    assert plans[0.22].steps[last].dcm_offset[1] == pytest.approx(aim, abs=1e-3)
    lead_width = {w: plans[w].positions[lead, 1] - plans[w].positions[last, 1] for w in plans}
    assert lead_width[0.22] < lead_width[0.0] - 0.05, lead_width
    assert _sole_overlaps(plans[0.22], box, base.foothold_geometry()) == []
    for value in (0.05, 0.35, -0.1, float("nan")):  # [2 x 0.04, 0.30] m
        with pytest.raises(ParameterError, match="obstacle_width_min="):
            dataclasses.replace(H1, obstacle_width_min=value)
    with pytest.raises(ParameterError, match=r"obstacle_width_min=0.22 m .* 'exact' backend only"):
        DcmFootstepPlanner(dataclasses.replace(base, obstacle_width_min=0.22), backend="osqp").plan(
            0.1, stance, measured, COMMAND, obstacles=(box,))


def test_trailing_settle_and_aim_duration_bad_input():
    for value in (0.05, 6.0, float("nan")):
        with pytest.raises(ParameterError, match="obstacle_trailing_double_support"):
            dataclasses.replace(H1, obstacle_trailing_double_support=value)
    for value in (0.2, 0.9, float("nan")):  # the crossing durations are [0.5, 0.8] s
        with pytest.raises(ParameterError, match="obstacle_aim_duration"):
            dataclasses.replace(H1, obstacle_aim_duration=value)
    for value in (0.2, 0.9, -1.0, float("nan")):  # [t_nom, 0.8] s
        with pytest.raises(ParameterError, match="obstacle_lateral_aim_duration="):
            dataclasses.replace(H1, obstacle_lateral_aim_duration=value)


TWO_STEPS = dataclasses.replace(H1, obstacle_step_duration_max=1.1, obstacle_swing_length_max=0.7)
"""The H1 geometry with a crossing duration bound above t_max and a swing travel bound (two steps ahead)."""


def _crossings(plan, start_along: float = 0.0):
    """(lead, trailing) indices of the first two crossing steps, and the footholds along x with the stance first."""
    crossings = [k for k, step in enumerate(plan.steps) if step.crossing is not None]
    assert len(crossings) >= 2, crossings
    assert crossings[1] == crossings[0] + 1
    return crossings[0], crossings[1], np.concatenate([[start_along], _along(plan, 0.0)])


@pytest.mark.parametrize("seed", range(8))
def test_the_trailing_swing_stays_within_its_travel_bound(seed):
    rng = np.random.default_rng(100 + seed)
    distance, depth = rng.uniform(0.4, 1.0), rng.uniform(0.08, 0.2)
    obstacle = Obstacle(np.array([distance + 0.5 * depth, 0.0]), 0.0, depth, 1.2, 0.1)
    geometry = TWO_STEPS.foothold_geometry()
    travels = {}
    for name, params in (("unbounded", H1), ("bounded", TWO_STEPS)):
        planner = DcmFootstepPlanner(params)
        stance, measured = _start(planner)
        plan = planner.plan(0.0, stance, measured, COMMAND, obstacles=(obstacle,))
        assert _sole_overlaps(plan, obstacle, params.foothold_geometry()) == []
        lead, trailing, along = _crossings(plan)
        travels[name] = along[trailing + 1] - along[trailing - 1]  # the trailing foot lifts off at the lead's stance
        if name == "bounded":
            for k in (lead, trailing):
                assert geometry.step_duration_min - 1e-9 <= plan.steps[k].duration <= 1.1 + 1e-9
    assert travels["bounded"] <= TWO_STEPS.obstacle_swing_length_max + 1e-9
    assert travels["bounded"] <= travels["unbounded"] + 1e-9


def test_the_lead_crossing_step_aims_at_the_offset_the_trailing_step_can_carry():
    """b_c = (ℓ_t + b_nom) exp(-ω T_c,min), ℓ_t = min(l_nom, s_max - ℓ_c) (module docstring, "Two steps ahead"):
    a box where the crossing is within the DCM's reach."""
    obstacle = Obstacle(np.array([0.9, 0.0]), 0.0, 0.1, 1.2, 0.1)
    planner = DcmFootstepPlanner(TWO_STEPS)
    stance, measured = _start(planner)
    plan = planner.plan(0.0, stance, measured, COMMAND, obstacles=(obstacle,))
    lead, trailing, along = _crossings(plan)
    crossing_length = along[lead + 1] - along[lead - 1]  # from the stance before it (the other foot)
    gait = planner.sequencer.nominal_gait((COMMAND.v_x, COMMAND.v_y), None)
    trailing_length = min(gait.step_length, TWO_STEPS.obstacle_swing_length_max - crossing_length)
    b_nominal = float(gait.dcm_offset(plan.steps[trailing].foot)[0])
    expected = (trailing_length + b_nominal) * np.exp(-TWO_STEPS.omega * TWO_STEPS.obstacle_step_duration_min)
    assert expected < b_nominal - 0.01  # the aim is not the nominal offset
    assert plan.steps[lead].dcm_offset[0] == pytest.approx(expected, abs=3e-3)
    # the trailing step then lands at the nominal offset, within its travel
    assert plan.steps[trailing].dcm_offset[0] == pytest.approx(b_nominal, abs=3e-3)
    assert along[trailing + 1] - along[trailing - 1] <= TWO_STEPS.obstacle_swing_length_max + 1e-9


@pytest.mark.parametrize("seed", range(4))
def test_a_crossing_bound_below_t_max_shortens_both_crossing_swings(seed):
    """obstacle_step_duration_max below t_max (the H1 preset's crossings, 0.6 s against its 0.8 s): the lead and
    trailing crossing steps last at most 0.6 s, every sole stays outside the box, and the walking steps keep their own
    bound t_max."""
    from wbmpc.walking.preset import load_walking_preset

    rng = np.random.default_rng(200 + seed)
    distance, depth = rng.uniform(0.8, 1.4), rng.uniform(0.1, 0.3)
    obstacle = Obstacle(np.array([distance + 0.5 * depth, 0.0]), 0.0, depth, 1.2, 0.2)
    durations = {}
    for name, overrides in (("t_max", {}), ("short", {"planner.obstacle_step_duration_max": 0.6,
                                                      "planner.obstacle_lateral_aim_duration": 0.6})):
        params = load_walking_preset("h1", {"planner.horizon": 5.0, **overrides}).planner_params
        assert params.crossing_duration_max == (0.6 if overrides else params.t_max)
        planner = DcmFootstepPlanner(params)
        stance, measured = _start(planner)
        plan = planner.plan(0.0, stance, measured, COMMAND, obstacles=(obstacle,))
        assert _sole_overlaps(plan, obstacle, params.foothold_geometry()) == []
        lead, trailing, _ = _crossings(plan)
        durations[name] = [plan.steps[k].duration for k in (lead, trailing)]
        assert max(step.duration for step in plan.steps if step.crossing is None) <= params.t_max + 1e-9
    assert all(0.6 - 1e-9 <= d <= 0.6 + 1e-9 for d in durations["short"])  # the preset's lower bound is 0.6 s too
    assert max(durations["t_max"]) > 0.6 + 1e-3  # the bound is active: without it a crossing takes longer


@pytest.mark.parametrize("seed", range(3))
def test_the_trailing_swing_has_its_own_duration_bound(seed):
    """obstacle_trailing_duration_min below obstacle_step_duration_min: the trailing crossing swing (its stance foot
    beyond the box) may be that short, the lead crossing keeps the crossing's bound, every sole stays outside the box;
    0 gives the trailing swing the crossing's bound (the preset's plan unchanged)."""
    from wbmpc.walking.preset import load_walking_preset

    rng = np.random.default_rng(300 + seed)
    distance, depth = rng.uniform(0.8, 1.4), rng.uniform(0.1, 0.3)
    obstacle = Obstacle(np.array([distance + 0.5 * depth, 0.0]), 0.0, depth, 1.2, 0.1)
    durations = {}
    for shortest in (0.0, 0.4):
        params = load_walking_preset("h1", {"planner.horizon": 5.0,
                                            "planner.obstacle_trailing_duration_min": shortest}).planner_params
        geometry = params.foothold_geometry()
        assert geometry.trailing_duration == (shortest or geometry.step_duration_min)
        planner = DcmFootstepPlanner(params)
        stance, measured = _start(planner)
        plan = planner.plan(0.0, stance, measured, COMMAND, obstacles=(obstacle,))
        assert _sole_overlaps(plan, obstacle, geometry) == []
        lead, trailing, _ = _crossings(plan)
        durations[shortest] = (plan.steps[lead].duration, plan.steps[trailing].duration)
        assert plan.steps[lead].duration >= geometry.step_duration_min - 1e-9
        assert plan.steps[trailing].duration >= geometry.trailing_duration - 1e-9
    assert durations[0.0][1] >= 0.6 - 1e-9  # the crossing's bound (the preset's 0.6 s)
    assert durations[0.4][1] < 0.6 - 1e-3  # the trailing swing's own bound is used
    # over an obstacle higher than obstacle_trailing_height_max the trailing swing keeps the crossing's bound
    params = load_walking_preset("h1", {"planner.horizon": 5.0, "planner.obstacle_trailing_duration_min": 0.4,
                                        "planner.obstacle_trailing_height_max": 0.09}).planner_params
    planner = DcmFootstepPlanner(params)
    stance, measured = _start(planner)
    plan = planner.plan(0.0, stance, measured, COMMAND, obstacles=(obstacle,))
    lead, trailing, _ = _crossings(plan)
    assert (plan.steps[lead].duration, plan.steps[trailing].duration) == pytest.approx(durations[0.0], abs=1e-12)


def test_trailing_duration_bad_input():
    with pytest.raises(ParameterError, match=r"obstacle_trailing_duration_min=0.2 s must be 0 "):
        dataclasses.replace(H1, obstacle_trailing_duration_min=0.2)  # below t_min
    with pytest.raises(ParameterError, match=r"obstacle_trailing_duration_min=0.9 s must be 0 "):
        dataclasses.replace(H1, obstacle_trailing_duration_min=0.9)  # above the crossing's bound t_max
    with pytest.raises(ParameterError, match=r"obstacle_trailing_height_max=-0.1 m must be 0 "):
        dataclasses.replace(H1, obstacle_trailing_height_max=-0.1)


def test_crossing_duration_and_travel_bad_input():
    with pytest.raises(ParameterError, match="obstacle_step_duration_max"):
        dataclasses.replace(H1, obstacle_step_duration_max=0.4)  # below the crossing's lower bound 0.5 s
    with pytest.raises(ParameterError, match="obstacle_step_duration_max"):
        dataclasses.replace(H1, obstacle_step_duration_max=4.0)
    with pytest.raises(ParameterError, match="obstacle_swing_length_max"):
        dataclasses.replace(H1, obstacle_swing_length_max=-0.1)
    with pytest.raises(ParameterError, match="obstacle_swing_length_max"):
        dataclasses.replace(H1, obstacle_swing_length_max=float("nan"))


def _h1_preset_plan(overrides: dict, box_x: float = 1.0):
    """The H1 preset's plan (5 s horizon) from a left stance at the origin with the nominal DCM, 0.3 m/s, towards
    a 10 cm box across the path at ``box_x`` [m] (the deterministic scene of docs/scripts/h1_step_over.py), with the
    crossing's and the passed box's centres of pressure on the foothold and no lateral aim unless overridden (the
    point-foot LIPM the approach and drift relations below are written in)."""
    from wbmpc.walking.preset import load_walking_preset

    pinned = {"planner.obstacle_crossing_cop": 0.0, "planner.obstacle_passed_cop": 0.0,
              "planner.obstacle_lateral_aim_duration": 0.0}
    params = load_walking_preset("h1", {"planner.horizon": 5.0, **pinned, **overrides}).planner_params
    planner = DcmFootstepPlanner(params)
    box = Obstacle(np.array([box_x, 0.0]), 0.0, 0.1, 1.2, 0.1)
    stance, measured = _start(planner)
    return params, box, planner.plan(0.0, stance, measured, COMMAND, obstacles=(box,))


@pytest.mark.parametrize("box_x", [1.0, 1.05, 1.12])
def test_without_an_approach_distance_the_plan_is_the_greedy_one(box_x):
    assert SequencerParams.__dataclass_fields__["obstacle_approach_distance"].default == 0.0  # greedy by default
    _, _, greedy = _h1_preset_plan({"planner.obstacle_approach_distance": 0.0}, box_x)
    far = _h1_preset_plan({"planner.obstacle_approach_distance": 0.2}, box_x)[2]  # the box beyond it until the end
    first = next(k for k, step in enumerate(greedy.steps) if step.position[0] > 0.45)  # where the approach begins
    np.testing.assert_array_equal(greedy.positions[:first], far.positions[:first])


@pytest.mark.parametrize("box_x", [1.0, 1.05, 1.12])
def test_the_even_approach_ends_on_the_bound_and_crosses_without_a_step_in_place(box_x):
    """obstacle_approach_distance = 1.5 m with obstacle_aim_duration = 0.6 s: the steps before the box are equal
    (a / n each), the last one lands on the foothold bound a, its DCM offset is the last step's aim, and the next
    swing crosses (greedy, the same box costs a short step and a step in place beside the last foothold)."""
    params, box, plan = _h1_preset_plan({"planner.obstacle_approach_distance": 1.5,
                                         "planner.obstacle_aim_duration": 0.6}, box_x)
    geometry = params.foothold_geometry()
    lead = next(k for k, step in enumerate(plan.steps) if step.crossing is not None)
    along = plan.positions[:lead, 0]
    lengths = np.diff(np.concatenate(([0.0], along)))
    bound = box_x - box.depth / 2 - geometry.margin - geometry.sole_front
    assert along[-1] == pytest.approx(bound, abs=2e-3)
    assert np.ptp(lengths[1:]) < 0.01 and lengths.min() > 0.1  # even steps, none in place
    omega = params.omega
    aim = (plan.positions[lead, 0] - along[-1] + params.b_nom("left")[0]) * np.exp(-omega * 0.6)
    assert plan.steps[lead - 1].dcm_offset[0] == pytest.approx(aim, abs=0.01)
    assert plan.steps[lead - 2].dcm_offset[0] < plan.steps[lead - 1].dcm_offset[0]  # the offsets build up to it
    assert _sole_overlaps(plan, box, geometry) == []
    _, _, greedy = _h1_preset_plan({"planner.obstacle_aim_duration": 0.6, "planner.obstacle_approach_distance": 0.0}, box_x)
    greedy_lead = next(k for k, step in enumerate(greedy.steps) if step.crossing is not None)
    greedy_lengths = np.diff(greedy.positions[:greedy_lead, 0])
    assert greedy_lengths.min() < 0.1 or np.ptp(greedy_lengths) > 0.05  # greedy: a short or an in-place step


def test_an_approach_step_from_which_the_box_is_crossable_aims_at_the_lateral_offset():
    """The even approach counts two steps to the bound a (a = 0.26 m, ℓ_nom = 0.15 m), but from the first one's
    foothold the box is already within a crossing step (b - a / 2 = 0.63 m <= 0.70 m), and the sequencer crosses from
    there when its DCM lets it (the H1 at seed 25, 10 cm, session 26): that step aims at the lateral aim's offset, the
    walk's steps behind it at the nominal one."""
    from wbmpc.walking.preset import load_walking_preset

    pinned = {"planner.horizon": 5.0, "planner.obstacle_crossing_cop": 0.0, "planner.obstacle_passed_cop": 0.0,
              "planner.obstacle_approach_distance": 1.5, "planner.obstacle_lateral_aim_duration": 0.7}
    params = load_walking_preset("h1", pinned).planner_params
    planner = DcmFootstepPlanner(params)
    geometry = params.foothold_geometry()
    near = 0.26 + geometry.margin + geometry.sole_front  # the bound a 0.26 m ahead of the stance at x = 0
    box = Obstacle(np.array([near + 0.05, 0.0]), 0.0, 0.1, 1.2, 0.1)
    b = near + 0.1 + geometry.margin + geometry.sole_rear
    assert round(0.26 / 0.15) == 2 and b - 0.13 <= geometry.step_length_max
    plan = planner.plan(0.0, *_start(planner), COMMAND, obstacles=(box,))
    fraction = np.exp(-params.omega * (0.7 - params.t_nom))
    first = plan.steps[0]
    assert first.crossing is None and first.position[0] == pytest.approx(0.13, abs=0.02)
    assert abs(first.dcm_offset[1]) == pytest.approx(fraction * abs(params.b_nom("left")[1]), abs=0.005)
    far = planner.plan(0.0, *_start(planner), COMMAND, obstacles=(Obstacle(np.array([1.3, 0.0]), 0.0, 0.1, 1.2, 0.1),))
    assert abs(far.steps[0].dcm_offset[1]) == pytest.approx(abs(params.b_nom("left")[1]), abs=0.005)
    assert _sole_overlaps(plan, box, geometry) == []


def test_an_approach_step_planned_out_of_crossing_reach_keeps_the_walking_lateral_offset():
    """The lateral aim goes by the foothold the step's QP plans, not the approach's nominal one: with the DCM 4 cm
    behind the plan at the stance of the approach's last step by count, the QP puts that step 16 cm short of the bound,
    out of a crossing's reach; it keeps the walking lateral offset and the step after it, from which the box is
    crossed, aims at the lateral aim's (the H1 at seed 1, 10 cm, session 26: two aimed steps in a row, the second on
    the negotiation's inner width bound, 8 cm from its DCM at the crossing's lift-off)."""
    from wbmpc.walking.preset import load_walking_preset

    pinned = {"planner.horizon": 5.0, "planner.obstacle_crossing_cop": 0.0, "planner.obstacle_passed_cop": 0.0,
              "planner.obstacle_approach_distance": 1.5, "planner.obstacle_lateral_aim_duration": 0.7}
    params = load_walking_preset("h1", pinned).planner_params
    geometry = params.foothold_geometry()
    box = Obstacle(np.array([1.05, 0.0]), 0.0, 0.1, 1.2, 0.1)
    planner = DcmFootstepPlanner(params)
    plan = planner.plan(0.0, *_start(planner), COMMAND, obstacles=(box,))
    lead = next(k for k, step in enumerate(plan.steps) if step.crossing is not None)
    last_stance = plan.steps[lead - 2]
    stance = StanceState(last_stance.foot, last_stance.position, 0.0, last_stance.touchdown_time,
                         swing_liftoff=plan.steps[lead - 3].position)
    dcm = last_stance.dcm_at_touchdown - np.array([0.04, 0.0])
    replan = DcmFootstepPlanner(params).plan(last_stance.touchdown_time, stance,
                                             ReducedState(np.array([*dcm, 0.97]), np.zeros(3), dcm), COMMAND,
                                             obstacles=(box,))
    far = 1.05 + 0.05 + geometry.margin + geometry.sole_rear
    first, second = replan.steps[0], replan.steps[1]
    assert first.crossing is None and far - first.position[0] > geometry.step_length_max  # out of reach
    assert second.crossing is None and replan.steps[2].crossing is not None
    nominal, fraction = abs(params.b_nom("left")[1]), np.exp(-params.omega * (0.7 - params.t_nom))
    assert abs(first.dcm_offset[1]) == pytest.approx(nominal, abs=0.005)
    assert abs(second.dcm_offset[1]) == pytest.approx(fraction * nominal, abs=0.005)


def test_approach_distance_bad_input():
    for value in (-0.1, float("nan"), float("inf")):
        with pytest.raises(ParameterError, match="obstacle_approach_distance"):
            dataclasses.replace(H1, obstacle_approach_distance=value)


@pytest.mark.parametrize("field, value", [("obstacle_double_support", 0.8), ("obstacle_trailing_double_support", 0.6),
                                          ("obstacle_resume_double_support", 0.5), ("obstacle_approach_distance", 1.0)])
def test_an_exact_only_option_with_another_backend_is_a_parameter_error(field, value):
    planner = DcmFootstepPlanner(dataclasses.replace(H1, **{field: value}), backend="osqp")
    stance, measured = _start(planner)
    with pytest.raises(ParameterError, match=f"{field}.*exact"):
        planner.plan(0.0, stance, measured, COMMAND, obstacles=(Obstacle(np.array([1.0, 0.0]), 0.0, 0.1, 1.0, 0.1),))


def test_the_crossing_drift_adds_the_swing_legs_dcm_gain_to_every_swing_over_the_box():
    """obstacle_crossing_drift κ_c: each swing over the box (the lead crossing, the trailing swing) ends with its DCM
    κ_c d past the LIPM's, ξ_T = p_0 + (ξ_0 - p_0) γ + κ_c d (d its travel from lift-off along the heading), and
    the crossing no longer waits for a step in place (the DCM check counts the swing's gain: the greedy plan of
    the same box steps in place beside the last foothold first)."""
    params, box, plan = _h1_preset_plan({"planner.obstacle_crossing_drift": 0.25}, 1.05)
    _, _, lipm = _h1_preset_plan({}, 1.05)
    omega = params.omega
    swings = [k for k, step in enumerate(plan.steps) if step.crossing is not None]
    assert len(swings) >= 2
    positions = np.vstack((np.array([[0.0, -0.203], [0.0, 0.203]]), plan.positions))  # lift-off, stance, steps
    for k in swings[:2]:
        step, previous = plan.steps[k], plan.steps[k - 1]
        stance, liftoff = positions[k + 1], positions[k]
        gamma = np.exp(omega * (step.touchdown_time - step.stance_start_time))
        lipm_dcm = stance[0] + (previous.dcm_at_touchdown[0] - stance[0]) * gamma
        travel = step.position[0] - liftoff[0]
        assert step.dcm_at_touchdown[0] == pytest.approx(lipm_dcm + 0.25 * travel, abs=1e-9), k
    lead = swings[0]
    assert plan.positions[lead - 1, 0] - plan.positions[lead - 2, 0] > 0.05  # the last step before it is a step
    lipm_lead = next(k for k, step in enumerate(lipm.steps) if step.crossing is not None)
    assert abs(lipm.positions[lipm_lead - 1, 0] - lipm.positions[lipm_lead - 2, 0]) < 0.01  # greedy: in place
    assert _sole_overlaps(plan, box, params.foothold_geometry()) == []


def test_crossing_drift_bad_input():
    for value in (-0.1, 1.0, float("nan")):
        with pytest.raises(ParameterError, match="obstacle_crossing_drift"):
            dataclasses.replace(H1, obstacle_crossing_drift=value)
