"""The planning stage of the walking controller: measured state -> footstep plan, every replan.

At each replan it measures the reduced state (CoM, CoM velocity, DCM with the planner's ω; the
feet; for a planner that reads it, the whole body's angular momentum about the stance contact),
switches the stance on a touchdown (:class:`~wbmpc.walking.stance.StanceTracker`),
updates the online estimates (:mod:`wbmpc.walking.estimators`) and asks the footstep planner
for a plan from the current stance with the velocity command (plus the speed integral's
correction). A planner failure (:class:`wbmpc.errors.SolverError`, e.g. an infeasible step QP)
keeps the previous plan and is reported in the record; it never stops the loop by itself
(``failing_since`` and ``failure_count`` say since when it has failed at every replan, for the
controller, which ends the run once the kept plan no longer covers the MPC's horizon).

Perceived obstacles switch the mode walking -> negotiation -> walking
(:mod:`wbmpc.walking.negotiation`); in negotiation the planner gets the obstacles of the negotiation and
the lift-off point of the swinging foot (``StanceState.swing_liftoff``: the previous stance's foothold).
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np
import pinocchio as pin

from robots.conventions import base_yaw
from sequencer.dcm_planner import DcmFootstepPlanner
from sequencer.planner import FootstepPlanner, ReducedState, StanceState, VelocityCommand, rotate_xy
from wbmpc.errors import ParameterError, SolverError
from wbmpc.walking.alip_state import contact_angular_momentum
from wbmpc.walking.controller_config import WalkingControllerConfig
from wbmpc.walking.estimators import LipmCorrectionEstimator, StanceSlide, VelocityIntegral
from wbmpc.walking.negotiation import NEGOTIATION, NegotiationMode
from wbmpc.walking.stance import StanceTracker


class PlanningStage:
    """Footstep planning from measurements (see the module docstring).

    Args:
        robot: ``robots.RobotDescription`` (Pinocchio model, foot frames).
        planner: the footstep planner.
        config: the controller's options (touchdown detection, estimator gains, ...).
        planner_after: None or (t_switch [s], planner): from the first touchdown at or after
            t_switch on, plan with this planner (same feet and ω; the LIPM corrections carry over).
        measure_angular_momentum: hand the planner the whole body's angular momentum about the stance
            contact (``ReducedState.angular_momentum``, exact:
            :func:`wbmpc.walking.alip_state.contact_angular_momentum`); False: None (a planner that needs it
            approximates it from the CoM state). Logged as ``angular_momentum_contact_x/y`` with the
            centroidal part ``angular_momentum_com_x/y`` [kg·m²/s], world axes.
    """

    def __init__(self, robot: Any, planner: FootstepPlanner, config: WalkingControllerConfig,
                 planner_after: tuple[float, FootstepPlanner] | None = None,
                 measure_angular_momentum: bool = False) -> None:
        self.model = robot.pinocchio_model
        self.data = self.model.createData()
        self.nq = self.model.nq
        self.feet = tuple(robot.foot_frames.keys())
        if tuple(planner.feet) != self.feet:
            raise ParameterError(f"the planner's feet {tuple(planner.feet)} must be the robot's {self.feet}")
        self.frame_ids = [self.model.getFrameId(robot.foot_frames[f]) for f in self.feet]
        self.config = config
        self.planner = planner
        self.omega = float(planner.omega)
        if planner_after is not None and abs(planner_after[1].omega - self.omega) > 1e-12:
            raise ParameterError(
                f"sequencer_params_from: the later planner's omega={planner_after[1].omega:.6g} 1/s must equal "
                f"the first one's {self.omega:.6g} 1/s (z_c fixes the run's omega)"
            )
        for candidate in (planner, None if planner_after is None else planner_after[1]):
            if candidate is not None and config.negotiation_lookahead > 0 and not getattr(candidate, "avoids_obstacles",
                                                                                           False):
                raise ParameterError(
                    f"negotiation_lookahead={config.negotiation_lookahead} m needs a footstep planner that avoids "
                    f"obstacles (the DCM planner); {type(candidate).__name__} does not: set negotiation_lookahead = 0")
        self._planner_after = planner_after
        self.measure_angular_momentum = bool(measure_angular_momentum)
        self.stance = StanceTracker(self.feet, config.touchdown_detection)
        self.slide = StanceSlide(config.stance_slide_follow)
        self.velocity_integral = VelocityIntegral(config.velocity_integral_gain, config.velocity_correction_max,
                                                  config.velocity_filter_time, config.replan_period,
                                                  config.lateral_velocity_integral_gain)
        self.lipm = None
        if isinstance(planner, DcmFootstepPlanner):
            self.lipm = LipmCorrectionEstimator(
                planner.corrections, self.omega, config.lipm_correction_gain, config.stance_drift_max,
                config.dcm_offset_bias_max, config.lipm_correction_max_error, config.lipm_correction_max_slide,
            )
        self.command = VelocityCommand()
        self._range = planner.command_range()
        self.negotiation = NegotiationMode(config.negotiation_lookahead, config.negotiation_corridor,
                                           config.negotiation_release)
        self.swing_liftoff = None  # world (x, y) [m] where the swinging foot lifted off
        self.plan = None
        self.blocked = False  # an obstacle of the negotiation too deep to cross (set by every update, _blocked)
        self._forward_bound = math.inf  # [m/s] the negotiation's bound on the forward command (_update_forward_bound)
        self._last_forward = None  # (time [s], planned forward command [m/s]) of the last update
        self.planner_time = 0.0  # [s], total wall time in the planner
        self._clear_failures()

    # ------------------------------------------------------------------ measurements
    def feet_position(self, q: np.ndarray) -> np.ndarray:
        """Foot frame positions (n_feet, 3) [m], world frame."""
        pin.framesForwardKinematics(self.model, self.data, q)
        return np.array([self.data.oMf[i].translation for i in self.frame_ids])

    def reduced_state(self, q: np.ndarray, v: np.ndarray) -> ReducedState:
        """CoM, CoM velocity and DCM (with the planner's ω), world frame."""
        com = pin.centerOfMass(self.model, self.data, q, v).copy()
        com_velocity = self.data.vcom[0].copy()
        return ReducedState(com, com_velocity, com[:2] + com_velocity[:2] / self.omega)

    # ------------------------------------------------------------------ episode
    def reset(self, x0: np.ndarray, t0: float, command: VelocityCommand) -> None:
        """Start with ``config.first_stance_foot`` in stance at its measured position, from
        ``t0 + config.start_double_support`` on (both feet on the ground until then)."""
        q0 = np.asarray(x0)[: self.nq]
        feet = self.feet_position(q0)
        index = self.feet.index(self.config.first_stance_foot)
        self.stance.reset(self.config.first_stance_foot, feet[index, :2], t0 + self.config.start_double_support,
                          yaw=float(base_yaw(q0[3:7])))
        self.slide.reset(self.stance.state.position)
        self.swing_liftoff = feet[1 - index, :2].copy() if len(self.feet) == 2 else None
        self.negotiation.reset()
        self.blocked = False
        self._forward_bound = math.inf
        self._last_forward = None
        self.set_command(command)
        self.plan = None
        self._clear_failures()

    def _clear_failures(self) -> None:
        """No planner failure since the last good plan."""
        self.failing_since: float | None = None  # [s] first of the replans that have all failed until now
        self.failure_count = 0  # replans failed in a row
        self.last_failure = ""  # the last failure's message

    def set_command(self, command: VelocityCommand) -> None:
        """The velocity command of the next plans (heading frame).

        Raises:
            ParameterError: the planner cannot plan it (names the component and the range).
        """
        command = VelocityCommand.from_tuple(command)
        self.planner.check_command(command)
        self.command = command

    @property
    def planned_command(self) -> VelocityCommand:
        """The command handed to the planner: the user's plus the speed integral's corrections,
        within the planner's command range (a correction may not push it outside)."""
        c = self.command
        dx, dy = self.velocity_integral.correction_xy
        (low_x, high_x), (low_y, high_y) = self._range["v_x"], self._range["v_y"]
        high_x = min(high_x, self._forward_bound)
        return VelocityCommand(min(max(c.v_x + dx, low_x), high_x), min(max(c.v_y + dy, low_y), high_y), c.yaw_rate)

    def _update_forward_bound(self, t: float) -> None:
        """The negotiation's bound on the forward command [m/s] at time ``t`` [s]: ``negotiation_speed_max``, 0 when
        blocked, none while walking; reached from the last planned forward command at most at
        ``negotiation_deceleration`` (> 0) [m/s^2]."""
        bound = math.inf
        if self.negotiation.mode == NEGOTIATION:
            bound = 0.0 if self.blocked else self.config.negotiation_speed_max
        deceleration = self.config.negotiation_deceleration
        if deceleration > 0.0 and self._last_forward is not None:
            t_last, forward = self._last_forward
            if bound < forward:
                bound = max(bound, forward - deceleration * max(t - t_last, 0.0))
        self._forward_bound = bound

    def _blocked(self) -> bool:
        """Whether an obstacle of the negotiation is too deep for one crossing step from the current stance (the
        planner's ``can_cross``): the forward command is then bounded by 0 (the robot stops before it, stepping in
        place, instead of running into its foothold bound at walking speed and falling)."""
        can_cross = getattr(self.planner, "can_cross", None)
        if can_cross is None or self.negotiation.mode != NEGOTIATION:
            return False
        stance = self.stance.state
        return not all(can_cross(obstacle, stance.position, stance.yaw) for obstacle in self.negotiation.active)

    # ------------------------------------------------------------------ every replan
    def update(self, t: float, x: np.ndarray, foot_in_contact: np.ndarray,
               obstacles=()) -> tuple[Any, ReducedState, dict]:
        """Switch the stance, update the estimates and the negotiation mode (``obstacles``: the perceived
        ones, world frame), plan. Returns (plan, reduced state, record).

        Raises:
            SolverError: the planner failed and there is no previous plan to keep.
        """
        q, v = x[: self.nq], x[self.nq:]
        measured = self.reduced_state(q, v)
        stance = self.stance.state
        self.velocity_integral.update(self.command.v_x, rotate_xy(measured.com_velocity[:2], -stance.yaw),
                                      self.command.v_y)
        feet = self.feet_position(q)
        first = self.plan.steps[0] if self.plan is not None and len(self.plan.steps) else None
        stance_index = self.feet.index(stance.foot)
        slide = self.slide.measure(stance.position, feet[stance_index, :2])
        previous_stance = stance
        swing_start = stance.t_start
        if first is not None and getattr(first, "double_support", None) is not None:  # a settled step: the swing
            swing_start += first.double_support - self.plan.double_support  # begins after its long double support
        switched = self.stance.update(
            t, None if first is None else first.foot, None if first is None else first.touchdown_time,
            swing_start, feet, foot_in_contact, 0.0 if first is None else first.yaw,
        )
        stance = self.stance.state
        stance_index = self.feet.index(stance.foot)
        if switched:  # the measurement before the switch covered the old stance foot up to now
            self.swing_liftoff = np.array(previous_stance.position, dtype=float)  # the foot that lifts off now
            ended_slide = self.slide.slide
            self.slide.reset(stance.position)
            slide = self.slide.measure(stance.position, feet[stance_index, :2])
            if self.lipm is not None:
                landed = first is not None and first.foot == stance.foot
                # a settled step (quasi-static crossing) aimed at no walking offset: the estimates skip it
                walked = landed and getattr(first, "settle_dcm", None) is None
                self.lipm.touchdown(t, measured.dcm, stance.position, stance.yaw,
                                    first.dcm_offset if walked else None, ended_slide)
            if self._planner_after is not None and t >= self._planner_after[0] - 1e-9:
                self._switch_planner(self._planner_after[1])
        self.slide.follow_if_sliding(slide, feet[stance_index, :2], bool(foot_in_contact[stance_index]))
        mode_switch = self.negotiation.update(t, obstacles, measured.com[:2], feet[:, :2], stance.yaw)
        self.blocked = self._blocked()
        self._update_forward_bound(t)
        planned_obstacles = self.negotiation.avoided
        command = self.planned_command
        self._last_forward = (t, command.v_x)
        record: dict[str, float] = {
            "stance_foot": float(stance_index),
            "stance_x": stance.position[0],
            "stance_y": stance.position[1],
            "stance_yaw": stance.yaw,
            "stance_slide": self.slide.slide,
            "sequencer_stance_x": self.slide.plan_position[0],
            "sequencer_stance_y": self.slide.plan_position[1],
            "t_stance_start": stance.t_start,
            "stance_switched": float(switched),
            "dcm_x": measured.dcm[0],
            "dcm_y": measured.dcm[1],
            "sequencer_ok": 1.0,
            "sequencer_v_x": command.v_x,
            "sequencer_v_y": command.v_y,
            "sequencer_yaw_rate": command.yaw_rate,
            "swing_drift": np.nan if self.lipm is None else self.lipm.corrections.swing_drift,
            "dcm_offset_bias": np.nan if self.lipm is None else self.lipm.corrections.dcm_offset_bias,
            "stance_drift": np.nan if self.lipm is None else self.lipm.corrections.stance_drift,
            "negotiation_mode": float(self.negotiation.mode),
            "negotiation_blocked": float(self.blocked),
            "negotiation_switch": float(mode_switch),
            "obstacles_perceived": float(len(obstacles)),
            "obstacles_planned": float(len(planned_obstacles)),
            **_nearest_obstacle_extent(planned_obstacles, stance.position, stance.yaw),
        }
        if self.measure_angular_momentum:  # about the planned contact: the sole's point on the ground under it
            contact = np.array([*self.slide.plan_position, feet[stance_index, 2]])
            centroidal = contact_angular_momentum(self.model, self.data, q, v, contact)
            measured = dataclasses.replace(measured, angular_momentum=centroidal.angular_momentum_contact)
            for axis, index in (("x", 0), ("y", 1)):
                record[f"angular_momentum_contact_{axis}"] = float(centroidal.angular_momentum_contact[index])
                record[f"angular_momentum_com_{axis}"] = float(centroidal.angular_momentum_com[index])
        tic = time.perf_counter()
        planned_stance = StanceState(stance.foot, self.slide.plan_position, stance.yaw, stance.t_start,
                                     swing_liftoff=self.swing_liftoff)
        try:
            if planned_obstacles:
                self.plan = self.planner.plan(t, planned_stance, measured, command, obstacles=planned_obstacles)
            else:  # the planner's own call, as without perception
                self.plan = self.planner.plan(t, planned_stance, measured, command)
        except SolverError as err:  # e.g. an infeasible step QP: keep following the last plan
            if self.plan is None:
                raise
            record["sequencer_ok"] = 0.0
            if self.failing_since is None:
                self.failing_since = t
            self.failure_count += 1
            self.last_failure = f"{type(err).__name__}: {err}".splitlines()[0]
        else:
            self._clear_failures()
        elapsed = time.perf_counter() - tic
        self.planner_time += elapsed
        record["sequencer_time"] = elapsed
        step = self.plan.steps[0]
        record["next_foot"] = float(self.feet.index(step.foot))
        record["next_x"], record["next_y"] = float(step.position[0]), float(step.position[1])
        record["next_touchdown_time"] = float(step.touchdown_time)
        crossing = getattr(step, "crossing", None)
        record["next_crossing_height"] = np.nan if crossing is None else float(crossing.obstacle.height)
        return self.plan, measured, record

    def _switch_planner(self, planner: FootstepPlanner) -> None:
        """Plan with ``planner`` from now on; the identified LIPM corrections carry over."""
        if self.lipm is not None and isinstance(planner, DcmFootstepPlanner):
            planner.corrections = self.lipm.corrections
        self.planner = planner
        self._range = planner.command_range()
        self._planner_after = None


def _nearest_obstacle_extent(obstacles, stance_position, stance_yaw: float) -> dict[str, float]:
    """The planned obstacle nearest the stance as the planner sees it, for the replan log: its footprint's near and
    far ends along the stance heading ``obstacle_near`` / ``obstacle_far`` [m] (world coordinates along the heading
    of ``stance_yaw`` [rad], the same axis as the stance's (x cos + y sin)) and ``obstacle_height`` [m]; NaN without
    one. What a perceived box was when a plan was made (the estimate changes as the robot approaches it)."""
    if not obstacles:
        return {"obstacle_near": np.nan, "obstacle_far": np.nan, "obstacle_height": np.nan}
    heading = np.array([math.cos(stance_yaw), math.sin(stance_yaw)])
    along = [obstacle.footprint_corners() @ heading for obstacle in obstacles]
    stance_along = float(np.asarray(stance_position, dtype=float)[:2] @ heading)
    nearest = min(range(len(obstacles)), key=lambda k: abs(float(along[k].mean()) - stance_along))
    return {"obstacle_near": float(along[nearest].min()), "obstacle_far": float(along[nearest].max()),
            "obstacle_height": float(obstacles[nearest].height)}
