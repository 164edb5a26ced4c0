"""One trial of a campaign: its parameters, their translation into ``run_scenario`` arguments, its run.

Campaign parameters that are not arguments of :func:`sim.run_scenario` (translated here):

- ``force_x``, ``force_y`` [N]: push force in the world frame (scenario "push") ->
  ``force = |(Fx, Fy)|``, ``direction = atan2(Fy, Fx)`` [deg].
- ``phase`` in [0, 1) and ``push_after`` [s] (scenario "push"): the push starts at
  ``push_after + phase * T_nom``, T_nom the nominal step period of the trial's footstep planner
  (the robot's walking preset with the trial's overrides: the DCM planner's ``t_nom``, the ALIP
  planner's ``t_des``; :attr:`wbmpc.walking.preset.WalkingPreset.step_period`). The phase
  measured from the controller's stance switches is recorded in the result
  (``metrics["push_phase_measured"]``): it can differ from the nominal one when the gait drifts.
- ``sequencer_params`` may be a preset name (``"table_i"``) or a table of fields that override the
  ``[planner]`` of the trial robot's walking preset (campaign files).
- ``step_timing`` (controller "walking"), for the planner the trial runs
  (``footstep_planner.kind``): "adaptive" (the walking preset's planner parameters), "fixed" (the
  step period cannot change: DCM T_min = T_max = T_nom; ALIP T = ``ALIP_FIXED_STEP_PERIOD``, the
  ALIP paper's fixed-timing study) or "stiff" (the timing weight raised to
  ``STIFF_TIMING_WEIGHT``: DCM alpha_2, ALIP R_T; timing changes cost far more than position
  changes).
- ``step_timing_from`` [s] (with ``step_timing``; default 0): the variant's timing applies from
  the first touchdown at or after this time, the start being adaptive
  (``WalkingControllerConfig.sequencer_params_from``), so that variants are compared on the same
  walking gait rather than on starting from standing.

:func:`run_trial` runs in worker processes (local pool or Ray): it takes a picklable
:class:`Trial`, never raises for a failing trial (the error text is recorded instead) and
returns a JSON-able record.
"""

from __future__ import annotations

import dataclasses
import datetime
import hashlib
import json
import math
import os
import socket
import subprocess
import time
import traceback
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from wbmpc.errors import ParameterError

STEP_TIMINGS = ("adaptive", "fixed", "stiff")
STIFF_TIMING_WEIGHT = 1e8  # alpha_2 (DCM; preset: 1, alpha_3 = 1e6) or R_T [1/s^2] (ALIP; preset: 100) of "stiff" timing
ALIP_FIXED_STEP_PERIOD = 0.35  # [s], the ALIP paper's fixed step period (section 4.3, Fig. 6 top; adaptive: 0.25-0.5 s)
CAMPAIGN_PARAMETERS = ("force_x", "force_y", "phase", "push_after", "step_timing", "step_timing_from")
PD_OPTIONS = ("kp", "kd")
MAX_TRACEBACK_CHARS = 4000


@dataclass(frozen=True)
class Trial:
    """One closed-loop run of a campaign.

    Attributes:
        key: identity of the trial in the results store (variant, parameters and seed).
        index: position in the campaign's trial order.
        campaign: campaign name.
        variant: variant name.
        params: campaign-level parameters (shared, point and variant overrides), JSON-able.
        seed: run seed.
        scenario, robot, controller: as in :func:`sim.run_scenario`.
        duration: simulated time [s] (None: scenario default).
        arguments: keyword arguments of :func:`sim.run_scenario` (resolved from ``params``).
    """

    key: str
    index: int
    campaign: str
    variant: str
    params: dict[str, Any]
    seed: int
    scenario: str
    robot: str
    controller: str
    duration: float | None
    arguments: dict[str, Any]


def trial_key(variant: str, params: dict[str, Any], seed: int) -> str:
    """Stable identity of a trial: a hash of its variant, parameters (canonical JSON) and seed."""
    text = json.dumps({"variant": variant, "params": _jsonable(params), "seed": int(seed)}, sort_keys=True)
    return hashlib.sha1(text.encode()).hexdigest()[:16]


