"""The walking controller's parts, each alone: the feedback law (eqs. 25-26, the library's gain
sign), the estimators (speed integral, LIPM corrections, stance slide), the touchdown delay, and
the per-robot walking preset."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest
from robot_extras import needs_h1_extra

from robots import load_robot
from sequencer.corrections import LipmCorrections
from sequencer.planner import VelocityCommand
from wbmpc.errors import NoSolutionError, ParameterError
from wbmpc.ocp.mpc import MPCSolution
from wbmpc.ocp.state import StateMultibody
from wbmpc.walking.controller_config import WalkingControllerConfig
from wbmpc.walking.estimators import LipmCorrectionEstimator, StanceSlide, VelocityIntegral
from wbmpc.walking.feedback import FeedbackLaw
from wbmpc.walking.preset import available_walking_presets, load_walking_preset
from wbmpc.walking.stance import delay_to_touchdown

# ---------------------------------------------------------------------------------------- feedback


@pytest.fixture(scope="module")
def known_solution():
    """A synthetic MPC solution (random xs, us, K) at t = 0.5 s and a random measured state."""
    model = load_robot("bolt").pinocchio_model
    rng = np.random.default_rng(0)
    n, nu, ndx = 5, model.nv - 6, 2 * model.nv

    def random_state():
        return np.concatenate([pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq)),
                               rng.normal(size=model.nv)])

    xs = np.array([random_state() for _ in range(n + 1)])
    solution = MPCSolution(True, "max_iter", 1, 0.0, 0.0, 0.5, xs, rng.normal(size=(n, nu)),
                           rng.normal(size=(n, nu, ndx)))
    return StateMultibody(model), solution, random_state()


def _law(state, **options):
    settings = dict(node_dt=0.01, delay_nodes=1, interpolate=False, feedback=True, computation_delay=0.0)
    settings.update(options)
    return FeedbackLaw(state, **settings)


def _riccati(model, solution, k, x):
    nq = model.nq
    dx = np.concatenate([pin.difference(model, solution.xs[k][:nq], x[:nq]), x[nq:] - solution.xs[k][nq:]])
    return solution.us[k] + solution.K[k] @ dx


def test_feedback_law_uses_node_one_by_default_and_the_library_gain_sign(known_solution):
    state, solution, x = known_solution
    law = _law(state)
    law.hand_over(0.5, solution)
    # 3 ms after the solution: node 1 (the paper's delay model)
    np.testing.assert_allclose(law.control(0.503, x), _riccati(state.pinocchio, solution, 1, x), rtol=1e-12, atol=1e-12)
    # 12 ms after (a failed update in between): node 2 of the same solution
    np.testing.assert_allclose(law.control(0.512, x), _riccati(state.pinocchio, solution, 2, x), rtol=1e-12, atol=1e-12)


def test_feedback_options_no_delay_no_feedback_interpolation(known_solution):
    state, solution, x = known_solution
    for options, expected in (
        (dict(delay_nodes=0), _riccati(state.pinocchio, solution, 0, x)),
        (dict(feedback=False), solution.us[1]),
        (dict(feedback=False, interpolate=True), 0.7 * solution.us[1] + 0.3 * solution.us[2]),  # 30 % to node 2
    ):
        law = _law(state, **options)
        law.hand_over(0.5, solution)
        np.testing.assert_allclose(law.control(0.503, x), expected, rtol=1e-9, atol=1e-12)


def test_computation_delay_applies_a_new_solution_only_after_the_latency(known_solution):
    state, solution, x = known_solution
    law = _law(state, delay_nodes=0, computation_delay=0.01, feedback=False)
    law.hand_over(0.5, solution)  # the first one applies at once: there is nothing else to follow
    newer = dataclasses.replace(solution, t=0.51, us=solution.us + 100.0)
    law.hand_over(0.51, newer)
    # at 0.515 s the solution of 0.51 s is still being "computed": node 1 of the 0.5 s one
    np.testing.assert_array_equal(law.control(0.515, x), solution.us[1])
    # from 0.52 s on the newer one applies, at its node 1 (10 ms after its own t)
    np.testing.assert_array_equal(law.control(0.52, x), newer.us[1])


def test_feedback_law_without_a_solution_says_so(known_solution):
    state, _, x = known_solution
    with pytest.raises(NoSolutionError, match="no MPC solution yet"):
        _law(state).control(0.0, x)


# ---------------------------------------------------------------------------------------- estimators


def test_speed_integral_acts_on_the_forward_speed_with_anti_windup():
    integral = VelocityIntegral(gain=1.0, correction_max=0.2, filter_time=1.0, period=0.01)
    assert integral.correction == 0.0
    for _ in range(1000):  # 10 s standing still while 0.3 m/s forward is asked, drifting sideways
        integral.update(0.3, np.array([0.0, 0.5]))
    assert integral.correction == pytest.approx(0.2)  # the bound
    for _ in range(150):  # now too fast: the clamped integral unwinds once the filtered speed passes 0.3
        integral.update(0.3, np.array([0.6, 0.0]))
    assert integral.correction < 0.2
    off = VelocityIntegral(gain=0.0, correction_max=0.2, filter_time=1.0, period=0.01)
    off.update(0.3, np.array([0.0, 0.0]))
    assert off.correction == 0.0
    assert integral.correction_xy[1] == 0.0  # no lateral gain: the sideways drift above is not corrected


def test_speed_integral_does_not_wind_up_on_a_ramp_the_robot_follows():
    integral = VelocityIntegral(gain=0.5, correction_max=0.3, filter_time=1.0, period=0.02, lateral_gain=0.5)
    for k in range(100):  # a 2 s ramp to (0.3, 0.1) m/s, followed exactly: the filter's lag is no error
        command = min(1.0, k / 100.0) * np.array([0.3, 0.1])
        integral.update(command[0], command, commanded_v_y=command[1])
    assert np.allclose(integral.correction_xy, 0.0, atol=1e-12)


def test_lateral_speed_integral_corrects_the_lateral_speed_only_when_its_gain_is_on():
    integral = VelocityIntegral(gain=0.0, correction_max=0.2, filter_time=0.5, period=0.02, lateral_gain=0.5)
    for _ in range(500):  # 10 s at 0.18 m/s sideways for 0.15 asked: the correction goes negative
        integral.update(0.0, np.array([0.0, 0.18]), commanded_v_y=0.15)
    dx, dy = integral.correction_xy
    assert dx == 0.0
    # k ∫ (v̄* - v̄) dt, command and speed through the same filter: k (0.15 - 0.18) (t - τ (1 - exp(-t / τ)))
    assert dy == pytest.approx(0.5 * -0.03 * (10.0 - 0.5), rel=0.05)
    for _ in range(2000):  # winding up: held at the bound
        integral.update(0.0, np.array([0.0, 0.5]), commanded_v_y=0.15)
    assert integral.correction_xy[1] == pytest.approx(-0.2)


def _estimator(corrections, gain=0.5):
    config = WalkingControllerConfig()
    return LipmCorrectionEstimator(corrections, omega=np.sqrt(9.81 / 0.295), gain=gain,
                                   stance_drift_max=config.stance_drift_max, offset_bias_max=config.dcm_offset_bias_max,
                                   max_error=config.lipm_correction_max_error, max_slide=config.lipm_correction_max_slide)


def test_lipm_corrections_are_identified_from_undisturbed_steps_only():
    """Stance drift = DCM gained over the LIPM over the stance [m]; offset bias = measured - planned b_T."""
    corrections = LipmCorrections()
    estimator = _estimator(corrections)
    omega, duration, length, kappa, epsilon = estimator.omega, 0.3, 0.1, 0.2, 0.003
    stance, landing = np.array([1.0, 0.05]), np.array([1.0 + length, -0.05])
    planned = np.array([0.017, 0.01])  # the offset the plan aimed at for this touchdown
    # the stance started from b0 and ended epsilon ahead of the plan after the LIPM growth + kappa L
    b0 = ((1.0 - kappa) * length + planned[0] + epsilon) / np.exp(omega * duration)
    # the first stance, started as planned: nothing to identify yet
    assert not estimator.touchdown(0.0, stance + np.array([b0, 0.0]), stance, 0.0, np.array([b0, 0.0]), 0.0)
    measured = landing + planned + np.array([epsilon, 0.0])
    assert measured[0] - stance[0] == pytest.approx(b0 * np.exp(omega * duration) + kappa * length)
    assert estimator.touchdown(duration, measured, landing, 0.0, planned, 0.0)
    assert corrections.stance_drift == pytest.approx(0.5 * kappa * length, rel=1e-9)
    assert corrections.swing_drift == 0.0  # no longer identified (set by hand only)
    assert corrections.dcm_offset_bias == pytest.approx(0.5 * epsilon, rel=1e-9)
    before = (corrections.stance_drift, corrections.dcm_offset_bias)
    # a pushed step (DCM 3 cm off the plan at touchdown) changes nothing, nor does the next one
    assert not estimator.touchdown(0.6, landing + [0.1, 0.1] + [0.05, -0.01], landing + [0.1, 0.1], 0.0,
                                   np.array([0.02, -0.01]), 0.0)
    assert not estimator.touchdown(0.9, landing + [0.2, 0.0] + [0.02, 0.01], landing + [0.2, 0.0], 0.0,
                                   np.array([0.02, 0.01]), 0.0)
    assert (corrections.stance_drift, corrections.dcm_offset_bias) == before
    assert len(estimator.steps) == 1


def test_the_stance_drift_is_identified_stepping_in_place_and_backwards():
    """A drift that does not vanish with the step: identified from zero-length and backward steps."""
    for length, drift in ((0.0, 0.005), (-0.06, -0.008)):
        corrections = LipmCorrections()
        estimator = _estimator(corrections)
        omega, duration = estimator.omega, 0.3
        stance, landing = np.array([1.0, 0.05]), np.array([1.0 + length, -0.05])
        planned = np.array([0.004, 0.015])
        b0 = (landing[0] + planned[0] - stance[0] - drift) / np.exp(omega * duration)
        estimator.touchdown(0.0, stance + np.array([b0, 0.0]), stance, 0.0, np.array([b0, 0.0]), 0.0)
        assert estimator.touchdown(duration, landing + planned, landing, 0.0, planned, 0.0)
        assert corrections.stance_drift == pytest.approx(0.5 * drift, rel=1e-9)


def test_a_step_whose_stance_foot_slid_is_not_used_for_the_lipm_corrections():
    """The swing drift is measured against the touchdown point: a slid stance foot is excluded."""
    max_slide = WalkingControllerConfig().lipm_correction_max_slide
    stance, landing = np.array([1.0, 0.05]), np.array([1.1, -0.05])
    planned = np.array([0.017, 0.01])
    measured = landing + np.array([0.018, 0.01])  # 1 mm from the plan: an undisturbed touchdown otherwise
    for slide, used in ((2.0 * max_slide, False), (0.5 * max_slide, True)):
        corrections = LipmCorrections()
        estimator = _estimator(corrections)
        estimator.touchdown(0.0, stance + np.array([0.018, 0.01]), stance, 0.0, planned + [0.001, 0.0], 0.0)
        assert estimator.touchdown(0.3, measured, landing, 0.0, planned, ended_slide=slide) == used
        assert len(estimator.steps) == int(used)


def test_lipm_corrections_are_measured_along_the_heading():
    """The same step walked along a heading rotated by 90 deg gives the same corrections."""
    results = []
    for yaw in (0.0, np.pi / 2):
        c, s = np.cos(yaw), np.sin(yaw)
        rotate = lambda v, c=c, s=s: np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])  # noqa: E731
        corrections = LipmCorrections()
        estimator = _estimator(corrections)
        stance, landing, planned = rotate([1.0, 0.05]), rotate([1.1, -0.05]), rotate([0.017, 0.01])
        estimator.touchdown(0.0, stance + rotate([0.02, 0.0]), stance, yaw, rotate([0.02, 0.0]), 0.0)
        estimator.touchdown(0.3, landing + planned + rotate([0.002, 0.0]), landing, yaw, planned, 0.0)
        results.append((corrections.stance_drift, corrections.dcm_offset_bias))
    np.testing.assert_allclose(results[0], results[1], atol=1e-12)
    assert results[0][0] > 0.0


def test_the_planner_plans_from_a_sliding_stance_foot():
    slide = StanceSlide(follow=0.02)
    touchdown = np.array([0.1, 0.05])
    slide.reset(touchdown)

    def at(offset, in_contact=True):
        foot = touchdown + offset
        slide.follow_if_sliding(slide.measure(touchdown, foot), foot, in_contact)

    at([0.005, 0.01])  # rolling: the touchdown point is kept
    np.testing.assert_array_equal(slide.plan_position, touchdown)
    at([0.01, 0.05])  # a slide: the planner plans from the measured foot
    np.testing.assert_allclose(slide.plan_position, touchdown + [0.01, 0.05])
    at([0.01, 0.08], in_contact=False)  # bouncing off the ground: kept
    np.testing.assert_allclose(slide.plan_position, touchdown + [0.01, 0.05])
    assert slide.slide == pytest.approx(np.hypot(0.01, 0.08))  # the largest slide of this stance
    slide.reset(np.array([0.2, -0.1]))  # the next stance
    assert slide.slide == 0.0
    np.testing.assert_array_equal(slide.plan_position, [0.2, -0.1])
    never = StanceSlide(follow=None)
    never.reset(touchdown)
    never.follow_if_sliding(never.measure(touchdown, touchdown + [0.01, 0.05]), touchdown + [0.01, 0.05], True)
    np.testing.assert_array_equal(never.plan_position, touchdown)
    with pytest.raises(ParameterError, match=r"stance_slide_follow=-0.01 m must be None or > 0"):
        WalkingControllerConfig(stance_slide_follow=-0.01)


# ---------------------------------------------------------------------------------------- touchdown


def test_a_due_but_unmeasured_touchdown_is_delayed_by_the_wait_nodes():
    from sequencer import FootstepSequencer

    plan = FootstepSequencer(load_walking_preset("bolt").planner).plan(
        t=0.0, stance_foot="left", stance_position=[0.0, 0.05], dcm_measured=[0.0, 0.0], t_stance_start=0.0
    )
    first = plan.steps[0].touchdown_time
    t = first - 0.005  # touchdown due in 5 ms, the foot still in the air
    delayed, delay = delay_to_touchdown(plan, t, False, 0.01, wait_nodes=2)
    assert delay == pytest.approx(t + 2 * 0.01 - first)
    np.testing.assert_allclose(delayed.touchdown_times, plan.touchdown_times + delay)
    np.testing.assert_array_equal(delayed.positions, plan.positions)
    same, no_delay = delay_to_touchdown(plan, t, True, 0.01, wait_nodes=2)  # foot already on the ground
    assert same is plan and no_delay == 0.0


def test_a_due_swing_foot_is_aimed_below_the_ground():
    """Waiting for a touchdown: the waiting nodes' height reference stays on the ground, and the
    OCP reference carries the depth the touchdown term aims the foot at."""
    from sequencer import FootstepSequencer
    from wbmpc.walking.reference import OcpReferenceStage

    plan = FootstepSequencer(load_walking_preset("bolt").planner).plan(
        t=0.0, stance_foot="left", stance_position=[0.0, 0.05], dcm_measured=[0.0, 0.0], t_stance_start=0.0
    )
    step = plan.steps[0]
    stage = OcpReferenceStage(("left", "right"), 10, 0.01, wait_for_contact=True, wait_nodes=2, wait_depth=0.005)
    in_air = np.array([True, False])  # the right foot swings
    reference = stage.sample(plan, step.touchdown_time, np.zeros(2), in_air)  # due now, still in the air
    assert reference.touchdown_wait > 0.0 and reference.touchdown_depth == 0.005
    j = reference.schedule.feet.index(step.foot)
    waiting = ~reference.schedule.in_contact[:, j] & (reference.schedule.times < step.touchdown_time + 0.02 - 1e-9)
    assert waiting[0] and np.all(reference.schedule.swing_phase[waiting, j] == 1.0)
    on_time = stage.sample(plan, step.touchdown_time - 0.1, np.zeros(2), in_air)  # not due yet: nothing changes
    assert on_time.touchdown_wait == 0.0 and on_time.touchdown_depth == 0.0


# ---------------------------------------------------------------------------------------- presets


# controller fields that are run options, not tuning (a preset may leave them to their defaults)
RUN_OPTIONS = {"mpc_prepare", "mpc_time_budget", "delay_nodes", "computation_delay", "interpolate", "feedback",
               "mpc_failure_times", "sequencer_params_from"}
LIPM_CORRECTIONS = {"swing_drift", "dcm_offset_bias", "stance_drift"}  # initial values, identified online
# obstacle negotiation (sequencer.footholds, the OCP's clearance terms, wbmpc.walking.negotiation): tuned for the
# H1 only; Bolt's preset keeps the defaults, the G1's scales the H1's (checked by
# test_g1_obstacle_settings_keep_its_walking_and_load_for_its_obstacle_runs, not field by field: a field added for the
# H1 need not be scaled for the G1 at once)
OBSTACLE_FIELDS = {
    "planner": {"obstacle_margin", "obstacle_approach_margin", "obstacle_step_length_max",
                "obstacle_step_duration_min", "obstacle_step_duration_max", "obstacle_swing_length_max",
                "obstacle_offset_tolerance", "obstacle_double_support", "obstacle_trailing_double_support",
                "obstacle_resume_double_support",
                "obstacle_aim_duration", "obstacle_approach_distance", "obstacle_crossing_drift",
                "obstacle_crossing_cop", "obstacle_passed_cop", "obstacle_crossing_offset", "obstacle_lateral_aim_duration",
                "obstacle_width_min",
                "obstacle_landing_room", "obstacle_far_margin_reduction", "obstacle_trailing_duration_min",
                "obstacle_trailing_height_max", "sole_front", "sole_rear", "sole_half_width"},
    "ocp": {"obstacle_clearance_weight", "obstacle_sole_points", "obstacle_shank_frames", "obstacle_clearance_margin",
            "obstacle_shank_margin", "obstacle_shank_gating", "obstacle_clearance_legs", "obstacle_footprint_margin",
            "obstacle_apex_margin",
            "obstacle_apex_height_max",
            "obstacle_swing_profile", "obstacle_plateau_transition_min", "obstacle_swing_path_timing",
            "obstacle_swing_path_weight", "obstacle_foothold_weight", "obstacle_clearance_gating",
            "obstacle_profile_transition", "obstacle_com_weight", "obstacle_leg_posture_scale",
            "obstacle_swing_orientation_scale", "obstacle_swing_abduction", "obstacle_swing_roll",
            "obstacle_abduction_height_min"},
    "controller": {"negotiation_lookahead", "negotiation_corridor", "negotiation_release", "negotiation_speed_max",
                   "negotiation_deceleration",
                   "negotiation_max_iterations", "negotiation_swing_path_weight", "crossing_max_iterations",
                   "crossing_iterations_hold"},
}

# the speed schedule (SequencerParams.fast_*, WalkingControllerConfig.fast_max_iterations / fast_speed): off unless a
# preset schedules its gait by speed (the H1's, for 1.0 m/s); the others keep the defaults
SPEED_SCHEDULE_FIELDS = {
    "planner": {"fast_speed_start", "fast_speed_full", "fast_t_nom", "fast_t_min", "fast_double_support", "fast_l_max"},
    "controller": {"fast_max_iterations", "fast_swing_path_weight", "fast_speed", "fast_swing_path_speed"},
}


def _assert_preset_states_every_field(robot: str, planner_skip: set[str], obstacles: bool = False,
                                      speed_schedule: bool = False):
    """Every field of the tuned sections is written in ``presets/<robot>.toml`` (nothing left to
    code defaults) but the run options and ``planner_skip`` (and the obstacle fields unless ``obstacles``);
    returns the loaded preset."""
    import tomllib

    from wbmpc.walking.preset import PRESET_DIR

    with (PRESET_DIR / f"{robot}.toml").open("rb") as stream:
        data = tomllib.load(stream)
    skip = {"controller": RUN_OPTIONS, "planner": planner_skip}
    for optional, fields in ((obstacles, OBSTACLE_FIELDS), (speed_schedule, SPEED_SCHEDULE_FIELDS)):
        if not optional:
            skip = {section: skip.get(section, set()) | fields.get(section, set()) for section in {*skip, *fields}}
    preset = load_walking_preset(robot)
    for section in ("planner", "ocp", "controller", "fall", "command"):
        fields = {f.name for f in dataclasses.fields(getattr(preset, section))} - skip.get(section, set())
        assert fields <= set(data[section]), (section, sorted(fields - set(data[section])))
    return preset


def test_bolt_preset_states_every_tuned_number_and_takes_overrides():
    assert "bolt" in available_walking_presets()
    preset = _assert_preset_states_every_field("bolt", LIPM_CORRECTIONS | {"double_support"})
    assert preset.planner.w_right_max == 0.30 and preset.ocp.foothold_weight == 1e5
    changed = load_walking_preset("bolt", {"planner.l_max": 0.25, "ocp.state_weights.joint_position": 2.0,
                                           "n_nodes": 80, "fall.min_base_height": 0.2})
    assert (changed.planner.l_max, changed.ocp.state_weights.joint_position, changed.controller.n_nodes,
            changed.fall.min_base_height) == (0.25, 2.0, 80, 0.2)
    with pytest.raises(ParameterError, match=r"unknown sequencer parameter\(s\) \['l_maxx'\]"):
        load_walking_preset("bolt", {"planner.l_maxx": 0.25})
    with pytest.raises(ParameterError, match=r"\[controller\] has no field \['n_nodez'\]"):
        load_walking_preset("bolt", {"n_nodez": 3})


def test_g1_preset_states_every_tuned_number():
    preset = _assert_preset_states_every_field("g1", LIPM_CORRECTIONS)
    assert preset.ocp.wrench_cone_weight > 0 and preset.controller.start_double_support > 0
    assert preset.planner.double_support > 0 and preset.command.yaw_rate[1] > 0
    weights = preset.ocp.state_weights
    assert dict(weights.joint_position_by_name)["waist"] > weights.joint_position


G1_OBSTACLE_CAMPAIGN = "sim/campaigns/examples/g1_obstacles.toml"


def test_g1_obstacle_settings_keep_its_walking_and_load_for_its_obstacle_runs():
    """The G1 preset's obstacle settings (scaled from the H1's) leave its walking as it was (no negotiation with the
    ALIP planner, no obstacle term in the batched OCP); in its obstacle runs (the preset's [scenarios.obstacle],
    which its campaign spec adds nothing to) the DCM planner keeps the whole foot mesh off the box, crosses boxes up
    to 0.52 - 0.337 = 0.183 m deep, and the OCP holds the clearance terms on the G1's knee frames."""
    from pathlib import Path

    from robots.g1 import SOLE_CENTER_IN_ANKLE, SOLE_SPHERES_IN_ANKLE
    from sequencer.dcm_planner import DcmFootstepPlanner
    from sequencer.obstacles import Obstacle
    from sim.campaigns.spec import CampaignSpec
    from sim.campaigns.trial import resolve_arguments, trial_preset
    from wbmpc.walking.ocp import WalkingOCP

    walking = load_walking_preset("g1")
    assert walking.footstep_planner.kind == "alip" and walking.controller.negotiation_lookahead == 0.0
    assert walking.ocp.obstacle_clearance_weight == walking.ocp.obstacle_swing_path_weight == 0.0
    assert walking.ocp.obstacle_com_weight == 0.0
    planner = walking.planner
    spheres = np.array(SOLE_SPHERES_IN_ANKLE)[:, :2] - SOLE_CENTER_IN_ANKLE[:2]  # sole frame [m]
    assert np.all(spheres[:, 0] < planner.sole_front) and np.all(-spheres[:, 0] < planner.sole_rear)
    assert np.all(np.abs(spheres[:, 1]) < planner.sole_half_width)
    assert [tuple(p) for p in walking.ocp.obstacle_sole_points] == [(planner.sole_front, 0.0, 0.0),
                                                                     (-planner.sole_rear, 0.0, 0.0)]

    assert dataclasses.replace(load_walking_preset("g1", scenario="walk"), scenario="") == walking  # no [scenarios.walk]
    spec = CampaignSpec.from_toml(Path(__file__).resolve().parents[1] / G1_OBSTACLE_CAMPAIGN)
    assert (spec.robot, spec.scenario, spec.seeds, spec.params) == ("g1", "obstacle", list(range(20)), {})
    assert spec.grid["height"] == [0.08, 0.16, 0.24, 0.32]  # the H1's 0.1-0.4 m x 0.80
    arguments = resolve_arguments(spec.scenario, spec.controller, spec.duration, {**spec.params, "height": 0.08},
                                  spec.robot)
    run = trial_preset(spec.robot, spec.scenario, arguments)
    assert run == load_walking_preset("g1", scenario="obstacle") and run.scenario == "obstacle"
    assert dict(run.scenario_overrides)["footstep_planner.kind"] == "dcm"
    assert run.footstep_planner.kind == "dcm" and run.controller.planner_backend == "exact"
    assert run.controller.negotiation_lookahead > 0 and run.perception.enabled
    # what the G1 needs to walk on the DCM step QP (every swing on its path, no speed integrals), to stop before a
    # box it cannot cross (the deceleration) and to perceive a box's depth across its near edge
    assert run.ocp.swing_path_weight > 0 and run.controller.negotiation_deceleration > 0
    assert run.controller.velocity_integral_gain == run.controller.lateral_velocity_integral_gain == 0.0
    assert run.perception.obstacle_axis == "near_edge"
    dcm = DcmFootstepPlanner(run.planner)
    for depth, crossable in ((0.18, True), (0.19, False)):
        box = Obstacle(center=np.array([1.0 + 0.5 * depth, 0.0]), yaw=0.0, depth=depth, width=1.2, height=0.08)
        assert bool(dcm.can_cross(box, np.array([0.5, 0.0]), 0.0)) is crossable, depth
    ocp = WalkingOCP(load_robot("g1"), run.ocp, n_nodes=2, dt=0.02)
    terms = ocp.problem.running_models[0].differential.costs.costs
    assert {"left_clearance_shank", "right_clearance_sole1", "com_path"} <= set(terms)
    assert ocp.evaluation == "batched"


