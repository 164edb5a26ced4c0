"""The closed loop: a scenario, a controller and MuJoCo at 1 kHz; returns a :class:`sim.log.RunLog`.

``run_scenario`` is a pure function of its arguments (scenario name and parameters, robot, seed):
it builds everything it needs, keeps no global state and returns plain data, so campaigns can run
trials in worker processes. The same seed gives the same log (timings aside).

Each tick (``model.opt.timestep``, 1 ms):

1. read MuJoCo's state and convert it to Pinocchio's convention (``robots.conventions``);
2. compute CoM, DCM and feet (logged for every controller), classify ground contacts, detect a fall;
3. build the measurement (optionally with Gaussian noise in the tangent space; with the walking
   preset's ``[perception]``, the obstacles the rangefinders have shown so far, scanned at their own
   rate from the measured pose: :class:`sim.perception.PerceptionPipeline`) and ask the scenario
   for its velocity command, given the measured base pose (x, y, yaw);
4. every ``controller.replan_period``: pass the scenario's velocity command, call ``replan``;
5. ``tau = controller.compute(...)``, clipped to the robot's torque limits, written to ``data.ctrl``;
6. the scenario acts (pushes), then ``mj_step``.

The tick logs grow by chunks of ``LOG_CHUNK_TICKS`` rows as the run goes (no allocation for
the whole duration up front: a long or open-ended ``duration`` costs memory only for the ticks run).

With perception on, the log's ``params["perception"]`` holds the scan counts and every reported
obstacle (first report time, last estimate), and ``params["obstacle_truth"]`` the scene's obstacles
of a scenario that places some (``true_obstacles()``, for the metrics only: the controller never sees
it); ``ticks["obstacle_contact"]`` records the robot's contacts with obstacles (:mod:`sim.falls`).

The log and ``metrics.json`` are written to ``out`` (when given) in a ``finally`` block, so a fall,
an exception or Ctrl-C still leaves a complete record of what happened up to that point.
"""

from __future__ import annotations

import dataclasses
import gc
import sys
import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import pinocchio as pin

from robots.conventions import base_yaw
from sequencer.planner import VelocityCommand
from sim.falls import ContactSensor, FallCriteria, detect_fall
from sim.log import RunLog
from sim.scenarios import make_scenario, scenario_class, scenario_parameters
from wbmpc.errors import NoSolutionError, ParameterError
from wbmpc.jsonable import to_jsonable
from wbmpc.walking.controller import WalkingController
from wbmpc.walking.interface import Controller
from wbmpc.walking.measurement import Measurement
from wbmpc.walking.pd import JointPDController
from wbmpc.walking.preset import (
    ALL_SECTIONS,
    WalkingPreset,
    available_walking_presets,
    is_preset_override,
    load_walking_preset,
)

CONTROLLERS = ("walking", "pd")
LOG_CHUNK_TICKS = 10_000  # rows of the tick logs allocated at a time (10 s at 1 kHz, ~7 MB for Bolt)


