"""Figures of a closed-loop run, in the layout of the paper's Figs. 5-8.

- :func:`plot_lateral`: CoM (purple), DCM (green) and feet (red left, blue right; drawn while in
  contact) along y over time (Figs. 5 and 7), with the planned footholds as dots;
- :func:`plot_velocity`: base velocity along x and y (blue), its running average (green) and the
  command (red) over time (Figs. 6 and 8); world axes, or the heading frame (the command's) when
  the run turns (:data:`TURNING_YAW_SPAN`);
- :func:`plot_plane`: foot contacts and DCM in the ground plane (as Fig. 3, for the executed walk);
  a flat-footed robot's footsteps are drawn as its sole rectangles at their yaw (:func:`footsteps`);
- :func:`plot_path` (runs that follow a path, ``waypoints``): the path (grey, corners as
  squares), the footholds (foot positions in contact) and the CoM trace in the ground plane,
  equal scales, with the path metrics in the title;
- :func:`save_figures`: all of them into one PNG (``--plot FILE``, and ``figures.png`` in ``--out``).
"""

from __future__ import annotations

import os

import numpy as np

from robots.conventions import base_yaw
from sim.metrics import running_average, velocity_in_heading_frame
from sim.paths import path_from_parameters

COLORS = {"com": "tab:purple", "dcm": "tab:green", "left": "tab:red", "right": "tab:blue", "command": "tab:red"}
TURNING_YAW_SPAN = 0.3  # [rad]: a run whose base yaw spans more is drawn in the heading frame
FOOTSTEP_MIN_CONTACT = 0.05  # [s]: a contact shorter than this is not drawn as a footstep (touchdown bounces)


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def _mark_events(ax, log) -> None:
    for name, value in log.params.get("events", {}).items():
        if name.startswith(("push", "speed")):
            ax.axvline(value, color="0.6", lw=0.8, ls="--")
    if log.fall_time is not None:
        ax.axvline(log.fall_time, color="k", lw=1.0)
        ax.text(log.fall_time, ax.get_ylim()[1], " fall", va="top", fontsize=8)


def plot_lateral(log, ax=None, t_range: tuple[float, float] | None = None):
    """CoM, DCM and feet along y [m] over time [s] (paper Figs. 5 and 7)."""
    plt = _pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 3))
    ticks = log.ticks
    t = ticks["t"]
    keep = np.ones(len(t), bool) if t_range is None else (t >= t_range[0]) & (t <= t_range[1])
    ax.plot(t[keep], ticks["com"][keep, 1], color=COLORS["com"], label="CoM")
    ax.plot(t[keep], ticks["dcm"][keep, 1], color=COLORS["dcm"], label="DCM")
    feet_names = ("left", "right")
    for j, foot in enumerate(feet_names[: ticks["feet"].shape[1]]):
        y = np.where(ticks["foot_contact"][:, j], ticks["feet"][:, j, 1], np.nan)
        ax.plot(t[keep], y[keep], color=COLORS[foot], lw=2.5, label=f"{foot} foot (contact)")
    replans = log.replans
    if "next_y" in replans and len(replans["next_y"]):
        rt = replans["t"]
        rkeep = np.ones(len(rt), bool) if t_range is None else (rt >= t_range[0]) & (rt <= t_range[1])
        for j, foot in enumerate(feet_names):
            sel = rkeep & (replans["next_foot"] == j)
            ax.scatter(replans["next_touchdown_time"][sel], replans["next_y"][sel], s=4, color=COLORS[foot], alpha=0.4)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("y [m]")
    ax.legend(loc="upper right", fontsize=7, ncol=4)
    _mark_events(ax, log)
    return ax


def turns(log) -> bool:
    """True when the run's base yaw spans more than :data:`TURNING_YAW_SPAN` (its velocities are then
    drawn in the heading frame: world axes would mix forward and lateral speed)."""
    yaw = np.unwrap(base_yaw(log.ticks["x"][:, 3:7])) if len(log.ticks["t"]) else np.zeros(1)
    return bool(np.ptp(yaw) > TURNING_YAW_SPAN)


def plot_velocity(log, axes=None):
    """Base velocity x and y [m/s] with its running average and the command (paper Figs. 6 and 8):
    world axes, or the heading frame for a run that :func:`turns` (the command is in that frame)."""
    plt = _pyplot()
    if axes is None:
        _, axes = plt.subplots(2, 1, figsize=(8, 4), sharex=True)
    t = log.ticks["t"]
    heading = turns(log)
    velocity = velocity_in_heading_frame(log.ticks) if heading else log.ticks["base_velocity_world"][:, :2]
    for j, (ax, axis) in enumerate(zip(axes, "xy")):
        v = velocity[:, j]
        ax.plot(t, v, color="tab:blue", lw=0.6, label=f"base v_{axis}")
        ax.plot(t, running_average(t, v), color="tab:green", label="running average (1 s)")
        ax.plot(t, log.ticks["velocity_command"][:, j], color=COLORS["command"], label="command")
        ax.set_ylabel(f"v_{axis} [m/s]" + (" (heading)" if heading else ""))
        _mark_events(ax, log)
    axes[0].legend(loc="lower right", fontsize=7, ncol=3)
    axes[-1].set_xlabel("t [s]")
    return axes