def test_h1_preset_states_every_tuned_number():
    preset = _assert_preset_states_every_field("h1", LIPM_CORRECTIONS, obstacles=True, speed_schedule=True)
    # the soles' undetermined squeeze is split by the sole-weighted damping, which the KKT backend solves
    assert preset.ocp.contact_damping > 0 and preset.ocp.contact_damping_moments == "sole"
    assert preset.ocp.dynamics_backend == "kkt"
    # the stance (sole centres 0.406 m apart) is inside the lateral step bounds
    assert preset.planner.w_right_min < preset.planner.pelvis_width < preset.planner.w_right_max
    assert -preset.planner.w_left_max < preset.planner.pelvis_width < -preset.planner.w_left_min
    assert dict(preset.ocp.state_weights.joint_position_by_name)["torso"] > preset.ocp.state_weights.joint_position


def test_a_robot_without_a_walking_preset_is_refused_at_once(monkeypatch, tmp_path):
    import wbmpc.walking.preset as preset_module

    (tmp_path / "bolt.toml").write_bytes((preset_module.PRESET_DIR / "bolt.toml").read_bytes())
    monkeypatch.setattr(preset_module, "PRESET_DIR", tmp_path)  # a registered robot with no file: the G1's
    with pytest.raises(ParameterError, match=r"robot='g1' has no walking preset yet \(robots that walk: bolt\)"):
        load_walking_preset("g1")


