"""The DCM step QP behind the :class:`~sequencer.planner.FootstepPlanner` interface, omnidirectional.

:class:`DcmFootstepPlanner` runs Algorithm 1 of Roux et al. 2024 (the one-step QP of eqs. 2-5,
repeated over the horizon H_u, eqs. 13-16; :class:`sequencer.horizon.FootstepSequencer`) with a
velocity command (v_x, v_y, yaw_rate) given at each call, and the live LIPM corrections of
:class:`sequencer.corrections.LipmCorrections`.

Heading frame (turning and lateral walking)
-------------------------------------------
Each step's QP is written in the frame of its stance rotated about z by the planned heading ψ_k
(x along the heading, y to the left). With R(ψ) the rotation about z, stance foothold p_k, DCM
ζ_k at the start of stance k, and the step QP's solution ℓ_k = p_{k+1} - p_k and b_{k+1} (offset
at touchdown) in that frame::

    ψ_0 = stance yaw,        ψ_{k+1} = ψ_k + yaw_rate · T_k       (T_k: planned duration of step k)
    QP_k in frame ψ_k:       p0 -> R(ψ_k)ᵀ p_k,  ζ -> R(ψ_k)ᵀ ζ_k
    p_{k+1} = p_k + R(ψ_k) ℓ_k,     b_{k+1} = R(ψ_k) b^h_{k+1},     ζ_{k+1} = p_{k+1} + b_{k+1}

so the footholds compose as in eq. (16) of the ALIP paper ("Hierarchical Reduced-Order Model
Predictive Control for Robust Locomotion on Humanoid Robots", the G1 step planner): the stance
foot positions relative to the current stance are p_k - p_0 = Σ_{i=1..k} R_z(ψ_{i-1}) ℓ_i. The first step's
duration T_0 counts from the start of the current stance, so the planned yaw of the next
foothold does not move while a stance goes on. This is exact: the LIPM (ζ̇ = ω (ζ - p)) commutes
with rotations about z, so the rotated QP is the same problem, and only its nominal values and
bounds, which are given along the heading, change meaning: the command (v_x, v_y) is in the
heading frame, and the nominal step (l_nom = v_x t_nom, w_nom = -+pelvis_width + v_y t_nom), the
nominal DCM offsets and the length and width bounds apply per step in the step's own frame.
Without turning (yaw_rate = 0) and with the stance yaw 0 no rotation is applied: the plan is the
paper's, bit for bit. Each :class:`~sequencer.horizon.PlannedStep` carries its foothold ``yaw``
ψ_{k+1}; yaws are not wrapped.

Command and corrections per call
--------------------------------
The command is not written into the frozen :class:`~sequencer.params.SequencerParams`: the
nominal steps and offsets are computed from the command and the corrections object when either
changes (a few exponentials; the last distinct pair is kept). ``SequencerParams.v_x``/``v_y`` are
the preset's nominal command (:attr:`DcmFootstepPlanner.nominal_command`) and its
``swing_drift``/``dcm_offset_bias`` the corrections' initial values.
"""

from __future__ import annotations

import math

import numpy as np

from sequencer.corrections import LipmCorrections
from sequencer.footholds import forbidden_box
from sequencer.horizon import FootstepPlan, FootstepSequencer
from sequencer.nominal import FEET, other_foot
from sequencer.params import SequencerParams
from sequencer.planner import ReducedState, StanceState, VelocityCommand, as_velocity_command, rotate_xy
from wbmpc.errors import ParameterError


