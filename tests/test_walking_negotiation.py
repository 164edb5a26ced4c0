"""Obstacle negotiation in the walking controller: the walking/negotiation mode (wbmpc.walking.negotiation),
the planning stage handing the obstacles on, the OCP reference's crossing swings (no MuJoCo)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from robots import load_robot
from sequencer.obstacles import Obstacle
from sequencer.planner import VelocityCommand
from sequencer.schedule import contact_schedule
from wbmpc.errors import ParameterError
from wbmpc.walking.negotiation import NEGOTIATION, WALKING, NegotiationMode
from wbmpc.walking.planning import PlanningStage
from wbmpc.walking.preset import load_walking_preset
from wbmpc.walking.reference import crossing_schedule, swing_liftoffs

BOX = Obstacle(np.array([0.5, 0.0]), 0.0, 0.1, 1.0, 0.1)  # across the path, near edge 0.45 m ahead
FEET = np.array([[0.0, 0.2], [0.0, -0.2]])


def test_the_mode_switches_to_negotiation_within_the_lookahead_and_back_once_past():
    mode = NegotiationMode(lookahead=1.0, corridor=0.3, release=0.05)
    assert mode.update(0.0, (), (0.0, 0.0), FEET, 0.0) == 0 and mode.mode == WALKING
    far = Obstacle(np.array([2.0, 0.0]), 0.0, 0.1, 1.0, 0.1)  # 1.95 m ahead: beyond the lookahead
    assert mode.update(0.1, (far,), (0.0, 0.0), FEET, 0.0) == 0 and mode.active == ()
    aside = Obstacle(np.array([0.5, 1.0]), 0.0, 0.1, 0.5, 0.1)  # 0.75 m to the left: outside the corridor
    assert mode.update(0.2, (aside,), (0.0, 0.0), FEET, 0.0) == 0
    assert mode.update(0.3, (far, BOX), (0.0, 0.0), FEET, 0.0) == 1
    assert mode.mode == NEGOTIATION and mode.active == (BOX,)
    one_foot_past = np.array([[0.7, 0.2], [0.5, -0.2]])  # the trailing foot still before the release line
    assert mode.update(1.0, (BOX,), (0.6, 0.0), one_foot_past, 0.0) == 0 and mode.mode == NEGOTIATION
    both_past = np.array([[0.7, 0.2], [0.62, -0.2]])
    assert mode.update(1.5, (BOX,), (0.66, 0.0), both_past, 0.0) == -1 and mode.mode == WALKING
    assert mode.switches == [(0.3, NEGOTIATION), (1.5, WALKING)]
    # passed, the box is still avoided by the planner (not counted) until it is a lookahead behind the feet
    assert mode.active == () and mode.avoided == (BOX,)
    far_past = both_past + np.array([1.0, 0.0])  # the rearmost foot 1.07 m beyond the far edge
    assert mode.update(4.0, (BOX,), (1.66, 0.0), far_past, 0.0) == 0 and mode.avoided == ()
    # along the heading: a robot turned away (heading +pi/2) does not negotiate the box ahead in x
    assert NegotiationMode(1.0, 0.3, 0.05).update(0.0, (BOX,), (0.0, 0.0), FEET, np.pi / 2) == 0
    assert NegotiationMode(0.0, 0.3, 0.05).update(0.0, (BOX,), (0.0, 0.0), FEET, 0.0) == 0  # lookahead 0: never
    with pytest.raises(ParameterError, match="measurement obstacles must be sequencer.obstacles.Obstacle"):
        NegotiationMode(1.0, 0.3, 0.05).update(0.0, ("box",), (0.0, 0.0), FEET, 0.0)


def _bolt_stage(**controller):
    robot = load_robot("bolt")
    preset = load_walking_preset("bolt")
    config = dataclasses.replace(preset.controller, **controller)
    from sequencer.dcm_planner import DcmFootstepPlanner

    stage = PlanningStage(robot, DcmFootstepPlanner(preset.planner), config)
    x0 = np.concatenate([robot.q_reference, np.zeros(robot.pinocchio_model.nv)])
    stage.reset(x0, 0.0, VelocityCommand(0.3))
    return robot, stage, x0


def test_the_planning_stage_plans_over_the_obstacles_of_a_negotiation_and_logs_the_mode():
    robot, stage, x0 = _bolt_stage(negotiation_lookahead=1.0, negotiation_speed_max=0.2)
    contact = np.ones(2, dtype=bool)
    box = Obstacle(np.array([0.3, 0.0]), 0.0, 0.05, 0.6, 0.03)
    plan, _, record = stage.update(0.0, x0, contact, obstacles=(box,))
    assert record["negotiation_mode"] == NEGOTIATION and record["negotiation_switch"] == 1.0
    assert record["obstacles_perceived"] == 1.0 and record["obstacles_planned"] == 1.0
    assert record["sequencer_v_x"] <= 0.2  # the negotiation's speed bound
    assert any(step.crossing is not None for step in plan.steps)
    grown = box.grown(stage.planner.params.obstacle_margin - 1e-9)  # a foothold may lie on the margin's line
    assert not np.any(grown.contains(plan.positions))  # Bolt's point feet: the footholds themselves
    assert stage.negotiation.switches == [(0.0, NEGOTIATION)]
    # the plan's crossing swings on the OCP grid: the foot over the box at some nodes, from its lift-off
    schedule = contact_schedule(plan, 0.0, 0.01, 250, rounding="nearest")
    crossings = crossing_schedule(plan, schedule)
    assert crossings is not None and crossings.obstacles == (box,)
    over = crossings.index >= 0
    assert over.any() and not np.any(over & schedule.in_contact)
    assert np.all(np.isfinite(crossings.liftoff_xy[over])) and np.all(np.isnan(crossings.liftoff_xy[~over]))


def test_an_obstacle_too_deep_to_cross_stops_the_walk_before_it():
    """A box deeper than one crossing step reaches (the planner's ``can_cross``) bounds the forward command by 0 while
    negotiating (logged ``negotiation_blocked``): the robot steps in place before it; a crossable one keeps the
    negotiation's speed."""
    robot, stage, x0 = _bolt_stage(negotiation_lookahead=1.0, negotiation_speed_max=0.2)
    contact = np.ones(2, dtype=bool)
    deep = Obstacle(np.array([1.0, 0.0]), 0.0, 1.2, 0.6, 0.05)  # 1.2 m deep, near edge 0.4 m ahead
    assert not stage.planner.can_cross(deep, np.zeros(2), 0.0) and stage.planner.can_cross(
        Obstacle(np.array([0.3, 0.0]), 0.0, 0.05, 0.6, 0.03), np.zeros(2), 0.0)
    plan, _, record = stage.update(0.0, x0, contact, obstacles=(deep,))
    assert record["negotiation_mode"] == NEGOTIATION and record["negotiation_blocked"] == 1.0
    assert record["sequencer_v_x"] == 0.0
    grown = deep.grown(stage.planner.params.obstacle_margin - 1e-9)
    assert not np.any(grown.contains(plan.positions)) and all(step.crossing is None for step in plan.steps)
    _, other, _ = _bolt_stage(negotiation_lookahead=1.0, negotiation_speed_max=0.2)
    _, _, record = other.update(0.0, x0, contact, obstacles=(Obstacle(np.array([0.3, 0.0]), 0.0, 0.05, 0.6, 0.03),))
    assert record["negotiation_blocked"] == 0.0 and record["sequencer_v_x"] == pytest.approx(0.2)


def test_the_negotiation_decelerates_to_its_bound_at_the_set_rate():
    """With ``negotiation_deceleration`` a > 0 the forward command falls to the negotiation's bound (0 before a box too
    deep to cross) by at most a dt per update from the last planned one, and holds once there; 0 stops at once."""
    robot, stage, x0 = _bolt_stage(negotiation_lookahead=1.0, negotiation_speed_max=0.2, negotiation_deceleration=0.5)
    contact = np.ones(2, dtype=bool)
    deep = Obstacle(np.array([1.0, 0.0]), 0.0, 1.2, 0.6, 0.05)
    _, _, record = stage.update(0.0, x0, contact)  # walking: the user's 0.3 m/s
    assert record["negotiation_mode"] == WALKING and record["sequencer_v_x"] == pytest.approx(0.3)
    forwards = []
    for t in (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8):
        _, _, record = stage.update(t, x0, contact, obstacles=(deep,))
        assert record["negotiation_blocked"] == 1.0
        forwards.append(record["sequencer_v_x"])
    assert forwards == pytest.approx([0.25, 0.2, 0.15, 0.1, 0.05, 0.0, 0.0, 0.0], abs=1e-12)
    _, at_once, _ = _bolt_stage(negotiation_lookahead=1.0, negotiation_speed_max=0.2)
    at_once.update(0.0, x0, contact)
    assert at_once.update(0.1, x0, contact, obstacles=(deep,))[2]["sequencer_v_x"] == 0.0
    with pytest.raises(ParameterError, match=r"negotiation_deceleration=-1.0 m/s\^2 must be finite and >= 0"):
        _bolt_stage(negotiation_deceleration=-1.0)


def test_a_passed_obstacle_bounds_a_step_back_onto_it():
    """After the crossing (both feet beyond the release line: walking again) a step back, commanded here by a
    backwards velocity, lands beyond the box's far side, not on it (the H1 was planned a step back onto the box it
    had just crossed with its DCM behind its feet, and fell)."""
    robot, stage, x0 = _bolt_stage(negotiation_lookahead=1.0)
    _, plain, _ = _bolt_stage(negotiation_lookahead=1.0)
    contact = np.ones(2, dtype=bool)
    box = Obstacle(np.array([-0.15, 0.0]), 0.0, 0.05, 0.6, 0.03)  # far edge 0.125 m behind both feet
    for planning in (stage, plain):
        planning.set_command(VelocityCommand(-0.3))
    plan, _, record = stage.update(0.0, x0, contact, obstacles=(box,))
    assert record["negotiation_mode"] == WALKING and record["obstacles_planned"] == 1.0
    unbounded, _, _ = plain.update(0.0, x0, contact, obstacles=())
    grown = box.grown(stage.planner.params.obstacle_margin - 1e-9)
    assert np.any(grown.contains(unbounded.positions))  # without it the backward steps land on the box
    assert not np.any(grown.contains(plan.positions))


def test_the_ocp_reference_of_a_crossing_carries_the_plans_com_path():
    """The OCP reference of a plan with crossing swings in the horizon holds the plan's CoM prediction at every node
    (the OCP's ``com_path`` references); without a crossing it holds none."""
    from wbmpc.walking.reference import OcpReferenceStage

    robot, stage, x0 = _bolt_stage(negotiation_lookahead=1.0, negotiation_speed_max=0.2)
    contact = np.ones(2, dtype=bool)
    sampler = OcpReferenceStage(("left", "right"), 250, 0.01, False, 2, 0.005)
    box = Obstacle(np.array([0.3, 0.0]), 0.0, 0.05, 0.6, 0.03)
    plan, measured, _ = stage.update(0.0, x0, contact, obstacles=(box,))
    reference = sampler.sample(plan, 0.0, measured.com[:2], contact)
    assert reference.crossings is not None and reference.com_path.shape == (251, 3)
    np.testing.assert_allclose(reference.com_path, plan.com_reference(0.01 * np.arange(251), measured.com[:2]))
    np.testing.assert_allclose(reference.com_path[-1], reference.com_terminal)
    _, plain, x0 = _bolt_stage()
    plan, measured, _ = plain.update(0.0, x0, contact)
    assert sampler.sample(plan, 0.0, measured.com[:2], contact).com_path is None


def test_without_obstacles_the_stage_plans_as_without_perception():
    _, stage, x0 = _bolt_stage(negotiation_lookahead=1.0)
    _, plain, x0 = _bolt_stage()
    contact = np.ones(2, dtype=bool)
    for t in (0.0, 0.01, 0.02):
        a, _, record = stage.update(t, x0, contact, obstacles=())
        b, _, _ = plain.update(t, x0, contact)
        assert record["negotiation_mode"] == WALKING and crossing_schedule(a, contact_schedule(a, t, 0.01, 50)) is None
        assert np.array_equal(a.positions, b.positions) and np.array_equal(a.touchdown_times, b.touchdown_times)


def test_a_negotiation_with_a_planner_that_cannot_avoid_obstacles_is_refused():
    from sequencer.alip import AlipParams
    from sequencer.alip.planner import AlipFootstepPlanner

    robot = load_robot("bolt")
    preset = load_walking_preset("bolt")
    config = dataclasses.replace(preset.controller, negotiation_lookahead=1.0)
    planner = AlipFootstepPlanner(AlipParams.preset("g1"))
    with pytest.raises(ParameterError, match="negotiation_lookahead=1.0 m needs a footstep planner that avoids"):
        PlanningStage(robot, planner, config)
    with pytest.raises(ParameterError, match=r"negotiation_lookahead=-1.0 m must be in \[0, 10.0\] m"):
        dataclasses.replace(preset.controller, negotiation_lookahead=-1.0)


def test_every_swing_lifts_off_from_its_previous_foothold_and_crossings_agree():
    """:func:`swing_liftoffs`: each swing on the OCP grid lifts off from its foot's previous foothold in the plan (the
    plan's stance position for the stance foot's first step, the given lift-off for the swinging foot's), NaN in
    contact; over the crossing swings it is the lift-off the planner gave the crossing."""
    robot, stage, x0 = _bolt_stage(negotiation_lookahead=1.0, negotiation_speed_max=0.2)
    box = Obstacle(np.array([0.3, 0.0]), 0.0, 0.05, 0.6, 0.03)
    plan, _, _ = stage.update(0.0, x0, np.ones(2, dtype=bool), obstacles=(box,))
    schedule = contact_schedule(plan, 0.0, 0.01, 250, rounding="nearest")
    liftoff = swing_liftoffs(plan, schedule, stage.swing_liftoff)
    swinging = ~schedule.in_contact
    assert liftoff.shape == schedule.touchdown_position.shape and np.all(np.isnan(liftoff[~swinging]))
    assert np.all(np.isfinite(liftoff[swinging]))
    for j, foot in enumerate(schedule.feet):
        footholds = [plan.stance_position if foot == plan.stance_foot else stage.swing_liftoff]
        footholds += [step.position for step in plan.steps if step.foot == foot]
        for k in np.flatnonzero(swinging[:, j]):
            i = next(i for i, p in enumerate(footholds[1:]) if np.allclose(p, schedule.touchdown_position[k, j]))
            assert liftoff[k, j] == pytest.approx(footholds[i]), (foot, k)
    crossings = crossing_schedule(plan, schedule)
    over = crossings.index >= 0
    assert over.any() and np.allclose(liftoff[over], crossings.liftoff_xy[over], rtol=0.0, atol=1e-12)
    unknown = swing_liftoffs(plan, schedule, None)  # the swinging foot's lift-off not known: its first swing NaN
    first = next(step for step in plan.steps).foot
    assert first != plan.stance_foot
    j = schedule.feet.index(first)
    k = int(np.flatnonzero(swinging[:, j])[0])
    assert np.all(np.isnan(unknown[k, j])) and np.array_equal(np.isnan(unknown[:, 1 - j]), np.isnan(liftoff[:, 1 - j]))
