"""Parameters of the DCM footstep sequencer (Roux et al. 2024, eqs. 2-5 and Table I).

Units: weights are dimensionless, lengths in metres, times in seconds, velocities in m/s.
Frames: world frame, x forward, y to the left.

The lateral bounds follow the labels of the paper's Table I: ``w_left_*`` bound the lateral
step ``p_T,y - p_0,y`` while the LEFT foot is the stance foot (the right foot steps, so the
width is negative), ``w_right_*`` while the RIGHT foot is the stance foot. This is the reading
consistent with the Table I example (stance foot p0 = (-0.12, 0.10) with the DCM at
y = -0.07 moving towards the right foot); see ``docs/sequencer.md``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from pathlib import Path

from sequencer.corrections import check_dcm_offset_bias, check_stance_drift, check_swing_drift
from sequencer.footholds import FootholdGeometry
from sequencer.nominal import FEET, NominalGait, aimed_dcm_offset, nominal_gait, nominal_step_width, stance_sign
from wbmpc.config import dataclass_from_table, named_preset, read_toml
from wbmpc.errors import ParameterError

PRESET_DIR = Path(__file__).resolve().parent / "presets"
# The fields of the speed schedule and the fields holding their values at fast_speed_full (SequencerParams.at_speed).
SCHEDULED_FIELDS = (("t_nom", "fast_t_nom"), ("t_min", "fast_t_min"), ("double_support", "fast_double_support"),
                    ("l_max", "fast_l_max"))


@dataclass(frozen=True)
class SequencerParams:
    """Weights, bounds, nominal gait and horizon of the footstep sequencer (frozen, validated).

    Attributes:
        alpha1: weight of the step position error, eq. (3a) [-], > 0.
        alpha2: weight of the step timing error |Gamma(T) - Gamma(T_nom)|^2 [-], > 0.
        alpha3: weight of the DCM offset error [-], > 0.
        z_c: constant CoM height of the LIPM [m], > 0.
        gravity: gravitational acceleration [m/s^2], > 0.
        v_x: default forward velocity command [m/s] (heading frame); the nominal step length is
            l_nom = v_x * t_nom. A planner given a command per call
            (:class:`sequencer.dcm_planner.DcmFootstepPlanner`) uses the command instead.
        v_y: default lateral velocity command [m/s] (heading frame, y to the left).
        l_min, l_max: bounds on the step length p_T,x - p_0,x along the stance's heading [m].
        pelvis_width: nominal lateral distance between the feet l_p [m] (Khadiv et al. 2020).
        w_left_min, w_left_max: bounds on p_T,y - p_0,y (heading frame) while the LEFT foot is
            in stance [m].
        w_right_min, w_right_max: the same while the RIGHT foot is in stance [m].
        t_min, t_nom, t_max: step duration (time from the start of a stance to the next
            touchdown) bounds and nominal value [s], 0 < t_min <= t_nom <= t_max.
        horizon: H_u, Algorithm 1 plans until a touchdown is at or after t0 + horizon [s], > 0.
        double_support: time both feet stay on the ground after each touchdown [s], in
            [0, t_min) (0 = point feet, the paper). It shapes the contact schedule only: the
            swing of the other foot starts double_support after the touchdown; the step QP and
            the LIPM predictions keep the instantaneous transfer of support at the touchdown.
        swing_drift: kappa in [0, 0.9], forward DCM gain per unit of step length over a stance
            beyond the LIPM [-] (0 = the pure LIPM of the paper, the default). The nominal offset
            becomes ``b_x = (1 - kappa) l_nom / (E - 1)``, the periodic gait of
            ``(1 - kappa) L + b_next = b E`` (see ``sequencer.nominal``). The step QP's dynamics
            stay the LIPM's: the closed loop re-plans every 10 ms from the measured DCM, which
            takes up the drift of the step in progress. Initial value only for a planner given a
            :class:`sequencer.corrections.LipmCorrections` (it reads the live value from it).
        dcm_offset_bias: how far ahead of the planned offset b_T,x the DCM is, on average, when the
            foot has landed [m], |.| <= 0.05 (0 = none, the paper). The nominal offset aimed at is
            b_x - dcm_offset_bias, so that the offset the next stance starts from is b_x. Initial
            value only, as swing_drift.
        stance_drift: d [m], |.| <= 0.1, forward DCM gain beyond the LIPM over a stance whatever
            the step length (0 = the paper's LIPM): b_x = ((1 - kappa) l_nom - d) / (E - 1). Bolt's
            DCM gains 5.5-8.5 mm per stance stepping in place and ~24 mm at 0.33 m/s: a drift that
            does not vanish with the step (docs/closed_loop.md). Initial value only, as swing_drift.
        obstacle_margin: obstacles' footprints grown by this on every side for the footholds [m], >= 0
            (:mod:`sequencer.footholds`: no sole lands within it of an obstacle).
        obstacle_approach_margin: the obstacle's near side (facing the stance along the heading) grown by this
            much more for the footholds [m], >= 0: the last step before it is the one a foot overshoots.
        obstacle_far_margin_reduction: [m] in [0, obstacle_margin]: the footprint's side further along the stance's
            heading (the far side of an obstacle crossed walking forwards, where both crossing feet land) grown by
            ``obstacle_margin`` minus this: the lead crossing that much shorter, and the trailing foot can land that
            much further back, under a DCM that lags the lead foot ("The far margin" in :mod:`sequencer.footholds`).
            0: ``obstacle_margin`` on every side.
        obstacle_step_length_max: length bound [m], > 0, of a step that goes beyond an obstacle (the planner
            uses max(l_max, this): the crossing step may be longer than a walking one).
        obstacle_step_duration_min: duration lower bound [s] of a step whose swing passes over an obstacle
            (the planner uses max(t_min, this)), <= :attr:`crossing_duration_max`.
        obstacle_trailing_duration_min: 0 (``obstacle_step_duration_min``) or the duration lower bound [s] of the
            trailing crossing swing (the one whose stance foot is already beyond the obstacle), in [t_min,
            :attr:`crossing_duration_max`]: its foothold lies next to the lead foot, so its DCM has no long step to
            travel, and the lateral DCM offset it lifts off with grows as exp(ω T) while it swings ("The trailing
            swing's duration" in :mod:`sequencer.footholds`).
        obstacle_trailing_height_max: [m] >= 0: ``obstacle_trailing_duration_min`` holds over obstacles up to this high
            only (a higher one's trailing swing keeps the crossing's bound); 0: over any obstacle.
        obstacle_step_duration_max: duration upper bound [s] of a step whose swing passes over an obstacle,
            0 (t_max, the walking bound) or in [max(t_min, obstacle_step_duration_min), 3], above t_max or below
            it (:attr:`crossing_duration_max`). Longer: a crossing step is longer than a walking one and its DCM,
            from a walking offset, needs longer to travel it (from 3 cm, a 0.58 m crossing on the H1's LIPM
            takes 0.93 s, beyond its t_max of 0.8 s). Shorter: on a robot without ankle roll the lateral DCM
            grows as exp(ω T) over the crossing's single support (x 12 over the H1's 0.8 s), so a short
            crossing keeps a lateral offset at lift-off small at touchdown.
        obstacle_swing_length_max: the travel bound [m] of a foot whose swing passes over an obstacle, from its
            lift-off to its touchdown along the heading, 0 (none) or > 0: the trailing foot, lifting off before
            the obstacle, lands beyond it within this of where it lifted off (a nominal step from the lead foot
            asked the H1 a 1.0 m swing), and the lead crossing step aims at the DCM offset from which that
            shorter trailing step ends at the nominal offset (:mod:`sequencer.footholds`).
        obstacle_offset_tolerance: a step crosses an obstacle only if its DCM offset at touchdown is at most
            this much behind the nominal one, along the heading [m], >= 0 (else one more step before it,
            aiming at the offset the crossing needs; :mod:`sequencer.footholds`).
        obstacle_double_support: a quasi-static crossing [s], 0 (off) or in [double_support, 5]: a step whose
            swing passes over an obstacle lifts off this long after the previous touchdown (instead of
            ``double_support``), a double support in which the centre of pressure brings the DCM onto the
            stance foot; the planner then models that stance as settled (DCM and CoM reference on the stance
            foothold along the heading; across it where the crossing step's LIPM reaches the nominal offset at
            the nominal width; the swing after it lasts at least max(t_min, obstacle_step_duration_min) -
            double_support), and crosses whatever the DCM (no offset tolerance, no aimed last step before the
            obstacle); the step after the trailing crossing resumes the walk after as long a double support.
        obstacle_trailing_double_support: a settle after the lead crossing [s], 0 (off) or in
            [double_support, 5]: the *trailing* crossing swing (the one whose stance foot has already crossed:
            the straight path from its lift-off to the stance foothold passes over the obstacle) lifts off this
            long after the lead touchdown, with the same settled model as ``obstacle_double_support`` (the DCM
            on the lead foothold along the heading), and so does the step after it, which resumes the walk.
            It is planned once the lead foot is down (the trailing swing is the plan's first step); before that
            the plan is the dynamic one (planned from the lead lift-off on, the H1's lead foot touched the box).
            With ``obstacle_double_support`` = 0 only that swing halts (the lead crossing stays dynamic: a
            halt before the lead swing left the H1 without the DCM velocity to reach beyond the box); with both
            > 0 this one replaces ``obstacle_double_support`` for the trailing swing and the step after it.
        obstacle_resume_double_support: [s], 0 or in [double_support, 5]: once the trailing crossing swing is down
            (both feet beyond the obstacle) the step that resumes the walk lifts off this long after that touchdown,
            with the settled model of ``obstacle_double_support`` (the DCM settling on the walk's stance-start DCM),
            the crossing swings themselves dynamic: the body, whose DCM the H1's trailing touchdown left behind the
            feet with the obstacle right behind them, is brought over the feet in a double support instead of a
            step in place that cannot step back (docs/ocp.md, "The walk after a crossing"). Planned once the
            trailing foot is down (the resuming step the plan's first): every plan before is the dynamic crossing's.
            Not with ``obstacle_double_support`` or ``obstacle_trailing_double_support`` (they settle the resuming
            step themselves). The 'exact' backend only.
        obstacle_aim_duration: the crossing duration [s] the last step before an obstacle aims for, 0 (the
            crossing's longest, :attr:`crossing_duration_max`) or in [max(t_min,
            obstacle_step_duration_min), that]: that step aims at the DCM offset from which the crossing step
            reaches its own aim within this long (a shorter one aims further ahead: it leans the robot into the
            crossing; :mod:`sequencer.footholds`).
        obstacle_approach_distance: > 0 [m]: once the last foothold before an obstacle the walk has to cross
            lies within this distance ahead of the stance, the steps up to it are spaced evenly (n of them, n
            the nearest whole number of nominal steps, at least 1) and aim at the DCM offsets that end the last
            one with the offset the crossing needs ("The approach" in :mod:`sequencer.footholds`; the 'exact'
            backend only); 0: the greedy approach (nominal steps until a foothold is bounded).
        obstacle_crossing_drift: κ_c [-] in [0, 1): a swing over an obstacle (the lead crossing, the trailing
            swing) ends with the DCM κ_c d further than the LIPM's, d its travel from lift-off along the heading
            (the swing leg's mass carried forward; "Crossing drift" in :mod:`sequencer.footholds`); 0: the LIPM's.
        obstacle_crossing_cop: δ [m] in [0, 0.2): every swing over an obstacle (the lead crossing, the trailing swing)
            pivots on a centre of pressure within δ of its stance foothold along the heading, the one its QP does
            best with (a flat foot's heel carries the DCM further, its toe holds it back; "The crossing's centre of
            pressure" in :mod:`sequencer.footholds`; the 'exact' backend only); 0: the foothold (a point foot's).
            The plan's CoM prediction pivots there too (``PlannedStep.cop_offset``), so the OCP's terminal CoM
            follows.
        obstacle_passed_cop: δ_p [m] in [0, 0.2): a step whose stance foot is beyond an obstacle it has just crossed
            and whose foothold that obstacle bounds (the trailing crossing swing, the steps pinned at its far bound
            after it) pivots on a centre of pressure within δ_p of its stance foothold along the heading (the trailing
            swing within max(δ, δ_p)): the heel carries a DCM that lags behind the feet forwards, where the point-foot
            plan has it fall back over the obstacle ("The passed obstacle's centre of pressure" in
            :mod:`sequencer.footholds`; the 'exact' backend only); 0: off.
        obstacle_crossing_offset: Δb [m] in [0, 0.3): the lead crossing (the step from before an obstacle to beyond it)
            aims at the nominal DCM offset along the heading plus Δb at its touchdown, and the last step before the
            obstacle at the offset that reaches it ("The crossing's momentum" in :mod:`sequencer.footholds`): the
            body keeps moving over the lead foot through the trailing swing; 0: the nominal offset.
        obstacle_landing_room: r [m] in [0, 0.5): the lead crossing lands at least r beyond the obstacle's far bound
            (within ``obstacle_step_length_max``), so that the trailing foot can land behind it, under a DCM that
            lags the lead foot, where the passed obstacle bounds every foothold ("The landing room" in
            :mod:`sequencer.footholds`); the last step before the obstacle aims for that longer crossing. 0: on the bound.
        obstacle_lateral_aim_duration: T_lat [s], 0 (off) or in [t_nom, :attr:`crossing_duration_max`]:
            the last step before an obstacle and the lead crossing aim at the lateral DCM offset
            b_y,nom exp(-ω (T_lat - t_nom)) instead of b_y,nom, the one from which a crossing step lasting T_lat ends at
            the nominal lateral offset and width ("The lateral aim" in :mod:`sequencer.footholds`); 0: b_y,nom (a
            crossing longer than t_nom then spreads the feet: the H1's lateral DCM bounded its crossing to 0.6 s, too
            short for the DCM to carry it).
        obstacle_width_min: [m], 0 (off) or in [2 sole_half_width, the walk's inner width bound min(w_right_min,
            -w_left_max)]: while obstacles are handed to the planner (a negotiation) every step's inner width bound
            (its feet's least distance across the heading) is this instead of the walk's, so that the last step
            before a crossing can land under its DCM across the heading. A crossing's long single support
            multiplies the lateral DCM offset it lifts off with by exp(ω T) (6.7 for the H1's 0.6 s): with the
            walk's 0.30 m bound the H1's last step before the box could not reach the lateral aim
            (``obstacle_lateral_aim_duration``), lifted off 10-11 cm from its DCM across the heading and the
            lead crossing landed on its 0.6 m width bound with the lateral DCM still running (docs/ocp.md,
            "The lateral DCM over a crossing"). The 'exact' backend only; 0: the walk's bounds.
        swing_commit_time: [s] >= 0: in the last this long of a swing (before the touchdown the previous plan
            planned) its foothold moves across the heading by at most ``swing_commit_rate`` times the time since the
            previous plan from where that plan put it (the 'exact' backend only); 0: off, Algorithm 1 re-plans the
            swing's foothold freely up to its touchdown (the paper's). A discrete change of the plan late in a swing
            (the last step before an obstacle switching to its lateral aim: 6-8 cm in one replan 0.14 s before the
            H1's touchdown) is more than the whole body can follow.
        swing_commit_rate: [m/s] >= 0, the lateral speed of the committed foothold (0 with swing_commit_time > 0:
            held where the plan put it when the commitment began).
        fast_speed_start, fast_speed_full: the speed schedule of the step timing [m/s] (0 and 0: off): with
            0 <= fast_speed_start < fast_speed_full <= 5, the fields of ``SCHEDULED_FIELDS`` (t_nom, t_min,
            double_support, l_max) keep their values while the commanded forward speed |v_x| is at most
            fast_speed_start, take their ``fast_*`` values from fast_speed_full on, and move linearly in between
            (:meth:`at_speed`; a walk at speed wants shorter, quicker steps than a slow one, docs/closed_loop.md
            "The H1 at 1.0 m/s, session 20").
        fast_t_nom, fast_t_min: the nominal step duration and its lower bound at fast_speed_full [s] (0: not
            scheduled, t_nom or t_min at every speed); fast_double_support: the double support after each
            touchdown at fast_speed_full [s] (0: not scheduled); fast_l_max: the step length's upper bound at
            fast_speed_full [m] (0: not scheduled). The fully fast set must be valid on its own (t_min <= t_nom,
            double_support < t_min, l_min <= l_max): every speed in between then is too.
        sole_front, sole_rear: the sole's extent ahead of and behind the foot frame along its heading [m],
            >= 0 (0: a point foot); sole_half_width: its half width [m], >= 0. The footholds keep the whole
            sole rectangle outside the grown footprints.
        name: label of the parameter set (for reports only).
    """

    alpha1: float = 1e3
    alpha2: float = 1.0
    alpha3: float = 1e6
    z_c: float = 0.31
    gravity: float = 9.81
    v_x: float = 0.1 / 0.3
    v_y: float = 0.0
    l_min: float = -0.3
    l_max: float = 0.3
    pelvis_width: float = 0.25
    w_left_min: float = -0.40
    w_left_max: float = -0.10
    w_right_min: float = 0.10
    w_right_max: float = 0.40
    t_min: float = 0.1
    t_nom: float = 0.3
    t_max: float = 1.0
    horizon: float = 3.0
    double_support: float = 0.0
    swing_drift: float = 0.0
    dcm_offset_bias: float = 0.0
    stance_drift: float = 0.0
    obstacle_margin: float = 0.05
    obstacle_approach_margin: float = 0.0
    obstacle_far_margin_reduction: float = 0.0
    obstacle_step_length_max: float = 0.3
    obstacle_step_duration_min: float = 0.0
    obstacle_step_duration_max: float = 0.0
    obstacle_swing_length_max: float = 0.0
    obstacle_offset_tolerance: float = 0.03
    obstacle_double_support: float = 0.0
    obstacle_trailing_double_support: float = 0.0
    obstacle_resume_double_support: float = 0.0
    obstacle_aim_duration: float = 0.0
    obstacle_approach_distance: float = 0.0
    obstacle_crossing_drift: float = 0.0
    obstacle_lateral_aim_duration: float = 0.0
    obstacle_crossing_cop: float = 0.0
    obstacle_passed_cop: float = 0.0
    obstacle_crossing_offset: float = 0.0
    obstacle_width_min: float = 0.0
    obstacle_landing_room: float = 0.0
    obstacle_trailing_duration_min: float = 0.0
    obstacle_trailing_height_max: float = 0.0
    swing_commit_time: float = 0.0
    swing_commit_rate: float = 0.0
    fast_speed_start: float = 0.0
    fast_speed_full: float = 0.0
    fast_t_nom: float = 0.0
    fast_t_min: float = 0.0
    fast_double_support: float = 0.0
    fast_l_max: float = 0.0
    sole_front: float = 0.0
    sole_rear: float = 0.0
    sole_half_width: float = 0.0
    name: str = "custom"

    # ------------------------------------------------------------------ validation
    def __post_init__(self) -> None:
        for field in dataclasses.fields(self):
            if field.name == "name":
                continue
            value = getattr(self, field.name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ParameterError(f"{field.name}={value!r} must be a real number")
            if not math.isfinite(value):
                raise ParameterError(f"{field.name}={value!r} must be finite (no NaN or inf)")
            # store plain floats (TOML or argparse may give ints)
            object.__setattr__(self, field.name, float(value))
        for name in ("alpha1", "alpha2", "alpha3", "z_c", "gravity", "horizon"):
            if getattr(self, name) <= 0:
                raise ParameterError(f"{name}={getattr(self, name)} must be > 0")
        for low, high, unit in (
            ("l_min", "l_max", "m"),
            ("w_left_min", "w_left_max", "m"),
            ("w_right_min", "w_right_max", "m"),
        ):
            if getattr(self, low) > getattr(self, high):
                raise ParameterError(
                    f"{low}={getattr(self, low)} {unit} must be <= {high}={getattr(self, high)} {unit}"
                )
        check_swing_drift(self.swing_drift)
        check_dcm_offset_bias(self.dcm_offset_bias)
        check_stance_drift(self.stance_drift)
        if not self.t_min > 0:
            raise ParameterError(f"t_min={self.t_min} s must be > 0")
        if not self.t_min <= self.t_nom <= self.t_max:
            raise ParameterError(
                f"step durations must satisfy 0 < t_min <= t_nom <= t_max, "
                f"got t_min={self.t_min} s, t_nom={self.t_nom} s, t_max={self.t_max} s"
            )
        if not 0.0 <= self.double_support < self.t_min:
            raise ParameterError(f"double_support={self.double_support} s must be in [0, t_min={self.t_min} s)")
        for name in ("obstacle_margin", "obstacle_approach_margin", "obstacle_offset_tolerance", "sole_front",
                     "sole_rear", "sole_half_width"):
            if getattr(self, name) < 0:
                raise ParameterError(f"{name}={getattr(self, name)} m must be >= 0")
        if not (0.0 <= self.obstacle_far_margin_reduction <= self.obstacle_margin):
            raise ParameterError(f"obstacle_far_margin_reduction={self.obstacle_far_margin_reduction} m must be in "
                                 f"[0, obstacle_margin={self.obstacle_margin} m]")
        if not self.obstacle_step_length_max > 0:
            raise ParameterError(f"obstacle_step_length_max={self.obstacle_step_length_max} m must be > 0")
        crossing_longest = self.crossing_duration_max
        if not 0.0 <= self.obstacle_step_duration_min <= crossing_longest:
            raise ParameterError(f"obstacle_step_duration_min={self.obstacle_step_duration_min} s must be in "
                                 f"[0, the crossing's duration bound {crossing_longest} s (obstacle_step_duration_max, "
                                 f"or t_max if 0)]")
        crossing_min = max(self.t_min, self.obstacle_step_duration_min)
        if not (self.obstacle_step_duration_max == 0.0 or crossing_min <= self.obstacle_step_duration_max <= 3.0):
            raise ParameterError(f"obstacle_step_duration_max={self.obstacle_step_duration_max} s must be 0 or in "
                                 f"[max(t_min, obstacle_step_duration_min)={crossing_min} s, 3 s]")
        if not (math.isfinite(self.obstacle_swing_length_max) and self.obstacle_swing_length_max >= 0.0):
            raise ParameterError(f"obstacle_swing_length_max={self.obstacle_swing_length_max} m must be 0 (none) "
                                 f"or a finite number > 0")
        if not (self.obstacle_double_support == 0.0 or self.double_support <= self.obstacle_double_support <= 5.0):
            raise ParameterError(f"obstacle_double_support={self.obstacle_double_support} s must be 0 or in "
                                 f"[double_support={self.double_support} s, 5 s]")
        if not (self.obstacle_trailing_double_support == 0.0
                or self.double_support <= self.obstacle_trailing_double_support <= 5.0):
            raise ParameterError(f"obstacle_trailing_double_support={self.obstacle_trailing_double_support} s must "
                                 f"be 0 or in [double_support={self.double_support} s, 5 s]")
        if not (self.obstacle_resume_double_support == 0.0
                or self.double_support <= self.obstacle_resume_double_support <= 5.0):
            raise ParameterError(f"obstacle_resume_double_support={self.obstacle_resume_double_support} s must "
                                 f"be 0 or in [double_support={self.double_support} s, 5 s]")
        if self.obstacle_resume_double_support > 0.0 and (self.obstacle_double_support > 0.0
                                                          or self.obstacle_trailing_double_support > 0.0):
            raise ParameterError(f"obstacle_resume_double_support={self.obstacle_resume_double_support} s needs "
                                 f"obstacle_double_support = obstacle_trailing_double_support = 0 (they settle the "
                                 f"resuming step themselves)")
        crossing_max = self.crossing_duration_max
        if not (math.isfinite(self.obstacle_trailing_height_max) and self.obstacle_trailing_height_max >= 0.0):
            raise ParameterError(f"obstacle_trailing_height_max={self.obstacle_trailing_height_max} m must be 0 (any "
                                 f"height) or a finite number > 0")
        if not (self.obstacle_trailing_duration_min == 0.0
                or self.t_min <= self.obstacle_trailing_duration_min <= crossing_max):
            raise ParameterError(f"obstacle_trailing_duration_min={self.obstacle_trailing_duration_min} s must be 0 "
                                 f"(obstacle_step_duration_min) or in [t_min={self.t_min} s, the crossing's duration "
                                 f"bound {crossing_max} s]")
        if not (self.obstacle_aim_duration == 0.0 or crossing_min <= self.obstacle_aim_duration <= crossing_max):
            raise ParameterError(f"obstacle_aim_duration={self.obstacle_aim_duration} s must be 0 or in "
                                 f"[max(t_min, obstacle_step_duration_min)={crossing_min} s, "
                                 f"the crossing's duration bound {crossing_max} s]")
        if not (math.isfinite(self.obstacle_approach_distance) and self.obstacle_approach_distance >= 0.0):
            raise ParameterError(f"obstacle_approach_distance={self.obstacle_approach_distance} m must be 0 (the "
                                 f"greedy approach) or a finite number > 0")
        if not (0.0 <= self.obstacle_crossing_drift < 1.0):
            raise ParameterError(f"obstacle_crossing_drift={self.obstacle_crossing_drift} must be in [0, 1) "
                                 f"(0: the LIPM's crossing)")
        if not (0.0 <= self.obstacle_crossing_cop < 0.2):
            raise ParameterError(f"obstacle_crossing_cop={self.obstacle_crossing_cop} m must be in [0, 0.2) m "
                                 f"(0: the foothold, a point foot's centre of pressure)")
        if not (0.0 <= self.obstacle_passed_cop < 0.2):
            raise ParameterError(f"obstacle_passed_cop={self.obstacle_passed_cop} m must be in [0, 0.2) m "
                                 f"(0: off)")
        if not (0.0 <= self.obstacle_crossing_offset < 0.3):
            raise ParameterError(f"obstacle_crossing_offset={self.obstacle_crossing_offset} m must be in [0, 0.3) m "
                                 f"(0: the lead crossing aims at the nominal DCM offset)")
        if not (0.0 <= self.obstacle_landing_room < 0.5):
            raise ParameterError(f"obstacle_landing_room={self.obstacle_landing_room} m must be in [0, 0.5) m "
                                 f"(0: the lead crossing lands on the obstacle's far bound)")
        if not (0.0 <= self.swing_commit_time <= self.t_max):
            raise ParameterError(f"swing_commit_time={self.swing_commit_time} s must be in [0 (off), t_max={self.t_max} s]")
        if not (0.0 <= self.swing_commit_rate <= 10.0):
            raise ParameterError(f"swing_commit_rate={self.swing_commit_rate} m/s must be in [0, 10] m/s")
        lateral = self.obstacle_lateral_aim_duration
        if not (lateral == 0.0 or self.t_nom <= lateral <= crossing_max):
            raise ParameterError(f"obstacle_lateral_aim_duration={lateral} s must be 0 (off) or in [t_nom={self.t_nom} s, "
                                 f"the crossing's duration bound {crossing_max} s]")
        inner = min(self.w_right_min, -self.w_left_max)  # the walk's least width across the heading [m]
        if not (self.obstacle_width_min == 0.0 or 2.0 * self.sole_half_width <= self.obstacle_width_min <= inner):
            raise ParameterError(f"obstacle_width_min={self.obstacle_width_min} m must be 0 (off) or in "
                                 f"[2 sole_half_width={2.0 * self.sole_half_width} m, "
                                 f"min(w_right_min, -w_left_max)={inner} m]")
        self._check_speed_schedule()
        self.check_velocity(self.v_x, self.v_y)

    def _check_speed_schedule(self) -> None:
        """The speed schedule's fields (see the class docstring): off with every one of them 0, or
        0 <= fast_speed_start < fast_speed_full <= 5 m/s and a valid fully fast parameter set."""
        start, full = self.fast_speed_start, self.fast_speed_full
        if full == 0.0:
            for name in ("fast_speed_start", *(fast for _, fast in SCHEDULED_FIELDS)):
                if getattr(self, name) != 0.0:
                    raise ParameterError(f"{name}={getattr(self, name)} needs fast_speed_full > 0 m/s (the speed "
                                         f"schedule is off with fast_speed_full = 0)")
            return
        if not 0.0 <= start < full <= 5.0:
            raise ParameterError(f"fast_speed_start={start} m/s and fast_speed_full={full} m/s must satisfy "
                                 f"0 <= fast_speed_start < fast_speed_full <= 5 m/s")
        try:
            _scheduled(self, 1.0)
        except ParameterError as err:
            raise ParameterError(f"the timing at fast_speed_full={full} m/s (the fast_* values) is invalid: "
                                 f"{err}") from None

    # ------------------------------------------------------------------ derived values
    @property
    def omega(self) -> float:
        """LIPM natural frequency sqrt(gravity / z_c) [1/s]."""
        return math.sqrt(self.gravity / self.z_c)

    def at_speed(self, v_x: float) -> "SequencerParams":
        """The parameters a plan at forward command ``v_x`` [m/s] (heading frame) uses: these, with the fields
        of the speed schedule (``fast_speed_start``, ``fast_speed_full``) interpolated at |v_x|; ``self`` itself
        when the schedule is off or |v_x| <= fast_speed_start. The returned set has the schedule off."""
        full = self.fast_speed_full
        if full == 0.0:
            return self
        fraction = (abs(float(v_x)) - self.fast_speed_start) / (full - self.fast_speed_start)
        return self if fraction <= 0.0 else _scheduled(self, min(fraction, 1.0))

    @property
    def l_nom(self) -> float:
        """Nominal step length v_x * t_nom [m]."""
        return self.v_x * self.t_nom

    def w_nom(self, stance_foot: str) -> float:
        """Nominal lateral step p_T,y - p_0,y [m] from ``stance_foot`` (negative from a left stance)."""
        return nominal_step_width(self.pelvis_width, self.v_y, self.t_nom, stance_foot)

    def width_bounds(self, stance_foot: str, negotiating: bool = False) -> tuple[float, float]:
        """(min, max) of p_T,y - p_0,y [m] while ``stance_foot`` is on the ground; ``negotiating`` (obstacles
        handed to the planner): the inner bound is ``obstacle_width_min`` when that is set."""
        narrow = self.obstacle_width_min if negotiating else 0.0
        if stance_sign(stance_foot) > 0:
            return self.w_left_min, (-narrow if narrow else self.w_left_max)
        return (narrow if narrow else self.w_right_min), self.w_right_max

    def b_nom(self, stance_foot: str) -> tuple[float, float]:
        """Nominal DCM offset (b_x, b_y) at touchdown [m], relative to the landing foot (the aim: minus
        ``dcm_offset_bias`` in x)."""
        return aimed_dcm_offset(
            self.omega, self.l_nom, self.pelvis_width, self.v_y, self.t_nom, stance_foot, self.swing_drift,
            self.dcm_offset_bias, self.stance_drift,
        )

    @property
    def crossing_duration_max(self) -> float:
        """The duration upper bound [s] of a step whose swing passes over an obstacle: ``obstacle_step_duration_max``,
        or ``t_max`` when it is 0."""
        return self.obstacle_step_duration_max or self.t_max

    def foothold_geometry(self) -> FootholdGeometry:
        """The obstacle margins, the crossing step's bounds and the sole of these parameters
        (:class:`sequencer.footholds.FootholdGeometry`; effective crossing bounds: max with l_max and t_min, the
        duration bound :attr:`crossing_duration_max`)."""
        return FootholdGeometry(self.obstacle_margin, max(self.l_max, self.obstacle_step_length_max),
                                max(self.t_min, self.obstacle_step_duration_min), self.sole_front, self.sole_rear,
                                self.sole_half_width, self.obstacle_offset_tolerance, self.obstacle_approach_margin,
                                self.obstacle_double_support, self.crossing_duration_max,
                                self.obstacle_swing_length_max,
                                trailing_double_support=self.obstacle_trailing_double_support,
                                resume_double_support=self.obstacle_resume_double_support,
                                aim_duration=self.obstacle_aim_duration,
                                approach_distance=self.obstacle_approach_distance,
                                crossing_drift=self.obstacle_crossing_drift,
                                crossing_cop=self.obstacle_crossing_cop,
                                passed_cop=self.obstacle_passed_cop,
                                crossing_offset=self.obstacle_crossing_offset,
                                landing_room=self.obstacle_landing_room,
                                far_margin_reduction=self.obstacle_far_margin_reduction,
                                trailing_duration_min=self.obstacle_trailing_duration_min,
                                trailing_height_max=self.obstacle_trailing_height_max,
                                lateral_aim_fraction=math.exp(-self.omega * (self.obstacle_lateral_aim_duration - self.t_nom))
                                if self.obstacle_lateral_aim_duration > 0.0 else 1.0)

    # ------------------------------------------------------------------ velocity commands
    def velocity_range(self) -> dict[str, tuple[float, float]]:
        """Velocity commands the bounds allow, heading frame [m/s]: ``{"v_x": (min, max), "v_y": (min, max)}``.

        v_x: ``v_x t_nom`` within [l_min, l_max]. v_y: the nominal width ``-+pelvis_width + v_y t_nom``
        of both stances within their width bounds (the intersection of the two ranges; min > max
        when no v_y fits both).
        """
        v_y_min, v_y_max = -math.inf, math.inf
        for timing in self._timing_ends():
            for foot in FEET:
                low, high = timing.width_bounds(foot)
                lateral = stance_sign(foot) * timing.pelvis_width
                v_y_min = max(v_y_min, (low + lateral) / timing.t_nom)
                v_y_max = min(v_y_max, (high + lateral) / timing.t_nom)
        if self.fast_speed_full == 0.0:
            return {"v_x": (self.l_min / self.t_nom, self.l_max / self.t_nom), "v_y": (v_y_min, v_y_max)}
        return {"v_x": (-self._v_x_reach(-1.0), self._v_x_reach(1.0)), "v_y": (v_y_min, v_y_max)}

    def _timing_ends(self) -> tuple["SequencerParams", ...]:
        """The parameters at both ends of the speed schedule (these alone when it is off)."""
        return (self,) if self.fast_speed_full == 0.0 else (self, _scheduled(self, 1.0))

    def _v_x_fits(self, v_x: float) -> bool:
        """Whether the nominal step v_x t_nom at ``v_x`` [m/s] lies within [l_min, l_max], both at that speed."""
        timing = self.at_speed(v_x)
        return timing.l_min / timing.t_nom <= v_x <= timing.l_max / timing.t_nom

    def _v_x_reach(self, direction: float) -> float:
        """The largest |v_x| [m/s] in ``direction`` (+1 forward, -1 backward) up to which every command from 0
        fits the step length bounds with the scheduled timing (:meth:`_v_x_fits`; 0.01 m/s scan, then bisection),
        at most 5 m/s."""
        if not self._v_x_fits(0.0):
            return 0.0
        fits = 0.0
        for step in range(1, 501):
            speed = 0.01 * step
            if not self._v_x_fits(direction * speed):
                break
            fits = speed
        else:
            return fits
        low, high = fits, fits + 0.01
        for _ in range(60):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if self._v_x_fits(direction * middle) else (low, middle)
        return low

    def check_velocity(self, v_x: float, v_y: float) -> None:
        """Raise ParameterError (naming the component, its value and the allowed range) unless command
        (v_x, v_y) [m/s] lies within :meth:`velocity_range` (its nominal steps within the step bounds).

        The check is on the range itself, so a command clipped to :meth:`velocity_range` always passes.
        """
        timing = self.at_speed(v_x)
        if not self._v_x_fits(v_x):
            v_x_min, v_x_max = self.velocity_range()["v_x"]
            scheduled = "" if timing is self else f" (t_nom={timing.t_nom:.4g} s at this speed)"
            raise ParameterError(
                f"v_x={v_x} m/s gives a nominal step length v_x*t_nom={v_x * timing.t_nom:.4g} m outside [l_min, l_max] "
                f"= [{timing.l_min}, {timing.l_max}] m{scheduled}: v_x must lie within [{v_x_min:.4g}, {v_x_max:.4g}] m/s"
            )
        for foot in FEET:
            low, high = self.width_bounds(foot)
            lateral = stance_sign(foot) * self.pelvis_width
            if not (low + lateral) / timing.t_nom <= v_y <= (high + lateral) / timing.t_nom:
                v_y_min, v_y_max = self.velocity_range()["v_y"]
                allowed = (f"v_y must lie within [{v_y_min:.4g}, {v_y_max:.4g}] m/s" if v_y_min <= v_y_max
                           else "no v_y fits the width bounds of both stances")
                nominal = nominal_step_width(self.pelvis_width, v_y, timing.t_nom, foot)
                raise ParameterError(
                    f"pelvis_width={self.pelvis_width} m and v_y={v_y} m/s give a nominal {foot}-stance width "
                    f"{nominal:.4g} m outside [w_{foot}_min, w_{foot}_max] = [{low}, {high}] m: {allowed}"
                )

    def nominal_gait(self, v_x: float | None = None, v_y: float | None = None, swing_drift: float | None = None,
                     dcm_offset_bias: float | None = None, stance_drift: float | None = None) -> NominalGait:
        """Nominal steps and aimed DCM offsets for a command and LIPM corrections (None = this set's own).

        Raises:
            ParameterError: the command is outside :meth:`velocity_range` or a correction out of range.
        """
        v_x = self.v_x if v_x is None else float(v_x)
        v_y = self.v_y if v_y is None else float(v_y)
        swing_drift = self.swing_drift if swing_drift is None else check_swing_drift(swing_drift)
        dcm_offset_bias = self.dcm_offset_bias if dcm_offset_bias is None else check_dcm_offset_bias(dcm_offset_bias)
        stance_drift = self.stance_drift if stance_drift is None else check_stance_drift(stance_drift)
        self.check_velocity(v_x, v_y)
        return nominal_gait(self.omega, self.at_speed(v_x).t_nom, self.pelvis_width, v_x, v_y, swing_drift,
                            dcm_offset_bias, stance_drift)

    # ------------------------------------------------------------------ presets and I/O
    @classmethod
    def from_toml(cls, path: str | Path) -> "SequencerParams":
        """Load parameters from a TOML file with one key per field (missing keys keep defaults)."""
        return cls.from_dict(read_toml(path, "parameter file"), source=str(path))

    @classmethod
    def from_dict(cls, data: dict, source: str = "dict") -> "SequencerParams":
        """Build parameters from a mapping of field names to values (unknown keys raise)."""
        return dataclass_from_table(cls, data, "sequencer parameter", source)

    @classmethod
    def preset(cls, name: str) -> "SequencerParams":
        """Load a named preset from ``sequencer/presets/<name>.toml``."""
        return named_preset(cls, PRESET_DIR, name, "preset")

    @classmethod
    def table_i(cls) -> "SequencerParams":
        """Table I of Roux et al. 2024 (the paper's walking parameters, v_x = l_nom / T_nom = 0.33 m/s)."""
        return cls.preset("table_i")

    @classmethod
    def bolt_walking(cls) -> "SequencerParams":
        """Parameters for Bolt in the MuJoCo closed loop.

        Differs from Table I in the lateral geometry only: Table I asks for 0.25 m between the
        feet, but Bolt's feet are 0.052 m apart at the standing pose and its legs are ~0.3 m
        long, so the preset uses a nominal width of 0.10 m within [0.04, 0.20] m, step lengths
        within +-0.20 m and step durations within [0.15, 0.6] s. z_c = 0.295 m is Bolt's CoM
        height at ``load_robot("bolt").q_reference`` (feet on the floor; Table I's 0.31 m is the
        SRDF pose with the feet 30 mm in the air). Weights, T_nom and v_x are Table I's.
        """
        return cls.preset("bolt_walking")

    def to_dict(self) -> dict:
        """Field name -> value (floats and the name string)."""
        return dataclasses.asdict(self)


@functools.lru_cache(maxsize=256)
def _scheduled(params: SequencerParams, fraction: float) -> SequencerParams:
    """``params`` with each scheduled field (``SCHEDULED_FIELDS``) moved ``fraction`` in [0, 1] of the way to its
    ``fast_*`` value (those at 0 stay), and the schedule off (validated by the constructor)."""
    values = {name: getattr(params, fast) if fraction == 1.0
              else getattr(params, name) + fraction * (getattr(params, fast) - getattr(params, name))
              for name, fast in SCHEDULED_FIELDS if getattr(params, fast) != 0.0}
    off = {name: 0.0 for name in ("fast_speed_start", "fast_speed_full", *(fast for _, fast in SCHEDULED_FIELDS))}
    return dataclasses.replace(params, **values, **off)