def test_a_presets_scenario_overrides_apply_to_that_scenario_only_and_under_the_runs_own(tmp_path):
    """[scenarios.<name>] of a preset file: applied for runs of that scenario before their own overrides, recorded on
    the preset, absent from other runs; a key that addresses no preset field is refused in one line, naming it."""
    import wbmpc.walking.preset as preset_module
    from sim.scenarios import available_scenarios

    text = (preset_module.PRESET_DIR / "bolt.toml").read_text()
    path = tmp_path / "bolt.toml"
    path.write_text(text + '\n[scenarios.push]\n"planner.l_max" = 0.18\ncontroller.max_iterations = 3\n')
    plain = load_walking_preset("bolt", path=path)
    assert plain.scenario_overrides == () and plain.planner.l_max != 0.18
    assert load_walking_preset("bolt", path=path, scenario="walk").planner == plain.planner
    push = load_walking_preset("bolt", path=path, scenario="push")
    assert push.planner.l_max == 0.18 and push.controller.max_iterations == 3
    assert push.scenario_overrides == (("planner.l_max", 0.18), ("controller.max_iterations", 3))
    assert load_walking_preset("bolt", {"planner.l_max": 0.25}, path=path, scenario="push").planner.l_max == 0.25
    path.write_text(text + '\n[scenarios.push]\n"planner.no_such_field" = 1.0\n')
    with pytest.raises(ParameterError, match=r"bolt.toml' \[scenarios.push\]: unknown sequencer parameter\(s\) "
                                             r"\['no_such_field'\]"):
        load_walking_preset("bolt", path=path, scenario="push")
    path.write_text(text + '\n[scenarios.push]\nl_max = 0.18\n')
    with pytest.raises(ParameterError, match=r"\[scenarios.push\] key 'l_max' must be 'section.field'"):
        load_walking_preset("bolt", path=path)  # refused whatever the scenario
    for robot in available_walking_presets():  # every preset's scenario tables name scenarios and load
        tables = preset_module.scenario_override_tables(
            preset_module.read_toml(preset_module.PRESET_DIR / f"{robot}.toml", "walking preset").get("scenarios", {}))
        for scenario in tables:
            assert scenario in available_scenarios(), (robot, scenario)
            assert load_walking_preset(robot, scenario=scenario).scenario_overrides


