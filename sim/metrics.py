"""Summary figures of a closed-loop run, comparable with the paper's (section IV).

Definitions (all times in s, velocities in m/s, world frame):

- ``velocity_error_x/y``: |mean base velocity - command| over the steady window, the paper's
  epsilon_V = |V_bar - V*| (paper, walk at 0.33 m/s: (5.2, 1.1) mm/s). The steady window starts
  ``steady_start`` after the beginning of the run or the last command change, whichever is later.
  The command is in the heading frame: these compare it with world velocities, as long as the
  heading stays near 0 (straight walks along x).
- ``velocity_error_heading_x/y``: the same in the heading frame, |mean(R(ψ)ᵀ v) - command| with ψ
  the base yaw at each tick (``mean_velocity_heading_x/y``): what a walk that turns is measured
  by (walking at 0.3 m/s while turning at 0.3 rad/s goes round a circle; its world velocity
  averages towards 0).
- ``mean_yaw_rate``: mean base yaw rate over the steady window [rad/s] (yaw change / time);
  ``yaw_rate_error``: |mean_yaw_rate - commanded yaw rate|.
- ``rise_time`` (scenarios with a ``speed_switch`` event): time from the switch until the running average of the
  base x velocity (window ``AVERAGE_WINDOW``) first reaches 90 % of the step in command
  (paper, transition 0 -> 0.3 m/s: 4.35 s).
- ``push_recovery_time``: time from the end of the push until the running average of the base y
  velocity is back within ``RECOVERY_BAND`` of its value before the push, and stays there.
- path following (scenarios whose parameters name a path, ``waypoints``; :func:`path_metrics`):
  ``path_deviation_max``, ``path_deviation_mean`` [m]: distance from the base's ground projection
  to the path over the run; ``heading_error_max``, ``heading_error_mean`` [rad]: |base yaw - the
  path's tangent heading at the closest point|, over the ticks whose closest point is more than
  ``HEADING_CORNER_MARGIN`` of arc length from every corner (the heading jumps by 90° at a
  corner of the square: the error there says how the turn is shared, not how well the robot
  follows); ``path_progress`` [m]: arc length of the closest point at the end of the run;
  ``path_completion``: ``path_progress`` / (laps x path length) (1 = back at the end point).
- obstacle crossing (scenario ``obstacle``): ``success``, ``touched``, ``crossing_time``, the
  perception's detection and errors (:mod:`sim.obstacle_metrics`).
- yaw disturbances (pushes with a ``moment`` about z, the ``yaw_push`` scenario, ALIP paper section
  4.2, Fig. 5; :func:`yaw_disturbance_metrics`): the heading error e(t) = ψ(t) − Ψ(t) − e₀, with ψ
  the base's (the G1's pelvis's) unwrapped yaw [rad], Ψ(t) the integral of the commanded yaw rate
  since the start of the run (0 walking straight) and e₀ the mean of ψ − Ψ over the
  ``YAW_AVERAGE_WINDOW`` before the push: how far the disturbance turned the robot away from the
  heading it would have kept. ``yaw_push_error`` [rad, signed]: the mean of e over the last
  ``YAW_AVERAGE_WINDOW`` of the run, "the yaw of the base after the robot is stabilized" (the paper
  records it after the recovery; the mean over two strides removes the gait's own yaw oscillation),
  None unless the run completed and that window starts ``YAW_SETTLE_TIME`` or more after the
  push's end; ``yaw_push_error_abs`` its magnitude; ``yaw_push_error_peak``: max |e| after the
  push's start; ``yaw_push_rate_peak`` / ``yaw_push_rate_before`` [rad/s]: max |ψ̇ − commanded rate|
  from the push's start to ``YAW_RATE_WINDOW`` after its end / over the window before the push.
  Given the yaw of the same run without the push (same seed; ``undisturbed_yaw``), Ψ is that yaw
  instead: the error is then the disturbance's effect alone, without the walk's own heading drift.
- ``max_stance_slide``: largest distance between the stance foot and its touchdown point (slips).
- ``max_torque_ratio``: max |tau_command| / torque limit (> 1 means the limits clipped the command);
  ``saturated_fraction``: fraction of ticks with at least one clipped joint.
- MPC tick time: wall time of each warm-started MPC update (median, p99) [s], the first (cold
  start, more iterations) reported apart as ``mpc_cold_start_time``; ``real_time_factor``: simulated
  time / wall time of the loop (> 1 is faster than real time), the setup (models, buffers, the
  controller's reset and cold first solve, ``setup_time``) excluded as on a robot, where it is
  done before the robot moves.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from robots.conventions import base_yaw
from sim.paths import PlanarPath, path_from_parameters, wrap_angle

HEADING_CORNER_MARGIN = 0.5  # [m] of arc length on each side of a path's corner, left out of the heading error
AVERAGE_WINDOW = 1.0  # [s], running average of the base velocity (about two steps)
RECOVERY_BAND = 0.03  # [m/s]
YAW_AVERAGE_WINDOW = 1.6  # [s], two G1 strides at its desired step period (0.4 s): the pelvis yaw's gait oscillation averages out
YAW_SETTLE_TIME = 2.0  # [s] after the end of a yaw push, the earliest start of the "after recovery" window (five steps)
YAW_RATE_WINDOW = 0.1  # [s] after the end of a yaw push, still searched for the peak yaw rate
PAPER_FIGURES = {
    "velocity_error_x": 5.2e-3,  # [m/s], walk at 0.33 m/s (section IV.B)
    "velocity_error_y": 1.1e-3,  # [m/s]
    "rise_time": 4.35,  # [s], transition 0 -> 0.3 m/s at t = 5 s (section IV.D)
}


def running_average(t: np.ndarray, signal: np.ndarray, window: float = AVERAGE_WINDOW) -> np.ndarray:
    """Trailing moving average of ``signal`` over ``window`` seconds (shorter at the start)."""
    if len(t) == 0:
        return np.asarray(signal, dtype=float)
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    n = max(1, int(round(window / dt)))
    cumulative = np.concatenate([[0.0], np.cumsum(signal)])
    index = np.arange(1, len(signal) + 1)
    start = np.maximum(index - n, 0)
    return (cumulative[index] - cumulative[start]) / (index - start)


def max_stance_slide(t: np.ndarray, feet: np.ndarray, replans: dict) -> float:
    """Largest horizontal distance between the stance foot and where it touched down [m].

    At every replan the stance foot's measured position is compared with the stance position the
    controller recorded at its touchdown (``stance_x``, ``stance_y``): a slip shows up as a large
    distance even when the sliding foot loses and regains contact.

    Args:
        t: (n,) tick times [s]; feet: (n, n_feet, 3) foot positions, world frame [m].
        replans: the replan log (``t``, ``stance_foot``, ``stance_x``, ``stance_y``).
    """
    if not {"stance_foot", "stance_x", "stance_y"} <= set(replans) or len(replans["t"]) == 0:
        return 0.0
    index = np.clip(np.searchsorted(t, replans["t"]), 0, len(t) - 1)
    foot = replans["stance_foot"].astype(int)
    measured = feet[index, foot, :2]
    recorded = np.column_stack([replans["stance_x"], replans["stance_y"]])
    return float(np.max(np.linalg.norm(measured - recorded, axis=1)))


def velocity_in_heading_frame(ticks: dict[str, np.ndarray]) -> np.ndarray:
    """The base's horizontal velocity in its heading frame, R(ψ)ᵀ v_xy at each tick [m/s], shape (n, 2):
    ψ the base yaw (``ticks["x"][:, 3:7]``, Pinocchio quaternion), v the world-frame
    ``base_velocity_world``; x forward along the base's heading, y to its left (the command's frame)."""
    yaw = base_yaw(ticks["x"][:, 3:7])
    c, s = np.cos(yaw), np.sin(yaw)
    vx, vy = ticks["base_velocity_world"][:, 0], ticks["base_velocity_world"][:, 1]
    return np.column_stack([c * vx + s * vy, c * vy - s * vx])


def path_metrics(path: PlanarPath, position: np.ndarray, yaw: np.ndarray, laps: float = 1.0) -> dict[str, float]:
    """How closely a walk followed ``path`` (definitions in the module docstring).

    Args:
        path: the path.
        position: (n, 2) base ground projection, world frame [m], in time order.
        yaw: (n,) base yaw [rad].
        laps: times round the path the walk was meant to go (the completion's denominator).
    """
    s, distance = path.project(position)
    progress = np.unwrap(s, period=path.length)  # continuous arc length, across the start of a lap
    progress -= path.length * np.round(progress[0] / path.length)  # from the start: within ±length/2 of 0
    metrics = {"path_deviation_max": float(np.max(distance)), "path_deviation_mean": float(np.mean(distance)),
               "path_progress": float(progress[-1]), "path_completion": float(progress[-1] / (laps * path.length))}
    half = 0.5 * path.length
    to_corners = np.abs((s[:, None] - path.corners[None, :] + half) % path.length - half)  # (n, k) [m], along the path
    away = np.all(to_corners > HEADING_CORNER_MARGIN, axis=1)
    error = np.abs(wrap_angle(np.asarray(yaw, dtype=float) - path.heading_at(s)))[away]
    metrics["heading_error_max"] = float(np.max(error)) if error.size else None
    metrics["heading_error_mean"] = float(np.mean(error)) if error.size else None
    return metrics


def yaw_error(t: np.ndarray, yaw: np.ndarray, yaw_rate_command: np.ndarray, push_start: float,
              undisturbed_yaw: np.ndarray | None = None) -> np.ndarray | None:
    """The heading error e(t) = ψ(t) − Ψ(t) − e₀ of a yaw disturbance (module docstring) [rad], shape (n,).

    Args:
        t: (n,) tick times [s], uniformly spaced.
        yaw: (n,) base yaw, world frame [rad] (wrapped or not: it is unwrapped here).
        yaw_rate_command: (n,) commanded yaw rate at each tick [rad/s].
        push_start: start of the disturbance [s]; e₀ is the mean of ψ − Ψ over the ``YAW_AVERAGE_WINDOW`` before it.
        undisturbed_yaw: (n,) the base yaw [rad] of the same run without the disturbance (same seed, same
            ticks), or None. Given, it is Ψ: e then holds the disturbance's effect alone, without the
            heading drift the walk has on its own (a deterministic simulation repeats the run up to the push,
            so e₀ = 0); None: Ψ is the integral of ``yaw_rate_command``.

    Returns:
        e (n,), or None when the log has no tick before the push.
    """
    t = np.asarray(t, dtype=float)
    if undisturbed_yaw is None:
        commanded = np.concatenate([[0.0], np.cumsum(np.asarray(yaw_rate_command, dtype=float)[:-1]) * (t[1] - t[0])])
    else:
        commanded = np.unwrap(np.asarray(undisturbed_yaw, dtype=float))
    relative = np.unwrap(np.asarray(yaw, dtype=float)) - commanded  # ψ − Ψ
    before = (t >= push_start - YAW_AVERAGE_WINDOW) & (t < push_start)
    return relative - np.mean(relative[before]) if before.any() else None


def yaw_disturbance_metrics(t: np.ndarray, yaw: np.ndarray, yaw_rate_command: np.ndarray, push_start: float,
                            push_end: float, completed: bool,
                            undisturbed_yaw: np.ndarray | None = None) -> dict[str, float | None]:
    """The pelvis's heading error after a yaw disturbance (definitions in the module docstring).

    Args:
        t, yaw, yaw_rate_command, push_start, undisturbed_yaw: as :func:`yaw_error`.
        push_end: end of the disturbance [s].
        completed: the run ended without a fall (else ``yaw_push_error`` is None).

    Returns:
        ``yaw_push_error`` [rad, signed] and ``yaw_push_error_abs`` [rad] (None when not measurable),
        ``yaw_push_error_peak`` [rad], ``yaw_push_rate_peak`` and ``yaw_push_rate_before`` [rad/s]
        (None when the log ends before the push or has no window before it).
    """
    t = np.asarray(t, dtype=float)
    metrics: dict[str, float | None] = dict.fromkeys(
        ("yaw_push_error", "yaw_push_error_abs", "yaw_push_error_peak", "yaw_push_rate_peak", "yaw_push_rate_before"))
    error = yaw_error(t, yaw, yaw_rate_command, push_start, undisturbed_yaw)  # e(t) [rad]
    if error is None or t[-1] < push_start:
        return metrics
    rate = np.gradient(error, t[1] - t[0])  # ψ̇ − commanded rate [rad/s]
    before = (t >= push_start - YAW_AVERAGE_WINDOW) & (t < push_start)
    during = (t >= push_start) & (t <= push_end + YAW_RATE_WINDOW)
    metrics["yaw_push_error_peak"] = float(np.max(np.abs(error[t >= push_start])))
    metrics["yaw_push_rate_peak"] = float(np.max(np.abs(rate[during])))
    metrics["yaw_push_rate_before"] = float(np.max(np.abs(rate[before])))
    after = t >= t[-1] - YAW_AVERAGE_WINDOW
    if completed and t[-1] - YAW_AVERAGE_WINDOW >= push_end + YAW_SETTLE_TIME:
        metrics["yaw_push_error"] = float(np.mean(error[after]))
        metrics["yaw_push_error_abs"] = abs(metrics["yaw_push_error"])
    return metrics


def compute_metrics(log) -> dict[str, Any]:
    """Metrics of a :class:`sim.log.RunLog` (works on partial logs of falls and errors)."""
    ticks, replans, timing = log.ticks, log.replans, log.timing
    t = ticks.get("t", np.zeros(0))
    metrics: dict[str, Any] = {
        "status": log.status,
        "fell": log.status == "fell",
        "fall_time": log.fall_time,
        "fall_reason": log.fall_reason,
        "simulated_time": float(len(t) * (t[1] - t[0])) if len(t) > 1 else 0.0,
    }
    loop = timing.get("loop", timing.get("total", 0.0))
    metrics["real_time_factor"] = metrics["simulated_time"] / loop if loop > 0 else None
    metrics["setup_time"] = timing.get("setup")
    if len(t) < 2:
        return metrics

    velocity = ticks["base_velocity_world"]
    command = ticks["velocity_command"]
    metrics["distance_x"] = float(ticks["x"][-1, 0] - ticks["x"][0, 0])

    # Steady window: after steady_start and after the last change of command.
    steady_start = float(log.params.get("steady_start", 3.0))
    changes = np.flatnonzero(np.any(np.diff(command, axis=0) != 0, axis=1))
    last_change = t[changes[-1] + 1] if len(changes) else t[0]
    start = max(t[0] + steady_start, last_change + steady_start)
    window = t >= start
    metrics["steady_window"] = [float(start), float(t[-1])] if window.any() else None
    if window.sum() > 1:
        mean_velocity = velocity[window, :2].mean(axis=0)
        error = np.abs(mean_velocity - command[window][-1, :2])
        metrics["mean_velocity_x"], metrics["mean_velocity_y"] = float(mean_velocity[0]), float(mean_velocity[1])
        metrics["velocity_error_x"], metrics["velocity_error_y"] = float(error[0]), float(error[1])
        heading_velocity = velocity_in_heading_frame(ticks)[window].mean(axis=0)
        yaw = np.unwrap(base_yaw(ticks["x"][window, 3:7]))
        heading_error = np.abs(heading_velocity - command[window][-1, :2])
        metrics["mean_velocity_heading_x"], metrics["mean_velocity_heading_y"] = (float(v) for v in heading_velocity)
        metrics["velocity_error_heading_x"], metrics["velocity_error_heading_y"] = (float(e) for e in heading_error)
        span = t[window][-1] - t[window][0]
        metrics["mean_yaw_rate"] = float((yaw[-1] - yaw[0]) / span)
        metrics["yaw_rate_error"] = float(abs(metrics["mean_yaw_rate"] - command[window][-1, 2]))

    # Rise time after a step in the command (scenarios with a "speed_switch" event).
    events = log.params.get("events", {})
    if "speed_switch" in events and t[-1] > events["speed_switch"]:
        i_change = int(np.searchsorted(t, events["speed_switch"] - 1e-9))
        before, after = command[max(i_change - 1, 0), 0], command[i_change, 0]
        average_x = running_average(t, velocity[:, 0])
        target = before + 0.9 * (after - before)
        later = np.arange(i_change, len(t))
        reached = later[(average_x[later] - target) * np.sign(after - before) >= 0]
        metrics["rise_time"] = float(t[reached[0]] - t[i_change]) if len(reached) else None

    # Push recovery.
    if "push_start" in events and "push_end" in events:
        push_start, push_end = events["push_start"], events["push_end"]
        metrics["push_applied"] = bool(t[-1] >= push_end)
        metrics["push_recovered"] = bool(t[-1] >= push_end) and log.status == "completed"
        average_y = running_average(t, velocity[:, 1])
        before = t < push_start
        if before.any() and t[-1] >= push_end:
            reference = average_y[before][-1]
            after = np.flatnonzero(t >= push_end)
            outside = np.abs(average_y[after] - reference) > RECOVERY_BAND
            if not outside.any():
                metrics["push_recovery_time"] = 0.0
            elif outside[-1]:
                metrics["push_recovery_time"] = None
            else:
                last_outside = after[np.flatnonzero(outside)[-1]]
                metrics["push_recovery_time"] = float(t[last_outside + 1] - push_end)
            metrics["push_max_dcm_deviation_y"] = float(
                np.max(np.abs(ticks["dcm"][after, 1] - ticks["dcm"][before][-1, 1]))
            )

    # Yaw disturbance: a push with a moment about z (yaw_push).
    if "push_start" in events and log.params.get("scenario", {}).get("moment", 0.0) != 0.0:
        metrics.update(yaw_disturbance_metrics(t, base_yaw(ticks["x"][:, 3:7]), command[:, 2], events["push_start"],
                                               events["push_end"], log.status == "completed"))

    # Path following (waypoints).
    scenario = log.params.get("scenario", {})
    path = path_from_parameters(scenario)
    if path is not None:
        metrics.update(path_metrics(path, ticks["x"][:, :2], base_yaw(ticks["x"][:, 3:7]), scenario.get("laps", 1.0)))

    # Obstacle crossing (scenario "obstacle"; definitions in sim.obstacle_metrics).
    if log.params.get("obstacle_truth"):
        from sim.obstacle_metrics import obstacle_metrics

        metrics.update(obstacle_metrics(log))

    # Foot slip: stance foot away from where it touched down.
    if "feet" in ticks:
        metrics["max_stance_slide"] = max_stance_slide(t, ticks["feet"], replans)

    # Torques.
    limit = np.asarray(log.params.get("torque_limit", np.full(ticks["tau"].shape[1], np.inf)))
    metrics["max_torque"] = float(np.max(np.abs(ticks["tau"])))
    metrics["max_torque_ratio"] = float(np.max(np.abs(ticks["tau_command"]) / limit))
    metrics["saturated_fraction"] = float(np.mean(np.any(np.abs(ticks["tau_command"]) > limit, axis=1)))

    # MPC.
    if "mpc_tick_time" in replans and len(replans["mpc_tick_time"]):
        ok = replans["mpc_ok"] > 0.5
        real = replans.get("mpc_injected_failure", np.zeros(len(ok))) < 0.5
        metrics["mpc_cold_start_time"] = float(replans["mpc_tick_time"][0])
        tick_time = replans["mpc_tick_time"][1:][real[1:]]  # warm-started updates only
        metrics["mpc_updates"] = int(len(ok))
        metrics["mpc_failures"] = int(np.sum(~ok))
        metrics["mpc_injected_failures"] = int(np.sum(replans.get("mpc_injected_failure", 0.0) > 0.5))
        if len(tick_time):
            metrics["mpc_tick_time_median"] = float(np.median(tick_time))
            metrics["mpc_tick_time_p99"] = float(np.percentile(tick_time, 99))
        if "mpc_prepare_time" in replans:  # work done ahead of the next update (WalkingMPC.prepare)
            prepare = np.nan_to_num(replans["mpc_prepare_time"], nan=0.0)
            # cycle of update k: its tick plus the preparation made for it after update k - 1
            cycle = (replans["mpc_tick_time"][1:] + prepare[:-1])[real[1:]]
            if len(cycle):
                made = prepare[prepare > 0]
                metrics["mpc_prepare_time_median"] = float(np.median(made)) if made.size else 0.0
                metrics["mpc_cycle_time_median"] = float(np.median(cycle))
                metrics["mpc_cycle_time_p99"] = float(np.percentile(cycle, 99))
        metrics["sequencer_failures"] = int(np.sum(replans.get("sequencer_ok", np.ones(1)) < 0.5))
        if "stance_switched" in replans:
            metrics["steps"] = int(np.sum(replans["stance_switched"] > 0.5))
    return metrics


def paper_comparison(metrics: dict[str, Any]) -> dict[str, dict[str, float | None]]:
    """{figure: {"ours": value, "paper": value}} for the figures the paper reports."""
    return {name: {"ours": metrics.get(name), "paper": value} for name, value in PAPER_FIGURES.items() if name in metrics}
