"""Online estimates of the walking controller: state objects it updates from measurements.

None of them writes into the frozen planner parameters: the velocity correction is added to the
command handed to the planner, the LIPM corrections live in the planner's
:class:`sequencer.dcm_planner.LipmCorrections` object (read at each plan), the stance slide
decides the stance position handed to the planner.

- :class:`VelocityIntegral`: integral action on the forward speed, with anti-windup;
- :class:`LipmCorrectionEstimator`: the stance drift and the touchdown offset bias of the DCM
  planner's LIPM, identified after every undisturbed step;
- :class:`StanceSlide`: how far the stance foot slid from its touchdown point, and the position
  the planner should plan from.

Frames: world frame unless said; "heading frame" = world rotated about z by the stance yaw.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sequencer.corrections import LipmCorrections
from sequencer.planner import rotate_xy


class VelocityIntegral:
    """Integral action on the walking speed: the planner is given v*_x + k_x ∫ (v*_x − v̄_x) dt
    and v*_y + k_y ∫ (v*_y − v̄_y) dt.

    v̄ is the measured CoM velocity in the heading frame, low-passed with time constant
    ``filter_time``; the command v* is low-passed by the same filter before it is compared, so that
    the filter's own lag behind a changing command (a start ramp) is not integrated as an error: with
    the raw command, the G1's 2 s ramp to 0.3 m/s wound the integral up and the walk overshot to
    0.47 m/s (0.5 m/s: a fall at 3.9 s). Each correction is bounded by ``correction_max`` and its
    integral clamped accordingly (anti-windup). A gain of 0 turns that axis off (the paper's pipeline: both off).
    The lateral axis is separate because a lateral correction shifts the planner's nominal step
    widths (∓ pelvis width + v_y T): off where the robot walks straight (Bolt), on where a lateral
    command must be followed (the G1's ALIP planner).

    Args:
        gain: k_x [1/s], >= 0 (forward).
        correction_max: bound of each correction [m/s].
        filter_time: low-pass time constant [s], > 0.
        period: update period [s] (the replan period).
        lateral_gain: k_y [1/s], >= 0 (lateral).
    """

    def __init__(self, gain: float, correction_max: float, filter_time: float, period: float,
                 lateral_gain: float = 0.0) -> None:
        self.gains = np.array([gain, lateral_gain], dtype=float)
        self.correction_max = float(correction_max)
        self._alpha = period / (filter_time + period)
        self.period = float(period)
        self.filtered = np.zeros(2)  # [m/s] heading frame; the robot starts at rest
        self.filtered_command = np.zeros(2)  # [m/s] heading frame, the command through the same filter
        self.integrals = np.zeros(2)  # [m] heading frame (forward, lateral)

    @property
    def gain(self) -> float:
        """k_x [1/s]."""
        return float(self.gains[0])

    def update(self, commanded_v_x: float, velocity_heading_xy: np.ndarray, commanded_v_y: float = 0.0) -> None:
        """One replan: filter the measured velocity (2,) [m/s, heading frame], integrate the errors."""
        if not self.gains.any():
            return
        self.filtered += self._alpha * (np.asarray(velocity_heading_xy, dtype=float) - self.filtered)
        self.filtered_command += self._alpha * (np.array([commanded_v_x, commanded_v_y]) - self.filtered_command)
        on = self.gains > 0.0
        self.integrals[on] += (self.filtered_command[on] - self.filtered[on]) * self.period
        bound = self.correction_max / np.where(on, self.gains, 1.0)
        self.integrals = np.clip(self.integrals, -bound, bound)

    @property
    def integral(self) -> float:
        """Forward integral [m]."""
        return float(self.integrals[0])

    @property
    def correction_xy(self) -> np.ndarray:
        """(forward, lateral) speed corrections [m/s] added to the command, heading frame, shape (2,)."""
        return np.clip(self.gains * self.integrals, -self.correction_max, self.correction_max)

    @property
    def correction(self) -> float:
        """Forward-speed correction [m/s] added to the command."""
        return float(self.correction_xy[0])


@dataclass(frozen=True)
class _StanceRecord:
    t: float  # touchdown time [s]
    dcm: np.ndarray  # DCM at the touchdown (2,) [m]
    foot: np.ndarray  # touchdown point (2,) [m]
    yaw: float  # heading of the stance [rad]
    steady: bool  # the DCM was where the plan had put it


class LipmCorrectionEstimator:
    """Identifies, after each step, two corrections of the DCM planner's LIPM.

    (1) Stance drift d: the DCM's gain over the LIPM during the stance that just ended,
    d = ζ_T − p − (ζ_0 − p) exp(ω T) (ζ_0, ζ_T measured at its touchdown and at the next one, p
    the stance foot, along the stance's heading), in metres, whatever the step's length (sign
    included). (2) Touchdown offset bias: the measured DCM offset at the touchdown minus the offset
    the plan aimed at (heading x). Each estimate moves by ``gain`` towards the step's value.

    Only undisturbed steps count: the DCM at both touchdowns within ``max_error`` of the plan and
    the stance foot within ``max_slide`` of its touchdown point. On Bolt the swing leg (half of
    the robot's mass) makes the DCM outrun the LIPM by ~24 mm per stance at 0.33 m/s, and by
    5.5-8.5 mm stepping in place (docs/closed_loop.md).

    Args:
        corrections: the planner's corrections object, written in place.
        omega: the run's pendulum frequency [1/s].
        gain: per-step gain in [0, 1] (0 = off).
        stance_drift_max: bound of each step's drift and of the estimate [m].
        offset_bias_max: bound of each step's offset error and of the estimate [m].
        max_error, max_slide: see above [m].
    """

    def __init__(self, corrections: LipmCorrections, omega: float, gain: float, stance_drift_max: float,
                 offset_bias_max: float, max_error: float, max_slide: float) -> None:
        self.corrections = corrections
        self.omega = float(omega)
        self.gain = float(gain)
        self.stance_drift_max, self.offset_bias_max = float(stance_drift_max), float(offset_bias_max)
        self.max_error, self.max_slide = float(max_error), float(max_slide)
        self._previous: _StanceRecord | None = None
        #: (touchdown time [s], drift of the stance that ended [m], touchdown offset error [m]) of every step used
        self.steps: list[tuple[float, float, float]] = []

    def touchdown(self, t: float, dcm: np.ndarray, foot: np.ndarray, yaw: float,
                  planned_offset: np.ndarray | None, ended_slide: float) -> bool:
        """A new stance began at ``t`` on ``foot`` (2,) with heading ``yaw``; ``dcm`` (2,) is the
        measured DCM, ``planned_offset`` (2,) the DCM offset the plan aimed at for this touchdown
        (world frame; None when the landed foot was not the planned one), ``ended_slide`` the
        largest slide [m] of the stance that just ended. Returns True when the step was used."""
        dcm, foot = np.asarray(dcm, dtype=float), np.asarray(foot, dtype=float)
        previous = self._previous
        if planned_offset is None:
            error = np.full(2, np.inf)
        else:
            error = rotate_xy((dcm - foot) - np.asarray(planned_offset, dtype=float), -yaw)
        steady = bool(np.all(np.abs(error) <= self.max_error))
        self._previous = _StanceRecord(float(t), dcm.copy(), foot.copy(), float(yaw), steady)
        # the first stance includes the start from standing; a stance foot that slid moved the pivot
        if previous is None or self.gain <= 0.0 or not (steady and previous.steady) or ended_slide > self.max_slide:
            return False
        growth = math.exp(self.omega * (t - previous.t))
        excess = rotate_xy((dcm - previous.foot) - (previous.dcm - previous.foot) * growth, -previous.yaw)[0]
        drift_max, bias_max = self.stance_drift_max, self.offset_bias_max
        drift = float(np.clip(excess, -drift_max, drift_max))
        offset_error = float(np.clip(error[0], -bias_max, bias_max))
        c = self.corrections
        c.stance_drift = float(np.clip(c.stance_drift + self.gain * (drift - c.stance_drift), -drift_max, drift_max))
        c.dcm_offset_bias = float(np.clip(c.dcm_offset_bias + self.gain * (offset_error - c.dcm_offset_bias),
                                          -bias_max, bias_max))
        self.steps.append((float(t), drift, offset_error))
        return True


class StanceSlide:
    """How far the stance foot slid from its touchdown point, and where the planner plans from.

    Past ``follow`` [m] of slide (None = never), the planner is given the sliding foot's
    measured position (while it is in contact) instead of the touchdown point: a sliding foot
    then shows up in the plan at once (the DCM runs away from the foot and the planner brings the
    next touchdown forward). With the touchdown point kept, the slip scenario at friction 0.15 fell
    at 4.68 s; with 0.02 m Bolt walked on (docs/closed_loop.md). 0.02 m lies above the 5-11 mm the
    point foot rolls in undisturbed steps, so walking on good ground is unchanged.
    """

    def __init__(self, follow: float | None) -> None:
        self.follow = follow
        self.slide = 0.0  # [m], largest distance of the stance foot from its touchdown point so far
        self.plan_position = np.zeros(2)  # [m], stance position given to the planner

    def reset(self, touchdown_xy: np.ndarray) -> None:
        """A stance begins at ``touchdown_xy`` (2,) [m]."""
        self.slide = 0.0
        self.plan_position = np.array(touchdown_xy[:2], dtype=float)

    def measure(self, touchdown_xy: np.ndarray, foot_xy: np.ndarray) -> float:
        """Distance [m] of the stance foot ``foot_xy`` from ``touchdown_xy`` (kept as the maximum)."""
        slide = math.hypot(foot_xy[0] - touchdown_xy[0], foot_xy[1] - touchdown_xy[1])
        self.slide = max(self.slide, slide)
        return slide

    def follow_if_sliding(self, slide: float, foot_xy: np.ndarray, in_contact: bool) -> None:
        """Plan from the foot's measured position once it slid past ``follow`` while in contact."""
        if self.follow is not None and slide > self.follow and in_contact:
            self.plan_position = np.array(foot_xy[:2], dtype=float)