def test_command_range_refuses_with_the_reason():
    command = load_walking_preset("bolt").command
    command.check(VelocityCommand(0.3, 0.1, 0.0), "bolt")
    with pytest.raises(ParameterError, match=r"velocity command v_x=0.9 m/s for robot 'bolt' must be in \[-0.3, 0.5\]"):
        command.check(VelocityCommand(0.9, 0.0, 0.0), "bolt")
    with pytest.raises(ParameterError, match=r"yaw_rate=0.3 rad/s for robot 'bolt' must be 0 rad/s \(Bolt's legs have "
                                             r"no hip yaw"):
        command.check(VelocityCommand(0.3, 0.0, 0.3), "bolt")


def test_a_custom_planners_command_limit_is_checked_before_the_run():
    """run_scenario asks the controller's own planner, not the preset's, before the first tick."""
    from sequencer.dcm_planner import DcmFootstepPlanner
    from sim import run_scenario
    from wbmpc.walking import WalkingController

    preset = load_walking_preset("bolt")
    short = DcmFootstepPlanner(dataclasses.replace(preset.planner, l_max=0.09, v_x=0.2))  # |v_x| <= 0.3 m/s
    with pytest.raises(ParameterError, match=r"v_x=0.4"):
        run_scenario("walk", duration=0.1, velocity_command=(0.4, 0.0, 0.0),
                     controller=WalkingController(preset, planner=short))