class DcmFootstepPlanner:
    """Footstep planner of the DCM step QP (Algorithm 1), implementing :class:`~sequencer.planner.FootstepPlanner`.

    Args:
        params: SequencerParams (weights, bounds, timing, horizon; ``v_x``/``v_y`` are only the
            nominal command, ``swing_drift``/``dcm_offset_bias`` the corrections' initial values).
        backend: QP backend, ``"exact"`` (closed form, the default), ``"osqp"`` or ``"proxqp"``.
        corrections: the live LIPM corrections, read at every plan; None = a new object holding
            the params' values (then :attr:`corrections` is the one to update).
        clamp_elapsed: a stance older than t_max (late touchdown) is planned as if its elapsed
            time were t_max (touchdown now) instead of raising InfeasibleStep (the closed loop's
            behaviour, the default).

    Attributes:
        params, corrections, clamp_elapsed: as given.
        sequencer: the :class:`~sequencer.horizon.FootstepSequencer` running Algorithm 1.
    """

    feet: tuple[str, ...] = FEET
    avoids_obstacles = True  # plan(obstacles=...) keeps the footholds off them (sequencer.footholds)

    def __init__(self, params: SequencerParams, backend: str = "exact", corrections: LipmCorrections | None = None,
                 clamp_elapsed: bool = True) -> None:
        if corrections is not None and not isinstance(corrections, LipmCorrections):
            raise ParameterError(f"corrections must be a LipmCorrections or None, got {type(corrections).__name__}")
        if not isinstance(clamp_elapsed, bool):
            raise ParameterError(f"clamp_elapsed={clamp_elapsed!r} must be True or False")
        self.sequencer = FootstepSequencer(params, backend=backend)
        self.params = params
        self.corrections = LipmCorrections.from_params(params) if corrections is None else corrections
        self.clamp_elapsed = clamp_elapsed
        self._swing_decision: tuple | None = None  # (stance foot, t_start, crossing?) of the current stance's step
        self._landing: tuple | None = None  # (foot, settled crossing?) of the last plan's first step
        self._resume: tuple | None = None  # (stance foot, t_start, resume?) of the current stance
        # (stance foot, t_start, t, world foothold (2,), touchdown) of the last plan's first step (swing_commit_time)
        self._swing_target: tuple | None = None

    # ------------------------------------------------------------------ model
    @property
    def omega(self) -> float:
        """LIPM natural frequency sqrt(gravity / z_c) [1/s]."""
        return self.params.omega

    @property
    def com_height(self) -> float:
        """LIPM CoM height z_c [m]."""
        return self.params.z_c

    @property
    def double_support(self) -> float:
        """Both feet on the ground after each touchdown for this long [s] (``params.double_support`` at the speed
        of the last plan, see ``SequencerParams.at_speed``)."""
        return self.sequencer.params.double_support

    @property
    def backend(self) -> str:
        """Name of the QP backend."""
        return self.sequencer.backend_name

    @property
    def nominal_command(self) -> VelocityCommand:
        """The preset's command (params.v_x, params.v_y, no turning)."""
        return VelocityCommand(self.params.v_x, self.params.v_y, 0.0)

    # ------------------------------------------------------------------ commands
    def command_range(self) -> dict[str, tuple[float, float]]:
        """(min, max) of each command component the bounds allow, heading frame.

        ``v_x`` [m/s]: v_x t_nom within [l_min, l_max]; ``v_y`` [m/s]: -+pelvis_width + v_y t_nom
        within both stances' width bounds; ``yaw_rate`` [rad/s]: (-inf, inf), the step QP has no
        bound on it (a robot that cannot turn refuses it elsewhere). A command clipped to these
        ranges passes :meth:`check_command`.
        """
        return {**self.params.velocity_range(), "yaw_rate": (-math.inf, math.inf)}

    def can_cross(self, obstacle, stance_position, yaw: float) -> bool:
        """Whether one crossing step can reach beyond ``obstacle`` (a :class:`sequencer.obstacles.Obstacle`) along
        the heading of ``yaw`` [rad]: the footholds' forbidden interval along the heading, the box's extent
        grown by the margins and the sole (:func:`sequencer.footholds.forbidden_box` from ``stance_position``,
        world (x, y) [m]), within the crossing step's length bound max(l_max, obstacle_step_length_max)."""
        geometry = self.params.foothold_geometry()
        a, b, _, _ = forbidden_box(obstacle, np.asarray(stance_position, dtype=float), float(yaw), geometry)
        return b - a <= geometry.step_length_max

    def check_command(self, command: VelocityCommand) -> None:
        """Raise ParameterError, naming the component, its value and the allowed range, when
        ``command`` is outside :meth:`command_range`."""
        command = as_velocity_command(command)
        self.params.check_velocity(command.v_x, command.v_y)

    # ------------------------------------------------------------------ planning
    def plan(self, t: float, stance: StanceState, measured: ReducedState, command: VelocityCommand,
             obstacles=()) -> FootstepPlan:
        """Footsteps from time ``t`` [s] until a touchdown at or after t + params.horizon.

        Uses the stance's foot, position, yaw (the heading ψ_0) and start time, the measured DCM
        (``measured.dcm``, world (x, y), with this planner's ω), the command and the current
        values of :attr:`corrections`.

        A stance that has not begun (``t < stance.t_start``) is a start from standing: both feet
        stay on the ground until ``stance.t_start`` (the contact schedule holds them there), a
        double support in which a flat-footed robot can move its centre of pressure and bring the
        DCM where the gait needs it. The steps are then planned from ``stance.t_start`` and from the
        DCM the nominal gait has at the start of a stance on this foot (the offset the previous
        touchdown aims at), not from the measured one: planned from the DCM between the feet, the
        first step would be a wide catch step (0.16 m wider on the G1) and the walk would drift
        sideways by as much.

        ``obstacles`` (:class:`sequencer.obstacles.Obstacle` s, world frame): every step's foothold, its whole
        sole rectangle (``params.sole_*``), lands outside their footprints grown by ``params.obstacle_margin``,
        before or beyond them (:mod:`sequencer.footholds`); a step whose swing passes over one carries its
        :class:`~sequencer.footholds.Crossing` (from ``stance.swing_liftoff`` for the swing in progress). The
        step of a stance keeps a crossing once planned; a step before the obstacle may become the crossing until
        its swing begins, and the swing in progress keeps the decision it lifted off with. With
        ``params.obstacle_double_support`` > 0 (a quasi-static crossing) a crossing swing lifts off after that
        long a double support, and the stance that begins with its touchdown resumes the walk with another such
        step (``first_resume`` of :meth:`FootstepSequencer.plan`); with ``params.obstacle_resume_double_support`` > 0
        only that resuming step is settled. Empty: the plan without obstacles, bit for bit.

        Raises:
            ParameterError: bad input, or a command outside :meth:`command_range` (clip it first).
            sequencer.footholds.FootholdInfeasible: no foothold outside an obstacle within a step's bounds.
            sequencer.step_qp.StepQPError: the step QP failed (``clamp_elapsed=False`` and a late
                touchdown, or a backend failure); a control loop keeps its last plan.
        """
        if not isinstance(stance, StanceState):
            raise ParameterError(f"stance must be a StanceState, got {type(stance).__name__}")
        if not isinstance(measured, ReducedState):
            raise ParameterError(f"measured must be a ReducedState, got {type(measured).__name__}")
        if stance.foot not in self.feet:
            raise ParameterError(f"stance foot={stance.foot!r} must be one of {self.feet}")
        command = as_velocity_command(command)
        dcm = measured.dcm
        if t < stance.t_start:  # start from standing (see above)
            dcm = self.stance_start_dcm(stance, command)
            t = stance.t_start
        # the step of this stance keeps a crossing once planned: called back in the double support to a step in
        # place (the measured DCM crossing the tolerance), the H1's foot, already rising into the crossing swing,
        # landed 10 cm long on the box's edge; a step before the obstacle may still become the crossing until the
        # swing begins (the DCM run on far enough: the H1's crossings came from there). The swing in progress keeps
        # the decision it lifted off with: flipped mid-swing, the H1's foot, low and before the box, was sent beyond it
        key = (stance.foot, stance.t_start)
        decided = self._swing_decision[2] if len(obstacles) > 0 and self._swing_decision is not None \
            and self._swing_decision[:2] == key else None
        timing = self.sequencer.set_speed(command.v_x)
        swinging = t >= stance.t_start + timing.double_support
        kept = decided if swinging else (True if decided else None)
        # a stance that began with the touchdown of a settled crossing swing resumes the walk with a settled step
        if self._resume is None or self._resume[:2] != key:
            landed = self._landing is not None and self._landing[0] == stance.foot and self._landing[1]
            self._resume = (*key, bool(landed and len(obstacles) > 0))
        plan = self.sequencer.plan(
            t, stance.foot, stance.position, dcm, stance.t_start, self.clamp_elapsed,
            stance_yaw=stance.yaw, yaw_rate=command.yaw_rate, velocity=(command.v_x, command.v_y),
            corrections=self.corrections, obstacles=obstacles, liftoff=stance.swing_liftoff, first_crossing=kept,
            first_resume=self._resume[2], first_lateral=self._committed_lateral(t, stance, key, swinging),
        )
        if self.params.swing_commit_time > 0.0:
            first = plan.steps[0]
            self._swing_target = (*key, t, first.position.copy(), first.touchdown_time) if swinging else None
        if len(obstacles) > 0 and kept is None:
            self._swing_decision = (*key, plan.steps[0].crossing is not None)
        first = plan.steps[0]
        # the stance its touchdown begins resumes the walk with a settled step: after a settled crossing swing, or
        # after any crossing swing with a resuming settle (the lead's next step crosses: it is no resuming step)
        self._landing = (first.foot, first.crossing is not None
                         and (first.settle_dcm is not None or self.params.obstacle_resume_double_support > 0.0))
        return plan

    def _committed_lateral(self, t: float, stance: StanceState, key: tuple, swinging: bool) -> tuple | None:
        """The lateral window (low, high) [m] of the swing's foothold across the stance's heading, from the stance
        foothold, in the last ``swing_commit_time`` of the swing: within ``swing_commit_rate`` times the time since
        the previous plan of where that plan put it (None: not committed: off, not swinging, a new stance, or
        earlier in the swing)."""
        commit = self.params.swing_commit_time
        target = self._swing_target
        if commit <= 0.0 or not swinging or target is None or target[:2] != key:
            return None
        _, _, t_previous, foothold, touchdown = target
        if touchdown - t > commit:
            return None
        c, s = math.cos(stance.yaw), math.sin(stance.yaw)
        dx, dy = foothold[0] - stance.position[0], foothold[1] - stance.position[1]
        lateral = c * dy - s * dx
        reach = self.params.swing_commit_rate * max(t - t_previous, 0.0)
        return lateral - reach, lateral + reach

    def stance_start_dcm(self, stance: StanceState, command: VelocityCommand) -> np.ndarray:
        """The DCM (world (x, y) [m]) the nominal gait of ``command`` has when a stance on
        ``stance.foot`` begins: the stance position plus the offset aimed at by the touchdown that
        ends a stance on the other foot, rotated by the stance yaw."""
        command = as_velocity_command(command)
        self.sequencer.set_speed(command.v_x)
        gait = self.sequencer.nominal_gait((command.v_x, command.v_y), self.corrections)
        return stance.position + rotate_xy(gait.dcm_offset(other_foot(stance.foot)), stance.yaw)