def make_trials(spec) -> list[Trial]:
    """All trials of ``spec`` (a :class:`sim.campaigns.spec.CampaignSpec`), resolved and validated.

    Raises:
        ParameterError: an unknown parameter or a value the scenario/controller rejects, naming the
            offending trial's parameters (raised before anything runs).
    """
    allowed = _allowed_names(spec.scenario, spec.controller)
    if spec.controller == "walking":  # and every "section.field" key of the walking preset
        from wbmpc.walking.preset import is_preset_override
    else:
        def is_preset_override(key: str) -> bool:
            return False
    trials: list[Trial] = []
    points = spec.points()
    for seed in spec.seeds:
        for point in points:
            for variant, overrides in spec.variants.items():
                params = {**spec.params, **point, **overrides}
                unknown = sorted(k for k in params if k not in allowed and not is_preset_override(k))
                if unknown:
                    raise ParameterError(
                        f"campaign {spec.name!r}: unknown parameter(s) {unknown}; allowed: {sorted(allowed)}"
                    )
                try:
                    arguments = resolve_arguments(spec.scenario, spec.controller, spec.duration, params, spec.robot)
                except ParameterError as err:
                    raise ParameterError(f"campaign {spec.name!r}, variant {variant!r}, point {point}: {err}") from err
                trials.append(
                    Trial(
                        key=trial_key(variant, params, seed),
                        index=len(trials),
                        campaign=spec.name,
                        variant=variant,
                        params=_jsonable(params),
                        seed=seed,
                        scenario=spec.scenario,
                        robot=spec.robot,
                        controller=spec.controller,
                        duration=spec.duration,
                        arguments=arguments,
                    )
                )
    return trials


def _allowed_names(scenario: str, controller: str) -> set[str]:
    from sim.runner import RunnerOptions
    from sim.scenarios import scenario_parameters
    from wbmpc.walking.preset import preset_override_keys

    names = set(scenario_parameters(scenario)) | {f.name for f in dataclasses.fields(RunnerOptions)}
    if controller == "walking":
        names |= preset_override_keys() | {"sequencer_params", "step_timing", "step_timing_from"}
    else:
        names |= set(PD_OPTIONS)
    if scenario == "push":
        names |= {"force_x", "force_y", "phase", "push_after"}
    return names


def resolve_arguments(scenario: str, controller: str, duration: float | None, params: dict[str, Any],
                      robot: str = "bolt") -> dict:
    """``run_scenario`` keyword arguments for campaign parameters ``params`` of a trial of ``robot`` (validated).

    Raises:
        ParameterError: conflicting or out-of-range parameters.
    """
    from sim.scenarios import make_scenario, scenario_parameters

    arguments = dict(params)
    arguments.setdefault("progress", False)
    if isinstance(arguments.get("sequencer_params"), (str, dict)):
        from sequencer import SequencerParams

        given = arguments["sequencer_params"]
        arguments["sequencer_params"] = (
            SequencerParams.preset(given)
            if isinstance(given, str)
            else SequencerParams.from_dict({**trial_preset(robot, scenario, {}).planner.to_dict(), **given},
                                           "sequencer_params")
        )
    step_timing = arguments.pop("step_timing", None)
    step_timing_from = _finite("step_timing_from", arguments.pop("step_timing_from", 0.0))
    if step_timing_from < 0:
        raise ParameterError(f"step_timing_from={step_timing_from} s must be >= 0")
    # [s], the step period of the planner the trial starts with (the phase's unit)
    nominal_period = nominal_step_period(robot, scenario, arguments) if "phase" in arguments else None
    if step_timing is not None:
        preset = trial_preset(robot, scenario, arguments)
        adaptive = preset.planner_params
        timed = timed_planner_params(step_timing, adaptive)
        planner_key = "sequencer_params" if preset.footstep_planner.kind == "dcm" else "footstep_planner.alip"
        if step_timing_from > 0:
            if planner_key == "sequencer_params":
                arguments["sequencer_params"] = adaptive
            arguments["sequencer_params_from"] = (step_timing_from, timed)
        else:
            arguments[planner_key] = timed if planner_key == "sequencer_params" else timed.to_dict()
    elif step_timing_from > 0:
        raise ParameterError("step_timing_from needs a step_timing")
    if "force_x" in arguments or "force_y" in arguments:
        clash = sorted({"force", "direction"} & set(arguments))
        if clash:
            raise ParameterError(f"force_x/force_y and {clash} both set the push; use one form")
        force_x = _finite("force_x", arguments.pop("force_x", 0.0))
        force_y = _finite("force_y", arguments.pop("force_y", 0.0))
        arguments["force"] = math.hypot(force_x, force_y)
        arguments["direction"] = math.degrees(math.atan2(force_y, force_x)) if arguments["force"] > 0 else 0.0
    if "phase" in arguments:
        if "push_time" in arguments:
            raise ParameterError("phase and push_time both set the push time; use one")
        phase = _finite("phase", arguments.pop("phase"))
        if not 0.0 <= phase < 1.0:
            raise ParameterError(f"phase={phase} must be in [0, 1) (fraction of the nominal step)")
        push_after = _finite("push_after", arguments.pop("push_after", 0.0))
        if push_after < 0:
            raise ParameterError(f"push_after={push_after} s must be >= 0")
        arguments["push_time"] = push_after + phase * nominal_period
    elif "push_after" in arguments:
        raise ParameterError("push_after needs a phase (push_time = push_after + phase * T_nom)")
    scenario_args = {k: v for k, v in arguments.items() if k in scenario_parameters(scenario)}
    instance = make_scenario(scenario, **scenario_args)
    events = instance.events()
    if duration is not None and "push_end" in events and events["push_end"] >= duration:
        raise ParameterError(
            f"the push ends at t = {events['push_end']:.3f} s, not before the end of the trial (duration={duration} s)"
        )
    if controller == "walking":
        trial_preset(robot, scenario, arguments)  # validated as the run will load it
    return arguments


