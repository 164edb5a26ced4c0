"""Changing the sequencer's parameters during a run (fixed step timing after a common start)."""

import dataclasses

import numpy as np
import pytest

from robots import load_robot
from sim.campaigns.trial import resolve_arguments
from wbmpc.errors import ParameterError
from wbmpc.walking.controller import WalkingController
from wbmpc.walking.measurement import Measurement
from wbmpc.walking.preset import load_walking_preset


def default_sequencer_params():
    """The walking controller's planner parameters for Bolt (its walking preset's)."""
    return load_walking_preset("bolt").planner


def fixed_timing(params):
    return dataclasses.replace(params, t_min=params.t_nom, t_max=params.t_nom, name=f"{params.name}+fixed_timing")


def test_the_controller_switches_parameters_at_the_first_touchdown_after_the_time_and_keeps_the_velocity():
    robot = load_robot("bolt")
    x0 = np.concatenate([robot.q_reference, robot.v_reference])
    adaptive = default_sequencer_params()
    preset = load_walking_preset("bolt", {"n_nodes": 10, "max_iterations": 1,
                                          "sequencer_params_from": (0.02, fixed_timing(adaptive))})
    controller = WalkingController(preset)
    controller.set_velocity_command((0.2, 0.0, 0.0))
    controller.reset(robot, x0, 0.0)
    standing = Measurement(0.0, x0, np.array([True, True]))  # both feet on the ground throughout
    for t in (0.0, 0.01, 0.02, 0.03):  # past t_switch, but in the middle of the first step
        controller.replan(t, dataclasses.replace(standing, t=t))
        params = controller.planning.planner.params
        assert params.t_min < params.t_max
    v_x_before = controller.planning.planned_command.v_x
    # the swing foot, on the ground, counts as landed past half of its swing: the stance switches there
    t = 0.03
    while controller.stance.n_switches == 0:
        t = round(t + 0.01, 2)
        assert t < 1.0
        controller.replan(t, dataclasses.replace(standing, t=t))
    params = controller.planning.planner.params
    assert params.t_min == params.t_max == adaptive.t_nom
    # the command (and the speed integral's correction) carry over
    assert controller.planning.planned_command.v_x == pytest.approx(v_x_before, abs=0.02)
    assert controller.plan.steps[0].touchdown_time - controller.plan.t0 == pytest.approx(adaptive.t_nom)


def test_a_switch_to_another_com_height_is_refused_before_the_run():
    robot = load_robot("bolt")
    other = dataclasses.replace(default_sequencer_params(), z_c=0.25)
    controller = WalkingController(load_walking_preset("bolt", {"n_nodes": 10, "sequencer_params_from": (1.0, other)}))
    message = r"sequencer_params_from: the later planner's omega=6.26418 1/s must equal the first one's 5.76665 1/s"
    with pytest.raises(ParameterError, match=message):
        controller.reset(robot, np.concatenate([robot.q_reference, robot.v_reference]), 0.0)


def test_campaign_step_timing_from_starts_adaptive_with_the_controller_defaults():
    arguments = resolve_arguments("push", "walking", 6.0, {"force_y": 4.0, "phase": 0.5, "push_after": 3.0,
                                                           "step_timing": "fixed", "step_timing_from": 2.0})
    start, (t_switch, later) = arguments["sequencer_params"], arguments["sequencer_params_from"]
    assert start == default_sequencer_params() and start.w_right_max == 0.30
    assert t_switch == 2.0 and later == fixed_timing(start)
    # without step_timing_from the variant applies from the start, over the same defaults
    arguments = resolve_arguments("push", "walking", 6.0, {"force_y": 4.0, "phase": 0.5, "push_after": 3.0,
                                                           "step_timing": "fixed"})
    assert arguments["sequencer_params"] == fixed_timing(default_sequencer_params())
    assert "sequencer_params_from" not in arguments
    with pytest.raises(ParameterError, match="step_timing_from needs a step_timing"):
        resolve_arguments("push", "walking", 6.0, {"force_y": 4.0, "phase": 0.5, "step_timing_from": 2.0})


def test_push_map_timing_study_switches_the_compared_timing_after_the_start():
    from sim.campaigns.spec import builtin_campaign

    spec = builtin_campaign("push-map", compare_timing="fixed", steps_x=1, steps_y=1, phases=(0.0,))
    assert spec.variants["fixed"] == {"step_timing": "fixed", "step_timing_from": 2.0}
    from_start = builtin_campaign("push-map", compare_timing="fixed", timing_from=0.0, steps_x=1, steps_y=1)
    assert from_start.variants["fixed"] == {"step_timing": "fixed"}
    with pytest.raises(ParameterError, match=r"timing_from=5.0 s must be in \[0, push_after=3.0 s\)"):
        builtin_campaign("push-map", compare_timing="fixed", timing_from=5.0)