EQUAL_ASPECT_MAX_RATIO = 4.0  # plane panel: equal x-y scales while the longer extent is at most this times the shorter


def plane_limits(x: np.ndarray, y: np.ndarray, aspect: float, margin: float = 0.05) -> tuple[tuple, tuple, bool]:
    """Axis limits of the ground-plane panel from the data drawn in it (NaN ignored).

    Args:
        x, y: the drawn points [m].
        aspect: the panel's height over its width (display units).
        margin: share of each extent added on both sides.

    Returns:
        (xlim, ylim, equal): equal scales when the data's extents are comparable (the longer at most
        ``EQUAL_ASPECT_MAX_RATIO`` times the other, once the panel's shape is taken out); else each
        axis spans its own data, so a 20 m walk keeps its ±0.1 m lateral sway readable.
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    keep = np.isfinite(x) & np.isfinite(y)
    if not keep.any():
        return (-1.0, 1.0), (-1.0, 1.0), True
    x, y = x[keep], y[keep]
    extent_x, extent_y = max(np.ptp(x), 0.02), max(np.ptp(y), 0.02)  # at least 2 cm: a still robot
    centre_x, centre_y = (x.min() + x.max()) / 2, (y.min() + y.max()) / 2
    ratio = (extent_x * aspect) / extent_y
    equal = 1.0 / EQUAL_ASPECT_MAX_RATIO <= ratio <= EQUAL_ASPECT_MAX_RATIO
    if equal:  # grow the shorter extent to the panel's shape
        extent_x, extent_y = max(extent_x, extent_y / aspect), max(extent_y, extent_x * aspect)
    half_x, half_y = (0.5 + margin) * extent_x, (0.5 + margin) * extent_y
    return (centre_x - half_x, centre_x + half_x), (centre_y - half_y, centre_y + half_y), equal


def footsteps(log) -> list[tuple[int, np.ndarray, float]]:
    """The run's footsteps: (foot index, sole centre (x, y) [m], sole yaw [rad]) of every contact that
    lasted :data:`FOOTSTEP_MIN_CONTACT` or more, taken at the contact's middle tick (world frame;
    the foot frame's yaw from the logged configuration by Pinocchio's forward kinematics)."""
    import pinocchio as pin

    from robots import load_robot

    ticks = log.ticks
    t = ticks["t"]
    if len(t) < 2:
        return []
    robot = load_robot(log.robot)
    model = robot.pinocchio_model
    data = model.createData()
    frames = [model.getFrameId(name) for name in robot.foot_frames.values()]
    shortest = int(round(FOOTSTEP_MIN_CONTACT / (t[1] - t[0])))
    steps = []
    for j, frame in enumerate(frames[: ticks["foot_contact"].shape[1]]):
        contact = np.concatenate([[False], ticks["foot_contact"][:, j], [False]]).astype(np.int8)
        starts, ends = np.flatnonzero(np.diff(contact) == 1), np.flatnonzero(np.diff(contact) == -1)
        for start, end in zip(starts, ends):
            if end - start < shortest:
                continue
            k = (start + end) // 2
            pin.framesForwardKinematics(model, data, ticks["x"][k, : model.nq])
            rotation = data.oMf[frame].rotation
            steps.append((j, ticks["feet"][k, j, :2].copy(), float(np.arctan2(rotation[1, 0], rotation[0, 0]))))
    return steps


def _draw_soles(ax, log, labels: bool) -> bool:
    """Draw the footsteps as sole rectangles (robots with a ``sole_size``); False when the robot has point feet."""
    from matplotlib.patches import Polygon

    from robots import load_robot

    size = load_robot(log.robot).sole_size
    if size is None:
        return False
    half = 0.5 * np.array(size)
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * half
    drawn = set()
    for j, centre, yaw in footsteps(log):
        c, s = np.cos(yaw), np.sin(yaw)
        foot = ("left", "right")[j]
        label = f"{foot} sole" if labels and foot not in drawn else None
        ax.add_patch(Polygon(centre + corners @ np.array([[c, s], [-s, c]]), closed=True, fill=False,
                             color=COLORS[foot], lw=0.8, label=label))
        drawn.add(foot)
    return True


def plot_plane(log, ax=None):
    """Foot contacts and DCM in the ground plane, x-y [m] (limits from the data: :func:`plane_limits`)."""
    plt = _pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 3))
    ticks = log.ticks
    ax.plot(ticks["dcm"][:, 0], ticks["dcm"][:, 1], color=COLORS["dcm"], lw=0.8, label="DCM")
    ax.plot(ticks["com"][:, 0], ticks["com"][:, 1], color=COLORS["com"], lw=0.8, label="CoM")
    xs, ys = [ticks["dcm"][:, 0], ticks["com"][:, 0]], [ticks["dcm"][:, 1], ticks["com"][:, 1]]
    soles = _draw_soles(ax, log, labels=True)
    for j, foot in enumerate(("left", "right")[: ticks["feet"].shape[1]]):
        contact = ticks["foot_contact"][:, j]
        ax.scatter(ticks["feet"][contact, j, 0], ticks["feet"][contact, j, 1], s=2 if not soles else 0.5,
                   color=COLORS[foot], label=None if soles else foot)
        xs.append(ticks["feet"][contact, j, 0])
        ys.append(ticks["feet"][contact, j, 1])
    bbox = ax.get_position()
    figure_width, figure_height = ax.figure.get_size_inches()
    aspect = (bbox.height * figure_height) / (bbox.width * figure_width)
    xlim, ylim, equal = plane_limits(np.concatenate(xs), np.concatenate(ys), aspect)
    if equal:  # matplotlib widens the shorter extent to the panel's shape
        ax.set_aspect("equal", adjustable="datalim")
    else:
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]" if equal else "y [m] (scale ≠ x)")
    ax.legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), fontsize=7, ncol=4, frameon=False)  # above the data
    return ax


def plot_path(log, ax=None):
    """The followed path, the footholds and the CoM trace in the ground plane, x-y [m], equal scales.

    Returns None (nothing drawn) when the run's scenario parameters name no path.
    """
    path = path_from_parameters(log.params.get("scenario", {}))
    if path is None:
        return None
    plt = _pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 6))
    ticks = log.ticks
    closed = np.vstack([path.vertices, path.vertices[:1]])
    ax.plot(closed[:, 0], closed[:, 1], color="0.6", lw=3.0, alpha=0.6, label=f"path ({path.name})")
    corners = path.point_at(path.corners)
    if len(corners):
        ax.scatter(corners[:, 0], corners[:, 1], marker="s", s=25, color="0.4", label="corners")
    soles = _draw_soles(ax, log, labels=True)
    for j, foot in enumerate(("left", "right")[: ticks["feet"].shape[1]]):
        contact = ticks["foot_contact"][:, j]
        ax.scatter(ticks["feet"][contact, j, 0], ticks["feet"][contact, j, 1], s=2 if not soles else 0.5,
                   color=COLORS[foot], label=None if soles else f"{foot} foot (contact)")
    ax.plot(ticks["com"][:, 0], ticks["com"][:, 1], color=COLORS["com"], lw=1.0, label="CoM")
    ax.scatter(*ticks["com"][0, :2], marker="o", s=30, color="k", zorder=3, label="start")
    m = log.metrics
    if m.get("path_deviation_max") is not None:
        heading = m.get("heading_error_max")
        ax.set_title(f"deviation max {m['path_deviation_max']:.3f} m, mean {m['path_deviation_mean']:.3f} m; "
                     f"heading error max {'n/a' if heading is None else f'{heading:.2f} rad'}; "
                     f"completion {100 * m['path_completion']:.0f} %", fontsize=9)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(loc="center", fontsize=7)  # inside the closed path, away from the traces
    return ax


def save_figures(log, path: str | os.PathLike) -> str:
    """Draw the figures of ``log`` into one PNG at ``path`` (with :func:`plot_path` below the others
    when the run followed a path); returns the path."""
    plt = _pyplot()
    follows_path = path_from_parameters(log.params.get("scenario", {})) is not None
    ratios = [1.2, 0.8, 0.8, 1.2] + ([3.0] if follows_path else [])
    fig = plt.figure(figsize=(10, 11 + (6 if follows_path else 0)))
    grid = fig.add_gridspec(len(ratios), 1, height_ratios=ratios)
    plot_lateral(log, fig.add_subplot(grid[0]))
    ax_x = fig.add_subplot(grid[1])
    plot_velocity(log, [ax_x, fig.add_subplot(grid[2], sharex=ax_x)])
    plot_plane(log, fig.add_subplot(grid[3]))
    if follows_path:
        plot_path(log, fig.add_subplot(grid[4]))
    title = f"{log.scenario} (seed {log.seed}): {log.status}"
    if log.fall_reason:
        title += f" at t = {log.fall_time:.2f} s ({log.fall_reason})"
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    directory = os.path.dirname(os.fspath(path))
    if directory:
        os.makedirs(directory, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return os.fspath(path)