def trial_preset(robot: str, scenario: str, arguments: dict[str, Any]):
    """The walking preset of ``robot`` for runs of ``scenario`` (its ``[scenarios.<scenario>]`` overrides) with the
    preset overrides among ``arguments`` (the trial's controller).

    Raises:
        ParameterError: an override the preset refuses, or a robot without a walking preset.
    """
    from sim.scenarios import scenario_parameters
    from wbmpc.walking.preset import is_preset_override, load_walking_preset

    scenario_keys = set(scenario_parameters(scenario))
    overrides = {("planner" if k == "sequencer_params" else k): v for k, v in arguments.items()
                 if k == "sequencer_params" or (is_preset_override(k) and k not in scenario_keys)}
    if "mpc_failure_times" in overrides:
        overrides["mpc_failure_times"] = tuple(float(t) for t in overrides["mpc_failure_times"])
    return load_walking_preset(robot, overrides, scenario=scenario)


def nominal_step_period(robot: str, scenario: str, arguments: dict[str, Any]) -> float:
    """The nominal step period [s] of the footstep planner of ``robot``'s walking preset with the preset
    overrides among ``arguments`` (:attr:`wbmpc.walking.preset.WalkingPreset.step_period`)."""
    return trial_preset(robot, scenario, arguments).step_period


def timed_planner_params(step_timing: str, params):
    """The footstep planner's parameters ``params`` (``SequencerParams`` or ``AlipParams``) with ``step_timing``.

    "adaptive": unchanged; "fixed": one step period (DCM: T_min = T_max = T_nom, a step over an obstacle keeping its
    own range when the parameters bound it, ``obstacle_step_duration_min`` > 0; ALIP: ``ALIP_FIXED_STEP_PERIOD``);
    "stiff": the timing weight set to ``STIFF_TIMING_WEIGHT`` (DCM alpha_2,
    ALIP R_T), the bounds kept.
    """
    from sequencer.alip.params import AlipParams

    if step_timing not in STEP_TIMINGS:
        raise ParameterError(f"step_timing={step_timing!r} must be one of {STEP_TIMINGS}")
    if step_timing == "adaptive":
        return params
    if isinstance(params, AlipParams):
        if step_timing == "fixed":
            timed = params.fixed_timing(ALIP_FIXED_STEP_PERIOD)
        else:
            timed = dataclasses.replace(params, r_period=STIFF_TIMING_WEIGHT)
    elif step_timing == "fixed":
        # the walking steps' timing; a step over an obstacle keeps its duration range (its lower bound is above
        # t_nom on the H1 and the G1)
        crossing = {}
        if params.obstacle_step_duration_min > 0.0:
            crossing["obstacle_step_duration_max"] = max(params.t_max, params.obstacle_step_duration_max)
        timed = dataclasses.replace(params, t_min=params.t_nom, t_max=params.t_nom, **crossing)
    else:
        timed = dataclasses.replace(params, alpha2=STIFF_TIMING_WEIGHT)
    return dataclasses.replace(timed, name=f"{params.name}+{step_timing}_timing")


def _finite(name: str, value: Any) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError) as err:
        raise ParameterError(f"{name}={value!r} must be a number") from err
    if not math.isfinite(value):
        raise ParameterError(f"{name}={value} must be finite")
    return value


