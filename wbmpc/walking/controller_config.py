"""Options of the walking controller: horizon, rates, delays, touchdown handling, estimator gains.

Every tuned value of a robot is in its walking preset (``wbmpc/walking/presets/<robot>.toml``,
section ``[controller]``, loaded by :func:`wbmpc.walking.preset.load_walking_preset`); the defaults
here are Bolt's, the robot the paper's pipeline was tuned on.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.mpc import HORIZON_ENDS
from wbmpc.walking.stance import TOUCHDOWN_DETECTIONS


@dataclass(frozen=True)
class WalkingControllerConfig:
    """Options of the walking controller (defaults: the paper's pipeline).

    Attributes:
        n_nodes: MPC horizon length N (nodes), 100 (H_u = 1 s, three 0.3 s steps). The paper
            gives the node spacing (~10 ms) but not N. Shorter horizons walk worse (20 s walk,
            seed 0: N = 80 speed error 12 mm/s, 70 34 mm/s, 60 falls at 1.7 s, 50 0.15 m/s;
            100: 4 mm/s; docs/closed_loop.md).
        node_dt: MPC node spacing [s], paper: ~0.01.
        replan_period: period of the sequencer + MPC update [s], paper: 0.01 (100 Hz).
        max_iterations: FDDP iterations per MPC update, paper and default: 1. Until the warm start
            filled the end of the horizon by a rollout (``mpc_horizon_end``), one iteration fell
            (after 2.1 s on terrain, 10.5 s in the transition) and the closed loop ran 3, 2.5x
            slower (docs/closed_loop.md). Three recover more pushes (push map 27.1 % against
            21.4 %, docs/campaigns.md).
        mpc_horizon_end: how the MPC's warm start fills the node entering at the end of the
            horizon: "repeat" (default, as ``wbmpc.ocp.mpc.RecedingHorizonMPC``), "rollout" or "phase" (the
            rollout with the control of the latest node in the same gait phase, else the quasi-static torques of the
            node's contact set: a double support entering after one foot's touchdown is not filled from the one
            after the other's). Bolt's preset uses "rollout": with "repeat", 1 iteration per update falls (see
            ``max_iterations``); on point feet "rollout" and "phase" are the same.
        mpc_restart_after_failures: after this many consecutive failed MPC updates the next one
            starts cold (``RecedingHorizonMPC(restart_after_failures=)``; the replan log's
            ``mpc_restart`` marks it), or None (default: never, the warm start from the last good
            solution is retried). Injected failures (``mpc_failure_times``) do not count.
        mpc_prepare: after each update, compute the next update's contact dynamics derivatives
            ahead (``WalkingMPC.prepare``): the same torques, ~2 ms less between measurement and
            torque (the ``mpc_tick_time`` metric), the same work per cycle (``mpc_prepare_time``).
        mpc_time_budget: wall time [s] an MPC update may take (``WalkingMPC(time_budget=)``: no
            FDDP iteration or line-search trial starts that would end after it; status
            "deadline"), or None (default). Set, it makes the run depend on the machine's speed:
            the same seed no longer gives the same log.
        delay_nodes: 1 applies node 1 of each solution as soon as it is computed (the paper's
            pipeline: its solver needs about one node, 10 ms, so node 1 is "now" when the solution
            arrives); 0 applies node 0.
        computation_delay: simulated solver latency [s]: a solution computed from the state at t
            is applied from t + computation_delay on (its node index still counts from t). 0 (default)
            makes it available at once. ``delay_nodes=0, computation_delay=0.01`` emulates the real
            system the paper's delay model stands for: node 1 applied from t + 10 ms.
        interpolate: interpolate u and x between nodes k and k+1 at 1 kHz (otherwise zero-order hold).
        feedback: apply the Riccati gains (False: feed-forward u_k only, to show what K buys).
        touchdown_detection: "contact" (switch the stance on the measured touchdown, default) or
            "plan" (at the planned time); see ``wbmpc.walking.stance``.
        touchdown_wait_nodes: with contact detection, a swing foot still in the air when its
            touchdown is due is kept swinging (and driven down by the height cost) for this many
            more nodes in the OCP's schedule (see ``wbmpc.walking.stance.delay_to_touchdown``).
        touchdown_wait_depth: while such a foot is due and still in the air, the OCP's
            touchdown-height term aims it this far below the ground [m], and the waiting nodes'
            height reference stays on the ground (``wbmpc.walking.stance.ground_waiting_nodes``).
            Aimed at the ground itself, eq. (19) brings the foot down with zero vertical speed and a
            sub-millimetre tracking error leaves it hovering: stepping in place or at 0.1 m/s Bolt's
            feet stopped 0.6 mm above the ground, never touched, and every stance ended on the
            stance tracker's 50 ms timeout (0.36 s steps for T_nom = 0.3 s: +52.6 and +25.5 mm/s
            forward); walking backwards the left foot landed 12 ms late (28.5 mm/s sideways). With
            5 mm the feet land 2-5 ms before the plan. Only the last nodes of a swing are
            concerned: aimed 1.5 mm below the ground over the whole swing, Bolt fell at 0.33 m/s;
            3 mm instead of 5 fell stepping in place (docs/closed_loop.md).
        first_stance_foot: stance foot at t0 (both feet are on the ground at start; the other one
            takes the first step).
        start_double_support: a start from standing [s]: the first stance begins this long after
            t0, both feet on the ground until then, and the first steps are planned from the DCM
            the nominal gait has at a stance start (:meth:`sequencer.dcm_planner.DcmFootstepPlanner.plan`),
            which the whole-body OCP reaches by moving the centre of pressure. 0 (Bolt: point feet
            cannot move it) starts stepping at once from the DCM between the feet. On the G1 that
            first step was a catch step 0.16 m wider than nominal and the walk drifted sideways by
            as much (docs/closed_loop.md).
        velocity_integral_gain: integral action on the forward speed [1/s] (0 = off, the default and
            the paper's pipeline): the sequencer is given v*_x + k ∫ (v*_x − v̄_x) dt, v̄ the CoM
            velocity low-passed over ``velocity_filter_time``, the correction bounded by
            ``velocity_correction_max`` (and the integral clamped accordingly: anti-windup). It was
            on (k = 1) while Bolt settled at 0.6 m/s for 0.33 m/s; that bias came from hovering
            touchdowns and the LIPM's missing swing drift (fixed, see the preset's ``[ocp]`` touchdown terms and
            ``lipm_correction_gain``), and with k = 1 the 20 s walk now overshoots to 0.48 m/s
            during the ramp and ends with a larger mean error (8.5 against 6.7 mm/s).
        lateral_velocity_integral_gain: the same integral action on the lateral speed v_y [1/s] (0 = off,
            Bolt's and the H1's; the filter and the bound are the forward one's). A lateral correction
            shifts the planner's nominal step widths, as a lateral command does; on the G1 (ALIP planner)
            0.15 m/s sideways ran at 0.18 m/s without it (docs/closed_loop.md).
        velocity_correction_max: bound of each correction [m/s].
        velocity_filter_time: time constant of the low-pass filter on the measured speed [s].
        lipm_correction_gain: per-step gain in [0, 1] of two corrections of the planner's LIPM,
            identified after every undisturbed step from the measured DCM (0 = off: the paper's
            pure LIPM and the parameters' own values) and written into the DCM planner's
            ``LipmCorrections``. (1) Stance drift (``stance_drift``): the DCM's gain over the LIPM
            during the stance that just ended, d = zeta_T - p - (zeta_0 - p) exp(omega T) (zeta_0,
            zeta_T measured at its touchdown and at the next one, p the stance foot, along the
            heading), in metres, at every step whatever its length (sign included). (2) Touchdown
            offset bias (``dcm_offset_bias``): measured DCM offset at the touchdown minus the
            offset the plan aimed at. Each estimate moves by this fraction towards the step's value.
            On Bolt the swing leg (the legs are half of the robot's mass) makes the DCM outrun the
            LIPM by ~24 mm per stance at 0.33 m/s and still 5.5-8.5 mm stepping in place (the
            swing leg's angular momentum): not proportional to the step, so the earlier model
            kappa L (identified from steps of 3 cm or more) left stepping in place drifting
            forward at 53-61 mm/s (docs/closed_loop.md). Uncorrected, the planner answers the drift
            with long, quick steps (0.12 m/s too fast at 0.33 m/s).
        lipm_correction_max_error: largest difference [m] (x and y) between the measured and the
            planned DCM offset at a touchdown for the step to count in the LIPM corrections (steady
            walking: 2-5 mm; after the paper's push: cm).
        lipm_correction_max_slide: largest slide [m] of the stance foot from its touchdown point
            for the step to count in the LIPM corrections (the point foot rolls 5-7 mm in
            undisturbed steps).
        stance_drift_max: bound of each step's stance drift and of the estimate [m], in [0, 0.1].
        dcm_offset_bias_max: bound of each step's touchdown offset bias and of the estimate [m].
        stance_slide_follow: slide [m] of the stance foot from its touchdown point beyond which the
            sequencer plans from the foot's measured position (updated at every replan while the foot
            is in contact) instead of the touchdown point; None = the touchdown point for the whole
            stance. A sliding foot then shows up in the plan at once: the DCM runs away from the
            foot and the sequencer brings the next touchdown forward. With the touchdown point kept,
            the slip scenario at friction 0.15 fell at 4.68 s (the left foot slid 0.36 m outwards,
            the sequencer kept the next touchdown at its nominal time); with 0.02 m the right foot
            landed 50 ms earlier (4.38 instead of 4.43 s), the slide stopped at 0.21 m and Bolt
            walked on (docs/closed_loop.md). The default 0.02 m lies above the 5-11 mm the point
            foot rolls in undisturbed steps, so that walking on good ground is unchanged.
        mpc_failure_times: injected failures [s]: the MPC update at the first replan at or after
            each time is discarded as if the solver had failed (the last good solution is kept).
        sequencer_params_from: None, or (t_switch [s], ``SequencerParams`` or ``AlipParams``, of the
            planner the run starts with): from the first
            touchdown at or after t_switch on, the sequencer uses these parameters instead (the
            current velocity command, integral correction included, and the identified LIPM
            corrections carry over). At a touchdown, not in the middle of a step: switching to
            fixed timing mid-step moved the current touchdown by up to T_nom - T (58 ms were seen)
            at once. Used to compare gaits after a common start, e.g. fixed step timing from
            t_switch (a start from standing with fixed timing falls).
        planner_backend: QP backend of the DCM planner: "exact" (closed-form solution of the same
            QP, verified against OSQP in the sequencer tests, fastest), "osqp" (the paper's) or
            "proxqp".
        negotiation_lookahead: obstacle negotiation (:mod:`wbmpc.walking.negotiation`): the controller
            switches from walking to negotiation when a perceived obstacle (``Measurement.obstacles``) has
            its near edge within this distance [m] ahead of the CoM along the stance heading, inside the
            corridor below; it then hands those obstacles to the footstep planner and the OCP. 0 = never.
        negotiation_corridor: half width [m] of the corridor about the CoM line along the heading in which an
            obstacle counts (the feet and the swing reach this far sideways).
        negotiation_release: back to walking once both feet are this far [m] beyond the far edge of every
            obstacle of the negotiation (along the heading).
        negotiation_speed_max: forward command bound [m/s] while negotiating (the approach and crossing
            speed; inf = the walking command).
        negotiation_deceleration: [m/s^2], finite and >= 0: while negotiating, the forward command falls to its bound
            (``negotiation_speed_max``, or 0 before an obstacle too deep to cross) from the last planned one at most
            this fast; 0: at once. The G1, walking at 0.4 m/s, fell stopping within one step before a box it could
            not cross (docs/closed_loop.md "The G1's obstacle runs on the DCM planner").
        negotiation_max_iterations: FDDP iterations per MPC update while negotiating, an integer >= 1, or
            0 (``max_iterations`` throughout). A crossing changes the OCP more from one update to the next
            than walking does (a plateau, clearance barriers, a long step entering the horizon), and a
            warm-started update of a few iterations then stays far above the optimum (docs/ocp.md,
            "Solved to convergence, measured"); the budget goes where the problem changes.
        negotiation_swing_path_weight: the OCP's ``swing_path_weight`` (every swing foot's (x, y) along the smooth path
            from its lift-off to its foothold) while negotiating, finite and >= 0 (0: the OCP's own). Near an obstacle
            a swing whose horizontal motion is free may move backwards into it (the H1's lead crossing foot and the
            first step after a trailing crossing, docs/ocp.md "Every swing on its path"); applied to the walk as well,
            the same term made the H1's steps in place drift twice as far. It needs the OCP's swing path terms
            (``swing_path_weight`` or ``obstacle_swing_path_weight`` > 0).
        crossing_max_iterations: FDDP iterations per MPC update while the OCP's horizon holds a swing over an
            obstacle (``crossing_nodes`` > 0 in the replan record), an integer >= 1, or 0 (none: the negotiation's
            or ``max_iterations``). It takes precedence over ``negotiation_max_iterations``: the approach walks
            with the walking budget and only the updates that see the crossing pay for it.
        crossing_iterations_hold: the ``crossing_max_iterations`` budget is kept this long [s] after the last update
            whose horizon held a crossing swing (>= 0; 0: none): the H1, both feet just across with its DCM behind
            them, failed at the first update back on the walking budget.
        fast_max_iterations: FDDP iterations per MPC update while the planner's forward command |v_x| (heading
            frame, the user's plus the speed integral's, ``sequencer_v_x`` in the replan record) is at least
            ``fast_speed``, an integer >= 1, or 0 (``max_iterations`` at every speed). The crossing and negotiation
            budgets take precedence. A walk at speed changes the OCP more from one update to the next (shorter,
            quicker steps): the H1 at 1.0 m/s kept its MPC cost 10-100x lower with 4 iterations than with 3
            (docs/closed_loop.md "The H1 at 1.0 m/s, session 20").
        fast_swing_path_weight: the OCP's ``swing_path_weight`` (the swing foot's (x, y) along a path from lift-off to
            its foothold, at rest at both ends with the "smooth" timing) from that speed (or ``fast_swing_path_speed``)
            on, >= 0 (0: the OCP's own at every speed). It needs the OCP's swing path terms (``swing_path_weight`` or
            ``obstacle_swing_path_weight`` > 0). At 1.0 m/s the H1's swing foot, free between lift-off and touchdown,
            stayed back and then landed 5-7 cm short of its foothold, still moving (docs/closed_loop.md "The H1 at
            1.0 m/s, session 20").
        fast_speed: [m/s], > 0 when ``fast_max_iterations`` is set, or ``fast_swing_path_weight`` without
            ``fast_swing_path_speed``, else 0: the planned |v_x| from which they apply.
        fast_swing_path_speed: [m/s], the planned |v_x| from which ``fast_swing_path_weight`` applies instead of
            ``fast_speed``, > 0 (only with ``fast_swing_path_weight`` set), or 0 (``fast_speed``): the swing path can
            then be tracked from a lower speed than the one that buys the extra FDDP iterations.
    """

    n_nodes: int = 100
    node_dt: float = 0.01
    replan_period: float = 0.01
    max_iterations: int = 1
    mpc_horizon_end: str = "repeat"
    mpc_restart_after_failures: int | None = None
    mpc_prepare: bool = True
    mpc_time_budget: float | None = None
    delay_nodes: int = 1
    computation_delay: float = 0.0
    interpolate: bool = False
    feedback: bool = True
    touchdown_detection: str = "contact"
    touchdown_wait_nodes: int = 2
    touchdown_wait_depth: float = 0.005
    first_stance_foot: str = "left"
    start_double_support: float = 0.0
    velocity_integral_gain: float = 0.0
    lateral_velocity_integral_gain: float = 0.0
    velocity_correction_max: float = 0.3
    velocity_filter_time: float = 1.0
    lipm_correction_gain: float = 0.2
    lipm_correction_max_error: float = 0.015
    lipm_correction_max_slide: float = 0.01
    stance_drift_max: float = 0.05
    dcm_offset_bias_max: float = 0.01
    stance_slide_follow: float | None = 0.02
    mpc_failure_times: tuple[float, ...] = ()
    sequencer_params_from: tuple[float, Any] | None = None
    planner_backend: str = "exact"
    negotiation_lookahead: float = 0.0
    negotiation_corridor: float = 0.3
    negotiation_release: float = 0.05
    negotiation_speed_max: float = float("inf")
    negotiation_deceleration: float = 0.0
    negotiation_max_iterations: int = 0
    negotiation_swing_path_weight: float = 0.0
    crossing_max_iterations: int = 0
    crossing_iterations_hold: float = 0.0
    fast_max_iterations: int = 0
    fast_swing_path_weight: float = 0.0
    fast_speed: float = 0.0
    fast_swing_path_speed: float = 0.0

    def __post_init__(self) -> None:
        for name in ("mpc_prepare", "interpolate", "feedback"):
            value = getattr(self, name)
            if not isinstance(value, (bool, np.bool_)):
                raise ParameterError(f"{name}={value!r} must be True or False")
        if not (isinstance(self.n_nodes, int) and self.n_nodes >= 2):
            raise ParameterError(f"n_nodes={self.n_nodes!r} must be an integer >= 2")
        for name in ("node_dt", "replan_period"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ParameterError(f"{name}={value} s must be a finite positive number")
        budget = self.mpc_time_budget
        if budget is not None and (isinstance(budget, bool) or not isinstance(budget, (int, float))
                                   or not 0.0 < budget < 1.0):
            raise ParameterError(f"mpc_time_budget={budget!r} must be None or a number of seconds in (0, 1)")
        if not (np.isfinite(self.computation_delay) and 0.0 <= self.computation_delay <= 0.1):
            raise ParameterError(f"computation_delay={self.computation_delay} s must be in [0, 0.1] s")
        if not (np.isfinite(self.start_double_support) and 0.0 <= self.start_double_support <= 60.0):
            raise ParameterError(f"start_double_support={self.start_double_support} s must be in [0, 60] s")
        for name in ("velocity_integral_gain", "lateral_velocity_integral_gain"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ParameterError(f"{name}={value} 1/s must be a finite number >= 0")
        if not (np.isfinite(self.velocity_filter_time) and self.velocity_filter_time > 0):
            raise ParameterError(f"velocity_filter_time={self.velocity_filter_time} s must be > 0")
        if not (np.isfinite(self.lipm_correction_gain) and 0.0 <= self.lipm_correction_gain <= 1.0):
            raise ParameterError(f"lipm_correction_gain={self.lipm_correction_gain} must be in [0, 1]")
        if not (np.isfinite(self.dcm_offset_bias_max) and 0.0 <= self.dcm_offset_bias_max <= 0.05):
            raise ParameterError(f"dcm_offset_bias_max={self.dcm_offset_bias_max} m must be in [0, 0.05] m")
        if not (np.isfinite(self.stance_drift_max) and 0.0 <= self.stance_drift_max <= 0.1):
            raise ParameterError(f"stance_drift_max={self.stance_drift_max} m must be in [0, 0.1] m")
        if self.stance_slide_follow is not None and not (
            np.isfinite(self.stance_slide_follow) and self.stance_slide_follow > 0
        ):
            raise ParameterError(f"stance_slide_follow={self.stance_slide_follow} m must be None or > 0")
        if not (np.isfinite(self.velocity_correction_max) and self.velocity_correction_max >= 0):
            raise ParameterError(f"velocity_correction_max={self.velocity_correction_max} m/s must be >= 0")
        if self.delay_nodes not in (0, 1):
            raise ParameterError(f"delay_nodes={self.delay_nodes!r} must be 0 (no delay) or 1 (paper)")
        if self.touchdown_detection not in TOUCHDOWN_DETECTIONS:
            raise ParameterError(
                f"touchdown_detection={self.touchdown_detection!r} must be one of {TOUCHDOWN_DETECTIONS}"
            )
        if isinstance(self.touchdown_wait_nodes, bool) or not isinstance(self.touchdown_wait_nodes, int) \
                or not 0 <= self.touchdown_wait_nodes <= 10:
            raise ParameterError(f"touchdown_wait_nodes={self.touchdown_wait_nodes!r} must be an integer in [0, 10]")
        for name, high in (("lipm_correction_max_error", 0.1), ("lipm_correction_max_slide", 0.1),
                           ("touchdown_wait_depth", 0.02)):
            value = getattr(self, name)
            if not (np.isfinite(value) and 0.0 <= value <= high):
                raise ParameterError(f"{name}={value} m must be in [0, {high}] m")
        for name, high in (("negotiation_lookahead", 10.0), ("negotiation_corridor", 5.0),
                           ("negotiation_release", 1.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not (np.isfinite(value) and 0.0 <= value <= high):
                raise ParameterError(f"{name}={value!r} m must be in [0, {high}] m")
        if isinstance(self.negotiation_speed_max, bool) or not self.negotiation_speed_max > 0:
            raise ParameterError(f"negotiation_speed_max={self.negotiation_speed_max!r} m/s must be > 0 (inf: none)")
        if isinstance(self.negotiation_deceleration, bool) or not (np.isfinite(self.negotiation_deceleration)
                                                                   and self.negotiation_deceleration >= 0.0):
            raise ParameterError(f"negotiation_deceleration={self.negotiation_deceleration!r} m/s^2 must be finite and "
                                 f">= 0 (0: at once)")
        if self.planner_backend not in ("exact", "osqp", "proxqp"):
            raise ParameterError(f"planner_backend={self.planner_backend!r} must be 'exact', 'osqp' or 'proxqp'")
        if self.first_stance_foot not in ("left", "right"):
            raise ParameterError(f"first_stance_foot={self.first_stance_foot!r} must be 'left' or 'right'")
        if not (isinstance(self.max_iterations, int) and self.max_iterations >= 1):
            raise ParameterError(f"max_iterations={self.max_iterations!r} must be an integer >= 1")
        for name, fallback in (("negotiation_max_iterations", "max_iterations"),
                               ("crossing_max_iterations", "the negotiation's or max_iterations")):
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, int) and value >= 0):
                raise ParameterError(f"{name}={value!r} must be 0 ({fallback}) or an integer >= 1")
        fast = self.fast_max_iterations
        if isinstance(fast, bool) or not (isinstance(fast, int) and fast >= 0):
            raise ParameterError(f"fast_max_iterations={fast!r} must be 0 (max_iterations) or an integer >= 1")
        negotiation_path = self.negotiation_swing_path_weight
        if isinstance(negotiation_path, bool) or not (np.isfinite(negotiation_path) and negotiation_path >= 0.0):
            raise ParameterError(f"negotiation_swing_path_weight={negotiation_path!r} must be finite and >= 0 "
                                 f"(0: the OCP's own)")
        path = self.fast_swing_path_weight
        if isinstance(path, bool) or not (np.isfinite(path) and path >= 0.0):
            raise ParameterError(f"fast_swing_path_weight={path!r} must be finite and >= 0 (0: the OCP's own)")
        path_speed = self.fast_swing_path_speed
        if isinstance(path_speed, bool) or not (np.isfinite(path_speed) and (path_speed >= 0.0 if path
                                                                            else path_speed == 0.0)):
            raise ParameterError(f"fast_swing_path_speed={path_speed!r} m/s must be >= 0 (0: fast_speed) with "
                                 f"fast_swing_path_weight={path} set, 0 without")
        speed = self.fast_speed
        if fast or (path and not path_speed):
            allowed = speed > 0.0
        else:  # unused with fast_swing_path_speed alone, which then needs no fast_speed
            allowed = speed >= 0.0 if path else speed == 0.0
        if isinstance(speed, bool) or not (np.isfinite(speed) and allowed):
            raise ParameterError(f"fast_speed={speed!r} m/s must be > 0 with fast_max_iterations={fast} or "
                                 f"fast_swing_path_weight={path} set (0 without)")
        hold = self.crossing_iterations_hold
        if isinstance(hold, bool) or not (np.isfinite(hold) and 0.0 <= hold <= 10.0):
            raise ParameterError(f"crossing_iterations_hold={hold!r} s must be in [0, 10] s")
        restart = self.mpc_restart_after_failures
        if restart is not None and (isinstance(restart, bool) or not isinstance(restart, int) or restart < 0):
            raise ParameterError(f"mpc_restart_after_failures={restart!r} must be None, 0 (never) or an integer >= 1")
        if self.mpc_horizon_end not in HORIZON_ENDS:
            raise ParameterError(f"mpc_horizon_end={self.mpc_horizon_end!r} must be one of {HORIZON_ENDS}")
        if self.sequencer_params_from is not None:
            switch = self.sequencer_params_from
            if not (isinstance(switch, tuple) and len(switch) == 2 and np.isfinite(switch[0]) and switch[0] >= 0):
                raise ParameterError(
                    f"sequencer_params_from={switch!r} must be None or (t_switch >= 0 [s], SequencerParams or AlipParams)"
                )
