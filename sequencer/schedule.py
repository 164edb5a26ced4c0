"""Per-node contact schedule: the data the sequencer hands to the whole-body OCP.

A :class:`ContactSchedule` samples a footstep plan on the OCP's time grid. Node ``k`` is at
time ``t0 + k * dt``; there are ``n_nodes + 1`` rows (running nodes and the terminal node).
Feet are indexed in the order of ``feet`` (``("left", "right")`` for bipeds); the robot
description maps these names to its frames.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbmpc.errors import ParameterError

SCHEDULE_ROUNDINGS = ("next", "nearest")


@dataclass(frozen=True)
class ContactSchedule:
    """Which feet touch the ground at each OCP node, and where each swing ends.

    Attributes:
        t0: time of node 0 [s] (same clock as the plan).
        dt: node spacing [s], > 0.
        feet: foot names, e.g. ``("left", "right")``.
        in_contact: shape (n_nodes + 1, n_feet), bool. True where the foot is in contact.
        swing_phase: shape (n_nodes + 1, n_feet), fraction of the current swing elapsed at
            the node, in [0, 1]; NaN where the foot is in contact.
        swing_duration: shape (n_nodes + 1, n_feet), total duration of the current swing [s];
            NaN where the foot is in contact.
        touchdown_position: shape (n_nodes + 1, n_feet, 2), world-frame (x, y) of the planned
            foothold ending the current swing [m]; NaN where the foot is in contact.
    """

    t0: float
    dt: float
    feet: tuple[str, ...]
    in_contact: np.ndarray
    swing_phase: np.ndarray
    swing_duration: np.ndarray
    touchdown_position: np.ndarray

    def __post_init__(self) -> None:
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise ParameterError(f"dt={self.dt} s must be a finite positive number")
        n_feet = len(self.feet)
        rows = self.in_contact.shape[0]
        expected = {
            "in_contact": (rows, n_feet),
            "swing_phase": (rows, n_feet),
            "swing_duration": (rows, n_feet),
            "touchdown_position": (rows, n_feet, 2),
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

    Point feet, no double support: between two touchdowns exactly one foot is in stance and the
    other one swings from the previous touchdown (the start of the current stance) to its own
    next touchdown. At a node exactly on a touchdown time the landing foot is in contact and the
    other foot starts its swing (phase 0).

    ``rounding`` says which node a touchdown between two nodes falls on: ``"next"`` (default) the
    first node at or after it, so the sampled contact starts up to one node (on average half a
    node) after the planned time; ``"nearest"`` the node nearest to it (half a node earlier or
    later at most, no bias on average). The closed loop uses "nearest": with "next" Bolt's feet
    landed ~4 ms after the planned touchdowns, when the DCM runs at ~0.9 m/s relative to the
    foot, and the sequencer answered the offset with longer steps (docs/closed_loop.md).

    Args:
        plan: FootstepPlan (feet ``"left"``/``"right"``).
        t0: time of node 0 [s], >= plan.t_stance_start.
        dt: node spacing [s], > 0.
        n_nodes: number of running nodes, >= 1; the grid must end before the last planned
            touchdown (the swing in progress there would have no planned end).
        rounding: ``"next"`` or ``"nearest"`` (see above).

    Returns:
        ContactSchedule with ``feet == ("left", "right")``.
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
    if not np.isfinite(t0) or t0 < plan.t_stance_start:
        raise ParameterError(
            f"t0={t0} s must be finite and >= the plan's current stance start {plan.t_stance_start} s"
        )
    feet = ("left", "right")
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
    stance_starts = np.concatenate([[plan.t_stance_start], touchdowns])
    stance_index = np.array([feet.index(plan.stance_foot)] + [feet.index(step.foot) for step in plan.steps])
    rows = np.arange(n_nodes + 1)
    stance = stance_index[interval]
    swing = 1 - stance
    start, end = stance_starts[interval], touchdowns[interval]
    in_contact = np.zeros((n_nodes + 1, 2), dtype=bool)
    in_contact[rows, stance] = True
    swing_phase = np.full((n_nodes + 1, 2), np.nan)
    swing_phase[rows, swing] = np.clip((times - start) / (end - start), 0.0, 1.0)
    swing_duration = np.full((n_nodes + 1, 2), np.nan)
    swing_duration[rows, swing] = end - start
    touchdown_position = np.full((n_nodes + 1, 2, 2), np.nan)
    touchdown_position[rows, swing] = plan.positions[interval]
    return ContactSchedule(
        t0=t0, dt=dt, feet=feet, in_contact=in_contact, swing_phase=swing_phase,
        swing_duration=swing_duration, touchdown_position=touchdown_position,
    )