# ---------------------------------------------------------------------- running
def run_trial(trial: Trial) -> dict[str, Any]:
    """Run one trial; returns its record (never raises for a failing trial; Ctrl-C propagates).

    Record keys: key, index, campaign, variant, params, arguments (the resolved ``run_scenario``
    arguments, e.g. the sequencer parameters of a step-timing variant), seed, success (the run completed its
    duration without a fall or an error), status ("completed", "fell", "failed", "error"), fall_time [s],
    fall_reason, error (exception text or None), traceback, metrics (``sim.metrics`` plus
    ``push_phase_measured``), code (:func:`code_version`), wall_time [s], cpu_time [s] (CPU time of the worker process during
    the trial; below wall_time when the cores are shared), host, pid, finished_at (UTC, ISO 8601).
    """
    from sim.runner import run_scenario

    code = code_version()  # before the trial: a commit checked out while it runs is not the code it ran
    record: dict[str, Any] = {
        "key": trial.key,
        "index": trial.index,
        "campaign": trial.campaign,
        "variant": trial.variant,
        "params": trial.params,
        "arguments": _jsonable(trial.arguments),
        "seed": trial.seed,
    }
    tic, cpu_tic = time.perf_counter(), time.process_time()
    try:
        log = run_scenario(
            trial.scenario,
            robot=trial.robot,
            duration=trial.duration,
            seed=trial.seed,
            controller=trial.controller,
            **trial.arguments,
        )
    except Exception as err:  # the trial's outcome, recorded; the campaign goes on
        record.update(
            success=False,
            status="error",
            fall_time=None,
            fall_reason=None,
            error=f"{type(err).__name__}: {err}",
            traceback=traceback.format_exc()[-MAX_TRACEBACK_CHARS:],
            metrics={},
        )
    else:
        metrics = dict(log.metrics)
        push_time = log.params.get("events", {}).get("push_start")
        if push_time is not None:
            t_nom = nominal_step_period(trial.robot, trial.scenario, trial.arguments)
            metrics["push_phase_measured"] = measured_gait_phase(log.replans, push_time, t_nom)
        record.update(
            success=log.status == "completed" and bool(metrics.get("success", True)),
            status=log.status,
            fall_time=log.fall_time,
            fall_reason=log.fall_reason,
            error=log.error,
            traceback=None,
            metrics=_jsonable(metrics),
        )
    record.update(
        code=code,
        wall_time=time.perf_counter() - tic,
        cpu_time=time.process_time() - cpu_tic,
        host=socket.gethostname(),
        pid=os.getpid(),
        finished_at=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
    )
    return record


@lru_cache(maxsize=1)
def code_version() -> str:
    """The code a trial ran: the git commit of the checkout the ``sim`` package is imported from, with
    ``-dirty`` when its tracked files differ from the commit, or ``unknown`` outside a git checkout (an
    installed wheel). A campaign resumed in a later session can thus tell its trials' code versions apart;
    computed once per worker process, when its first trial starts (:func:`run_trial`; its modules are imported
    once, by the forkserver at the campaign's start: a checkout during a campaign is not the code its trials run,
    and their records still name the commit of the worker's first trial)."""
    root = Path(__file__).resolve().parents[2]

    def git(*args: str) -> str:
        return subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True, timeout=10,
                              check=True).stdout.strip()

    try:
        commit = git("rev-parse", "HEAD")
        dirty = bool(git("status", "--porcelain", "--untracked-files=no"))
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return f"{commit}-dirty" if dirty else commit


def measured_gait_phase(replans: dict[str, np.ndarray], t: float, t_nom: float | None = None) -> float | None:
    """Phase of the walking controller's step at time ``t`` [s], from its logged stance switches.

    phase = (t - start of the current stance) / (duration of the previous step), the previous step
    being the gait as it was before ``t`` (a push changes the current step's duration). Falls back
    on ``t_nom`` [s] when no previous step is logged.

    Args:
        replans: ``RunLog.replans`` (needs the walking controller's ``t`` and ``t_stance_start``).
        t: time [s].
        t_nom: nominal step duration [s] for the fallback (None: no fallback).

    Returns:
        The phase (>= 0; can exceed 1 when the step is late), or None when it cannot be measured
        (no stance information, e.g. the PD controller, or ``t`` before the first replan).
    """
    times = np.asarray(replans.get("t", ()), dtype=float)
    starts = np.asarray(replans.get("t_stance_start", ()), dtype=float)
    if len(times) == 0 or len(starts) != len(times):
        return None
    before = np.flatnonzero(times <= t + 1e-9)
    if len(before) == 0:
        return None
    current = starts[before[-1]]
    previous = np.unique(starts[: before[-1] + 1])
    previous = previous[previous < current - 1e-9]
    duration = current - previous[-1] if len(previous) else t_nom
    if duration is None or not duration > 0:
        return None
    return float((t - current) / duration)


def _jsonable(value: Any) -> Any:
    from wbmpc.jsonable import to_jsonable

    return to_jsonable(value)
