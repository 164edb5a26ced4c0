"""Which foot is in stance, where it stands and since when: the sequencer's initial condition.

The footstep sequencer plans from the current stance foot (``p0``), the time elapsed since its
touchdown (``t`` in eqs. (5a)-(5b)) and the measured DCM. The closed loop must therefore track the
stance switches. :class:`StanceTracker` switches the stance to the swinging foot:

- ``detection="plan"``: when the plan says its touchdown has come, whatever the contacts say;
- ``detection="contact"`` (default of the walking controller): when the simulator reports the swing
  foot on the ground past half of its planned swing (early touchdown, e.g. on an obstacle), or past
  the planned time once it touches; a foot still in the air ``late_tolerance`` after the planned
  time is switched anyway. Waiting for the contact matters: declaring a foot that is still 3-4 cm
  above the ground in stance makes the OCP hold it there as a rigid contact, and the next solution
  asks for large torques (a fall after 13 s in the ``transition`` scenario with "plan").

The new stance position is the *measured* foot position, so that slips and terrain show up in the
next plan. It stays the touchdown point for the whole stance (the metrics measure slides against
it); the walking controller gives the sequencer the sliding foot's measured position instead once
it has slid ``WalkingControllerConfig.stance_slide_follow`` away from it.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from sequencer.planner import StanceState
from wbmpc.errors import ParameterError

TOUCHDOWN_DETECTIONS = ("plan", "contact")


class StanceTracker:
    """Tracks the stance foot of a biped from the footstep plan and the measured contacts.

    Args:
        feet: foot names in the order of the measurements, e.g. ``("left", "right")``.
        detection: ``"plan"`` or ``"contact"`` (see the module docstring).
        late_tolerance: with "contact", how long after the planned touchdown to wait for the
            contact before switching anyway [s].
    """

    def __init__(self, feet: tuple[str, ...], detection: str = "contact", late_tolerance: float = 0.05) -> None:
        if detection not in TOUCHDOWN_DETECTIONS:
            raise ParameterError(f"touchdown_detection={detection!r} must be one of {TOUCHDOWN_DETECTIONS}")
        if len(feet) != 2:
            raise ParameterError(f"feet={feet!r}: the stance tracker handles bipeds (2 feet)")
        if not (np.isfinite(late_tolerance) and late_tolerance >= 0):
            raise ParameterError(f"late_tolerance={late_tolerance} s must be >= 0")
        self.feet = tuple(feet)
        self.detection = detection
        self.late_tolerance = float(late_tolerance)
        self.state: StanceState | None = None
        self.n_switches = 0

    def reset(self, foot: str, position_xy: np.ndarray, t_start: float, yaw: float = 0.0) -> None:
        """Start with ``foot`` in stance at ``position_xy`` (world, m) since ``t_start`` [s], heading
        ``yaw`` [rad]."""
        if foot not in self.feet:
            raise ParameterError(f"stance foot {foot!r} must be one of {self.feet}")
        self.state = StanceState(foot, np.array(position_xy[:2], dtype=float), float(yaw), float(t_start))
        self.n_switches = 0
        self.due_since: float | None = None  # first time the current swing's touchdown was due

    def update(
        self,
        t: float,
        next_touchdown_foot: str | None,
        next_touchdown_time: float | None,
        swing_start_time: float | None,
        feet_position_world: np.ndarray,
        foot_in_contact: np.ndarray,
        next_touchdown_yaw: float = 0.0,
    ) -> bool:
        """Switch the stance if the swing foot has touched down; returns True on a switch.

        Args:
            t: current time [s].
            next_touchdown_foot: foot of the first planned step (None if there is no plan yet).
            next_touchdown_time: its planned touchdown time [s].
            swing_start_time: when its swing began [s] (the current stance's start).
            feet_position_world: shape (n_feet, 3), measured foot positions [m], world frame.
            foot_in_contact: shape (n_feet,), measured contacts.
            next_touchdown_yaw: planned heading of the landing foot [rad] (the new stance's yaw).
        """
        if self.state is None:
            raise RuntimeError("StanceTracker.update() called before reset()")
        if next_touchdown_foot is None or next_touchdown_foot == self.state.foot:
            return False
        index = self.feet.index(next_touchdown_foot)
        if self.detection == "plan":
            touched = t >= next_touchdown_time - 1e-9
            t_switch = min(float(next_touchdown_time), t)
        else:
            # the sequencer re-plans a late touchdown to "now", so lateness counts from the first time
            # the touchdown was due, not from the latest plan
            if self.due_since is None and t >= next_touchdown_time - 1e-9:
                self.due_since = t
            half_swing = swing_start_time + 0.5 * (next_touchdown_time - swing_start_time)
            in_contact = bool(foot_in_contact[index])
            late = self.due_since is not None and t >= self.due_since + self.late_tolerance - 1e-9
            touched = (in_contact and t >= half_swing) or late
            t_switch = t
        if not touched:
            return False
        self.state = StanceState(next_touchdown_foot, np.array(feet_position_world[index, :2]),
                                 float(next_touchdown_yaw), t_switch)
        self.n_switches += 1
        self.due_since = None
        return True


def delay_to_touchdown(plan: Any, t: float, swing_foot_in_contact: bool, node_dt: float,
                       wait_nodes: int) -> tuple[Any, float]:
    """The plan shifted in time so that a due but not yet measured touchdown lies ahead.

    The planner re-plans a late touchdown to "now"; sampled as is, the OCP would hold the swing
    foot as a rigid contact wherever it is in the air (3-7 cm above the ground were seen on
    Bolt), and the next solutions ask for large torques. Instead the whole sequence is delayed
    so that the swing ends ``wait_nodes`` nodes from now, its height reference reaching the
    ground there.

    Args:
        plan: ``sequencer.FootstepPlan``.
        t: now [s].
        swing_foot_in_contact: the foot of the plan's first step is measured on the ground.
        node_dt: OCP node spacing [s].
        wait_nodes: nodes from now at which the delayed swing ends.

    Returns:
        (plan to sample, delay applied [s], 0 when none).
    """
    first = plan.steps[0]
    target = t + wait_nodes * node_dt
    if swing_foot_in_contact or first.touchdown_time >= target:
        return plan, 0.0
    delay = target - first.touchdown_time
    steps = tuple(dataclasses.replace(s, touchdown_time=s.touchdown_time + delay) for s in plan.steps)
    return dataclasses.replace(plan, steps=steps), delay


def ground_waiting_nodes(schedule: Any, step: Any, delayed: Any) -> Any:
    """The schedule of a delayed swing with its waiting nodes at the undelayed phase (clipped to 1).

    :func:`delay_to_touchdown` stretches the swing; sampled as is, eq. (19) on the stretched
    swing puts the height reference back ~2.6 mm above the ground at the node due now (phase
    0.94 on Bolt), against the touchdown-height term. The waiting nodes keep the phase of the
    planned swing instead, clipped to 1: their reference stays on the ground.

    Args:
        schedule: the ``ContactSchedule`` sampled from the delayed plan.
        step: the swing's planned step (``plan.steps[0]`` before the delay).
        delayed: the same step in the delayed plan.
    """
    j = schedule.feet.index(step.foot)
    times = schedule.times
    phase = schedule.swing_phase.copy()
    waiting = (times < delayed.touchdown_time) & ~schedule.in_contact[:, j]
    duration = max(step.touchdown_time - step.stance_start_time, 1e-9)
    phase[waiting, j] = np.clip((times[waiting] - step.stance_start_time) / duration, 0.0, 1.0)
    return dataclasses.replace(schedule, swing_phase=phase)
