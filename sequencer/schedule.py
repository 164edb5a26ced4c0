"""Per-node contact schedule: the data a footstep plan hands to the whole-body OCP.

A :class:`ContactSchedule` samples a footstep plan on the OCP's time grid. Node ``k`` is at
time ``t0 + k * dt``; there are ``n_nodes + 1`` rows (running nodes and the terminal node).
Feet are indexed in the order of ``feet`` (the plan's ``feet``, ``("left", "right")`` for the
DCM planner); the robot description maps these names to its frames. Positions are world (x, y)
[m], yaws world yaws about z [rad].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbmpc.errors import ParameterError

SCHEDULE_ROUNDINGS = ("next", "nearest")


@dataclass(frozen=True)
class ContactSchedule:
    """Which feet touch the ground at each OCP node, and where and how each swing ends.

    Attributes:
        t0: time of node 0 [s] (same clock as the plan).
        dt: node spacing [s], > 0.
        feet: foot names, e.g. ``("left", "right")``; column j of every array is ``feet[j]``.
        in_contact: shape (n_nodes + 1, n_feet), bool. True where the foot is in contact
            (single and double support).
        swing_phase: shape (n_nodes + 1, n_feet), fraction of the current swing elapsed at
            the node, in [0, 1]; NaN where the foot is in contact.
        swing_duration: shape (n_nodes + 1, n_feet), total duration of the current swing (lift-off
            to touchdown) [s]; NaN where the foot is in contact.
        touchdown_position: shape (n_nodes + 1, n_feet, 2), world-frame (x, y) of the planned
            foothold ending the current swing [m]; NaN where the foot is in contact.
        touchdown_yaw: shape (n_nodes + 1, n_feet), world yaw of that foothold [rad]; NaN where
            the foot is in contact. Omitted (None): 0 for every swinging foot (a plan without
            heading), NaN in contact.
        contact_yaw: shape (n_nodes + 1, n_feet), world yaw of the foothold a foot in contact
            stands on [rad] (the stance yaw of the plan, or the yaw of the foot's last planned
            touchdown); NaN where the foot swings, and where it landed before the plan was made
            (the trailing foot of a double support at the start of the plan). Omitted (None): 0
            in contact, NaN in swing.
    """

    t0: float
    dt: float
    feet: tuple[str, ...]
    in_contact: np.ndarray
    swing_phase: np.ndarray
    swing_duration: np.ndarray
    touchdown_position: np.ndarray
    touchdown_yaw: np.ndarray | None = None
    contact_yaw: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise ParameterError(f"dt={self.dt} s must be a finite positive number")
        n_feet = len(self.feet)
        rows = self.in_contact.shape[0]
        if self.touchdown_yaw is None:
            object.__setattr__(self, "touchdown_yaw", np.where(np.asarray(self.in_contact, dtype=bool), np.nan, 0.0))
        if self.contact_yaw is None:
            object.__setattr__(self, "contact_yaw", np.where(np.asarray(self.in_contact, dtype=bool), 0.0, np.nan))
        expected = {
            "in_contact": (rows, n_feet),
            "swing_phase": (rows, n_feet),
            "swing_duration": (rows, n_feet),
            "touchdown_position": (rows, n_feet, 2),
            "touchdown_yaw": (rows, n_feet),
            "contact_yaw": (rows, n_feet),
        }
        for name, shape in expected.items():
            if getattr(self, name).shape != shape:
                raise ParameterError(f"{name} has shape {getattr(self, name).shape}, expected {shape}")

    @property
    def n_nodes(self) -> int:
        """Number of running nodes (the schedule has ``n_nodes + 1`` rows)."""
        return self.in_contact.shape[0] - 1

    @property
    def times(self) -> np.ndarray:
        """Node times [s], shape (n_nodes + 1,)."""
        return self.t0 + self.dt * np.arange(self.n_nodes + 1)


def contact_schedule(plan, t0: float, dt: float, n_nodes: int, rounding: str = "next") -> ContactSchedule:
    """Sample a :class:`sequencer.horizon.FootstepPlan` on the OCP grid ``t0 + k dt``, k = 0..n_nodes.

    The plan is a sequence of touchdowns, one foot each (``plan.steps[i].foot`` lands at
    ``plan.steps[i].touchdown_time``). The foot landing at touchdown i lifts off
    ``plan.double_support`` seconds after the previous touchdown (after ``plan.t_stance_start``
    for the first one) and swings until its touchdown; every other foot is in contact. Nodes before
    ``plan.t_stance_start`` (a plan for a stance that has not begun: a start from standing, see
    :meth:`sequencer.dcm_planner.DcmFootstepPlanner.plan`) have every foot in contact. With
    ``double_support = 0`` (point feet) exactly one foot of a biped is in stance between two
    touchdowns, and at a node exactly on a touchdown time the landing foot is in contact and the
    other foot starts its swing (phase 0). The swing phase and duration run over the swing itself
    (lift-off to touchdown), shortened by the double support.

    ``rounding`` says which node a touchdown (or a lift-off) between two nodes falls on:
    ``"next"`` (default) the first node at or after it, so the sampled contact starts up to one
    node (on average half a node) after the planned time; ``"nearest"`` the node nearest to it
    (half a node earlier or later at most, no bias on average). The closed loop uses "nearest":
    with "next" Bolt's feet landed ~4 ms after the planned touchdowns, when the DCM runs at
    ~0.9 m/s relative to the foot, and the sequencer answered the offset with longer steps
    (docs/closed_loop.md).

    Args:
        plan: FootstepPlan; its ``feet`` name the columns, its ``double_support`` [s] the time both
            feet stay on the ground after each touchdown.
        t0: time of node 0 [s] (before ``plan.t_stance_start``: double support until then).
        dt: node spacing [s], > 0.
        n_nodes: number of running nodes, >= 1; the grid must end before the last planned
            touchdown (the swing in progress there would have no planned end).
        rounding: ``"next"`` or ``"nearest"`` (see above).

    Returns:
        ContactSchedule with ``feet == plan.feet``; ``touchdown_yaw`` and ``contact_yaw`` from the
        plan's ``stance_yaw`` and the steps' ``yaw``.
    """
    t0 = float(t0)
    dt = float(dt)
    if not (np.isfinite(dt) and dt > 0):
        raise ParameterError(f"dt={dt} s must be a finite positive number")
    if isinstance(n_nodes, bool) or int(n_nodes) != n_nodes or n_nodes < 1:
        raise ParameterError(f"n_nodes={n_nodes!r} must be an integer >= 1")
    n_nodes = int(n_nodes)
    if rounding not in SCHEDULE_ROUNDINGS:
        raise ParameterError(f"rounding={rounding!r} must be one of {SCHEDULE_ROUNDINGS}")
    if not np.isfinite(t0):
        raise ParameterError(f"t0={t0} s must be finite")
    feet = tuple(plan.feet)
    column = {foot: j for j, foot in enumerate(feet)}
    try:
        stance_column = column[plan.stance_foot]
        landing_columns = [column[step.foot] for step in plan.steps]
    except KeyError:
        unknown = sorted({plan.stance_foot, *(step.foot for step in plan.steps)} - set(column))
        raise ParameterError(f"the plan's stance and steps use feet {unknown} that are not in its feet {feet}") from None
    times = t0 + dt * np.arange(n_nodes + 1)
    touchdowns = plan.touchdown_times
    if times[-1] >= touchdowns[-1]:
        raise ParameterError(
            f"the grid ends at t0 + n_nodes*dt = {times[-1]:.4g} s, at or after the plan's last touchdown "
            f"{touchdowns[-1]:.4g} s: plan with a longer horizon or use fewer nodes"
        )
    # index of the stance interval of each node: 0 = current stance, k = after the k-th touchdown
    shift = 0.5 * dt if rounding == "nearest" else 0.0
    interval = np.searchsorted(touchdowns, times + shift, side="right")
    rows = np.arange(n_nodes + 1)
    node_interval, node_times = interval, times
    start = np.concatenate([[plan.t_stance_start], touchdowns])[interval]  # the previous touchdown
    end = touchdowns[interval]
    double_support = float(plan.double_support)
    start = start + double_support  # lift-off of the landing foot
    if double_support > 0.0 and np.any(end <= start):
        late = float(end[np.argmax(end <= start)])
        raise ParameterError(
            f"double_support={double_support} s leaves no swing before the touchdown at {late:.4g} s"
        )
    swinging = times + shift >= start  # (all nodes for point feet, once the stance has begun)
    rows, interval, start, end = rows[swinging], interval[swinging], start[swinging], end[swinging]
    node_times = times[swinging]
    swing = np.array(landing_columns)[interval]
    in_contact = np.ones((n_nodes + 1, len(feet)), dtype=bool)
    in_contact[rows, swing] = False
    swing_phase = np.full((n_nodes + 1, len(feet)), np.nan)
    swing_phase[rows, swing] = np.clip((node_times - start) / (end - start), 0.0, 1.0)
    swing_duration = np.full((n_nodes + 1, len(feet)), np.nan)
    swing_duration[rows, swing] = end - start
    touchdown_position = np.full((n_nodes + 1, len(feet), 2), np.nan)
    touchdown_position[rows, swing] = plan.positions[interval]
    touchdown_yaw = np.full((n_nodes + 1, len(feet)), np.nan)
    touchdown_yaw[rows, swing] = plan.yaws[interval]
    # yaw of the foothold each foot stands on in each stance interval (NaN: it landed before the plan)
    standing = [np.nan] * len(feet)
    standing[stance_column] = plan.stance_yaw
    standing_yaw = [standing]
    for step, j in zip(plan.steps[: int(node_interval[-1])], landing_columns):
        standing = standing.copy()
        standing[j] = step.yaw
        standing_yaw.append(standing)
    contact_yaw = np.array(standing_yaw)[node_interval]
    contact_yaw[rows, swing] = np.nan
    return ContactSchedule(
        t0=t0, dt=dt, feet=feet, in_contact=in_contact, swing_phase=swing_phase,
        swing_duration=swing_duration, touchdown_position=touchdown_position, touchdown_yaw=touchdown_yaw,
        contact_yaw=contact_yaw,
    )
