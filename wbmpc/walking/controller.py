"""Controllers for the closed loop: the interface, a posture-holding PD and the paper's walking controller.

A controller is driven by the runner (``sim.runner``) at two rates:

- ``replan(t, measurement)`` every ``replan_period`` (10 ms in the paper): the slow, expensive part
  (footstep sequencer + whole-body MPC). Returns a flat dict of scalars that the runner logs.
- ``compute(t, measurement)`` at every simulation tick (1 kHz): the torque command, shape (nu,) [N·m].
  The runner clips it to the torque limits and logs both the command and the applied torque.

Every state is in the Pinocchio convention (see :class:`wbmpc.walking.measurement.Measurement`).

The :class:`WalkingController` is the pipeline of section III.C of the paper: measured DCM
``zeta = c + c_dot / omega`` -> footstep sequencer -> per-node contact schedule -> whole-body MPC
(warm start, one FDDP iteration) -> at 1 kHz the Riccati feedback of eqs. (25)-(26)::

    tau = u_k + K_k (x_meas ⊖ x_k),     K = du*/dx  (library-wide gain convention)

where ⊖ is ``pin.difference`` on q and a plain difference on v, and k is node 1 of the latest
solution (the paper's computation-delay model) or node 0 (``delay_nodes=0``), advanced by the time
elapsed since that solution was computed (so a failed update keeps following the last good plan).
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError
from wbmpc.walking.measurement import Measurement
from wbmpc.walking.stance import TOUCHDOWN_DETECTIONS, StanceTracker

GRAVITY = 9.81  # [m/s^2]


@runtime_checkable
class Controller(Protocol):
    """What the runner needs from a controller."""

    replan_period: float  # [s], period of ``replan``; a multiple of the simulation time step

    def reset(self, robot: Any, x0: np.ndarray, t0: float) -> None:
        """Prepare a new episode from state ``x0`` (nq + nv, Pinocchio) at time ``t0`` [s]."""

    def replan(self, t: float, measurement: Measurement) -> dict[str, float]:
        """Slow update (planning); returns scalars to log (same keys at every call)."""

    def compute(self, t: float, measurement: Measurement) -> np.ndarray:
        """Torque command at time ``t``, shape (nu,) [N·m], before clipping."""


class JointPDController:
    """Holds the robot's reference posture with a joint PD (no balance: Bolt falls within ~1 s).

    Useful to exercise the runner (logging, fall detection) without any planning.

    Args:
        kp: proportional gain [N·m/rad], > 0.
        kd: derivative gain [N·m·s/rad], >= 0.
        replan_period: period of the (empty) slow update [s].
    """

    def __init__(self, kp: float = 3.0, kd: float = 0.05, replan_period: float = 0.01) -> None:
        if not kp > 0:
            raise ParameterError(f"kp={kp} N·m/rad must be > 0")
        if not kd >= 0:
            raise ParameterError(f"kd={kd} N·m·s/rad must be >= 0")
        self.kp, self.kd, self.replan_period = float(kp), float(kd), float(replan_period)
        self._q_joints_reference = None
        self._nq = 0

    def reset(self, robot: Any, x0: np.ndarray, t0: float) -> None:
        self._nq = robot.pinocchio_model.nq
        self._q_joints_reference = np.asarray(robot.q_reference)[7:].copy()

    def replan(self, t: float, measurement: Measurement) -> dict[str, float]:
        return {}

    def compute(self, t: float, measurement: Measurement) -> np.ndarray:
        q_joints = measurement.x[7 : self._nq]
        v_joints = measurement.x[self._nq + 6 :]
        return self.kp * (self._q_joints_reference - q_joints) - self.kd * v_joints


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
            horizon: "rollout" (default) or "repeat" (see ``wbmpc.walking.WalkingMPC``). With "repeat",
            1 iteration per update falls (see ``max_iterations``).
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
        first_stance_foot: stance foot at t0 (both feet are on the ground at start; the other one
            takes the first step).
        velocity_command: initial (v_x, v_y) command [m/s] (world frame); None keeps the preset's.
        velocity_integral_gain: integral action on the forward speed [1/s] (0 = off, the default and
            the paper's pipeline): the sequencer is given v*_x + k ∫ (v*_x − v̄_x) dt, v̄ the CoM
            velocity low-passed over ``velocity_filter_time``, the correction bounded by
            ``velocity_correction_max`` (and the integral clamped accordingly: anti-windup). It was
            on (k = 1) while Bolt settled at 0.6 m/s for 0.33 m/s; that bias came from hovering
            touchdowns and the LIPM's missing swing drift (fixed, see ``default_ocp_config`` and
            ``lipm_correction_gain``), and with k = 1 the 20 s walk now overshoots to 0.48 m/s
            during the ramp and ends with a larger mean error (8.5 against 6.7 mm/s).
        velocity_correction_max: bound of that correction [m/s].
        velocity_filter_time: time constant of the low-pass filter on the measured speed [s].
        lipm_correction_gain: per-step gain in [0, 1] of two corrections of the sequencer's LIPM,
            identified after every step from the measured DCM (0 = off: the paper's pure LIPM and
            the parameters' own ``swing_drift``, ``dcm_offset_bias``). (1) Swing drift
            (``SequencerParams.swing_drift``): the DCM's gain over the LIPM during the stance that
            just ended, d = zeta_T - p - (zeta_0 - p) exp(omega T) (zeta_0, zeta_T measured at its
            touchdown and at the next one, p the stance foot), per unit of the step taken,
            kappa_k = d / L (steps of at least ``LIPM_CORRECTION_MIN_STEP``). (2) Touchdown offset
            bias (``SequencerParams.dcm_offset_bias``): measured DCM offset at the touchdown minus
            the offset the plan aimed at. Each estimate moves by this fraction towards the step's
            value. On Bolt the swing leg (the legs are half of the robot's mass) makes the DCM
            outrun the LIPM by ~0.22 L per step and the touchdowns end ~2.5 mm ahead of the plan:
            uncorrected, the sequencer answers with long, quick steps (0.12 m/s too fast with the
            touchdown fixes, docs/closed_loop.md).
        swing_drift_max: bound of each step's kappa_k and of the estimate, in [0, 0.9].
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
        sequencer_params: ``sequencer.SequencerParams``; None = :func:`default_sequencer_params`.
        sequencer_params_from: None, or (t_switch [s], ``SequencerParams``): from the first
            touchdown at or after t_switch on, the sequencer uses these parameters instead (the
            current velocity command, integral correction included, and the identified LIPM
            corrections carry over). At a touchdown, not in the middle of a step: switching to
            fixed timing mid-step moved the current touchdown by up to T_nom - T (58 ms were seen)
            at once. Used to compare gaits after a common start, e.g. fixed step timing from
            t_switch (a start from standing with fixed timing falls).
        sequencer_backend: QP backend of the sequencer: "exact" (closed-form solution of the same QP,
            verified against OSQP in the sequencer tests, fastest), "osqp" (the paper's) or "proxqp".
        ocp: ``wbmpc.walking.WalkingOCPConfig``; None = :func:`default_ocp_config` (the OCP's defaults with
            the planned footholds tracked, see there).
    """

    n_nodes: int = 100
    node_dt: float = 0.01
    replan_period: float = 0.01
    max_iterations: int = 1
    mpc_horizon_end: str = "rollout"
    mpc_prepare: bool = True
    mpc_time_budget: float | None = None
    delay_nodes: int = 1
    computation_delay: float = 0.0
    interpolate: bool = False
    feedback: bool = True
    touchdown_detection: str = "contact"
    first_stance_foot: str = "left"
    velocity_command: tuple[float, float] | None = None
    velocity_integral_gain: float = 0.0
    velocity_correction_max: float = 0.3
    velocity_filter_time: float = 1.0
    lipm_correction_gain: float = 0.2
    swing_drift_max: float = 0.5
    dcm_offset_bias_max: float = 0.01
    stance_slide_follow: float | None = 0.02
    mpc_failure_times: tuple[float, ...] = ()
    sequencer_params: Any = None
    sequencer_params_from: tuple[float, Any] | None = None
    sequencer_backend: str = "exact"
    ocp: Any = None

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
        if not (np.isfinite(self.velocity_integral_gain) and self.velocity_integral_gain >= 0):
            raise ParameterError(f"velocity_integral_gain={self.velocity_integral_gain} 1/s must be >= 0")
        if not (np.isfinite(self.velocity_filter_time) and self.velocity_filter_time > 0):
            raise ParameterError(f"velocity_filter_time={self.velocity_filter_time} s must be > 0")
        if not (np.isfinite(self.lipm_correction_gain) and 0.0 <= self.lipm_correction_gain <= 1.0):
            raise ParameterError(f"lipm_correction_gain={self.lipm_correction_gain} must be in [0, 1]")
        if not (np.isfinite(self.dcm_offset_bias_max) and 0.0 <= self.dcm_offset_bias_max <= 0.05):
            raise ParameterError(f"dcm_offset_bias_max={self.dcm_offset_bias_max} m must be in [0, 0.05] m")
        if not (np.isfinite(self.swing_drift_max) and 0.0 <= self.swing_drift_max <= 0.9):
            raise ParameterError(f"swing_drift_max={self.swing_drift_max} must be in [0, 0.9]")
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
        if self.first_stance_foot not in ("left", "right"):
            raise ParameterError(f"first_stance_foot={self.first_stance_foot!r} must be 'left' or 'right'")
        if not (isinstance(self.max_iterations, int) and self.max_iterations >= 1):
            raise ParameterError(f"max_iterations={self.max_iterations!r} must be an integer >= 1")
        from wbmpc.ocp.mpc import HORIZON_ENDS

        if self.mpc_horizon_end not in HORIZON_ENDS:
            raise ParameterError(f"mpc_horizon_end={self.mpc_horizon_end!r} must be one of {HORIZON_ENDS}")
        if self.sequencer_params_from is not None:
            switch = self.sequencer_params_from
            if not (isinstance(switch, tuple) and len(switch) == 2 and np.isfinite(switch[0]) and switch[0] >= 0):
                raise ParameterError(
                    f"sequencer_params_from={switch!r} must be None or (t_switch >= 0 [s], SequencerParams)"
                )