@dataclass(frozen=True)
class RunnerOptions:
    """Options of the simulation loop itself.

    Attributes:
        noise_q: standard deviation of the configuration measurement noise, applied in the tangent
            space (base position [m], base orientation [rad], joints [rad]); 0 = exact.
        noise_v: standard deviation of the velocity measurement noise [m/s, rad/s]; 0 = exact.
        min_base_height: see :class:`sim.falls.FallCriteria` [m]; None = the robot's walking
            preset's (``[fall]``), or half the base's standing height for a robot without one.
        max_tilt_deg: largest base tilt before a fall is declared [deg]; None = the preset's, or 50.
        stop_on_fall: end the run at the first fall (otherwise only record it).
        progress: show a progress bar of simulated time (None: on runs > 3 s when stderr is a TTY).
    """

    noise_q: float = 0.0
    noise_v: float = 0.0
    min_base_height: float | None = None
    max_tilt_deg: float | None = None
    stop_on_fall: bool = True
    progress: bool | None = None

    def __post_init__(self) -> None:
        for name in ("noise_q", "noise_v"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ParameterError(f"{name}={value} must be a finite number >= 0")

    def fall_criteria(self, robot, preset: WalkingPreset | None) -> FallCriteria:
        """The fall thresholds of this run: the options', else the preset's (see the attributes)."""
        height = self.min_base_height
        tilt = self.max_tilt_deg
        if preset is not None:
            height = preset.fall.min_base_height if height is None else height
            tilt = preset.fall.max_tilt_deg if tilt is None else tilt
        height = 0.5 * robot.base_height_reference if height is None else height
        tilt = 50.0 if tilt is None else tilt
        return FallCriteria(min_base_height=height, max_tilt=np.deg2rad(tilt))


def run_scenario(
    name: str,
    robot: str = "bolt",
    duration: float | None = None,
    seed: int = 0,
    out: str | None = None,
    controller: "str | Controller" = "walking",
    velocity_command: Any = None,
    on_tick: Callable[[Any, Any], None] | None = None,
    **params: Any,
) -> RunLog:
    """Run scenario ``name`` in closed loop and return its log (metrics included).

    Args:
        name: registered scenario ("walk", "push", "terrain", "transition", "slip").
        robot: registered robot name.
        duration: simulated time [s]; None = the scenario's default.
        seed: seed of every random choice (terrain, noise).
        out: directory for ``log.npz`` and ``metrics.json`` (None: nothing written).
        controller: "walking" (sequencer + MPC + Riccati feedback), "pd" (posture hold, falls), or
            an object implementing :class:`wbmpc.walking.controller.Controller` (then ``params`` holds no
            controller options).
        velocity_command: (v_x [m/s], v_y [m/s], yaw_rate [rad/s]) in the heading frame, the
            scenario's command after its ramp (sets its ``speed``, ``lateral_speed``, ``yaw_rate``);
            None = the scenario's. Checked before the run against the robot's command range.
        **params: scenario parameters (e.g. ``speed``, ``force``), :class:`RunnerOptions` fields,
            and for "walking" overrides of the robot's walking preset
            (:func:`wbmpc.walking.preset.load_walking_preset`: controller fields by name,
            ``"planner.l_max"``-style keys, whole sections ``planner=``/``ocp=``; the legacy
            ``sequencer_params=`` is the ``planner`` section); ``kp``, ``kd`` for "pd".
        on_tick: optional observer ``on_tick(mj_model, mj_data)`` called after every ``mj_step``
            (e.g. a live viewer, :class:`sim.render.LiveViewer`); it must not change the state.

    Returns:
        The :class:`RunLog`; ``status`` tells whether the run completed or fell.

    Raises:
        ParameterError: unknown scenario, controller or parameter (the message lists the allowed ones).
    """
    scenario_cls = scenario_class(name)
    custom = not isinstance(controller, str)
    if custom and not isinstance(controller, Controller):
        raise ParameterError(f"controller={controller!r} does not implement wbmpc.walking.controller.Controller")
    if not custom and controller not in CONTROLLERS:
        raise ParameterError(f"controller={controller!r} must be one of {CONTROLLERS} or a Controller object")
    scenario_keys = set(scenario_parameters(name))
    runner_keys = {f.name for f in dataclasses.fields(RunnerOptions)}
    params = dict(params)
    if "sequencer_params" in params:  # the planner section, whole
        params["planner"] = params.pop("sequencer_params")
    if velocity_command is not None:
        command = VelocityCommand.from_tuple(velocity_command)
        clash = sorted({"speed", "lateral_speed", "yaw_rate"} & set(params))
        if clash:
            raise ParameterError(f"velocity_command={velocity_command!r} and {clash} both set the command: give one")
        params.update(speed=command.v_x, lateral_speed=command.v_y, yaw_rate=command.yaw_rate)
    if custom:
        is_controller_key = lambda key: False  # noqa: E731
    elif controller == "walking":
        is_controller_key = is_preset_override
    else:
        is_controller_key = {"kp", "kd"}.__contains__
    unknown = sorted(k for k in params if k not in scenario_keys and k not in runner_keys and not is_controller_key(k))
    if unknown:
        allowed = ("walking preset overrides: controller fields or 'section.field' (sections "
                   f"{', '.join(ALL_SECTIONS)})" if controller == "walking" else
                   "controller ['kd', 'kp']" if controller == "pd" else "no controller options (custom controller)")
        raise ParameterError(
            f"run_scenario({name!r}): unknown parameter(s) {unknown}; allowed: scenario {sorted(scenario_keys)}, "
            f"runner {sorted(runner_keys)}, {allowed}"
        )
    scenario = make_scenario(name, **{k: v for k, v in params.items() if k in scenario_keys})
    options = RunnerOptions(**{k: v for k, v in params.items() if k in runner_keys})
    controller_options = {k: v for k, v in params.items()
                          if k not in scenario_keys and k not in runner_keys and is_controller_key(k)}
    duration = float(scenario_cls.default_duration if duration is None else duration)
    if not (np.isfinite(duration) and duration > 0):
        raise ParameterError(f"duration={duration} s must be a finite positive number")
    preset = None
    if custom:
        ctrl: Controller = controller
    elif controller == "walking":
        if "mpc_failure_times" in controller_options:
            controller_options["mpc_failure_times"] = tuple(
                float(t) for t in np.atleast_1d(controller_options["mpc_failure_times"]))
        preset = load_walking_preset(robot, controller_options, scenario=name)
        ctrl = WalkingController(preset)
    else:
        ctrl = JointPDController(**controller_options)
    if isinstance(ctrl, WalkingController):  # refuse, before the first tick, what it cannot follow
        preset = ctrl.preset
        for command in scenario.commands():
            ctrl.check_command(command)
    if preset is None and robot in available_walking_presets():
        preset = load_walking_preset(robot)  # the robot's fall thresholds

    log = RunLog(
        scenario=name,
        robot=robot,
        seed=int(seed),
        params={
            "duration": duration,
            "controller": controller if not custom else type(controller).__name__,
            "scenario": dataclasses.asdict(scenario),
            "runner": dataclasses.asdict(options),
            "controller_options": {k: _jsonable_param(v) for k, v in controller_options.items()},
            "preset_scenario_overrides": {} if preset is None else dict(preset.scenario_overrides),
            "events": scenario.events(),
            "steady_start": scenario_cls.steady_start,
        },
    )
    return _ClosedLoop(scenario, ctrl, options, robot, duration, int(seed), log, out, preset, on_tick).run()


def controller_command_range(controller: Controller) -> dict[str, tuple[float, float]] | None:
    """The velocity commands ``controller`` accepts, heading frame: {"v_x": (min, max) [m/s], "v_y": (min,
    max) [m/s], "yaw_rate": (min, max) [rad/s]}, what :meth:`WalkingController.check_command` lets
    through (the preset's ``[command]`` range within the planner's bounds); None for other controllers."""
    if not isinstance(controller, WalkingController):
        return None
    preset, planner = controller.preset.command, controller.planner.command_range()
    return {name: (max(getattr(preset, name)[0], planner[name][0]), min(getattr(preset, name)[1], planner[name][1]))
            for name in ("v_x", "v_y", "yaw_rate")}


def _jsonable_param(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return dataclasses.asdict(value)
    return value


class _ClosedLoop:
    """One run's simulation state (built and used by :func:`run_scenario` only)."""

    def __init__(self, scenario, controller, options, robot_name, duration, seed, log, out, preset,
                 on_tick=None) -> None:
        self.scenario, self.controller, self.options, self.preset = scenario, controller, options, preset
        self.robot_name, self.duration, self.seed, self.log, self.out = robot_name, duration, seed, log, out
        self.on_tick = on_tick

    def _build(self) -> None:
        import mujoco

        from robots import load_robot
        from robots.conventions import mujoco_to_pinocchio_state, pinocchio_to_mujoco_state
        from robots.mujoco_model import build_mujoco_spec

        self.to_pinocchio = mujoco_to_pinocchio_state
        self.rng = np.random.default_rng(self.seed)
        self.robot = robot = load_robot(self.robot_name)
        self.scenario.setup(robot, controller_command_range(self.controller))
        spec = build_mujoco_spec(robot, link_collisions=True)
        self.scenario.modify_spec(spec, self.rng)
        perception = None if self.preset is None else self.preset.perception
        sensing = perception is not None and perception.enabled
        if sensing:
            from sim.perception import PerceptionPipeline

            PerceptionPipeline.add_to_spec(spec, perception, robot.base_body)
        self.mj_model = spec.compile()
        self.perception = PerceptionPipeline(self.mj_model, perception, self.seed, robot) if sensing else None
        self.mj_data = mujoco.MjData(self.mj_model)
        qpos, qvel = pinocchio_to_mujoco_state(robot, np.asarray(robot.q_reference), np.asarray(robot.v_reference))
        self.mj_data.qpos[:] = qpos
        self.mj_data.qvel[:] = qvel
        self.scenario.initialize_episode(self.mj_model, self.mj_data, self.rng)
        mujoco.mj_forward(self.mj_model, self.mj_data)
        self.mj_step = mujoco.mj_step

        self.model = robot.pinocchio_model
        self.data = self.model.createData()
        self.nq, self.nv = self.model.nq, self.model.nv
        self.nu = self.nv - 6
        self.feet = tuple(robot.foot_frames.keys())
        self.frame_ids = [self.model.getFrameId(robot.foot_frames[f]) for f in self.feet]
        self.torque_limit = np.asarray(robot.torque_limit, dtype=float)
        self.criteria = self.options.fall_criteria(robot, self.preset)
        self.contacts = ContactSensor(self.mj_model, robot)
        self.dt = float(self.mj_model.opt.timestep)
        self.n_ticks = int(round(self.duration / self.dt))
        period = self.controller.replan_period / self.dt
        self.replan_every = int(round(period))
        if self.replan_every < 1 or abs(period - self.replan_every) > 1e-6:
            raise ParameterError(
                f"replan_period={self.controller.replan_period} s must be a multiple of the simulation "
                f"time step {self.dt} s"
            )

    def _allocate(self, start: int) -> dict[str, np.ndarray]:
        """The next chunk of the tick logs: rows for ticks ``start`` .. ``start + LOG_CHUNK_TICKS`` (or the end)."""
        n, n_feet = min(LOG_CHUNK_TICKS, self.n_ticks - start), len(self.feet)
        return {
            "t": np.zeros(n),
            "qpos": np.zeros((n, self.mj_model.nq)),
            "qvel": np.zeros((n, self.mj_model.nv)),
            "x": np.zeros((n, self.nq + self.nv)),
            "tau_command": np.zeros((n, self.nu)),
            "tau": np.zeros((n, self.nu)),
            "com": np.zeros((n, 3)),
            "com_velocity": np.zeros((n, 3)),
            "feet": np.zeros((n, n_feet, 3)),
            "foot_contact": np.zeros((n, n_feet), dtype=bool),
            "obstacle_contact": np.zeros((n, n_feet + 1), dtype=bool),
            "base_velocity_world": np.zeros((n, 3)),
            "velocity_command": np.zeros((n, 3)),
        }

    def _measure_noise(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        x = np.concatenate([q, v])
        if self.options.noise_q > 0:
            x[: self.nq] = pin.integrate(self.model, q, self.rng.normal(0.0, self.options.noise_q, self.nv))
        if self.options.noise_v > 0:
            x[self.nq :] += self.rng.normal(0.0, self.options.noise_v, self.nv)
        return x

    def run(self) -> RunLog:
        log, ticks_done = self.log, 0
        replan_rows: list[dict[str, float]] = []
        cold_timers = None  # the controller's part timers after the cold first solve
        timing = {"simulation": 0.0, "replan": 0.0, "feedback": 0.0, "logging": 0.0, "perception": 0.0, "setup": 0.0,
                  "cold_start": 0.0, "total": 0.0}
        wall_start = time.perf_counter()
        bar = None
        chunks: list[dict[str, np.ndarray]] = []  # the tick logs, LOG_CHUNK_TICKS rows each
        try:
            self._build()
            chunks.append(self._allocate(0))
            ticks, row0 = chunks[-1], 0  # the chunk being filled and the tick of its first row
            timing["setup"] = time.perf_counter() - wall_start
            # The models, solvers and buffers built above live for the whole run: move them out of
            # the collector's reach, so a full collection in the loop (~35 ms with them) stays short.
            gc.collect()
            gc.freeze()
            show = self.options.progress
            if show is None:
                show = self.duration > 3.0 and sys.stderr.isatty()
            if show:
                from tqdm import tqdm

                bar = tqdm(total=round(self.duration, 3), unit="s", desc=f"{log.scenario} (sim time)", leave=False)
            x0 = None
            data, model = self.mj_data, self.mj_model
            on_tick = self.on_tick
            for i in range(self.n_ticks):
                tic = time.perf_counter()
                t = i * self.dt
                r = i - row0  # row of tick i in the current chunk
                if r == LOG_CHUNK_TICKS:
                    chunks.append(self._allocate(i))
                    ticks, row0, r = chunks[-1], i, 0
                q, v = self.to_pinocchio(self.robot, data.qpos, data.qvel)
                com = pin.centerOfMass(self.model, self.data, q, v)
                com_velocity = self.data.vcom[0]
                pin.updateFramePlacements(self.model, self.data)
                feet = np.array([self.data.oMf[f].translation for f in self.frame_ids])
                foot_contact, other_contact, obstacle_contact = self.contacts.classify_with_obstacles(data)
                x_measured = self._measure_noise(q, v)
                obstacles, perception_time = (), 0.0
                if self.perception is not None:
                    tic_perception = time.perf_counter()
                    obstacles = self.perception.step(i, t, model, data, x_measured)
                    perception_time = time.perf_counter() - tic_perception
                    timing["perception"] += perception_time
                measurement = Measurement(t, x_measured, foot_contact, obstacles)
                pose = (measurement.x[0], measurement.x[1], float(base_yaw(measurement.x[3:7])))
                command = self.scenario.velocity_command(t, pose)
                ticks["t"][r] = t
                ticks["qpos"][r] = data.qpos
                ticks["qvel"][r] = data.qvel
                ticks["x"][r, : self.nq] = q
                ticks["x"][r, self.nq :] = v
                ticks["com"][r] = com
                ticks["com_velocity"][r] = com_velocity
                ticks["feet"][r] = feet
                ticks["foot_contact"][r] = foot_contact
                ticks["obstacle_contact"][r] = obstacle_contact
                ticks["base_velocity_world"][r] = data.qvel[:3]
                ticks["velocity_command"][r] = command
                ticks_done = i + 1
                timing["logging"] += time.perf_counter() - tic - perception_time

                reason = detect_fall(self.criteria, q, other_contact)
                if reason is not None and log.fall_time is None:
                    log.status, log.fall_time, log.fall_reason = "fell", t, reason
                    if self.options.stop_on_fall:
                        break

                if x0 is None:
                    x0 = measurement.x.copy()
                    tic = time.perf_counter()
                    self.controller.reset(self.robot, x0, t)  # the controller's parts, at the first tick
                    timing["setup"] += time.perf_counter() - tic
                if i % self.replan_every == 0:
                    tic = time.perf_counter()
                    self.controller.set_velocity_command(command)
                    try:
                        record = self.controller.replan(t, measurement)
                    except NoSolutionError as err:  # e.g. the planner failed until its last plan ran out
                        if log.status == "running":  # a fall recorded before stays the outcome
                            log.status = "failed"
                        log.error = str(err)
                        break
                    # the first replan is the cold solve (more iterations, the compiled kernels loaded): setup,
                    # as on a robot, where it is done before the robot moves; not a loop tick
                    if replan_rows:
                        timing["replan"] += time.perf_counter() - tic
                    else:
                        timing["cold_start"] = time.perf_counter() - tic
                        timing["setup"] += timing["cold_start"]
                        cold_timers = _timer_parts(self.controller)
                    replan_rows.append({"t": t, **record})
                tic = time.perf_counter()
                try:
                    tau_command = np.asarray(self.controller.compute(t, measurement), dtype=float)
                except NoSolutionError as err:  # nothing to follow (the first solve failed): end the run, keep the log
                    log.status, log.error = "failed", str(err)
                    break
                timing["feedback"] += time.perf_counter() - tic
                tau = np.minimum(np.maximum(tau_command, -self.torque_limit), self.torque_limit)  # clip, 4x faster
                ticks["tau_command"][r] = tau_command
                ticks["tau"][r] = tau

                tic = time.perf_counter()
                self.scenario.before_step(t, model, data)
                data.ctrl[:] = tau
                self.mj_step(model, data)
                timing["simulation"] += time.perf_counter() - tic
                if on_tick is not None:
                    on_tick(model, data)
                if bar is not None and i % 100 == 99:
                    bar.update(0.1)
            if log.status == "running":
                log.status = "completed"
        except KeyboardInterrupt:
            log.status, log.error = "interrupted", "KeyboardInterrupt"
            raise
        except BaseException as err:
            log.status, log.error = "error", f"{type(err).__name__}: {err}"
            raise
        finally:
            if bar is not None:
                bar.close()
            timing["total"] = time.perf_counter() - wall_start
            timing["loop"] = timing["total"] - timing["setup"]
            self._finish(chunks, ticks_done, replan_rows, timing, cold_timers)
        return log

    def _finish(self, chunks, ticks_done, replan_rows, timing, cold_timers=None) -> None:
        from sim.metrics import compute_metrics

        log = self.log
        log.ticks = {k: np.concatenate([chunk[k] for chunk in chunks])[:ticks_done] for k in (chunks[0] if chunks else {})}
        if "com" in log.ticks:  # the DCM with the controller's omega (the planner's): one omega per run
            omega = float(self.controller.omega)
            log.ticks["dcm"] = log.ticks["com"][:, :2] + log.ticks["com_velocity"][:, :2] / omega
            log.params["omega"] = omega
        keys = sorted({k for row in replan_rows for k in row})
        log.replans = {k: np.array([row.get(k, np.nan) for row in replan_rows], dtype=float) for k in keys}
        parts = _timer_parts(self.controller)
        if parts is not None:  # the loop's share: the controller's timers less their cold start (in the setup)
            cold = cold_timers or {name: 0.0 for name in parts}
            timing.update({name: value - cold[name] for name, value in parts.items()})
        timing["simulated_time"] = ticks_done * getattr(self, "dt", 0.0)
        log.timing = timing
        if getattr(self, "robot", None) is not None:
            log.params["torque_limit"] = np.asarray(self.robot.torque_limit).tolist()
        if getattr(self, "perception", None) is not None:
            log.params["perception"] = self.perception.summary()
        true_obstacles = getattr(self.scenario, "true_obstacles", None)
        if true_obstacles is not None and getattr(self, "robot", None) is not None:
            log.params["obstacle_truth"] = [to_jsonable(o) for o in true_obstacles()]
        try:
            log.metrics = compute_metrics(log)
        except Exception as err:  # metrics must never hide the run's own outcome
            log.metrics = {"error": f"metrics failed: {type(err).__name__}: {err}"}
        if self.out is not None:
            log.save(self.out)


def _timer_parts(controller) -> dict[str, float] | None:
    """The controller's part timers [s] (``sequencer``, ``mpc``, ``mpc_prepare``) so far, or None without
    timers."""
    timers = getattr(controller, "timers", None)
    if timers is None:
        return None
    return {"sequencer": timers.sequencer, "mpc": timers.mpc, "mpc_prepare": getattr(timers, "mpc_prepare", 0.0)}
