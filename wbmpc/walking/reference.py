"""The OCP reference stage: a footstep plan sampled for the whole-body OCP of one MPC update.

From the plan it makes the contact schedule on the OCP grid (which feet are on the ground at
each node, swing phases, footholds) and the terminal CoM reference (eq. 24): the planner's CoM
prediction at the end of the horizon, at the planner's CoM height. Holding z at the model's
height (not at the measured height) matters: with the measured height the terminal cost let
Bolt's CoM creep up by 1 cm per second of walking (legs stretching) until it fell.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sequencer.schedule import ContactSchedule, contact_schedule
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
    """

    schedule: ContactSchedule
    com_terminal: np.ndarray
    touchdown_wait: float
    touchdown_depth: float


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

    def sample(self, plan: Any, t: float, com_xy: np.ndarray, foot_in_contact: np.ndarray) -> OcpReference:
        """The OCP reference of the update at ``t`` [s] from ``plan``; ``com_xy`` (2,) [m] is the
        measured CoM, ``foot_in_contact`` (n_feet,) the measured contacts."""
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
        return OcpReference(schedule, np.asarray(com_end, dtype=float), wait, depth)