# ------------------------------------------------------------------------------ quasi-static load


@pytest.mark.parametrize("robot_name", ["g1", pytest.param("h1", marks=needs_h1_extra)])
def test_the_quasi_static_load_keeps_each_centre_of_pressure_in_its_sole(robot_name):
    """Both soles on the ground at the reference posture: the wrenches and torques balance gravity,
    and each sole's centre of pressure lies inside its sole rectangle (the H1's 2 cm wide soles got
    5 cm outside with moments weighted like forces)."""
    from wbmpc_fixtures import alternating_schedule, standing_state

    from wbmpc.walking.ocp import WalkingOCP, WalkingOCPConfig, quasi_static_controls, quasi_static_load

    robot = load_robot(robot_name)
    ocp = WalkingOCP(robot, WalkingOCPConfig(evaluation="nodes"), n_nodes=2, dt=0.02)
    x0 = standing_state(robot)
    ocp.update(x0, alternating_schedule(0.0, 0.02, 2, t_start=1.0), np.zeros(3))  # both feet in contact
    tau, wrenches = quasi_static_load(ocp, x0)
    np.testing.assert_array_equal(tau, quasi_static_controls(ocp, x0))
    assert sorted(wrenches) == ["left", "right"]
    model = robot.pinocchio_model
    data = model.createData()
    q = x0[: model.nq]
    gravity = pin.computeGeneralizedGravity(model, data, q)
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    load = np.concatenate([np.zeros(6), tau])
    half_length, half_width = 0.5 * np.asarray(robot.sole_size)
    for foot, wrench in wrenches.items():
        J = pin.getFrameJacobian(model, data, model.getFrameId(robot.foot_frames[foot]), pin.LOCAL)
        load += J.T @ wrench
        cop_x, cop_y = wrench[4] / wrench[2], -wrench[3] / wrench[2]  # sole frame [m]
        assert abs(cop_x) < 0.5 * half_length and abs(cop_y) < 0.5 * half_width, (foot, cop_x, cop_y)
        assert wrench[2] > 0.3 * ocp.mass * 9.81
    np.testing.assert_allclose(load, gravity, rtol=0, atol=1e-8 * np.max(np.abs(gravity)))


