"""The walking controller's footstep planner, chosen by the preset: the DCM step QP or the ALIP NMPC, both used
through the same FootstepPlanner interface by the planning stage (start from standing, measured angular
momentum, a failed solve keeps the last plan). No simulation: the G1's Pinocchio model at its standing pose."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from robots import load_robot
from sequencer import FootstepPlanner, contact_schedule
from sequencer.alip import AlipFootstepPlanner, AlipParams
from sequencer.alip.nlp import AlipSolverError
from sequencer.dcm_planner import DcmFootstepPlanner
from wbmpc.errors import ParameterError
from wbmpc.walking import WalkingController, load_walking_preset
from wbmpc.walking.alip_state import contact_angular_momentum
from wbmpc.walking.planning import PlanningStage
from wbmpc.walking.preset import FootstepPlannerChoice

BOTH_FEET = np.array([True, True])


@pytest.fixture(scope="module")
def g1():
    robot = load_robot("g1")
    return robot, np.concatenate([robot.q_reference, np.zeros(robot.pinocchio_model.nv)])


def test_the_preset_chooses_the_planner_and_the_alip_gets_the_robots_double_support():
    assert load_walking_preset("bolt").footstep_planner == FootstepPlannerChoice()  # no section: the DCM step QP
    dcm = load_walking_preset("g1", {"footstep_planner.kind": "dcm"})
    assert dcm.planner_params is dcm.planner
    assert isinstance(WalkingController(dcm).planner, DcmFootstepPlanner)
    alip = load_walking_preset("g1")  # the G1 preset's [footstep_planner] names the ALIP NMPC
    assert alip.footstep_planner.kind == "alip"
    controller = WalkingController(alip)
    assert isinstance(controller.planner, AlipFootstepPlanner) and isinstance(controller.planner, FootstepPlanner)
    # the ALIP preset's model and bounds, the contact schedule's double support of the robot's preset and the
    # walking preset's own [footstep_planner.alip] fields (the G1's wider catch step) over them
    preset_params = AlipParams.preset("g1")
    assert alip.footstep_planner.alip == dataclasses.replace(preset_params, double_support=dcm.planner.double_support,
                                                             width_max=0.5)
    assert preset_params.width_max == 0.40 and controller.planner.params.width_max == 0.5
    assert preset_params.double_support == 0.0 and controller.planner.double_support == 0.1
    assert controller.omega == pytest.approx(preset_params.omega) == alip.omega != dcm.omega
    assert alip.step_period == preset_params.t_des and dcm.step_period == dcm.planner.t_nom
    # fields over the preset's, the solver
    tuned = load_walking_preset("g1", {"footstep_planner.kind": "alip", "footstep_planner.alip.double_support": 0.05,
                                       "footstep_planner.alip.t_des": 0.45, "footstep_planner.alip_solver": "ipopt"})
    assert tuned.footstep_planner.alip.double_support == 0.05 and tuned.step_period == 0.45
    assert WalkingController(tuned).planner.solver.name == "ipopt"


@pytest.mark.parametrize("overrides, message", [
    ({"footstep_planner.kind": "lipm"}, r"footstep_planner.kind='lipm' must be one of \('dcm', 'alip'\)"),
    ({"footstep_planner.kind": "alip", "footstep_planner.alip_preset": "atlas"},
     r"footstep_planner.alip_preset='atlas': no ALIP preset of that name \(available: \['g1', 'h1'\]\)"),
    ({"footstep_planner.kind": "alip", "footstep_planner.alip.t_min": 0.05},
     r"\[footstep_planner.alip\] over the ALIP preset 'g1': double_support=0.1 s must be in \[0, t_min=0.05 s\)"),
    ({"footstep_planner.kind": "alip", "footstep_planner.alip.steps_k": 3}, r"steps_k"),
    ({"footstep_planner.angular_momentum": "guess"}, r"angular_momentum='guess' must be one of"),
    ({"footstep_planner.solver": "sqp"}, r"\[footstep_planner\] has no field \['solver'\]"),
])
def test_bad_planner_choices_are_one_line_parameter_errors(overrides, message):
    with pytest.raises(ParameterError, match=message) as info:
        load_walking_preset("g1", overrides)
    assert "\n" not in str(info.value)


def test_a_robot_without_an_alip_preset_is_refused_with_the_available_ones():
    with pytest.raises(ParameterError, match=r"alip_preset='bolt': no ALIP preset"):
        load_walking_preset("bolt", {"footstep_planner.kind": "alip"})


@pytest.mark.parametrize("kind", ["dcm", "alip"])
def test_the_planning_stage_starts_either_planner_from_standing(g1, kind):
    robot, x0 = g1
    preset = load_walking_preset("g1", {"footstep_planner.kind": kind})
    controller = WalkingController(preset)
    planner = controller.planner
    stage = PlanningStage(robot, planner, preset.controller, measure_angular_momentum=kind == "alip")
    stage.reset(x0, 0.0, controller.command)
    t_start = preset.controller.start_double_support
    assert stage.stance.state.t_start == t_start > 0
    plan, measured, record = stage.update(0.0, x0, BOTH_FEET)
    # planned from the stance start, the feet down until then, the first step one nominal period later
    assert plan.t0 == plan.t_stance_start == t_start
    assert plan.steps[0].foot == "right" and plan.steps[0].touchdown_time == pytest.approx(t_start + preset.step_period)
    schedule = contact_schedule(plan, t0=0.0, dt=preset.controller.node_dt, n_nodes=preset.controller.n_nodes,
                                rounding="nearest")
    assert schedule.in_contact[schedule.times < t_start - 1e-9].all()
    assert not schedule.in_contact.all()  # and then a swing
    assert record["sequencer_ok"] == 1.0
    if kind == "alip":  # the exact angular momentum about the stance contact, handed to the planner and logged
        feet = stage.feet_position(x0[:robot.pinocchio_model.nq])
        exact = contact_angular_momentum(stage.model, stage.data, x0[:robot.pinocchio_model.nq],
                                         x0[robot.pinocchio_model.nq:], feet[0])
        assert np.allclose(measured.angular_momentum, exact.angular_momentum_contact)
        assert record["angular_momentum_contact_y"] == pytest.approx(exact.angular_momentum_contact[1])
        assert np.array_equal(planner.last_instance.x0, planner.stance_start_state("left", controller.command))
    else:
        assert measured.angular_momentum is None and "angular_momentum_contact_y" not in record


def test_a_failed_alip_solve_keeps_the_last_plan_and_is_logged(g1, monkeypatch):
    robot, x0 = g1
    preset = load_walking_preset("g1", {"footstep_planner.kind": "alip"})
    planner = WalkingController(preset).planner
    stage = PlanningStage(robot, planner, preset.controller, measure_angular_momentum=True)
    stage.reset(x0, 0.0, stage.command)
    first, _, record = stage.update(0.0, x0, BOTH_FEET)
    assert record["sequencer_ok"] == 1.0

    def fail(instance, warm=None):
        raise AlipSolverError("ALIP NMPC failed: injected", instance, "Infeasible_Problem_Detected", "sqp")

    monkeypatch.setattr(planner.solver, "solve", fail)
    kept, _, record = stage.update(0.02, x0, BOTH_FEET)
    assert kept is first and record["sequencer_ok"] == 0.0
    assert record["next_touchdown_time"] == first.steps[0].touchdown_time
    # without a previous plan there is nothing to keep: the failure is raised
    fresh = PlanningStage(robot, planner, preset.controller)
    fresh.reset(x0, 0.0, fresh.command)
    with pytest.raises(AlipSolverError, match="injected"):
        fresh.update(0.0, x0, BOTH_FEET)