@dataclass
class _Reference:
    """The solution the 1 kHz loop follows (a snapshot of the last good MPC solution)."""

    t: float  # time of node 0 [s]
    xs: np.ndarray  # (N+1, nx)
    us: np.ndarray  # (N, nu)
    K: np.ndarray  # (N, nu, ndx)


@dataclass
class _Timers:
    sequencer: float = 0.0
    mpc: float = 0.0
    mpc_prepare: float = 0.0
    feedback: float = 0.0


class WalkingController:
    """Footstep sequencer + whole-body MPC at ``replan_period`` + Riccati feedback at every tick.

    Args:
        config: :class:`WalkingControllerConfig`.
        mpc_solver: callable (problem, default solver) -> solver with
            :class:`wbmpc.ocp.mpc.MPCSolver`'s interface, the MPC's solver (the benchmarks pass
            Crocoddyl's FDDP behind an adapter); None = the library's FDDP.
    """

    def __init__(self, config: WalkingControllerConfig | None = None, mpc_solver=None) -> None:
        self.config = config or WalkingControllerConfig()
        self.mpc_solver = mpc_solver
        self.replan_period = self.config.replan_period
        self.timers = _Timers()
        self._pending_failures: list[float] = sorted(float(t) for t in self.config.mpc_failure_times)

    # ------------------------------------------------------------------ episode setup
    def reset(self, robot: Any, x0: np.ndarray, t0: float) -> None:
        from sequencer import FootstepSequencer
        from wbmpc.walking.mpc import WalkingMPC

        cfg = self.config
        self.robot = robot
        self.model = robot.pinocchio_model
        self.data = self.model.createData()
        self.nq, self.nv = self.model.nq, self.model.nv
        self.feet = tuple(robot.foot_frames.keys())
        self.frame_ids = [self.model.getFrameId(robot.foot_frames[f]) for f in self.feet]
        params = cfg.sequencer_params or default_sequencer_params()
        if cfg.velocity_command is not None:
            params = _with_velocity(params, cfg.velocity_command)
        self.sequencer_params = params
        self.sequencer = FootstepSequencer(params, backend=cfg.sequencer_backend)
        self._params_switch = cfg.sequencer_params_from  # applied once, at the first touchdown at or after its time
        if self._params_switch is not None and self._params_switch[1].z_c != params.z_c:
            raise ParameterError(
                f"sequencer_params_from z_c={self._params_switch[1].z_c} m must equal the initial "
                f"sequencer_params z_c={params.z_c} m (the LIPM frequency omega is fixed for the run)"
            )
        self.command = np.array([params.v_x, getattr(params, "v_y", 0.0)], dtype=float)
        self._velocity_filtered = np.zeros(2)  # Bolt starts at rest
        self._velocity_integral = np.zeros(2)
        self.com_height = _com_height(params)  # LIPM z_c [m], also the terminal CoM height reference
        self.omega = float(np.sqrt(GRAVITY / self.com_height))
        self.mpc = WalkingMPC(
            robot,
            cfg.ocp if cfg.ocp is not None else default_ocp_config(),
            n_nodes=cfg.n_nodes,
            dt=cfg.node_dt,
            max_iterations=cfg.max_iterations,
            horizon_end=cfg.mpc_horizon_end,
            time_budget=cfg.mpc_time_budget,
            solver=self.mpc_solver,
        )
        self.stance = StanceTracker(self.feet, cfg.touchdown_detection)
        feet_world = self._feet_position(np.asarray(x0)[: self.nq])
        stance_index = self.feet.index(cfg.first_stance_foot)
        self.stance.reset(cfg.first_stance_foot, feet_world[stance_index, :2], t0)
        self.plan = None
        self.reference: _Reference | None = None
        self._pending: list[tuple[float, _Reference]] = []  # (activation time [s], solution)
        self.n_failures = 0
        self.timers = _Timers()
        self._pending_failures = sorted(float(t) for t in cfg.mpc_failure_times)
        self._x_ref = np.zeros(self.nq + self.nv)
        # (touchdown time [s], swing drift kappa of the stance that ended, touchdown offset error [m])
        self.lipm_correction_steps: list[tuple[float, float, float]] = []
        self._stance_record: tuple[float, np.ndarray, np.ndarray, bool] | None = None  # (t, DCM, foot, steady)
        self._stance_slide = 0.0  # [m], largest distance of the stance foot from its touchdown point so far
        self._stance_plan_position = self.stance.state.position.copy()  # stance position given to the sequencer

    def set_velocity_command(self, v_x: float, v_y: float = 0.0) -> None:
        """Change the walking velocity command [m/s] (takes effect at the next replan)."""
        self.command = np.array([v_x, v_y], dtype=float)
        self._apply_sequencer_velocity(self.command + self._velocity_correction())

    def _velocity_correction(self) -> np.ndarray:
        bound = self.config.velocity_correction_max
        return np.clip(self.config.velocity_integral_gain * self._velocity_integral, -bound, bound)

    def _apply_sequencer_velocity(self, velocity: np.ndarray) -> None:
        from sequencer import FootstepSequencer

        current = np.array([self.sequencer_params.v_x, getattr(self.sequencer_params, "v_y", 0.0)])
        if np.max(np.abs(current - velocity)) > 1e-4:
            self.sequencer_params = _with_velocity(self.sequencer_params, tuple(velocity))
            self.sequencer = FootstepSequencer(self.sequencer_params, backend=self.config.sequencer_backend)

    def _switch_sequencer_params(self, params: Any) -> None:
        """Plan with ``params`` from now on, keeping the current sequencer velocity (command + correction)."""
        from sequencer import FootstepSequencer

        velocity = (self.sequencer_params.v_x, getattr(self.sequencer_params, "v_y", 0.0))
        params = _with_velocity(params, velocity)
        if self.config.lipm_correction_gain > 0.0:  # the identified corrections carry over
            params = dataclasses.replace(params, swing_drift=self.sequencer_params.swing_drift,
                                         dcm_offset_bias=self.sequencer_params.dcm_offset_bias)
        self.sequencer_params = params
        self.sequencer = FootstepSequencer(self.sequencer_params, backend=self.config.sequencer_backend)
        self._params_switch = None

    def _update_velocity_integral(self, com_velocity_xy: np.ndarray) -> None:
        if self.config.velocity_integral_gain <= 0:
            return
        period = self.config.replan_period
        alpha = period / (self.config.velocity_filter_time + period)
        self._velocity_filtered += alpha * (com_velocity_xy - self._velocity_filtered)
        # forward speed only: a lateral correction would shift the sequencer's nominal step widths
        self._velocity_integral[0] += (self.command[0] - self._velocity_filtered[0]) * period
        bound = self.config.velocity_correction_max / self.config.velocity_integral_gain  # anti-windup
        np.clip(self._velocity_integral, -bound, bound, out=self._velocity_integral)
        self._apply_sequencer_velocity(self.command + self._velocity_correction())

    def _measure_stance_slide(self, feet_world: np.ndarray) -> float:
        """Distance [m] of the current stance foot from its touchdown point (also kept as the stance's maximum)."""
        state = self.stance.state
        slide = float(np.linalg.norm(feet_world[self.feet.index(state.foot), :2] - state.position))
        self._stance_slide = max(self._stance_slide, slide)
        return slide

    def _update_stance_slide(self, switched: bool, slide: float, feet_world: np.ndarray,
                             foot_in_contact: np.ndarray) -> float:
        """Track how far the stance foot has slid from its touchdown point; past
        ``stance_slide_follow`` the sequencer plans from where the foot is.

        Args:
            switched: the stance switched at this replan.
            slide: :meth:`_measure_stance_slide` before the switch [m] (the stance foot's slide
                when there was no switch; re-measured for the new stance foot after one).

        Returns:
            at a stance switch, the largest slide [m] of the stance that just ended; otherwise 0.
        """
        ended = 0.0
        if switched:  # the measurement before the switch covered the old stance foot up to now
            ended = self._stance_slide
            self._stance_slide = 0.0
            self._stance_plan_position = self.stance.state.position.copy()
            slide = self._measure_stance_slide(feet_world)
        index = self.feet.index(self.stance.state.foot)
        tolerance = self.config.stance_slide_follow
        if tolerance is not None and slide > tolerance and foot_in_contact[index]:
            self._stance_plan_position = feet_world[index, :2].copy()
        return ended

    def _update_lipm_corrections(
        self, t: float, dcm: np.ndarray, switched: bool, plan: Any, ended_slide: float = 0.0
    ) -> None:
        """At a touchdown: identify the swing drift and the touchdown offset bias (see the config).

        Only undisturbed steps count: a step is used when the DCM at both of its touchdowns was
        within ``LIPM_CORRECTION_MAX_ERROR`` of where the plan had put it (a push, a slip or a
        stumble is not a model error) and its stance foot stayed within ``LIPM_CORRECTION_MAX_SLIDE``
        of its touchdown point (``ended_slide``, the largest distance measured during the stance):
        the drift is measured against that point, and 1 cm of slide along x would change the
        step's kappa by about (exp(omega T) - 1) 1 cm / L, i.e. 0.4 for a 0.11 m step.
        """
        if not switched:
            return
        previous = self._stance_record
        foot = np.array(self.stance.state.position, dtype=float)
        landed = plan is not None and len(plan.steps) and plan.steps[0].foot == self.stance.state.foot
        error = (dcm - foot) - plan.steps[0].dcm_offset if landed else np.full(2, np.inf)
        steady = bool(np.all(np.abs(error) <= LIPM_CORRECTION_MAX_ERROR))
        self._stance_record = (t, dcm.copy(), foot, steady)
        gain = self.config.lipm_correction_gain
        # the first stance includes the start from standing; a stance foot that slid moved the LIPM's pivot
        slipped = ended_slide > LIPM_CORRECTION_MAX_SLIDE
        if previous is None or gain <= 0.0 or not (steady and previous[3]) or slipped:
            return
        t0, dcm0, stance, _ = previous
        step = foot[0] - stance[0]
        if abs(step) < LIPM_CORRECTION_MIN_STEP:
            return
        params = self.sequencer_params
        growth = float(np.exp(self.omega * (t - t0)))
        excess = (dcm[0] - stance[0]) - (dcm0[0] - stance[0]) * growth  # DCM gained over the LIPM [m]
        kappa_max, bias_max = self.config.swing_drift_max, self.config.dcm_offset_bias_max
        kappa = float(np.clip(excess / step, 0.0, kappa_max))
        drift = float(np.clip(params.swing_drift + gain * (kappa - params.swing_drift), 0.0, kappa_max))
        offset_error = float(np.clip(error[0], -bias_max, bias_max))
        bias = float(np.clip(params.dcm_offset_bias + gain * (offset_error - params.dcm_offset_bias), -bias_max, bias_max))
        self.lipm_correction_steps.append((t, kappa, offset_error))
        if abs(drift - params.swing_drift) > 1e-4 or abs(bias - params.dcm_offset_bias) > 1e-5:
            from sequencer import FootstepSequencer

            self.sequencer_params = dataclasses.replace(params, swing_drift=drift, dcm_offset_bias=bias)
            self.sequencer = FootstepSequencer(self.sequencer_params, backend=self.config.sequencer_backend)

    # ------------------------------------------------------------------ helpers
    def _feet_position(self, q: np.ndarray) -> np.ndarray:
        pin.framesForwardKinematics(self.model, self.data, q)
        return np.array([self.data.oMf[i].translation for i in self.frame_ids])

    def _dcm(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        com = pin.centerOfMass(self.model, self.data, q, v)
        com_velocity = self.data.vcom[0]
        return com.copy(), com[:2] + com_velocity[:2] / self.omega

    # ------------------------------------------------------------------ 100 Hz
    def replan(self, t: float, measurement: Measurement) -> dict[str, float]:
        from sequencer import contact_schedule

        cfg = self.config
        x = measurement.x
        q, v = x[: self.nq], x[self.nq :]
        com, dcm = self._dcm(q, v)
        self._update_velocity_integral(np.array(self.data.vcom[0][:2]))
        feet_world = self._feet_position(q)

        # Stance switch from the previous plan (touchdown time reached, or early contact).
        first = self.plan.steps[0] if self.plan is not None and len(self.plan.steps) else None
        slide = self._measure_stance_slide(feet_world)
        switched = self.stance.update(
            t,
            None if first is None else first.foot,
            None if first is None else first.touchdown_time,
            self.stance.state.t_start,
            feet_world,
            measurement.foot_in_contact,
        )
        ended_slide = self._update_stance_slide(switched, slide, feet_world, measurement.foot_in_contact)
        self._update_lipm_corrections(t, dcm, switched, self.plan, ended_slide)
        if switched and self._params_switch is not None and t >= self._params_switch[0] - 1e-9:
            self._switch_sequencer_params(self._params_switch[1])

        record: dict[str, float] = {
            "stance_foot": float(self.feet.index(self.stance.state.foot)),
            "stance_x": self.stance.state.position[0],
            "stance_y": self.stance.state.position[1],
            "stance_slide": self._stance_slide,
            "sequencer_stance_x": self._stance_plan_position[0],
            "sequencer_stance_y": self._stance_plan_position[1],
            "t_stance_start": self.stance.state.t_start,
            "stance_switched": float(switched),
            "dcm_x": dcm[0],
            "dcm_y": dcm[1],
            "sequencer_ok": 1.0,
            "sequencer_v_x": float(self.sequencer_params.v_x),
            "swing_drift": float(self.sequencer_params.swing_drift),
            "dcm_offset_bias": float(self.sequencer_params.dcm_offset_bias),
        }

        tic = time.perf_counter()
        try:
            self.plan = self.sequencer.plan(
                t=t,
                stance_foot=self.stance.state.foot,
                stance_position=self._stance_plan_position,
                dcm_measured=dcm,
                t_stance_start=self.stance.state.t_start,
                clamp_elapsed=True,  # a late touchdown: plan as if it were T_max (touchdown now)
            )
        except Exception as err:  # infeasible step QP: keep following the last plan
            if self.plan is None or not _is_solver_failure(err):
                raise
            record["sequencer_ok"] = 0.0
        sequencer_time = time.perf_counter() - tic
        self.timers.sequencer += sequencer_time
        record["sequencer_time"] = sequencer_time
        step = self.plan.steps[0]
        record["next_foot"] = float(self.feet.index(step.foot))
        record["next_x"], record["next_y"] = float(step.position[0]), float(step.position[1])
        record["next_touchdown_time"] = float(step.touchdown_time)

        tic = time.perf_counter()
        plan_for_mpc = self.plan
        if cfg.touchdown_detection == "contact":
            plan_for_mpc, record["touchdown_wait"] = _wait_for_touchdown(
                self.plan, t, measurement.foot_in_contact[self.feet.index(step.foot)], cfg.node_dt
            )
        schedule = contact_schedule(plan_for_mpc, t, cfg.node_dt, cfg.n_nodes, rounding="nearest")
        com_terminal = _terminal_com(self.plan, t + cfg.n_nodes * cfg.node_dt, com, self.com_height)
        injected = bool(self._pending_failures) and t >= self._pending_failures[0] - 1e-9
        if injected:
            self._pending_failures.pop(0)
            ok, status, iterations, cost, solve_time = False, "injected_failure", 0, np.nan, 0.0
        else:
            solution = self.mpc.update(t, x, schedule, com_terminal)
            ok, status = bool(solution.ok), str(solution.status)
            record["mpc_prepared_used"] = float(getattr(self.mpc.problem, "prepared_used", 0))
            record["mpc_rollouts"] = float(getattr(self.mpc.solver, "rollouts", np.nan))
            iterations, cost, solve_time = int(solution.iterations), float(solution.cost), solution.solve_time
            if ok:
                reference = _Reference(
                    float(solution.t), np.array(solution.xs), np.array(solution.us), np.array(solution.K)
                )
                if cfg.computation_delay > 0.0 and self.reference is not None:
                    self._pending.append((t + cfg.computation_delay, reference))
                else:
                    self.reference = reference
        self.timers.mpc += time.perf_counter() - tic
        if not ok:
            self.n_failures += 1
        record.update(
            mpc_ok=float(ok),
            mpc_injected_failure=float(injected),
            mpc_iterations=float(iterations),
            mpc_cost=cost,
            mpc_solve_time=float(solve_time),
            mpc_tick_time=time.perf_counter() - tic,
            mpc_reference_age=np.nan if self.reference is None else t - self.reference.t,
            mpc_status_code=float(mpc_status_code(status)),
        )
        self.last_status = status
        if cfg.mpc_prepare and ok:  # the solution is handed over: prepare the next update
            tic = time.perf_counter()
            record["mpc_prepared_nodes"] = float(self.mpc.prepare())
            record["mpc_prepare_time"] = time.perf_counter() - tic
            self.timers.mpc_prepare += record["mpc_prepare_time"]
        return record

    # ------------------------------------------------------------------ 1 kHz
    def compute(self, t: float, measurement: Measurement) -> np.ndarray:
        while self._pending and self._pending[0][0] <= t + 1e-9:
            self.reference = self._pending.pop(0)[1]
        if self.reference is None:
            raise RuntimeError(
                "WalkingController.compute(): no MPC solution yet (the first update failed: "
                f"status {getattr(self, 'last_status', 'none')!r})"
            )
        tic = time.perf_counter()
        cfg, ref = self.config, self.reference
        n = ref.us.shape[0]
        elapsed_nodes = (t - ref.t) / cfg.node_dt
        base = int(np.floor(elapsed_nodes + 1e-9))
        k = min(max(base + cfg.delay_nodes, 0), n - 1)
        if cfg.interpolate and k + 1 < n:
            alpha = min(max(elapsed_nodes - base, 0.0), 1.0)
            u = (1.0 - alpha) * ref.us[k] + alpha * ref.us[k + 1]
            x_k, x_next = ref.xs[k], ref.xs[k + 1]
            self._x_ref[: self.nq] = pin.interpolate(self.model, x_k[: self.nq], x_next[: self.nq], alpha)
            self._x_ref[self.nq :] = (1.0 - alpha) * x_k[self.nq :] + alpha * x_next[self.nq :]
            x_ref = self._x_ref
        else:
            u, x_ref = ref.us[k], ref.xs[k]
        tau = np.array(u, dtype=float)
        if cfg.feedback:
            x = measurement.x
            dx = np.empty(2 * self.nv)
            dx[: self.nv] = pin.difference(self.model, x_ref[: self.nq], x[: self.nq])
            dx[self.nv :] = x[self.nq :] - x_ref[self.nq :]
            tau += ref.K[k] @ dx
        self.timers.feedback += time.perf_counter() - tic
        return tau


MAX_STEP_WIDTH = 0.30
"""Largest step width of the closed loop's sequencer [m] (bolt_walking preset: 0.20, Table I: 0.40)."""


def default_sequencer_params():
    """``SequencerParams.bolt_walking()`` with the largest step width raised to ``MAX_STEP_WIDTH``.

    The paper's 6.3 N, 0.1 s lateral push moves Bolt's DCM by about 0.25 m within two steps; with
    widths bounded at 0.20 m the stepping foot cannot catch it and Bolt fell (push at t = 5 s,
    seed 0), with 0.30 m it recovered. Table I allows 0.40 m; 0.30 m keeps the hip abduction
    Bolt can reach. The nominal width (0.10 m) is unchanged, so nominal walking is not affected.
    """
    from sequencer import SequencerParams

    return dataclasses.replace(
        SequencerParams.bolt_walking(), w_left_min=-MAX_STEP_WIDTH, w_right_max=MAX_STEP_WIDTH
    )


FOOTHOLD_WEIGHT = 1e5
"""Weight of the planned-foothold tracking in the closed loop's default OCP (see default_ocp_config)."""

TOUCHDOWN_HEIGHT_WEIGHT = 1e5
"""Weight of the ground height at the last swing node in the closed loop's default OCP."""


def default_ocp_config():
    """The walking OCP used by the closed loop: ``WalkingOCPConfig`` defaults + foothold tracking.

    The paper lets the footholds emerge from the whole-body OCP (no foothold cost). In MuJoCo
    with one FDDP iteration per update that lets the swing foot land up to 18 cm short of the
    sequencer's foothold once the steps lengthen, the DCM then outruns the feet and Bolt falls
    within 1.5 s; tracking the planned foothold at the last swing node (weight
    ``FOOTHOLD_WEIGHT``) keeps the executed steps on the plan (docs/closed_loop.md). With 1e4 the
    feet still landed ~7 mm short of it, each time a little more DCM offset for the next step
    (Bolt walked faster); with 1e5, 1-2 mm.

    The touchdown height term (``TOUCHDOWN_HEIGHT_WEIGHT``) puts the foot on the ground at the end
    of its planned swing. Without it the OCP's own plan ended the swing 7 mm above the ground
    (the eq. (19) height cost weighs a few millimetres at 1e4 x dt = 100), the foot hovered, no
    touchdown was ever measured, every stance switched on the 50 ms timeout of the stance tracker,
    and in those 50 ms the DCM ran on: Bolt settled at 0.62 m/s for 0.33 m/s (docs/closed_loop.md).
    """
    from wbmpc.walking.ocp import WalkingOCPConfig

    return WalkingOCPConfig(foothold_weight=FOOTHOLD_WEIGHT, touchdown_height_weight=TOUCHDOWN_HEIGHT_WEIGHT)


MPC_STATUS_CODES = {"converged": 0, "max_iter": 1, "failed": 2, "injected_failure": 3, "deadline": 4}
"""Numeric codes of the MPC statuses in the replan log (``mpc_status_code``); -1 = other."""


def mpc_status_code(status: str) -> int:
    """Code of an MPC status string ("failed: <reason>" counts as "failed")."""
    return MPC_STATUS_CODES.get(status.split(":", 1)[0], -1)


def _is_solver_failure(err: Exception) -> bool:
    from wbmpc.errors import SolverError

    return isinstance(err, SolverError) or type(err).__name__.lower().startswith("infeasible")


def _com_height(params: Any) -> float:
    for name in ("com_height", "z_c", "zc"):
        if hasattr(params, name):
            return float(getattr(params, name))
    raise ParameterError(f"sequencer parameters {type(params).__name__} have no CoM height field")


def _with_velocity(params: Any, command: tuple[float, float]) -> Any:
    v_x, v_y = float(command[0]), float(command[1])
    changes = {"v_x": v_x}
    if hasattr(params, "v_y"):
        changes["v_y"] = v_y
    elif v_y != 0.0:
        raise ParameterError(f"velocity_command v_y={v_y} m/s: the sequencer only takes a forward speed")
    return dataclasses.replace(params, **changes)


LIPM_CORRECTION_MIN_STEP = 0.03
"""Shortest step [m] from which the LIPM corrections are identified (stepping in place: little
swing drift and too little signal)."""

LIPM_CORRECTION_MAX_ERROR = 0.015
"""Largest difference [m] (x and y) between the measured and the planned DCM offset at a touchdown
for the step to count in the LIPM corrections (steady walking: 2-5 mm; after the paper's push: cm)."""


LIPM_CORRECTION_MAX_SLIDE = 0.01
"""Largest slide [m] of the stance foot from its touchdown point for the step to count in the LIPM
corrections (the point foot rolls 5-7 mm in undisturbed steps)."""


TOUCHDOWN_WAIT_NODES = 2
"""With contact detection, a swing foot still in the air when its touchdown is due is kept swinging
(and driven down by the height cost) for this many more nodes in the OCP's schedule."""


def _wait_for_touchdown(plan: Any, t: float, swing_foot_in_contact: bool, node_dt: float) -> tuple[Any, float]:
    """The plan shifted in time so that a due but not yet measured touchdown lies ahead.

    The sequencer re-plans a late touchdown to "now"; sampled as is, the OCP would hold the swing
    foot as a rigid contact wherever it is in the air (3-7 cm above the ground were seen), and the
    next solutions ask for large torques. Instead the whole sequence is delayed so that the swing
    ends ``TOUCHDOWN_WAIT_NODES`` nodes from now, its height reference reaching the ground there.

    Returns:
        (plan to sample, delay applied [s], 0 when none).
    """
    first = plan.steps[0]
    target = t + TOUCHDOWN_WAIT_NODES * node_dt
    if swing_foot_in_contact or first.touchdown_time >= target:
        return plan, 0.0
    delay = target - first.touchdown_time
    steps = tuple(dataclasses.replace(s, touchdown_time=s.touchdown_time + delay) for s in plan.steps)
    return dataclasses.replace(plan, steps=steps), delay


def _terminal_com(plan: Any, t_horizon: float, com: np.ndarray, height: float) -> np.ndarray:
    """CoM reference at the end of the horizon (eq. 24): LIPM prediction in xy, the LIPM height z_c.

    Holding z at z_c (not at the measured height) matters: with the measured height the terminal
    cost let the CoM creep up by 1 cm per second of walking (legs stretching) until Bolt fell.
    """
    com_xy = np.asarray(plan.lipm_com_at(t_horizon, com[:2]), dtype=float)
    return np.array([com_xy[0], com_xy[1], height])