@needs_h1_extra
def test_cop_rear_extension_moves_the_wrench_cones_rear_edge_back_and_keeps_its_front_edge():
    """A vertical load at a centre of pressure x along the sole frame (τ = p × f): inside the cone between the
    rear edge moved back by the extension and the sole rectangle's front edge, outside beyond either."""
    from wbmpc.walking.ocp import WalkingOCP, WalkingOCPConfig

    h1 = load_robot("h1")
    half_length = 0.5 * h1.sole_size[0]
    extension = 0.035
    with pytest.raises(ParameterError, match=r"cop_rear_extension=0.2 m must be in \[0, 0.1\] m"):
        WalkingOCPConfig(cop_rear_extension=0.2)
    ocp = WalkingOCP(h1, WalkingOCPConfig(wrench_cone_weight=1e2, cop_rear_extension=extension), n_nodes=2, dt=0.02)
    residual = ocp.problem.running_models[0].differential.costs.costs["left_wrench_cone"].cost.residual
    lower, upper = residual.lower_bounds, residual.upper_bounds

    def inside(cop_x):
        force = np.array([0.0, 0.0, 500.0])
        wrench = np.concatenate([force, np.cross([cop_x, 0.0, 0.0], force)])
        r = residual.A @ wrench
        return bool(np.all(r >= lower - 1e-12) and np.all(r <= upper + 1e-12))

    for cop_x, expected in ((half_length - 1e-3, True), (half_length + 1e-3, False),
                            (-half_length - extension + 1e-3, True), (-half_length - extension - 1e-3, False),
                            (-half_length - 1e-3, True)):
        assert inside(cop_x) is expected, cop_x


