"""The OCP reference stage: a footstep plan sampled for the whole-body OCP of one MPC update.

From the plan it makes the contact schedule on the OCP grid (which feet are on the ground at
each node, swing phases, footholds) and the terminal CoM reference (eq. 24): the planner's CoM
prediction at the end of the horizon, at the planner's CoM height. Holding z at the model's
height (not at the measured height) matters: with the measured height the terminal cost let
Bolt's CoM creep up by 1 cm per second of walking (legs stretching) until it fell.

A plan whose steps pass over obstacles (``PlannedStep.crossing``, :mod:`sequencer.footholds`) also gives
the OCP its crossing swings on the grid (:class:`CrossingSchedule`): which obstacle each swinging foot
passes over and the swing's lift-off at each node; the foot's path from there to the schedule's touchdown
(:func:`wbmpc.walking.ocp.swing_path`, straight or smoothly timed) is where the OCP raises the swing apex and turns on its
clearance terms. Every swing's lift-off point on the grid (:func:`swing_liftoffs`) gives the OCP the path
its ``{foot}_swing_path`` terms track (``WalkingOCPConfig.swing_path_weight``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sequencer.schedule import ContactSchedule, contact_schedule, plan_covers_grid
from wbmpc.walking.stance import delay_to_touchdown, ground_waiting_nodes


@dataclass(frozen=True)
class OcpReference:
    """What one MPC update is given.

    Attributes:
        schedule: the contact schedule on the OCP grid (n_nodes + 1 rows).
        com_terminal: CoM reference at the end of the horizon (3,) [m], world frame.
        touchdown_wait: delay [s] applied to the plan so that a due but unmeasured touchdown
            lies ahead (0 when none, see :func:`wbmpc.walking.stance.delay_to_touchdown`).
        touchdown_depth: how far below the ground the OCP aims that foot [m] (0 when no wait).
        crossings: the swings over obstacles on the grid, or None (the plan crosses none).
        com_path: the plan's CoM prediction at the nodes (n_nodes + 1, 3) [m], world (z at the planner's CoM
            height), when ``crossings`` is not None; else None.
        swing_liftoff: where the swing running at each node lifted off (:func:`swing_liftoffs`), or None when the
            stage is not asked for it.
    """

    schedule: ContactSchedule
    com_terminal: np.ndarray
    touchdown_wait: float
    touchdown_depth: float
    crossings: "CrossingSchedule | None" = None
    com_path: np.ndarray | None = None
    swing_liftoff: np.ndarray | None = None


@dataclass(frozen=True)
class CrossingSchedule:
    """The swings that pass over obstacles, on the OCP grid (rows and feet as the contact schedule's).

    Attributes:
        obstacles: the obstacles crossed (:class:`sequencer.obstacles.Obstacle`).
        index: (n_nodes + 1, n_feet) int, the index in ``obstacles`` of the obstacle the swinging foot passes
            over at that node, -1 where none (or in contact).
        liftoff_xy: (n_nodes + 1, n_feet, 2), world (x, y) [m] of the foot frame where that crossing swing
            lifted off; NaN where index is -1. It lands at the schedule's ``touchdown_position``; the foot's
            path between them: :func:`wbmpc.walking.ocp.swing_path`.
        path_yaw: (n_nodes + 1, n_feet), the touchdown yaw [rad] there (the sole's heading); NaN elsewhere.
        feet: foot names of the columns.
    """

    obstacles: tuple
    index: np.ndarray
    liftoff_xy: np.ndarray
    path_yaw: np.ndarray
    feet: tuple[str, ...]


def swing_liftoffs(plan: Any, schedule: ContactSchedule, current_liftoff=None) -> np.ndarray:
    """World (x, y) [m] of the foot frame where the swing running at each node of ``schedule`` (made from
    ``plan``) lifts off: (n_nodes + 1, n_feet, 2), NaN where the foot is in contact.

    A node's swing is the plan's step of that foot landing at the schedule's touchdown position; it lifts off
    from the foot's previous foothold in the plan, or, for the foot's first step, from the plan's stance
    position (the stance foot) or ``current_liftoff`` ((2,) [m]: where the foot swinging at the plan's start
    lifted off; None: unknown, NaN at those nodes)."""
    rows, n_feet = schedule.in_contact.shape
    liftoff = np.full((rows, n_feet, 2), np.nan)
    start = None if current_liftoff is None else np.asarray(current_liftoff, dtype=float)
    for j, foot in enumerate(schedule.feet):
        steps = [step for step in plan.steps if step.foot == foot]
        swinging = np.flatnonzero(~np.asarray(schedule.in_contact[:, j], dtype=bool))
        if not steps or not swinging.size:
            continue
        previous = [np.asarray(plan.stance_position, dtype=float) if foot == plan.stance_foot else start]
        previous += [np.asarray(step.position, dtype=float) for step in steps[:-1]]
        # the first step landing within 1e-9 m (per coordinate) of each swinging node's touchdown
        positions = np.array([step.position for step in steps], dtype=float)  # (steps, 2)
        touchdowns = np.asarray(schedule.touchdown_position, dtype=float)[swinging, j]  # (nodes, 2)
        lands = np.all(np.abs(touchdowns[:, None, :] - positions[None, :, :]) <= 1e-9, axis=2)  # (nodes, steps)
        first = np.argmax(lands, axis=1)
        for k, i, found in zip(swinging.tolist(), first.tolist(), lands.any(axis=1).tolist()):
            if found and previous[i] is not None:
                liftoff[k, j] = previous[i]
    return liftoff


def crossing_schedule(plan: Any, schedule: ContactSchedule) -> CrossingSchedule | None:
    """The :class:`CrossingSchedule` of ``plan``'s crossing steps on ``schedule`` (made from that plan), or None
    when no swing of the schedule is a crossing. A node's swing is the plan's step of that foot that lands at
    the schedule's touchdown position."""
    crossing_steps = [step for step in plan.steps if step.crossing is not None]
    if not crossing_steps:
        return None
    rows, n_feet = schedule.in_contact.shape
    index = np.full((rows, n_feet), -1, dtype=int)
    liftoff = np.full((rows, n_feet, 2), np.nan)
    path_yaw = np.full((rows, n_feet), np.nan)
    obstacles: list = []
    for j, foot in enumerate(schedule.feet):
        for k in np.flatnonzero(~np.asarray(schedule.in_contact[:, j], dtype=bool)).tolist():
            touchdown = schedule.touchdown_position[k, j]
            step = next((s for s in crossing_steps if s.foot == foot and np.allclose(s.position, touchdown,
                                                                                      rtol=0.0, atol=1e-9)), None)
            if step is None:
                continue
            obstacle = step.crossing.obstacle
            which = next((i for i, known in enumerate(obstacles) if known is obstacle), None)
            if which is None:
                obstacles.append(obstacle)
                which = len(obstacles) - 1
            index[k, j] = which
            liftoff[k, j] = step.crossing.liftoff
            path_yaw[k, j] = step.yaw
    if not obstacles:
        return None
    return CrossingSchedule(tuple(obstacles), index, liftoff, path_yaw, tuple(schedule.feet))


class OcpReferenceStage:
    """Samples footstep plans on the OCP grid.

    Args:
        feet: foot names in the measurement order.
        n_nodes: OCP running nodes N.
        node_dt: node spacing [s].
        wait_for_contact: with contact touchdown detection, delay a due but unmeasured touchdown
            by ``wait_nodes`` nodes (see :func:`~wbmpc.walking.stance.delay_to_touchdown`).
        wait_nodes: see above.
        wait_depth: while waiting, the foot is aimed this far below the ground [m] and the waiting
            nodes' height reference stays on the ground (:func:`~wbmpc.walking.stance.ground_waiting_nodes`).
    """

    def __init__(self, feet: tuple[str, ...], n_nodes: int, node_dt: float, wait_for_contact: bool,
                 wait_nodes: int, wait_depth: float) -> None:
        self.feet = tuple(feet)
        self.n_nodes, self.node_dt = int(n_nodes), float(node_dt)
        self.wait_for_contact, self.wait_nodes = bool(wait_for_contact), int(wait_nodes)
        self.wait_depth = float(wait_depth)

    @property
    def horizon(self) -> float:
        """The OCP grid's length n_nodes * node_dt [s]."""
        return self.n_nodes * self.node_dt

    def covers(self, plan: Any, t: float) -> bool:
        """Whether ``plan`` can be sampled on the grid that starts at ``t`` [s]
        (:func:`~sequencer.schedule.plan_covers_grid`; waiting for a late touchdown only moves touchdowns later)."""
        return plan_covers_grid(plan, t, self.node_dt, self.n_nodes)

    def sample(self, plan: Any, t: float, com_xy: np.ndarray, foot_in_contact: np.ndarray,
               current_liftoff=None, liftoffs: bool = False) -> OcpReference:
        """The OCP reference of the update at ``t`` [s] from ``plan``; ``com_xy`` (2,) [m] is the
        measured CoM, ``foot_in_contact`` (n_feet,) the measured contacts. With ``liftoffs`` the reference
        holds every swing's lift-off (:func:`swing_liftoffs`; ``current_liftoff`` (2,) [m] or None: where the
        foot swinging at ``t`` lifted off)."""
        wait = 0.0
        sampled = plan
        if self.wait_for_contact:
            swing_foot = self.feet.index(plan.steps[0].foot)
            sampled, wait = delay_to_touchdown(plan, t, bool(foot_in_contact[swing_foot]), self.node_dt,
                                               self.wait_nodes)
        schedule = contact_schedule(sampled, t, self.node_dt, self.n_nodes, rounding="nearest")
        depth = 0.0
        if wait > 0.0:  # the swing foot is due and still in the air
            schedule = ground_waiting_nodes(schedule, plan.steps[0], sampled.steps[0])
            depth = self.wait_depth
        # (a plan for a stance that has not begun starts later than t: it predicts from its start)
        com_end = plan.com_reference(max(t + self.n_nodes * self.node_dt, plan.t0), com_xy)
        crossings = crossing_schedule(sampled, schedule)
        com_path = None
        if crossings is not None:  # the plan's CoM at the nodes, for the OCP's CoM tracking over a crossing
            times = np.maximum(t + self.node_dt * np.arange(self.n_nodes + 1), plan.t0)
            com_path = plan.com_reference(times, com_xy)
        liftoff = swing_liftoffs(sampled, schedule, current_liftoff) if liftoffs else None
        return OcpReference(schedule, np.asarray(com_end, dtype=float), wait, depth, crossings, com_path, liftoff)
