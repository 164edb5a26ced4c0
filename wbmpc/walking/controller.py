"""The walking controller: footstep planner + whole-body MPC every replan, Riccati feedback every tick.

The pipeline of section III.C of the paper, composed of parts that are each one concept:

- planning stage (:mod:`wbmpc.walking.planning`): measured reduced state, stance switches,
  online estimates (:mod:`wbmpc.walking.estimators`), footstep plan from a
  :class:`sequencer.planner.FootstepPlanner`;
- OCP reference stage (:mod:`wbmpc.walking.reference`): the plan sampled on the OCP grid (contact
  schedule, terminal CoM), with the touchdown handling of :mod:`wbmpc.walking.stance`;
- the whole-body MPC (:class:`~wbmpc.walking.mpc.WalkingMPC`: warm start, one FDDP iteration,
  last good plan kept on failure), prepared ahead between updates;
- the 1 kHz feedback law (:mod:`wbmpc.walking.feedback`), eqs. (25)-(26)::

      tau = u_k + K_k (x_meas ⊖ x_k),     K = du*/dx  (library-wide gain convention)

Everything it is tuned with comes from the robot's walking preset
(:func:`wbmpc.walking.preset.load_walking_preset`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from sequencer.alip.params import AlipParams
from sequencer.alip.planner import AlipFootstepPlanner
from sequencer.dcm_planner import DcmFootstepPlanner
from sequencer.params import SequencerParams
from sequencer.planner import VelocityCommand
from wbmpc.errors import NoSolutionError, ParameterError
from wbmpc.walking.controller_config import WalkingControllerConfig
from wbmpc.walking.feedback import FeedbackLaw
from wbmpc.walking.measurement import Measurement
from wbmpc.walking.mpc import WalkingMPC
from wbmpc.walking.negotiation import NEGOTIATION
from wbmpc.walking.planning import PlanningStage
from wbmpc.walking.preset import WalkingPreset, load_walking_preset
from wbmpc.walking.reference import OcpReferenceStage

MPC_STATUS_CODES = {"converged": 0, "max_iter": 1, "failed": 2, "injected_failure": 3, "deadline": 4}
"""Numeric codes of the MPC statuses in the replan log (``mpc_status_code``); -1 = other."""


def mpc_status_code(status: str) -> int:
    """Code of an MPC status string ("failed: <reason>" counts as "failed")."""
    return MPC_STATUS_CODES.get(status.split(":", 1)[0], -1)


@dataclass
class ControllerTimers:
    """Wall time spent in each part over a run [s]."""

    sequencer: float = 0.0
    mpc: float = 0.0
    mpc_prepare: float = 0.0
    feedback: float = 0.0


class WalkingController:
    """Footstep planner + whole-body MPC at ``replan_period`` + Riccati feedback at every tick.

    Args:
        preset: the robot's walking preset (a :class:`~wbmpc.walking.preset.WalkingPreset`), or
            None for Bolt's.
        mpc_solver: callable (problem, default solver) -> solver with
            :class:`wbmpc.ocp.mpc.MPCSolver`'s interface, the MPC's solver (the benchmarks pass
            Crocoddyl's FDDP behind an adapter); None = the library's FDDP.
        planner: a :class:`sequencer.planner.FootstepPlanner` to use instead of the preset's
            (``[footstep_planner]``: the DCM step QP of ``[planner]`` by default, or the ALIP NMPC).

    A planner that reads the measured angular momentum (attribute ``uses_angular_momentum``, the ALIP
    planner's) gets the whole body's about the stance contact when the preset's
    ``footstep_planner.angular_momentum`` is "exact" (the default), else None (its own approximation).
    """

    def __init__(self, preset: WalkingPreset | None = None, mpc_solver=None, planner=None) -> None:
        self.preset = load_walking_preset("bolt") if preset is None else preset
        self.config: WalkingControllerConfig = self.preset.controller
        ocp = self.preset.ocp
        for name in ("fast_swing_path_weight", "negotiation_swing_path_weight"):
            if getattr(self.config, name) and not (ocp.swing_path_weight or ocp.obstacle_swing_path_weight):
                raise ParameterError(f"{name}={getattr(self.config, name)} needs the OCP's swing path terms: "
                                     f"[ocp] swing_path_weight or obstacle_swing_path_weight > 0 (both are 0)")
        self._last_crossing_update: float | None = None  # [s], the last update whose horizon held a crossing
        self.replan_period = self.config.replan_period
        self.mpc_solver = mpc_solver
        self.planner = self._make_planner(self.preset.planner_params) if planner is None else planner
        self.omega = float(self.planner.omega)
        self.command = VelocityCommand()
        self.timers = ControllerTimers()
        self.planning: PlanningStage | None = None  # built by reset (it needs the robot)

    # ------------------------------------------------------------------ episode setup
    def _make_planner(self, params: SequencerParams | AlipParams):
        """The footstep planner of ``params``: the DCM step QP (SequencerParams, ``planner_backend``) or the
        ALIP NMPC (AlipParams, the preset's ``footstep_planner.alip_solver``)."""
        if isinstance(params, AlipParams):
            return AlipFootstepPlanner(params, solver=self.preset.footstep_planner.alip_solver)
        if isinstance(params, SequencerParams):
            return DcmFootstepPlanner(params, backend=self.config.planner_backend)
        raise ParameterError(f"footstep planner parameters must be SequencerParams or AlipParams, "
                             f"got {type(params).__name__}")

    def reset(self, robot: Any, x0: np.ndarray, t0: float) -> None:
        """Build the parts for ``robot`` at ``t0`` (the first :meth:`replan` then solves the MPC cold)."""
        cfg, preset = self.config, self.preset
        if robot.name != preset.robot:
            raise ParameterError(f"robot {robot.name!r} cannot walk with the walking preset of {preset.robot!r}")
        planner = self.planner
        switch = None
        if cfg.sequencer_params_from is not None:
            switch = (float(cfg.sequencer_params_from[0]), self._make_planner(cfg.sequencer_params_from[1]))
        measure = (getattr(planner, "uses_angular_momentum", False)
                   and preset.footstep_planner.angular_momentum == "exact")
        self.planning = PlanningStage(robot, planner, cfg, switch, measure_angular_momentum=measure)
        self.omega = self.planning.omega
        self.feet = self.planning.feet
        self.reference_stage = OcpReferenceStage(self.feet, cfg.n_nodes, cfg.node_dt,
                                                 cfg.touchdown_detection == "contact", cfg.touchdown_wait_nodes,
                                                 cfg.touchdown_wait_depth)
        self.mpc = WalkingMPC(robot, preset.ocp, n_nodes=cfg.n_nodes, dt=cfg.node_dt, max_iterations=cfg.max_iterations,
                              horizon_end=cfg.mpc_horizon_end, time_budget=cfg.mpc_time_budget, solver=self.mpc_solver,
                              restart_after_failures=cfg.mpc_restart_after_failures)
        self.feedback = FeedbackLaw(self.mpc.ocp.state, cfg.node_dt, cfg.delay_nodes, cfg.interpolate, cfg.feedback,
                                    cfg.computation_delay)
        self.planning.reset(x0, t0, self.command)
        self.n_failures = 0
        self._last_crossing_update = None
        self.last_status = "none"
        self.timers = ControllerTimers()
        self._pending_failures = sorted(float(t) for t in cfg.mpc_failure_times)

    def check_command(self, command) -> None:
        """Raise ParameterError (naming the component, its value and the allowed range) when the
        robot's preset (``[command]``) or the planner cannot follow ``command``; called before a run."""
        command = VelocityCommand.from_tuple(command)
        self.preset.command.check(command, self.preset.robot)
        self.planner.check_command(command)

    def set_velocity_command(self, command) -> None:
        """The walking command (v_x [m/s], v_y [m/s], yaw_rate [rad/s]) in the heading frame
        (a :class:`~sequencer.planner.VelocityCommand` or a tuple); takes effect at the next replan."""
        self.command = VelocityCommand.from_tuple(command)
        if self.planning is not None:
            self.planning.set_command(self.command)

    @property
    def plan(self):
        """The footstep plan followed now (None before the first replan)."""
        return self.planning.plan

    @property
    def negotiation_switches(self) -> list[tuple[float, int]]:
        """(time [s], mode code) of every walking/negotiation switch of the run
        (:mod:`wbmpc.walking.negotiation`: 0 walking, 1 negotiation)."""
        return [] if self.planning is None else list(self.planning.negotiation.switches)

    @property
    def stance(self):
        """The stance tracker (current stance foot, position, yaw, start time)."""
        return self.planning.stance

    @property
    def lipm_correction_steps(self) -> list[tuple[float, float, float]]:
        """(touchdown time [s], swing drift κ, touchdown offset error [m]) of each step the LIPM
        corrections were identified from (empty without a DCM planner)."""
        return [] if self.planning.lipm is None else self.planning.lipm.steps

    # ------------------------------------------------------------------ every replan
    def replan(self, t: float, measurement: Measurement) -> dict[str, float]:
        """Plan footsteps, sample them for the OCP, update the MPC; returns the scalars to log."""
        cfg = self.config
        x = measurement.x
        tic = time.perf_counter()
        plan, measured, record = self.planning.update(t, x, measurement.foot_in_contact, measurement.obstacles)
        self.timers.sequencer += record["sequencer_time"]
        planning = self.planning
        if planning.failing_since is not None and not self.reference_stage.covers(plan, t):
            raise NoSolutionError(
                f"the footstep planner has failed at every replan since t={planning.failing_since:.3f} s "
                f"({planning.failure_count} replans; last: {planning.last_failure}) and the last good plan's "
                f"steps end at {plan.touchdown_times[-1]:.3f} s, before the end of the MPC's horizon "
                f"{t + self.reference_stage.horizon:.3f} s: nothing left to follow"
            )
        tic = time.perf_counter()
        path_weight = self._swing_path_weight(record)
        reference = self.reference_stage.sample(plan, t, measured.com[:2], measurement.foot_in_contact,
                                                planning.swing_liftoff,
                                                liftoffs=self.mpc.ocp.config.swing_path_weight > 0 or bool(path_weight))
        if cfg.touchdown_detection == "contact":
            record["touchdown_wait"] = reference.touchdown_wait
        record["crossing_nodes"] = 0.0 if reference.crossings is None else float(np.sum(reference.crossings.index >= 0))
        injected = bool(self._pending_failures) and t >= self._pending_failures[0] - 1e-9
        if injected:
            self._pending_failures.pop(0)
            ok, status, iterations, cost, solve_time = False, "injected_failure", 0, np.nan, 0.0
            restart = False
        else:
            solution = self.mpc.update(t, x, reference.schedule, reference.com_terminal, reference.touchdown_depth,
                                       reference.crossings, max_iterations=self._iteration_budget(record, t),
                                       com_path=reference.com_path, swing_liftoff=reference.swing_liftoff,
                                       swing_path_weight=path_weight)
            ok, status = bool(solution.ok), str(solution.status)
            restart = bool(solution.restart)
            record["mpc_prepared_used"] = float(getattr(self.mpc.problem, "prepared_used", 0))
            record["mpc_rollouts"] = float(getattr(self.mpc.solver, "rollouts", np.nan))
            iterations, cost, solve_time = int(solution.iterations), float(solution.cost), solution.solve_time
            if ok:
                self.feedback.hand_over(t, solution)
        self.timers.mpc += time.perf_counter() - tic
        if not ok:
            self.n_failures += 1
        age = self.feedback.age_reference
        record.update(
            mpc_ok=float(ok),
            mpc_injected_failure=float(injected),
            mpc_restart=float(restart),
            mpc_iterations=float(iterations),
            mpc_cost=cost,
            mpc_solve_time=float(solve_time),
            mpc_tick_time=time.perf_counter() - tic,
            mpc_reference_age=np.nan if age is None else t - age,
            mpc_status_code=float(mpc_status_code(status)),
        )
        self.last_status = status
        if cfg.mpc_prepare and ok:  # the solution is handed over: prepare the next update
            tic = time.perf_counter()
            record["mpc_prepared_nodes"] = float(self.mpc.prepare())
            record["mpc_prepare_time"] = time.perf_counter() - tic
            self.timers.mpc_prepare += record["mpc_prepare_time"]
        return record

    def _iteration_budget(self, record: dict[str, float], t: float | None = None) -> int | None:
        """FDDP iterations of the update at ``t`` [s]: ``crossing_max_iterations`` while the horizon holds a crossing
        swing and ``crossing_iterations_hold`` after, else ``negotiation_max_iterations`` while negotiating, else
        ``fast_max_iterations`` at a planned |v_x| of ``fast_speed`` or more, else None (``max_iterations``); 0 means
        unset. An update that sees a crossing records its ``t`` (the hold's start)."""
        cfg = self.config
        if cfg.crossing_max_iterations:
            if record.get("crossing_nodes", 0.0) > 0:
                self._last_crossing_update = t
                return cfg.crossing_max_iterations
            last = self._last_crossing_update
            if t is not None and last is not None and t - last <= cfg.crossing_iterations_hold + 1e-9:
                return cfg.crossing_max_iterations
        if cfg.negotiation_max_iterations and record.get("negotiation_mode") == NEGOTIATION:
            return cfg.negotiation_max_iterations
        if cfg.fast_max_iterations and self._at_speed(record):
            return cfg.fast_max_iterations
        return None

    def _swing_path_weight(self, record: dict[str, float]) -> float | None:
        """The OCP's swing path weight of this replan: ``negotiation_swing_path_weight`` while negotiating, else
        ``fast_swing_path_weight`` at a planned |v_x| of ``fast_swing_path_speed`` (0: ``fast_speed``) or more, else
        None (the OCP's own)."""
        cfg = self.config
        if cfg.negotiation_swing_path_weight and record.get("negotiation_mode") == NEGOTIATION:
            return cfg.negotiation_swing_path_weight
        if cfg.fast_swing_path_weight and self._at_speed(record, cfg.fast_swing_path_speed or cfg.fast_speed):
            return cfg.fast_swing_path_weight
        return None

    def _at_speed(self, record: dict[str, float], speed: float | None = None) -> bool:
        """Whether this replan's planned |v_x| (``sequencer_v_x``) is at least ``speed`` [m/s] (default ``fast_speed``;
        > 0: the fast_* options apply; ``fast_swing_path_speed`` for the swing path)."""
        speed = self.config.fast_speed if speed is None else speed
        return speed > 0.0 and abs(record.get("sequencer_v_x", 0.0)) >= speed

    # ------------------------------------------------------------------ every tick
    def compute(self, t: float, measurement: Measurement) -> np.ndarray:
        """Torque command (nu,) [N·m] from the followed MPC solution and its gains."""
        tic = time.perf_counter()
        try:
            tau = self.feedback.control(t, measurement.x)
        except NoSolutionError as err:
            raise NoSolutionError(f"{err}: last MPC status {self.last_status!r}") from None
        self.timers.feedback += time.perf_counter() - tic
        return tau