@needs_h1_extra
def test_passed_feet_reach_behind_the_sole_only_beyond_a_crossed_box():
    """cop_rear_extension_feet = "passed": the stance foot before the box (during the first crossing swing) keeps
    the sole rectangle, a foot landed beyond it gets the extended cone, at its contact nodes only."""
    from wbmpc_fixtures import crossing_schedule, standing_state

    from wbmpc.walking.ocp import WalkingOCP, WalkingOCPConfig

    h1 = load_robot("h1")
    with pytest.raises(ParameterError, match="cop_rear_extension_feet='lead' must be 'all' or 'passed'"):
        WalkingOCPConfig(cop_rear_extension_feet="lead")
    config = WalkingOCPConfig(wrench_cone_weight=1e2, cop_rear_extension=0.035, cop_rear_extension_feet="passed")
    ocp = WalkingOCP(h1, config, n_nodes=30, dt=0.02)
    schedule, crossings = crossing_schedule(30)  # right swings over the box (x in [0.2, 0.3]) on nodes 0-9, left 10-19
    x0 = standing_state(h1)  # soles at x = 0.018 m, before the box
    passed = ocp.passed_feet(x0, crossings, schedule.in_contact, schedule.touchdown_position, [0, 1])
    left, right = passed[:, 0], passed[:, 1]
    assert not left[:10].any()  # the stance before the box while the right foot crosses
    assert not right[:10].any() and not left[10:20].any()  # swinging
    assert right[10:20].all() and left[20:30].all()  # landed beyond the box
    ocp.update(x0, schedule, np.array([0.0, 0.0, 0.97]), crossings=crossings)
    costs = [model.differential.costs.costs for model in ocp.problem.running_models]
    for k in (5, 15):
        assert costs[k]["left_wrench_cone"].active is (k == 5)
        assert costs[k]["left_wrench_cone_passed"].active is False
        assert costs[k]["right_wrench_cone"].active is False
        assert costs[k]["right_wrench_cone_passed"].active is (k == 15)
    ocp.update(x0, schedule, np.array([0.0, 0.0, 0.97]))  # no crossing: the sole rectangle everywhere
    assert not any(c[f"{foot}_wrench_cone_passed"].active for c in costs for foot in ("left", "right"))


def test_contact_wrench_scales_weigh_moments_by_the_sole():
    from wbmpc.walking.ocp import contact_wrench_scales

    np.testing.assert_allclose(contact_wrench_scales(100.0, (0.2, 0.1)),
                               [100.0, 100.0, 100.0, 5.0, 10.0, 100.0 * 0.5 * np.hypot(0.2, 0.1)])
    np.testing.assert_array_equal(contact_wrench_scales(100.0), np.full(6, 100.0))
    with pytest.raises(ParameterError, match=r"sole_size=\(0.2, 0.0\) must be \(length > 0, width > 0\)"):
        contact_wrench_scales(100.0, (0.2, 0.0))


def test_the_plateau_profile_rises_holds_and_falls_smoothly_with_zero_vertical_velocity_at_its_ends():
    from wbmpc.walking.ocp import plateau_height_reference, plateau_height_reference_derivative

    height, rise_end, fall_start = 0.2, 0.3, 0.75
    s = np.linspace(0.0, 1.0, 2001)
    z = plateau_height_reference(s, height, rise_end, fall_start)
    dz = plateau_height_reference_derivative(s, height, rise_end, fall_start)
    np.testing.assert_allclose(z[[0, -1]], 0.0, atol=1e-15)  # on the ground at lift-off and touchdown
    np.testing.assert_allclose(plateau_height_reference([rise_end, fall_start], height, rise_end, fall_start), height)
    plateau = (s >= rise_end) & (s <= fall_start)
    np.testing.assert_allclose(z[plateau], height)  # held over the whole plateau
    assert np.all(z <= height + 1e-15) and np.all(z >= 0.0)
    assert np.all(np.diff(z[s <= rise_end]) >= 0.0) and np.all(np.diff(z[s >= fall_start]) <= 0.0)
    # zero vertical velocity at lift-off, at both plateau ends and at touchdown
    ends = plateau_height_reference_derivative([0.0, rise_end, fall_start, 1.0], height, rise_end, fall_start)
    np.testing.assert_allclose(ends, 0.0, atol=1e-12)
    # the derivative is the profile's (central differences), and continuous: no jump between samples
    h = s[1] - s[0]
    np.testing.assert_allclose(dz[1:-1], (z[2:] - z[:-2]) / (2 * h), atol=1e-4)
    assert np.max(np.abs(np.diff(dz))) < 50 * h * height / rise_end**2
    assert np.max(np.abs(np.diff(z))) < 2 * h * np.max(np.abs(dz)) + 1e-12
    # the peak vertical speed of a quintic smoothstep: 15/8 H over the rise's and the fall's durations
    np.testing.assert_allclose(dz.max(), 15 / 8 * height / rise_end, rtol=1e-4)
    np.testing.assert_allclose(dz.min(), -15 / 8 * height / (1 - fall_start), rtol=1e-4)
    for bad in ((0.0, 0.5), (0.6, 0.5), (0.3, 1.0)):
        with pytest.raises(ParameterError, match="plateau breakpoints"):
            plateau_height_reference(0.5, height, *bad)
