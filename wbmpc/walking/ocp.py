"""Walking OCP builder: the paper's whole-body problem (section III, eqs. 17-24) from a contact
schedule.

Per running node k (time t0 + k dt), with the feet in contact given by the schedule:

- dynamics: contact forward dynamics with the stance feet as rigid contacts (Baumgarte gains),
  explicit Euler over dt;
- ``{foot}_height``: swing-foot height tracking, eq. (18), reference eq. (19)
  z*(s) = z_ground + 16 H s² (1 − s)², s = swing phase in [0, 1], apex H at s = ½;
- ``{foot}_touchdown_height``: the same residual at the last swing node with a larger weight, so
  the foot lands on the ground (the contact that follows freezes its height);
- ``{foot}_touchdown_velocity``: foot linear velocity at the first stance node (no bounce at
  touchdown). These two touchdown terms are optional additions to the paper's list (off by
  default): they bring the planned stance feet from 3-5 mm to 1-2 mm above the ground, but in
  the MuJoCo closed loop (one iteration per tick, foothold tracking) Bolt fell at 1.6 s with
  them (weights 1e5 / 1e3) and walked without them;
- ``control_regularization``: ‖u‖², eq. (20);
- ``state_regularization``: ‖x ⊖ x*‖²_W around the reference posture, eq. (21) (with
  ``obstacle_leg_posture_scale`` ≠ 1 its leg joint-position rows are the term ``leg_posture``, scaled while
  the horizon holds a crossing swing);
- ``control_bounds``: quadratic barrier outside the robot's torque limits, eq. (22);
- optional ``joint_limits`` (``joint_limit_weight`` > 0, running and terminal nodes): quadratic barrier on the
  joint angles outside the model's position limits narrowed by ``joint_limit_margin``. Not in the paper (Bolt's
  plans stay inside its limits); without it the H1's swing knee was planned past its extension stop (-0.26 rad)
  over the 20 cm box and MuJoCo's stop held it straight (docs/ocp.md "The knee's extension stop");
- optional ``{foot}_foothold`` (track the planned touchdown xy at the last swing node; off by
  default: footholds emerge, the paper's choice), ``{foot}_contact_force`` (regularise the
  stance forces towards m g / n_stance) and ``{foot}_friction_cone`` (point feet);
- optional ``{foot}_swing_path`` (``swing_path_weight`` > 0): the swing foot's (x, y) along its path from
  lift-off to the planned foothold (:func:`swing_path`) at every swing node: without it the horizontal
  motion between lift-off and the last node's foothold term is free (the H1's crossing foot went 12 cm
  back while rising, docs/ocp.md "The lead swing traced"; a crossing swing's own path term is
  ``obstacle_swing_path_weight``). 3e3 in the H1's preset (its obstacle crossings: docs/ocp.md "Every swing on its
  path"), off in Bolt's and the G1's.

- optional obstacle clearance (``obstacle_clearance_weight`` > 0): ``{foot}_clearance_sole{i}`` keeps
  the swing sole's points ``obstacle_sole_points`` (toe and heel) and ``{foot}_clearance_shank`` the
  shank frame (``obstacle_shank_frames``, the knee) above an obstacle's top plus a margin while a
  crossing swing passes over it (:class:`~wbmpc.ocp.residuals.ResidualFramePointHeight` under a
  one-sided barrier: no cost above), and a crossing swing's apex H of eq. (19) is raised above the
  obstacle (:meth:`WalkingOCP.update`, ``clearance``; docs/ocp.md "Obstacle clearance").

The terminal node has the state costs (state regularisation, swing-foot height) and
``com_position``, eq. (23), towards the caller's reference (eq. 24).

Every term follows Crocoddyl's convention: cost = weight · ½ ‖r‖²_activation, running costs are
integrated (× dt), the terminal cost is not.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError, check_finite
from wbmpc.ocp.activations import ActivationQuadraticBarrier, ActivationWeightedQuad
from wbmpc.ocp.actuation import ActuationFloatingBase
from wbmpc.ocp.batched_problem import BatchedShootingProblem, batched_evaluation_support
from wbmpc.ocp.contacts import ContactModel3D, ContactModel6D, sole_lever_arms
from wbmpc.ocp.costs import CostModelResidual, CostModelSum
from wbmpc.ocp.dynamics import DERIVATIVE_DYNAMICS, ROLLOUT_DYNAMICS, DifferentialActionModelContactFwdDynamics
from wbmpc.ocp.integrator import IntegratedActionModelEuler
from wbmpc.ocp.problem import ShootingProblem
from wbmpc.ocp.residuals import (
    ResidualCoMPosition,
    ResidualContactForce,
    ResidualControl,
    ResidualFrameHeight,
    ResidualFramePointAboveBox,
    ResidualFramePointHeight,
    ResidualFrameRotation,
    ResidualFrameTranslation,
    ResidualFrameVelocity,
    ResidualFrictionCone,
    ResidualJointPosition,
    ResidualState,
    ResidualWrenchCone,
)
from wbmpc.ocp.residuals.frame_rotation import yaw_rotation
from wbmpc.ocp.state import StateMultibody

GRAVITY = 9.81  # [m/s²]


class SlowPathWarning(UserWarning):
    """The walking OCP is evaluated node by node because a term cannot be batched (the message names it)."""


def set_by_name_part(values: np.ndarray, pairs, joint_names, field: str) -> None:
    """values[j] = value for every joint j whose name contains ``part``, for each (part, value) of ``pairs`` in
    order (the last pair that matches a joint wins); values (n_j,) and joint_names (n_j,) in the same order. A part
    that matches no joint is a ParameterError naming ``field``."""
    for part, value in pairs:
        matched = [j for j, name in enumerate(joint_names) if str(part) in name]
        if not matched:
            raise ParameterError(f"{field}: {part!r} matches no joint (joints: {list(joint_names)})")
        values[matched] = float(value)


@dataclass(frozen=True)
class StateWeights:
    """Diagonal weights of the state regularisation (eq. 21), per component of x ⊖ x*.

    Base position and orientation errors are in the world/base tangent space
    (pin.difference); velocities in the base frame. Base x, y (and yaw) are free by default:
    walking moves them.
    """

    base_position: tuple[float, float, float] = (0.0, 0.0, 10.0)
    base_orientation: tuple[float, float, float] = (10.0, 10.0, 1.0)
    joint_position: float = 1.0
    base_linear_velocity: tuple[float, float, float] = (0.1, 0.1, 1.0)
    base_angular_velocity: tuple[float, float, float] = (1.0, 1.0, 1.0)
    joint_velocity: float = 0.1
    joint_position_by_name: tuple[tuple[str, float], ...] = ()

    def vector(self, nv: int, joint_names: tuple[str, ...] = ()) -> np.ndarray:
        """Weights as a vector (2 nv,) for a floating-base robot.

        ``joint_position_by_name`` holds (name part, weight) pairs: a joint whose name contains the
        part gets that position weight instead of ``joint_position`` (the last pair that matches
        wins), e.g. ``(("waist", 10.0), ("shoulder", 3.0))`` holds a humanoid's torso and arms
        closer to the reference posture than its legs. ``joint_names`` (nv − 6,) are the actuated
        joints in velocity order.
        """
        nj = nv - 6
        joint_position = np.full(nj, float(self.joint_position))
        if self.joint_position_by_name:
            if len(joint_names) != nj:
                raise ParameterError(f"joint_position_by_name needs the {nj} joint names, got {len(joint_names)}")
            set_by_name_part(joint_position, self.joint_position_by_name, joint_names, "joint_position_by_name")
        w = np.concatenate([
            self.base_position, self.base_orientation, joint_position,
            self.base_linear_velocity, self.base_angular_velocity, np.full(nj, self.joint_velocity),
        ]).astype(float)
        if np.any(w < 0) or not np.all(np.isfinite(w)):
            raise ParameterError(f"state weights must be finite and >= 0, got {w}")
        return w


@dataclass(frozen=True)
class WalkingOCPConfig:
    """Weights and options of the walking OCP (defaults tuned for Bolt at dt = 10 ms, N = 100).

    Attributes:
        swing_apex_height: H of eq. (19), swing-foot apex above the ground [m].
        foot_height_weight: w_track of eq. (18).
        touchdown_height_weight: extra weight on the ground height at the last swing node (the
            contact then holds the foot where it landed: without it the plan lands a few mm above
            the ground); 0 = off (default, see the module docstring).
        touchdown_velocity_weight: weight on the foot's linear velocity at the first
            stance node, so it lands without the bounce a velocity-level contact allows (the
            Baumgarte Kd term only damps it afterwards); 0 = off.
        state_weight: global factor of the state regularisation (eq. 21).
        state_weights: per-component state weights (see :class:`StateWeights`).
        control_weight: w_u of eq. (20) [1/(N·m)²].
        control_bound_weight: w_bu of eq. (22).
        control_bound_fraction: the barrier starts at this fraction of the torque limit, (0, 1].
        joint_limit_weight: weight of the joint-limit barrier ``joint_limits`` [1/rad²]; 0 = off.
        joint_limit_margin: the barrier starts this far inside each joint's position limits [rad], >= 0 and
            less than half of every joint's range.
        joint_limit_margin_by_name: (name part, margin [rad]) pairs: a joint whose name contains the part gets
            that margin instead of ``joint_limit_margin`` (the last pair that matches wins), e.g.
            ``(("knee", 0.05),)`` keeps the plan off the knees' stops and lets the other joints use their range.
        joint_limit_joints: name parts of the joints the barrier covers (a joint whose name contains one of
            them); empty = every joint. ``("knee",)`` keeps the plan off the knees' extension stops (a swing
            planned through a straight knee's stop) and leaves the hips the range beyond their stops that
            MuJoCo's soft limits give.
        com_terminal_weight: w_CoM of eq. (23) (terminal node).
        foothold_weight: planned-foothold xy tracking at the last swing node; 0 = footholds
            emerge (the paper's choice).
        contact_force_weight: stance-force regularisation towards m g / n_stance; 0 = off.
        friction_cone_weight: linearised friction-cone barrier (point feet); 0 = off.
        friction_coefficient: μ of the friction and wrench cones.
        wrench_cone_weight: flat feet: rectangular contact wrench cone barrier (friction, centre
            of pressure inside the sole, yaw torque; :mod:`wbmpc.ocp.residuals.wrench_cone`) on
            every stance foot; 0 = off.
        cop_sole_fraction: the fraction of the robot's ``sole_size`` the wrench cone lets the
            centre of pressure use, (0, 1] (a margin against the sole's edges).
        cop_rear_extension: e [m] in [0, 0.1]: the wrench cone's centre-of-pressure rectangle reaches this much
            further behind the sole rectangle's rear edge (along the sole frame's -x, its width and front edge
            kept; its centre e/2 behind the sole frame). The H1's sole rectangle ends at the ankle axis, its
            heel spheres 3.5 cm behind it (robots.h1); 0 = the sole rectangle.
        cop_rear_extension_feet: where that extension holds: "all" (every stance foot at every node) or "passed"
            (only a stance foot beyond an obstacle that a crossing swing of the horizon passes over, on the far
            side from the swing's lift-off, by :meth:`WalkingOCP.passed_feet`: the lead foot from its touchdown
            beyond the box, under a DCM that lags it, while the trailing foot is still to cross; the other feet
            keep the sole rectangle, as the stance before the box during the lead crossing).
        swing_orientation_weight: flat feet: orientation of the swing foot towards flat with
            the planned touchdown yaw, log3(R_ref^T R) [rad], at every swing node; 0 = off.
        swing_path_weight: weight of ``{foot}_swing_path`` at every swing node of every swing: the foot frame's
            (x, y) [m] tracking its path from lift-off to the planned foothold (:func:`swing_path`, timed by
            ``swing_path_timing``), when :meth:`WalkingOCP.update` is given the swings' lift-off points; 0 = off
            (the swing's horizontal motion free between lift-off and the foothold term). A crossing swing
            tracks its own path with ``obstacle_swing_path_weight`` instead, when that is > 0.
        swing_path_timing: the timing of that path (:func:`swing_path_fraction`): "straight" or "smooth".
        base_yaw_reference: the world yaw of the base in the state regularisation's reference:
            "fixed" (the reference posture's, the paper's choice; Bolt cannot turn) or
            "footholds" (at each node the mean of the feet's planned yaws: the foothold each
            stance foot stands on, the touchdown yaw of a swinging foot; see
            :func:`foothold_heading`), so the pelvis turns with the feet when the plan turns. With
            "fixed" the G1 turning in place at 0.3 rad/s put its feet within 3 deg of the plan
            while the pelvis lagged by a third of the planned heading (49 deg after 10 s), the
            hips twisting until the fall (docs/closed_loop.md).
        baumgarte_gains: (Kp [1/s²], Kd [1/s]) of the contact constraints.
        contact_damping: μ >= 0 of the contact dynamics' KKT system (:mod:`wbmpc.ocp.dynamics`,
            Crocoddyl's ``JMinvJt_damping``), in [m/s² per N] on force rows and [rad/s² per N·m]
            on moment rows: the contact acceleration gives way by μ λ (a compliant contact; with
            Kp = 0 a stance foot's velocity error settles at μ λ / Kd), and a force the rigid
            contacts leave undetermined gets the damped least-squares split. 0 = rigid (default,
            the paper's). Needed where the stacked contact Jacobian is (near) rank deficient: the
            H1's two flat soles without ankle roll, whose lateral squeeze loads no joint
            (docs/ocp.md "Contact damping").
        contact_damping_moments: how the damping weighs a flat foot's moment rows: "uniform" (μ
            on every row, Crocoddyl's ``JMinvJt_damping``) or "sole" (μ / r² on the moment rows,
            r the sole's lever arms, :func:`wbmpc.ocp.contacts.sole_lever_arms`: the sole as four
            damped corner contacts, whose split of an undetermined force keeps each centre of
            pressure near its sole's centre; the 6D contact's spatial drift; needs dynamics_backend
            "kkt" and the robot's ``sole_size``) or "corners" (the same compliance with the four
            corner point contacts' classical drift, a0 + δ; both backends, the Pinocchio one
            batched, with baumgarte_gains Kp = 0; docs/ocp.md "Contact damping").
        dynamics_backend: "pinocchio" (constraintDynamics and its derivatives, fast, batched) or
            "kkt" (Crocoddyl's formulas written out); same results (see :mod:`wbmpc.ocp.dynamics`).
        evaluation: how the horizon is evaluated, same results: "batched" (the Pinocchio calls
            node by node, everything else in one compiled pass, see :mod:`wbmpc.ocp.batched_problem`),
            "nodes" (every node model's calc/calcDiff, the reference pipeline), or "auto"
            (default: batched when the problem's terms allow it, else nodes with a
            :class:`SlowPathWarning` naming the term that cannot be batched).
        rollout_dynamics: the contact dynamics of the FDDP rollouts (and of the batched ``calc``) at the
            "kkt" backend's nodes with contacts, a choice of code path, no unit: "pinocchio" (default:
            Pinocchio's ``crba`` and ``nonLinearEffects``, the explicit-inverse damped KKT solve the
            derivatives use, node by node) or "compiled" (M and b compiled on the contacts' tree, the KKT
            solve by triangular solves on M = Lᵀ D L, the horizon's rollout in one compiled call:
            :class:`~wbmpc.ocp.batched_problem.BatchedShootingProblem`). The same dynamics to rounding
            (~1e-15 relative), a rollout cheaper (docs/benchmarks.md "H1 loop, session 24"), but the
            closed loop is chaotic in the last bits: the H1's 20 s walk at 0.5 m/s falls at 8.76 s with
            "compiled" and completes with "pinocchio". "compiled" needs dynamics_backend "kkt" and the
            batched evaluation (the node-wise one and the "pinocchio" backend's ``constraintDynamics`` do
            not read it).
        derivative_dynamics: the contact dynamics of the derivative pass (the batched ``calcDiff`` and its
            preparation) at the "kkt" backend's nodes with contacts, a choice of code path, no unit: "pinocchio"
            (default: Pinocchio's ``crba``, ``nonLinearEffects`` and ``computeRNEADerivatives``) or "compiled"
            (M and b compiled on the contacts' tree, the RNEA derivatives with the contact forces compiled too, in
            one compiled call with the contacts' and the KKT derivatives:
            :class:`~wbmpc.ocp.batched_problem.BatchedShootingProblem`). The same dynamics and derivatives to
            rounding (~1e-15 relative), a derivative pass cheaper (docs/benchmarks.md "H1 loop, session 25"); the
            closed loop's trajectory changes in the last bits. "compiled" needs dynamics_backend "kkt" and the
            batched evaluation, as ``rollout_dynamics``; the two are independent.
        obstacle_clearance_weight: weight of the one-sided clearance barriers of a crossing swing
            (``{foot}_clearance_sole{i}``, ``{foot}_clearance_shank``); 0 = the terms are absent (the
            problem is the one without obstacles).
        obstacle_sole_points: points of the swing sole kept above the obstacle, (x, y, z) [m] in the foot
            frame (the toe and the heel).
        obstacle_shank_frames: (foot, frame name) pairs: the shank frame of each foot (its knee) kept
            above the obstacle during a crossing swing (``obstacle_shank_gating``); () = none.
        obstacle_clearance_margin: the sole points stay this far above the obstacle's top [m] while their
            path position (``obstacle_swing_path_timing``) is over its footprint grown by ``obstacle_footprint_margin``.
        obstacle_shank_margin: the shank frame stays this far above the top [m].
        obstacle_shank_gating: where the shank frame's clearance applies: "swing" (at every node of the crossing
            swing, the reference top + ``obstacle_shank_margin`` wherever the knee is: lift-off and touchdown
            included, where a flat sole on the floor bounds the knee's height, the H1's to 0.470 m and the G1's to
            0.353 m, so the barrier cannot be met there for boxes above those minus the margin; docs/robots.md) or
            "profile" (at every node of the crossing swing, the box's height profile at the knee's own position:
            top + ``obstacle_shank_margin`` over the footprint grown by ``obstacle_footprint_margin``, the ground
            beyond ``obstacle_profile_transition`` outside it, as the sole points' "profile" gating).
        obstacle_clearance_legs: which legs the clearance terms hold: "crossing" (the swings that pass over an
            obstacle) or "all" (while a crossing is planned in the horizon, also every other swing's soles and knee
            and every standing leg's knee, on the profile of the crossed obstacle nearest the foot: the last step
            before a box lands next to it, and on the H1 at 40 cm its shank struck the box's top edge as that foot
            came down, then, with that swing held, the standing leg's thigh as the body went over it; docs/ocp.md).
            "all" needs both gatings "profile": a sole or a knee away from the box is then asked nothing.
        obstacle_footprint_margin: the footprint grown by this for the sole points' gating [m].
        obstacle_clearance_gating: where the sole points' clearance applies: "path" (at the nodes where their
            planned path position is over the grown footprint, the reference top + ``obstacle_clearance_margin``)
            or "profile" (at every node of the crossing swing, wherever the points actually are: the box's height
            profile, top + ``obstacle_clearance_margin`` over the grown footprint falling to the ground over
            ``obstacle_profile_transition`` outside it, :class:`~wbmpc.ocp.residuals.ResidualFramePointAboveBox`;
            node by node only). With "path" a foot lagging its path is not held above the box once the path has
            passed it: the H1's trailing foot came down on the box 30 cm behind its path.
        obstacle_profile_transition: the "profile" clearance's fall outside the grown footprint [m] (> 0).
        obstacle_apex_margin: a crossing swing's height H (the plateau, or the apex of eq. 19) is at least the
            top plus this [m] (with the "apex" profile also high enough that eq. 19 clears the top plus
            ``obstacle_clearance_margin`` at the first and last gated node).
        obstacle_apex_height_max: upper bound of a crossing swing's height H [m] (what the legs can lift).
        obstacle_swing_profile: a crossing swing's height reference: "plateau" (a smooth rise to the top +
            ``obstacle_apex_margin`` before the sole reaches the grown footprint, held until it is past it, a
            smooth fall: :func:`plateau_height_reference`) or "apex" (eq. 19 with its apex raised until it
            clears the top at the first and last gated node).
        obstacle_plateau_transition_min: the plateau profile's rise and fall each last at least this fraction
            of the swing, in (0, 0.5] (the breakpoints moved inwards if the footprint asks a shorter one: the
            gated sole barriers keep the clearance there).
        obstacle_swing_path_timing: how a crossing swing's foot is timed along its lift-off -> touchdown segment
            (:func:`swing_path_fraction`): "straight" (constant velocity) or "smooth" (at rest at lift-off and
            touchdown). The clearance gating and the plateau breakpoints follow this path, and so does the
            ``{foot}_swing_path`` term.
        obstacle_swing_path_weight: weight of ``{foot}_swing_path``, the foot frame's (x, y) tracking that path
            at every node of a crossing swing (the foot neither goes back while rising nor overshoots its
            foothold); 0 = a crossing swing tracks no path of its own (the path of ``swing_path_weight``, if on).
        obstacle_foothold_weight: the ``{foot}_foothold`` weight of every swing while the horizon holds a
            crossing swing (the footholds next to an obstacle must be where the plan puts them, not where
            they emerge); 0 = ``foothold_weight`` always. Needs ``foothold_weight`` > 0 (the term exists).
        obstacle_com_weight: weight of ``com_path``, the CoM's (x, y) tracking the footstep plan's CoM prediction at
            every running node while the horizon holds a crossing swing (the plan's pivots included: a crossing
            planned on the heel side of the stance foot carries the CoM further than the foothold's pendulum);
            0 = the term is absent (only the terminal CoM reference ties the OCP to the plan's momentum, and the H1
            realised the point-foot DCM travel, landing the lead crossing with the DCM behind it).
        obstacle_leg_posture_scale: factor on the legs' joint-position weights of the state regularisation (the
            joints supporting the feet) at every node while the horizon holds a crossing swing, >= 0: the standing
            posture's legs pull the pelvis between feet 0.6 m apart, against the ``com_path`` that carries it over
            the lead foot (docs/ocp.md "The legs' posture over a crossing"). 1 = unchanged (one
            ``state_regularization`` term); otherwise those rows are the separate term ``leg_posture``.
        obstacle_swing_orientation_scale: factor on ``swing_orientation_weight`` at the nodes of a crossing swing,
            >= 0: the flat-sole term charges the swing hip's abduction (a rolled sole), the H1's one way to lift the
            lead foot higher than its sagittal reach (docs/robots.md "Can the H1 step over 40 cm?"). 1 = unchanged.
        obstacle_swing_abduction: the abducted crossing swing, given as the reference rather than only allowed: a
            crossing swing over an obstacle at least ``obstacle_abduction_height_min`` high has its path (the
            ``{foot}_swing_path`` reference; the clearance gating and the plateau's breakpoints keep the straight
            lift-off -> touchdown path) moved outwards, away from the body's
            sagittal plane across the path's heading, by this times the swing's normalised height profile (0 at
            lift-off and touchdown, 1 over the box) [m], >= 0; 0 = the path of lift-off -> touchdown. The H1's swing
            hip rolled to its 0.43 rad limit moves the sole 18 cm out and lifts it to 0.48 m at the box's near edge,
            against 0.40-0.43 m with the leg in its sagittal plane (docs/robots.md "Can the H1 step over 40 cm?").
        obstacle_swing_roll: the same swings' ``{foot}_orientation`` reference rolled outwards about the sole's
            forward axis by this times the profile [rad], >= 0 (a leg without ankle roll abducts with its sole
            rolled by the hip's roll); 0 = a flat sole.
        obstacle_abduction_height_min: the obstacles whose crossing swings ``obstacle_swing_abduction`` and
            ``obstacle_swing_roll`` shape: top at least this above the ground [m], >= 0.
        max_line_search_trials: FDDP line-search steps tried (1, ½, …).
        reg_min, reg_max: FDDP regularisation bounds.
        th_stop: FDDP stopping threshold.
    """

    swing_apex_height: float = 0.05
    foot_height_weight: float = 1e4
    touchdown_height_weight: float = 0.0
    touchdown_velocity_weight: float = 0.0
    state_weight: float = 1.0
    state_weights: StateWeights = field(default_factory=StateWeights)
    control_weight: float = 1e-1
    control_bound_weight: float = 1e4
    control_bound_fraction: float = 1.0
    joint_limit_weight: float = 0.0
    joint_limit_margin: float = 0.0
    joint_limit_margin_by_name: tuple[tuple[str, float], ...] = ()
    joint_limit_joints: tuple[str, ...] = ()
    com_terminal_weight: float = 1e3
    foothold_weight: float = 0.0
    contact_force_weight: float = 0.0
    friction_cone_weight: float = 0.0
    friction_coefficient: float = 0.7
    wrench_cone_weight: float = 0.0
    cop_sole_fraction: float = 1.0
    cop_rear_extension: float = 0.0
    cop_rear_extension_feet: str = "all"
    swing_orientation_weight: float = 0.0
    swing_path_weight: float = 0.0
    swing_path_timing: str = "smooth"
    base_yaw_reference: str = "fixed"
    baumgarte_gains: tuple[float, float] = (0.0, 50.0)
    contact_damping: float = 0.0
    contact_damping_moments: str = "uniform"
    dynamics_backend: str = "pinocchio"
    evaluation: str = "auto"
    rollout_dynamics: str = "pinocchio"
    derivative_dynamics: str = "pinocchio"
    obstacle_clearance_weight: float = 0.0
    obstacle_sole_points: tuple[tuple[float, float, float], ...] = ()
    obstacle_shank_frames: tuple[tuple[str, str], ...] = ()
    obstacle_clearance_margin: float = 0.05
    obstacle_shank_margin: float = 0.05
    obstacle_shank_gating: str = "swing"
    obstacle_clearance_legs: str = "crossing"
    obstacle_footprint_margin: float = 0.02
    obstacle_clearance_gating: str = "path"
    obstacle_profile_transition: float = 0.05
    obstacle_apex_margin: float = 0.1
    obstacle_apex_height_max: float = 0.5
    obstacle_swing_profile: str = "plateau"
    obstacle_plateau_transition_min: float = 0.05
    obstacle_swing_path_timing: str = "straight"
    obstacle_swing_path_weight: float = 0.0
    obstacle_foothold_weight: float = 0.0
    obstacle_com_weight: float = 0.0
    obstacle_leg_posture_scale: float = 1.0
    obstacle_swing_orientation_scale: float = 1.0
    obstacle_swing_abduction: float = 0.0
    obstacle_swing_roll: float = 0.0
    obstacle_abduction_height_min: float = 0.0
    max_line_search_trials: int = 10
    reg_min: float = 1e-9
    reg_max: float = 1e9
    th_stop: float = 1e-9

    def __post_init__(self) -> None:
        for name in ("foot_height_weight", "touchdown_height_weight", "touchdown_velocity_weight", "state_weight",
                     "control_weight", "control_bound_weight", "joint_limit_weight",
                     "com_terminal_weight", "foothold_weight", "contact_force_weight", "friction_cone_weight",
                     "wrench_cone_weight", "swing_orientation_weight", "swing_path_weight", "obstacle_clearance_weight",
                     "obstacle_swing_path_weight", "obstacle_foothold_weight", "obstacle_com_weight",
                     "obstacle_leg_posture_scale", "obstacle_swing_orientation_scale"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ParameterError(f"{name}={value} must be finite and >= 0")
        if not (np.isfinite(self.swing_apex_height) and self.swing_apex_height >= 0):
            raise ParameterError(f"swing_apex_height={self.swing_apex_height} m must be finite and >= 0")
        for name in ("obstacle_clearance_margin", "obstacle_shank_margin", "obstacle_footprint_margin",
                     "obstacle_apex_margin", "obstacle_apex_height_max", "obstacle_swing_abduction",
                     "obstacle_abduction_height_min"):
            value = getattr(self, name)
            if isinstance(value, bool) or not (np.isfinite(value) and value >= 0):
                raise ParameterError(f"{name}={value!r} m must be finite and >= 0")
        if isinstance(self.obstacle_swing_roll, bool) or not (np.isfinite(self.obstacle_swing_roll)
                                                               and 0.0 <= self.obstacle_swing_roll < 0.5 * np.pi):
            raise ParameterError(f"obstacle_swing_roll={self.obstacle_swing_roll!r} rad must be in [0, pi/2)")
        if isinstance(self.obstacle_plateau_transition_min, bool) or not (
                0.0 < self.obstacle_plateau_transition_min <= 0.5):
            raise ParameterError(f"obstacle_plateau_transition_min={self.obstacle_plateau_transition_min!r} "
                                 "must be in (0, 0.5]")
        for name, allowed in (("swing_path_timing", SWING_PATH_TIMINGS), ("obstacle_swing_path_timing", SWING_PATH_TIMINGS),
                              ("obstacle_clearance_gating", CLEARANCE_GATINGS), ("obstacle_shank_gating", SHANK_GATINGS),
                              ("obstacle_clearance_legs", CLEARANCE_LEGS)):
            if getattr(self, name) not in allowed:
                raise ParameterError(f"{name}={getattr(self, name)!r} must be one of {allowed}")
        if self.obstacle_clearance_legs == "all" and (self.obstacle_clearance_gating,
                                                         self.obstacle_shank_gating) != ("profile", "profile"):
            raise ParameterError("obstacle_clearance_legs='all' needs obstacle_clearance_gating='profile' and "
                                 f"obstacle_shank_gating='profile' (got {self.obstacle_clearance_gating!r} and "
                                 f"{self.obstacle_shank_gating!r})")
        if isinstance(self.obstacle_profile_transition, bool) or not (
                np.isfinite(self.obstacle_profile_transition) and self.obstacle_profile_transition > 0):
            raise ParameterError(f"obstacle_profile_transition={self.obstacle_profile_transition!r} m must be "
                                 "finite and > 0")
        if self.obstacle_swing_profile not in ("plateau", "apex"):
            raise ParameterError(f"obstacle_swing_profile={self.obstacle_swing_profile!r} must be one of "
                                 "('plateau', 'apex')")
        try:  # TOML arrays as the tuples a frozen config holds
            object.__setattr__(self, "obstacle_sole_points", tuple(tuple(float(v) for v in point)
                                                                      for point in self.obstacle_sole_points))
            object.__setattr__(self, "obstacle_shank_frames", tuple(tuple(pair) for pair in self.obstacle_shank_frames))
        except (TypeError, ValueError):
            raise ParameterError(f"obstacle_sole_points={self.obstacle_sole_points!r} must be (x, y, z) triples [m] "
                                 f"and obstacle_shank_frames={self.obstacle_shank_frames!r} (foot, frame) pairs") from None
        for point in self.obstacle_sole_points:
            if len(point) != 3 or not np.all(np.isfinite(np.asarray(point, dtype=float))):
                raise ParameterError(f"obstacle_sole_points: {point!r} must be (x, y, z) [m] in the foot frame")
        for pair in self.obstacle_shank_frames:
            if len(pair) != 2 or not all(isinstance(name, str) for name in pair):
                raise ParameterError(f"obstacle_shank_frames: {pair!r} must be (foot, frame name)")
        if isinstance(self.joint_limit_margin, bool) or not (np.isfinite(self.joint_limit_margin)
                                                              and self.joint_limit_margin >= 0):
            raise ParameterError(f"joint_limit_margin={self.joint_limit_margin!r} rad must be finite and >= 0")
        try:  # TOML arrays as the tuples a frozen config holds
            pairs = tuple((str(part), float(margin)) for part, margin in self.joint_limit_margin_by_name)
        except (TypeError, ValueError):
            raise ParameterError(f"joint_limit_margin_by_name={self.joint_limit_margin_by_name!r} must be (joint name "
                                 "part, margin [rad]) pairs") from None
        for part, margin in pairs:
            if not (np.isfinite(margin) and margin >= 0):
                raise ParameterError(f"joint_limit_margin_by_name: {part!r} has margin={margin} rad, must be finite "
                                     "and >= 0")
        object.__setattr__(self, "joint_limit_margin_by_name", pairs)
        if isinstance(self.joint_limit_joints, str) or not all(isinstance(part, str) and part
                                                               for part in self.joint_limit_joints):
            raise ParameterError(f"joint_limit_joints={self.joint_limit_joints!r} must be a list of joint name parts "
                                 "(non-empty strings; empty list = every joint)")
        object.__setattr__(self, "joint_limit_joints", tuple(self.joint_limit_joints))
        if not (0 < self.control_bound_fraction <= 1):
            raise ParameterError(f"control_bound_fraction={self.control_bound_fraction} must be in (0, 1]")
        if not (0 < self.cop_sole_fraction <= 1):
            raise ParameterError(f"cop_sole_fraction={self.cop_sole_fraction} must be in (0, 1]")
        if isinstance(self.cop_rear_extension, bool) or not (np.isfinite(self.cop_rear_extension)
                                                              and 0.0 <= self.cop_rear_extension <= 0.1):
            raise ParameterError(f"cop_rear_extension={self.cop_rear_extension} m must be in [0, 0.1] m")
        if self.cop_rear_extension_feet not in ("all", "passed"):
            raise ParameterError(f"cop_rear_extension_feet={self.cop_rear_extension_feet!r} must be 'all' or 'passed'")
        if not (np.isfinite(self.friction_coefficient) and self.friction_coefficient > 0):
            raise ParameterError(f"friction_coefficient={self.friction_coefficient} must be > 0")
        if len(self.baumgarte_gains) != 2 or min(self.baumgarte_gains) < 0:
            raise ParameterError(f"baumgarte_gains={self.baumgarte_gains} must be (Kp >= 0, Kd >= 0)")
        if isinstance(self.contact_damping, bool) or not (np.isfinite(self.contact_damping)
                                                           and self.contact_damping >= 0):
            raise ParameterError(f"contact_damping={self.contact_damping} must be finite and >= 0 "
                                 "([m/s² per N], 0 = rigid contacts)")
        if self.contact_damping_moments not in CONTACT_DAMPING_MOMENTS:
            raise ParameterError(f"contact_damping_moments={self.contact_damping_moments!r} must be one of "
                                 f"{CONTACT_DAMPING_MOMENTS}")
        if self.contact_damping_moments == "sole" and self.dynamics_backend != "kkt":
            raise ParameterError("contact_damping_moments='sole' needs dynamics_backend='kkt' (Pinocchio's "
                                 f"constraintDynamics damps every row by one mu), got {self.dynamics_backend!r}; "
                                 "'corners' runs on both")
        if self.contact_damping_moments == "corners" and self.dynamics_backend == "pinocchio" and self.baumgarte_gains[0]:
            raise ParameterError(f"contact_damping_moments='corners' with dynamics_backend='pinocchio' needs "
                                 f"baumgarte_gains Kp = 0 (a corner's position error is not the sole's log6), got "
                                 f"Kp={self.baumgarte_gains[0]}; or use dynamics_backend='kkt'")
        if int(self.max_line_search_trials) != self.max_line_search_trials or self.max_line_search_trials < 1:
            raise ParameterError(f"max_line_search_trials={self.max_line_search_trials} must be an integer >= 1")
        if self.dynamics_backend not in ("pinocchio", "kkt"):
            raise ParameterError(f"dynamics_backend={self.dynamics_backend!r} must be 'pinocchio' or 'kkt'")
        if self.evaluation not in ("auto", "batched", "nodes"):
            raise ParameterError(f"evaluation={self.evaluation!r} must be 'auto', 'batched' or 'nodes'")
        # the two compiled code paths' options, checked alike: (name, allowed, what the "pinocchio" backend runs)
        for name, allowed, pinocchio_backend in (
                ("rollout_dynamics", ROLLOUT_DYNAMICS, "rollouts are constraintDynamics"),
                ("derivative_dynamics", DERIVATIVE_DYNAMICS, "derivatives are computeConstraintDynamicsDerivatives")):
            value = getattr(self, name)
            if value not in allowed:
                raise ParameterError(f"{name}={value!r} must be 'pinocchio' or 'compiled'")
            if value == "compiled" and self.dynamics_backend != "kkt":
                raise ParameterError(f"{name}='compiled' needs dynamics_backend='kkt' (the 'pinocchio' backend's "
                                     f"{pinocchio_backend}), got {self.dynamics_backend!r}")
            if value == "compiled" and self.evaluation == "nodes":
                raise ParameterError(f"{name}='compiled' needs the batched evaluation (evaluation 'auto' or "
                                     "'batched'), got evaluation='nodes'")
        if self.base_yaw_reference not in BASE_YAW_REFERENCES:
            raise ParameterError(f"base_yaw_reference={self.base_yaw_reference!r} must be one of {BASE_YAW_REFERENCES}")
        if not (0 < self.reg_min <= self.reg_max):
            raise ParameterError(f"need 0 < reg_min={self.reg_min} <= reg_max={self.reg_max}")

    def node_wise(self, **changes) -> "WalkingOCPConfig":
        """This configuration evaluated node by node (``evaluation="nodes"``: a timed OCP's spacings, the
        reference pipeline of the tests), with ``changes`` (fields by name) applied too. The compiled
        dynamics paths run only in the batched evaluation, so both are ``"pinocchio"`` there: the same
        numbers to ~1e-15."""
        return replace(self, evaluation="nodes", rollout_dynamics="pinocchio",
                       derivative_dynamics="pinocchio", **changes)


BASE_YAW_REFERENCES = ("fixed", "footholds")
CONTACT_DAMPING_MOMENTS = ("uniform", "sole", "corners")


def foothold_heading(in_contact: np.ndarray, contact_yaw: np.ndarray, touchdown_yaw: np.ndarray) -> np.ndarray:
    """Planned heading of the base at each node [rad], shape (n,): the mean of the feet's yaws.

    A foot in contact counts with the yaw of the foothold it stands on, a swinging foot with its
    touchdown yaw; a yaw the plan does not know (NaN: a foot that landed before the plan) is left
    out. Yaws are the plan's, not wrapped, so the mean of two footholds either side of ±π is right.

    Args:
        in_contact: (n, n_feet) bool; contact_yaw, touchdown_yaw: (n, n_feet) [rad], NaN where
            undefined (a ``sequencer.schedule.ContactSchedule``'s arrays).
    """
    yaws = np.where(np.asarray(in_contact, dtype=bool), contact_yaw, touchdown_yaw)
    known = np.isfinite(yaws)
    if not np.all(known.any(axis=1)):
        raise ParameterError("foothold_heading: a node has no foot with a planned yaw")
    return np.where(known, yaws, 0.0).sum(axis=1) / known.sum(axis=1)


def swing_height_reference(phase, apex_height: float):
    """Eq. (19) in terms of the swing phase s = t / t_f: 16 H s² (1 − s)² [m] above the ground."""
    s = np.asarray(phase, dtype=float)
    return 16.0 * apex_height * s**2 * (1.0 - s) ** 2


def swing_height_reference_derivative(phase, apex_height: float):
    """d/ds of :func:`swing_height_reference`: 32 H s (1 − s)(1 − 2 s) [m]."""
    s = np.asarray(phase, dtype=float)
    return 32.0 * apex_height * s * (1.0 - s) * (1.0 - 2.0 * s)


SWING_PATH_TIMINGS = ("straight", "smooth")
CLEARANCE_GATINGS = ("path", "profile")
"""``WalkingOCPConfig.obstacle_clearance_gating`` values."""
SHANK_GATINGS = ("swing", "profile")
"""``WalkingOCPConfig.obstacle_shank_gating`` values."""
CLEARANCE_LEGS = ("crossing", "all")
"""``WalkingOCPConfig.obstacle_clearance_legs`` values."""
_YAW_CACHE_SIZE = 256  # yaws kept by WalkingOCP's per-yaw caches (a turning walk meets a new one every step)


def swing_path_fraction(phase, timing: str = "straight"):
    """How far along its lift-off -> touchdown segment a swinging foot is at swing phase s = t / t_f (any
    shape, clipped to [0, 1]): "straight", s (constant velocity: the foot lifts off and lands moving);
    "smooth", the quintic smoothstep 10 s³ − 15 s⁴ + 6 s⁵ (zero horizontal velocity and acceleration at
    lift-off and touchdown, peak velocity 1.875 times the mean at s = ½)."""
    s = np.clip(np.asarray(phase, dtype=float), 0.0, 1.0)
    if timing == "straight":
        return s
    if timing == "smooth":
        return s**3 * (10.0 - 15.0 * s + 6.0 * s**2)
    raise ParameterError(f"timing={timing!r} must be one of {SWING_PATH_TIMINGS}")


def swing_path(liftoff_xy, touchdown_xy, phase, timing: str = "straight") -> np.ndarray:
    """World (x, y) [m] of a swinging foot's frame on its path from ``liftoff_xy`` to ``touchdown_xy``
    (..., 2) [m] at swing phase ``phase`` (...), timed by :func:`swing_path_fraction`: shape (..., 2)."""
    liftoff, touchdown = np.asarray(liftoff_xy, dtype=float), np.asarray(touchdown_xy, dtype=float)
    return liftoff + swing_path_fraction(phase, timing)[..., None] * (touchdown - liftoff)


PLATEAU_SAMPLES = 401  # phases sampled on a crossing swing's path to find where it meets the footprint


def _turned_points(centre_xy: np.ndarray, yaw: np.ndarray, point) -> np.ndarray:
    """World (x, y) (m, 2) [m] of the foot-frame ``point`` (x, y, ...) [m] of feet at ``centre_xy`` (m, 2) [m]
    with yaws ``yaw`` (m,) [rad]."""
    c, s = np.cos(yaw), np.sin(yaw)
    return centre_xy + np.column_stack((c * point[0] - s * point[1], s * point[0] + c * point[1]))


def _plateau_breakpoints(rise_end: float, fall_start: float) -> tuple[float, float]:
    """The checked phase breakpoints (rise_end, fall_start) of :func:`plateau_height_reference`."""
    rise_end, fall_start = float(rise_end), float(fall_start)
    if not (0.0 < rise_end <= fall_start < 1.0):
        raise ParameterError(f"plateau breakpoints rise_end={rise_end}, fall_start={fall_start} must satisfy "
                             "0 < rise_end <= fall_start < 1")
    return rise_end, fall_start


def plateau_height_reference(phase, height: float, rise_end: float, fall_start: float):
    """A crossing swing's height above the ground [m] at swing phase s = t / t_f (any shape): a quintic
    smoothstep rise q(s / s_r) H on [0, s_r], the plateau H on [s_r, s_f] and the mirrored fall
    q((1 − s) / (1 − s_f)) H on [s_f, 1], with q(u) = 10 u³ − 15 u⁴ + 6 u⁵ (zero vertical velocity and
    acceleration at lift-off, both plateau ends and touchdown). ``height`` H [m]; ``rise_end`` s_r and
    ``fall_start`` s_f with 0 < s_r <= s_f < 1 (ParameterError otherwise)."""
    rise_end, fall_start = _plateau_breakpoints(rise_end, fall_start)
    s = np.clip(np.asarray(phase, dtype=float), 0.0, 1.0)
    u = np.minimum(np.minimum(s / rise_end, (1.0 - s) / (1.0 - fall_start)), 1.0)
    return height * u**3 * (10.0 - 15.0 * u + 6.0 * u**2)


def plateau_height_reference_derivative(phase, height: float, rise_end: float, fall_start: float):
    """d/ds of :func:`plateau_height_reference` [m]: 30 H u² (1 − u)² du/ds, du/ds = 1 / s_r on the rise,
    0 on the plateau, −1 / (1 − s_f) on the fall (0 outside [0, 1])."""
    rise_end, fall_start = _plateau_breakpoints(rise_end, fall_start)
    s = np.asarray(phase, dtype=float)
    rise, fall = s / rise_end, (1.0 - s) / (1.0 - fall_start)
    rising = rise < fall
    u = np.clip(np.where(rising, rise, fall), 0.0, 1.0)
    slope = np.where(rising, 1.0 / rise_end, -1.0 / (1.0 - fall_start))
    inside = (s >= 0.0) & (s <= 1.0)
    return np.where(inside, 30.0 * height * u**2 * (1.0 - u) ** 2 * slope, 0.0)


class WalkingOCP:
    """The walking OCP of a robot on a fixed grid; :meth:`update` sets it from a contact schedule.

    The node models are built once (every foot has a contact model and a height cost at every
    node); an update switches contacts and costs on and off and writes the references, so a
    receding-horizon loop allocates nothing.

    Args:
        robot: a ``robots.RobotDescription`` (pinocchio_model with armature and torque limits,
            foot_frames, contact_type, q_reference, torque_limit, contact_frame_height).
        config: weights and options.
        n_nodes: number of running nodes N, ≥ 1.
        dt: node spacing [s], > 0.
    """

    def __init__(self, robot, config: WalkingOCPConfig, n_nodes: int, dt: float):
        if isinstance(n_nodes, bool) or int(n_nodes) != n_nodes or n_nodes < 1:
            raise ParameterError(f"n_nodes={n_nodes!r} must be an integer >= 1")
        if not (np.isfinite(dt) and dt > 0):
            raise ParameterError(f"dt={dt} s must be a finite positive number")
        self.robot = robot
        self.config = config
        self.n_nodes = int(n_nodes)
        self.dt = float(dt)
        model = robot.pinocchio_model
        self.state = StateMultibody(model)
        self.actuation = ActuationFloatingBase(self.state)
        self.nu = self.actuation.nu
        self.feet = tuple(robot.foot_frames.keys())
        self.foot_frame_ids = {foot: model.getFrameId(name) for foot, name in robot.foot_frames.items()}
        if robot.contact_type not in ("point3d", "flat6d"):
            raise ParameterError(f"contact_type={robot.contact_type!r} must be 'point3d' or 'flat6d'")
        self.contact_type = robot.contact_type
        self.ground_height = float(robot.contact_frame_height)
        torque_limit = np.asarray(robot.torque_limit, dtype=float)
        if torque_limit.shape != (self.nu,):
            raise ParameterError(f"robot.torque_limit has shape {torque_limit.shape}, expected ({self.nu},)")
        self.torque_limit = torque_limit
        self.mass = float(sum(inertia.mass for inertia in model.inertias))
        self.x_reference = np.concatenate([np.asarray(robot.q_reference, dtype=float), np.zeros(model.nv)])
        self._shank_frame_ids = self._shank_frames(config.obstacle_shank_frames)
        #: rows of the state residual (tangent, (2 nv,)) that are the legs' joint positions: the joints supporting
        #: the feet, the free flyer excluded
        self.leg_position_rows = np.array(sorted({
            model.joints[j].idx_v + i for fid in self.foot_frame_ids.values()
            for j in model.supports[model.frames[fid].parentJoint] if j > 1
            for i in range(model.joints[j].nv)}), dtype=int)
        self._kinematics_data = pdata = model.createData()  # here the reference posture; the feet at x0 (passed_feet)
        pin.framesForwardKinematics(model, pdata, self.x_reference[: model.nq])
        self._reference_placements = {foot: pin.SE3(pdata.oMf[fid]) for foot, fid in self.foot_frame_ids.items()}
        #: per foot, +1 where the reference posture has it on the base's left (+y), -1 on its right: "outwards"
        #: for ``obstacle_swing_abduction`` and ``obstacle_swing_roll``
        self.foot_sides = np.array([1.0 if self._reference_placements[foot].translation[1] >= self.x_reference[1]
                                    else -1.0 for foot in self.feet])
        running = [self._node(terminal=False) for _ in range(self.n_nodes)]
        terminal = self._node(terminal=True)
        # per node: (differential model, per foot (height, touchdown height, touchdown velocity,
        # foothold, contact force, friction cone, wrench cone, orientation) cost items, None where
        # the term is absent)
        self._node_terms = []
        # per node: the legs' posture cost item (with obstacle_leg_posture_scale != 1)
        self._leg_posture_terms = [model.differential.costs.costs["leg_posture"] for model in running + [terminal]
                                   ] if config.obstacle_leg_posture_scale != 1.0 else None
        # per node: the state residuals whose base orientation follows the heading (the regularisation's, and the
        # legs' posture one when it is a term of its own)
        self._state_residuals = [
            [model.differential.costs.costs[name].cost.residual for name in ("state_regularization", "leg_posture")
             if name in model.differential.costs.costs]
            for model in running + [terminal]]
        # the reference posture's base orientation (Pinocchio's q[3:7] = (x, y, z, w)), turned by the heading
        self._base_rotation_reference = pin.Quaternion(self.x_reference[3:7]).toRotationMatrix()
        # yaw [rad] -> the rotation about z (3, 3) and the reference posture's base orientation turned by it
        # (Pinocchio's (x, y, z, w)), computed once per yaw value: a plan's nodes share a few yaws (one per foothold)
        # and each update meets them again; the arrays are read-only (their users copy them)
        self._yaw_rotation = lru_cache(maxsize=_YAW_CACHE_SIZE)(yaw_rotation)
        rotation, base = self._yaw_rotation, self._base_rotation_reference
        self._heading_quaternion = lru_cache(maxsize=_YAW_CACHE_SIZE)(
            lambda yaw: pin.Quaternion(rotation(yaw) @ base).coeffs().copy())
        for model in running + [terminal]:
            items = model.differential.costs.costs
            self._node_terms.append((model.differential, [
                tuple(items.get(f"{foot}_{term}") for term in (
                    "height", "touchdown_height", "touchdown_velocity", "foothold", "contact_force", "friction_cone",
                    "wrench_cone", "wrench_cone_passed", "orientation"))
                for foot in self.feet]))
        self._has_passed_cones = any(f"{foot}_wrench_cone_passed" in model.differential.costs.costs
                                     for model in running for foot in self.feet)
        # per running node, per foot: (the sole points' clearance cost items, the shank's or None)
        self._clearance_terms = [
            [([items[f"{foot}_clearance_sole{i}"] for i in range(len(config.obstacle_sole_points))],
              items.get(f"{foot}_clearance_shank")) for foot in self.feet]
            for items in (model.differential.costs.costs for model in running)
        ] if config.obstacle_clearance_weight > 0 else None
        # per running node, per foot: the swing path tracking cost item
        self._swing_path_terms = [[items[f"{foot}_swing_path"] for foot in self.feet]
                                  for items in (model.differential.costs.costs for model in running)
                                  ] if config.swing_path_weight > 0 or config.obstacle_swing_path_weight > 0 else None
        # per running node: the CoM path tracking cost item (while a crossing is in the horizon)
        self._com_path_terms = [model.differential.costs.costs["com_path"] for model in running
                                ] if config.obstacle_com_weight > 0 else None
        self.problem = ShootingProblem(self.x_reference, running, terminal)
        self._timed = False  # running nodes carry a timed schedule's spacing (see update)
        #: "batched" or "nodes" (see WalkingOCPConfig.evaluation); evaluation_note says why nodes
        self.evaluation, self.evaluation_note = "nodes", ""
        if config.evaluation != "nodes":
            reason = batched_evaluation_support(self.problem)
            if reason is None:
                self.problem = BatchedShootingProblem(self.x_reference, running, terminal,
                                                      rollout_dynamics=config.rollout_dynamics,
                                                      derivative_dynamics=config.derivative_dynamics)
                self.evaluation = "batched"
            elif config.evaluation == "batched":
                raise ParameterError(f"evaluation='batched' is not possible for this problem: {reason}")
            elif compiled := next((name for name in ("rollout_dynamics", "derivative_dynamics")
                                   if getattr(config, name) == "compiled"), None):
                raise ParameterError(f"{compiled}='compiled' needs the batched evaluation, not possible for this "
                                     f"problem: {reason}")
            else:  # said, not silent: the node-wise path is several times slower
                self.evaluation_note = f"node-wise evaluation: {reason}"
                warnings.warn(f"WalkingOCP: {self.evaluation_note} (evaluation='auto'; set evaluation='nodes' to "
                              "choose it, or 'batched' to make this an error)", SlowPathWarning, stacklevel=2)

    # ------------------------------------------------------------------ construction
    def _shank_frames(self, pairs) -> dict[str, int]:
        """foot -> shank frame id of ``obstacle_shank_frames`` (checked against the robot)."""
        model = self.robot.pinocchio_model
        frames = {}
        for foot, name in pairs:
            if foot not in self.feet:
                raise ParameterError(f"obstacle_shank_frames: foot {foot!r} must be one of {self.feet}")
            if not model.existFrame(name):
                raise ParameterError(f"obstacle_shank_frames: robot {self.robot.name!r} has no frame {name!r}")
            frames[foot] = model.getFrameId(name)
        return frames

    def _joint_bounds(self, residual: ResidualJointPosition) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) (n_j,) of the joint-limit barrier: the model's position limits of ``residual``'s joints
        narrowed by ``joint_limit_margin`` or the joint's ``joint_limit_margin_by_name`` [rad]; (-inf, inf) for a
        joint outside ``joint_limit_joints`` (when it is not empty)."""
        model = self.robot.pinocchio_model
        margin = np.full(residual.nr, self.config.joint_limit_margin)
        set_by_name_part(margin, self.config.joint_limit_margin_by_name, residual.joint_names,
                         "joint_limit_margin_by_name")
        lower = model.lowerPositionLimit[residual.q_rows] + margin
        upper = model.upperPositionLimit[residual.q_rows] - margin
        if self.config.joint_limit_joints:
            covered = np.zeros(residual.nr)
            set_by_name_part(covered, [(part, 1.0) for part in self.config.joint_limit_joints], residual.joint_names,
                             "joint_limit_joints")
            lower[covered == 0] = -np.inf
            upper[covered == 0] = np.inf
        narrow = np.flatnonzero(lower >= upper)
        if narrow.size:
            j = narrow[0]
            raise ParameterError(f"joint_limit_margin={margin[j]} rad leaves no range for joint {residual.joint_names[j]!r} "
                                 f"(limits [{model.lowerPositionLimit[residual.q_rows[j]]:.3f}, "
                                 f"{model.upperPositionLimit[residual.q_rows[j]]:.3f}] rad); it must be less than half "
                                 "of every joint's range")
        return lower, upper

    def _contact(self, foot: str):
        fid = self.foot_frame_ids[foot]
        gains = self.config.baumgarte_gains
        if self.contact_type == "point3d":
            return ContactModel3D(self.state, fid, self._reference_placements[foot].translation, gains)
        return ContactModel6D(self.state, fid, self._reference_placements[foot], gains)

    def _node(self, terminal: bool) -> IntegratedActionModelEuler:
        cfg = self.config
        state, nu = self.state, self.nu
        costs = CostModelSum(state, nu)
        w_state = cfg.state_weights.vector(state.nv, tuple(self.robot.actuated_joint_names))
        w_legs = None
        if cfg.obstacle_leg_posture_scale != 1.0:  # the legs' joint-position rows as their own term
            w_legs = np.zeros_like(w_state)
            w_legs[self.leg_position_rows] = w_state[self.leg_position_rows]
            w_state = w_state.copy()
            w_state[self.leg_position_rows] = 0.0
        costs.add("state_regularization",
                  CostModelResidual(ResidualState(state, self.x_reference, nu), ActivationWeightedQuad(w_state)),
                  cfg.state_weight)
        if w_legs is not None:
            costs.add("leg_posture",
                      CostModelResidual(ResidualState(state, self.x_reference, nu), ActivationWeightedQuad(w_legs)),
                      cfg.state_weight)
        if not terminal:
            costs.add("control_regularization", CostModelResidual(ResidualControl(state, nu)), cfg.control_weight)
            limit = cfg.control_bound_fraction * self.torque_limit
            costs.add("control_bounds",
                      CostModelResidual(ResidualControl(state, nu), ActivationQuadraticBarrier(-limit, limit)),
                      cfg.control_bound_weight)
        if cfg.joint_limit_weight > 0:
            residual = ResidualJointPosition(state, nu)
            costs.add("joint_limits", CostModelResidual(residual, ActivationQuadraticBarrier(*self._joint_bounds(residual))),
                      cfg.joint_limit_weight)
        for foot in self.feet:
            fid = self.foot_frame_ids[foot]
            costs.add(f"{foot}_height",
                      CostModelResidual(ResidualFrameHeight(state, fid, self.ground_height, nu)),
                      cfg.foot_height_weight, active=False)
            if not terminal and cfg.touchdown_height_weight > 0:
                costs.add(f"{foot}_touchdown_height",
                          CostModelResidual(ResidualFrameHeight(state, fid, self.ground_height, nu)),
                          cfg.touchdown_height_weight, active=False)
            if not terminal and cfg.touchdown_velocity_weight > 0:
                costs.add(f"{foot}_touchdown_velocity",
                          CostModelResidual(ResidualFrameVelocity(state, fid, nu),
                                            ActivationWeightedQuad(np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0]))),
                          cfg.touchdown_velocity_weight, active=False)
            if not terminal and cfg.foothold_weight > 0:
                costs.add(f"{foot}_foothold", self._frame_xy_cost(foot), cfg.foothold_weight, active=False)
            if not terminal and cfg.contact_force_weight > 0:
                nc = 3 if self.contact_type == "point3d" else 6
                costs.add(f"{foot}_contact_force",
                          CostModelResidual(ResidualContactForce(state, foot, np.zeros(nc), nu)),
                          cfg.contact_force_weight, active=False)
            if not terminal and cfg.friction_cone_weight > 0 and self.contact_type == "point3d":
                residual = ResidualFrictionCone(state, foot, cfg.friction_coefficient, nu)
                costs.add(f"{foot}_friction_cone",
                          CostModelResidual(residual, ActivationQuadraticBarrier(residual.lower_bounds,
                                                                                 residual.upper_bounds)),
                          cfg.friction_cone_weight, active=False)
            flat = self.contact_type == "flat6d"
            if not terminal and cfg.wrench_cone_weight > 0 and flat:
                length, width = self._sole_size("wrench_cone_weight > 0")
                passed_only = cfg.cop_rear_extension > 0 and cfg.cop_rear_extension_feet == "passed"
                cones = {"wrench_cone": 0.0 if passed_only else cfg.cop_rear_extension}
                if passed_only:
                    cones["wrench_cone_passed"] = cfg.cop_rear_extension
                for term, extension in cones.items():
                    residual = ResidualWrenchCone(state, foot, cfg.friction_coefficient,
                                                  0.5 * (cfg.cop_sole_fraction * length + extension),
                                                  0.5 * cfg.cop_sole_fraction * width, nu, center_x=-0.5 * extension)
                    costs.add(f"{foot}_{term}",
                              CostModelResidual(residual, ActivationQuadraticBarrier(residual.lower_bounds,
                                                                                     residual.upper_bounds)),
                              cfg.wrench_cone_weight, active=False)
            if not terminal and cfg.obstacle_clearance_weight > 0:
                barrier = (np.zeros(1), np.full(1, np.inf))  # one-sided: no cost above the reference
                for i, point in enumerate(cfg.obstacle_sole_points):
                    residual = self._clearance_residual(fid, point, cfg.obstacle_clearance_gating == "profile")
                    costs.add(f"{foot}_clearance_sole{i}",
                              CostModelResidual(residual, ActivationQuadraticBarrier(*barrier)),
                              cfg.obstacle_clearance_weight, active=False)
                shank = self._shank_frame_ids.get(foot)
                if shank is not None:
                    residual = self._clearance_residual(shank, np.zeros(3), cfg.obstacle_shank_gating == "profile")
                    costs.add(f"{foot}_clearance_shank",
                              CostModelResidual(residual, ActivationQuadraticBarrier(*barrier)),
                              cfg.obstacle_clearance_weight, active=False)
            if not terminal and (cfg.swing_path_weight > 0 or cfg.obstacle_swing_path_weight > 0):
                costs.add(f"{foot}_swing_path", self._frame_xy_cost(foot),
                          cfg.swing_path_weight or cfg.obstacle_swing_path_weight, active=False)
            if not terminal and cfg.swing_orientation_weight > 0 and flat:
                costs.add(f"{foot}_orientation",
                          CostModelResidual(ResidualFrameRotation(state, fid, self._reference_placements[foot].rotation,
                                                                  nu)),
                          cfg.swing_orientation_weight, active=False)
        if terminal:
            costs.add("com_position",
                      CostModelResidual(ResidualCoMPosition(state, np.zeros(3), nu)), cfg.com_terminal_weight)
        elif cfg.obstacle_com_weight > 0:
            costs.add("com_path", CostModelResidual(ResidualCoMPosition(state, np.zeros(3), nu),
                                                    ActivationWeightedQuad(np.array([1.0, 1.0, 0.0]))),
                      cfg.obstacle_com_weight, active=False)
        contacts = {foot: self._contact(foot) for foot in self.feet}
        lever_arms = None
        moments = cfg.contact_damping_moments
        if moments != "uniform":
            if self.contact_type != "flat6d":
                raise ParameterError(f"contact_damping_moments={moments!r} needs flat feet (robot {self.robot.name!r} "
                                     f"has {self.contact_type!r} contacts)")
            lever_arms = {foot: sole_lever_arms(self._sole_size(f"contact_damping_moments={moments!r}"))
                          for foot in self.feet}
        dam = DifferentialActionModelContactFwdDynamics(state, self.actuation, contacts, costs,
                                                        backend=cfg.dynamics_backend,
                                                        contact_damping=cfg.contact_damping,
                                                        damping_lever_arms=lever_arms,
                                                        sole_corners=moments == "corners")
        return IntegratedActionModelEuler(dam, 0.0 if terminal else self.dt)

    def _frame_xy_cost(self, foot: str) -> CostModelResidual:
        """The (x, y) [m] of ``foot``'s frame against a world reference (``cost.residual.reference``, (3,),
        z weighted 0): the foothold and the swing path terms."""
        residual = ResidualFrameTranslation(self.state, self.foot_frame_ids[foot],
                                            self._reference_placements[foot].translation, self.nu)
        return CostModelResidual(residual, ActivationWeightedQuad(np.array([1.0, 1.0, 0.0])))

    def _sole_size(self, needed_by: str) -> tuple[float, float]:
        size = self.robot.sole_size
        if size is None:
            raise ParameterError(f"{needed_by} needs the robot's sole_size (robot {self.robot.name!r} has none)")
        return size

    # ------------------------------------------------------------------ update
    def update(self, x0: np.ndarray, schedule, com_terminal_reference: np.ndarray,
               touchdown_depth: float = 0.0, crossings=None, com_path=None, swing_liftoff=None,
               swing_path_weight: float | None = None) -> None:
        """Set the initial state, the per-node contacts and references from a schedule.

        Args:
            x0: initial state (nx,), Pinocchio convention.
            schedule: ``sequencer.schedule.ContactSchedule`` with n_nodes rows + 1 on this grid; a
                timed one (``node_spacing`` set, :func:`sequencer.timed_contact_schedule`) gives
                running node k the spacing node_spacing[k] (evaluation="nodes" only).
            com_terminal_reference: CoM reference at the end of the horizon (3,) [m], world.
            touchdown_depth: how far below the ground the ``{foot}_touchdown_height`` term aims
                the foot at the last swing node [m], >= 0 (0: on the ground; the walking
                controller aims a due foot still in the air below it).
            crossings: the swings that pass over obstacles on this grid (a
                :class:`wbmpc.walking.reference.CrossingSchedule`, same rows and feet as ``schedule``), or None
                (none: the problem without obstacles). Their apex and clearance terms: :meth:`_clearance`.
            com_path: the footstep plan's CoM prediction at the nodes, (n_nodes + 1, 3) [m], world, or None: the
                ``com_path`` references, active at every running node when ``crossings`` is given (with
                ``obstacle_com_weight`` > 0).
            swing_liftoff: world (x, y) [m] where the swing running at each node lifted off (or lifts off),
                (n_nodes + 1, n_feet, 2) in the schedule's foot order, NaN in contact or where unknown
                (:func:`wbmpc.walking.reference.swing_liftoffs`), or None: the ``{foot}_swing_path`` terms of
                ``swing_path_weight`` track :func:`swing_path` from there to the schedule's touchdown (off at
                NaN rows and with None).
            swing_path_weight: this update's weight of those terms instead of the config's (None: the config's;
                e.g. the controller's ``fast_swing_path_weight`` at speed); > 0 needs the terms (the config's
                ``swing_path_weight`` or ``obstacle_swing_path_weight`` > 0).
        """
        self.problem.set_x0(x0)
        if schedule.n_nodes != self.n_nodes:
            raise ParameterError(f"schedule has n_nodes={schedule.n_nodes}, the OCP has {self.n_nodes}")
        if abs(schedule.dt - self.dt) > 1e-9:
            raise ParameterError(f"schedule dt={schedule.dt} s differs from the OCP dt={self.dt} s")
        missing = set(self.feet) - set(schedule.feet)
        if missing:
            raise ParameterError(f"schedule feet {schedule.feet} lack the robot's feet {sorted(missing)}")
        com_ref = np.asarray(com_terminal_reference, dtype=float)
        if com_ref.shape != (3,):
            raise ParameterError(f"com_terminal_reference has shape {com_ref.shape}, expected (3,)")
        check_finite("com_terminal_reference", com_ref)
        if not (np.isfinite(touchdown_depth) and touchdown_depth >= 0.0):
            raise ParameterError(f"touchdown_depth={touchdown_depth} m must be finite and >= 0")
        touchdown_reference = self.ground_height - float(touchdown_depth)
        self._set_node_spacing(schedule.node_spacing)
        cfg = self.config
        columns = [schedule.feet.index(foot) for foot in self.feet]
        in_contact = np.asarray(schedule.in_contact, dtype=bool)[:, columns]
        phase = np.asarray(schedule.swing_phase, dtype=float)[:, columns]
        touchdown = np.asarray(schedule.touchdown_position, dtype=float)[:, columns]
        touchdown_yaw = np.nan_to_num(np.asarray(schedule.touchdown_yaw, dtype=float)[:, columns])
        apex = cfg.swing_apex_height
        foothold_weight = cfg.foothold_weight
        if crossings is not None and cfg.obstacle_foothold_weight > 0:
            foothold_weight = cfg.obstacle_foothold_weight
        if self._clearance_terms is not None:  # off until a crossing swing turns them on
            for node_terms in self._clearance_terms:
                for soles, shank in node_terms:
                    for item in soles:
                        item.active = False
                    if shank is not None:
                        shank.active = False
        path_weight = cfg.swing_path_weight if swing_path_weight is None else float(swing_path_weight)
        if path_weight > 0 and self._swing_path_terms is None:
            raise ParameterError(f"swing_path_weight={path_weight} needs the OCP's swing path terms: built with "
                                 f"swing_path_weight or obstacle_swing_path_weight > 0 (both are 0)")
        if self._swing_path_terms is not None:  # off until a swing with a known lift-off turns them on
            for node_items in self._swing_path_terms:
                for item in node_items:
                    item.active = False
            if path_weight > 0 and swing_liftoff is not None:
                liftoff = np.asarray(swing_liftoff, dtype=float)
                if liftoff.shape != np.shape(schedule.touchdown_position):
                    raise ParameterError(f"swing_liftoff has shape {liftoff.shape}, the schedule's touchdowns "
                                         f"{np.shape(schedule.touchdown_position)}")
                self._swing_paths(liftoff[:, columns], ~in_contact, np.nan_to_num(phase), touchdown, path_weight)
        heights = self.ground_height + swing_height_reference(np.nan_to_num(phase), apex)
        crossing = None  # the (node, foot) pairs of a crossing swing: where _clearance gave a height reference
        rolls = None  # the sole's outward roll reference [rad] of each (node, foot) (obstacle_swing_roll)
        if crossings is not None:
            crossing_heights, rolls = self._clearance(crossings, ~in_contact, np.nan_to_num(phase), touchdown,
                                                      columns)
            crossing = ~np.isnan(crossing_heights)
            heights = np.where(crossing, self.ground_height + crossing_heights, heights)
        n_stance = np.maximum(in_contact.sum(axis=1), 1)
        last_swing = np.zeros_like(in_contact)
        last_swing[:-1] = ~in_contact[:-1] & in_contact[1:]
        first_stance = np.zeros_like(in_contact)
        first_stance[1:] = in_contact[1:] & ~in_contact[:-1]
        stance_names = [tuple(foot for j, foot in enumerate(self.feet) if row[j]) for row in in_contact.tolist()]
        swing_rows, last_rows, first_rows = (~in_contact).tolist(), last_swing.tolist(), first_stance.tolist()
        orientation_weight = cfg.swing_orientation_weight
        orientation_rows = None  # the orientation weight of each (node, foot) where a crossing scales it
        if crossing is not None and cfg.obstacle_swing_orientation_scale != 1.0:
            orientation_rows = np.where(crossing, orientation_weight * cfg.obstacle_swing_orientation_scale,
                                        orientation_weight).tolist()
        heights_rows = heights.tolist()
        passed = None  # the (node, foot) pairs whose stance cone reaches behind the sole (cop_rear_extension_feet)
        if crossings is not None and self._has_passed_cones:
            passed = self.passed_feet(x0, crossings, in_contact, touchdown, columns).tolist()
        force_reference = (self.mass * GRAVITY / n_stance).tolist()
        for k, (dam, feet_terms) in enumerate(self._node_terms):
            terminal = k == self.n_nodes
            if not terminal:
                dam.set_active_contacts(stance_names[k])
            for j, (height, touchdown_height, touchdown_velocity, foothold, force, cone, wrench, wrench_passed,
                    orientation) in enumerate(feet_terms):
                swing = swing_rows[k][j]
                height.active = swing
                if swing:
                    height.cost.residual.reference = heights_rows[k][j]
                if terminal:
                    continue
                if touchdown_height is not None:
                    touchdown_height.active = last_rows[k][j]
                    touchdown_height.cost.residual.reference = touchdown_reference
                if touchdown_velocity is not None:
                    touchdown_velocity.active = first_rows[k][j]
                if foothold is not None:
                    foothold.active = last_rows[k][j]
                    if foothold.weight != foothold_weight:
                        foothold.weight = foothold_weight
                    if last_rows[k][j]:
                        foothold.cost.residual.reference[:] = (touchdown[k, j, 0], touchdown[k, j, 1],
                                                                self.ground_height)
                if force is not None:
                    force.active = not swing
                    force.cost.residual.reference[2] = force_reference[k]
                if cone is not None:
                    cone.active = not swing
                if wrench is not None:
                    wrench.active = not swing and not (passed is not None and passed[k][j])
                if wrench_passed is not None:
                    wrench_passed.active = not swing and passed is not None and passed[k][j]
                if orientation is not None:
                    orientation.active = swing
                    weight = orientation_weight if orientation_rows is None else orientation_rows[k][j]
                    if orientation.weight != weight:
                        orientation.weight = weight
                    if swing:
                        rotation = self._yaw_rotation(float(touchdown_yaw[k, j]))
                        if rolls is not None and rolls[k, j] != 0.0:
                            rotation = rotation @ pin.utils.rotate("x", float(rolls[k, j]))
                        orientation.cost.residual.reference[:] = rotation
        if cfg.base_yaw_reference == "footholds":
            heading = foothold_heading(in_contact, np.asarray(schedule.contact_yaw, dtype=float)[:, columns],
                                       np.asarray(schedule.touchdown_yaw, dtype=float)[:, columns])
            for residuals, yaw in zip(self._state_residuals, heading.tolist()):  # (a batched problem's rows)
                quaternion = self._heading_quaternion(yaw)
                for residual in residuals:
                    residual.reference[3:7] = quaternion
        self.problem.terminal_model.differential.costs.costs["com_position"].cost.residual.reference[:] = com_ref
        if self._leg_posture_terms is not None:
            leg_weight = cfg.state_weight * (cfg.obstacle_leg_posture_scale if crossings is not None else 1.0)
            for item in self._leg_posture_terms:
                if item.weight != leg_weight:
                    item.weight = leg_weight
        if self._com_path_terms is not None:
            tracking = crossings is not None and com_path is not None
            if tracking:
                path = np.asarray(com_path, dtype=float)
                if path.shape != (self.n_nodes + 1, 3):
                    raise ParameterError(f"com_path has shape {path.shape}, expected ({self.n_nodes + 1}, 3)")
                check_finite("com_path", path)
            for k, item in enumerate(self._com_path_terms):
                item.active = tracking
                if tracking:
                    item.cost.residual.reference[:] = path[k]
        if self.evaluation == "batched":  # contact sets (references, weights and activity are shared)
            self.problem.sync()

    def _swing_paths(self, liftoff: np.ndarray, swinging: np.ndarray, phase: np.ndarray,
                     touchdown: np.ndarray, weight: float) -> None:
        """Turn on ``{foot}_swing_path`` (with ``weight``) at every running swing node whose lift-off
        ``liftoff`` (n + 1, n_feet, 2) [m] is known (finite), with the reference :func:`swing_path` from it to the
        schedule's ``touchdown`` (n + 1, n_feet, 2) [m] at the node's phase (both in the OCP's foot order)."""
        cfg = self.config
        known = swinging & np.isfinite(liftoff).all(axis=2)
        path = swing_path(np.nan_to_num(liftoff), np.nan_to_num(touchdown), phase, cfg.swing_path_timing)
        for k, j in zip(*np.nonzero(known[:self.n_nodes]), strict=True):
            item = self._swing_path_terms[k][j]
            item.active = True
            if item.weight != weight:
                item.weight = weight
            item.cost.residual.reference[:2] = path[k, j]

    def passed_feet(self, x0: np.ndarray, crossings, in_contact: np.ndarray, touchdown: np.ndarray,
                    columns: list[int]) -> np.ndarray:
        """Where a stance foot stands beyond an obstacle that a crossing swing of this horizon passes over:
        (n + 1, n_feet) bool in the OCP's foot order (``cop_rear_extension_feet = "passed"``).

        A foot stands where it is at ``x0`` (its frame's world (x, y)) until its first swing of the horizon,
        then on that swing's ``touchdown`` (n + 1, n_feet, 2) [m], and so on. It is beyond obstacle o when its
        position is outside o's footprint along o's depth axis, on the other side of o's centre from the lift-off
        of a crossing swing over o (``crossings``, a :class:`wbmpc.walking.reference.CrossingSchedule` in the
        schedule's foot order, ``columns`` the OCP's feet in it); only at nodes where it is in contact."""
        model, data = self.state.pinocchio, self._kinematics_data
        pin.forwardKinematics(model, data, np.asarray(x0[: model.nq], dtype=float))
        position = np.array([pin.updateFramePlacement(model, data, self.foot_frame_ids[foot]).translation[:2]
                             for foot in self.feet])
        index = np.asarray(crossings.index)[:, columns]
        liftoff = np.asarray(crossings.liftoff_xy, dtype=float)[:, columns]
        sides = []  # per crossed obstacle: (the obstacle, the side of its centre the lift-off is on: +1 or -1)
        for which, obstacle in enumerate(crossings.obstacles):
            rows = np.argwhere(index == which)
            if rows.size:
                sides.append((obstacle, np.sign(obstacle.local(liftoff[rows[0, 0], rows[0, 1]])[0])))
        passed = np.zeros(in_contact.shape, dtype=bool)
        for k in range(in_contact.shape[0]):
            for j in range(in_contact.shape[1]):
                if not in_contact[k, j]:
                    position[j] = touchdown[k, j]
                    continue
                for obstacle, liftoff_side in sides:
                    along = obstacle.local(position[j])[0]  # along the depth axis from the centre [m]
                    if abs(along) > 0.5 * obstacle.depth and np.sign(along) == -liftoff_side:
                        passed[k, j] = True
        return passed

    def _clearance(self, crossings, swinging: np.ndarray, phase: np.ndarray, touchdown: np.ndarray,
                   columns: list[int]) -> tuple[np.ndarray, np.ndarray | None]:
        """Write the clearance terms of ``crossings`` and return the swing height references (n + 1, n_feet)
        [m] above the ground of the crossing swings' nodes, NaN at every other node (eq. 19 there), and the
        soles' outward roll references (n + 1, n_feet) [rad] (0 where flat; None without
        ``obstacle_swing_roll``).

        For each crossing swing (a run of swing nodes of one foot over one obstacle) the foot's path position
        is :func:`swing_path` (lift-off -> the schedule's ``touchdown`` (n + 1, n_feet, 2) [m], in the OCP's
        foot order, timed by ``obstacle_swing_path_timing``); there
        ``{foot}_swing_path`` (when present) is active with that (x, y) reference. Each sole point p_i's path
        position (the foot's plus p_i turned by the touchdown yaw) is over the footprint grown by
        ``obstacle_footprint_margin`` at some nodes: there ``{foot}_clearance_sole{i}`` is active with the
        reference top + ``obstacle_clearance_margin``; ``{foot}_clearance_shank`` is active over the whole
        crossing swing with top + ``obstacle_shank_margin`` (with ``obstacle_shank_gating`` "profile" on the box's
        profile at the knee's position). The height reference
        (``obstacle_swing_profile``): "plateau", :func:`plateau_height_reference` at H = the largest of
        ``swing_apex_height`` and top + ``obstacle_apex_margin``, at most ``obstacle_apex_height_max``, its
        rise over until the first sole point's path enters the grown footprint and its fall begun
        only once the last has left it (:meth:`_plateau_phases`); "apex", eq. (19) with that H raised until
        the profile is at the clearance reference at the first and the last gated node (same cap). World
        z = 0 is the ground the obstacles stand on. Over an obstacle at least ``obstacle_abduction_height_min`` high
        the path is moved outwards by ``obstacle_swing_abduction`` and the sole rolled by ``obstacle_swing_roll``,
        each times the height reference over H (:meth:`_abduct`)."""
        cfg = self.config
        index = np.asarray(crossings.index)[:, columns]
        liftoff = np.asarray(crossings.liftoff_xy, dtype=float)[:, columns]
        timing = cfg.obstacle_swing_path_timing
        path = swing_path(liftoff, touchdown, phase, timing)
        path_yaw = np.nan_to_num(np.asarray(crossings.path_yaw, dtype=float)[:, columns])
        if index.shape != swinging.shape:
            raise ParameterError(f"crossings.index has shape {index.shape}, the schedule {swinging.shape}")
        heights = np.full(swinging.shape, np.nan)
        rolls = np.zeros(swinging.shape) if cfg.obstacle_swing_roll > 0 else None
        terms = self._clearance_terms
        points = np.asarray(cfg.obstacle_sole_points, dtype=float).reshape(-1, 3)
        n_running = self.n_nodes
        cap = max(float(cfg.obstacle_apex_height_max), float(cfg.swing_apex_height))
        for j in range(swinging.shape[1]):
            k = 0
            while k < swinging.shape[0]:
                if not (swinging[k, j] and index[k, j] >= 0):
                    k += 1
                    continue
                start, which = k, index[k, j]
                while k < swinging.shape[0] and swinging[k, j] and index[k, j] == which:
                    k += 1
                obstacle = crossings.obstacles[which]
                region = obstacle.grown(cfg.obstacle_footprint_margin)
                nodes = np.arange(start, k)
                gated = np.column_stack([region.contains(_turned_points(path[nodes, j], path_yaw[nodes, j], point))
                                         for point in points]) if points.size else np.zeros((nodes.size, 0), bool)
                top = float(obstacle.height)
                height = max(float(cfg.swing_apex_height), top + cfg.obstacle_apex_margin - self.ground_height)
                over = np.flatnonzero(gated.any(axis=1))
                s = phase[nodes, j]
                if cfg.obstacle_swing_profile == "plateau":
                    breaks = self._plateau_phases(region, liftoff[start, j], touchdown[start, j], timing,
                                                  path_yaw[start, j], points, cfg.obstacle_plateau_transition_min)
                    if breaks is None:
                        heights[nodes, j] = swing_height_reference(s, min(height, cap))
                    else:
                        heights[nodes, j] = plateau_height_reference(s, min(height, cap), *breaks)
                else:
                    if over.size:
                        need = top + cfg.obstacle_clearance_margin - self.ground_height
                        edge = float(np.min(swing_height_reference(s[[over[0], over[-1]]], 1.0)))
                        height = max(height, need / edge if edge > 0 else np.inf)
                    heights[nodes, j] = swing_height_reference(s, min(height, cap))
                if top >= cfg.obstacle_abduction_height_min and min(height, cap) > 0:
                    self._abduct(path, rolls, nodes, j, heights[nodes, j] / min(height, cap), path_yaw[nodes, j])
                for row, node in enumerate(nodes.tolist()):
                    if node >= n_running:
                        continue
                    if self._swing_path_terms is not None and cfg.obstacle_swing_path_weight > 0:
                        tracking = self._swing_path_terms[node][j]
                        tracking.active = True
                        if tracking.weight != cfg.obstacle_swing_path_weight:
                            tracking.weight = cfg.obstacle_swing_path_weight
                        tracking.cost.residual.reference[:2] = path[node, j]
                    if terms is None:
                        continue
                    soles, shank = terms[node][j]
                    for i, item in enumerate(soles):
                        if cfg.obstacle_clearance_gating == "profile":  # wherever the point is: the box's profile
                            self._hold_on_profile(item, obstacle, cfg.obstacle_clearance_margin)
                        else:
                            item.active = bool(gated[row, i])
                            item.cost.residual.reference = top + cfg.obstacle_clearance_margin
                    if shank is not None:
                        if cfg.obstacle_shank_gating == "profile":  # wherever the knee is: the box's profile
                            self._hold_on_profile(shank, obstacle, cfg.obstacle_shank_margin)
                        else:
                            shank.active = True
                            shank.cost.residual.reference = top + cfg.obstacle_shank_margin
            if terms is not None and cfg.obstacle_clearance_legs == "all":
                self._clearance_beside(crossings.obstacles, swinging[:, j], index[:, j] < 0, touchdown[:, j],
                                       [node[j] for node in terms])
        return heights, rolls

    def _abduct(self, path: np.ndarray, rolls: np.ndarray | None, nodes: np.ndarray, foot: int, profile: np.ndarray,
                yaw: np.ndarray) -> None:
        """Move foot ``foot``'s path ``path`` (n + 1, n_feet, 2) [m] outwards at ``nodes`` by ``obstacle_swing_abduction``
        times ``profile`` (the normalised height reference, in [0, 1], per node), across the path's heading
        ``yaw`` (per node) [rad], and write ``obstacle_swing_roll`` times ``profile`` outwards into ``rolls``
        (n + 1, n_feet) [rad] (when not None). Outwards is the foot's side, :attr:`foot_sides`."""
        cfg, side = self.config, self.foot_sides[foot]
        if cfg.obstacle_swing_abduction > 0:
            offset = side * cfg.obstacle_swing_abduction * profile
            path[nodes, foot, 0] -= offset * np.sin(yaw)
            path[nodes, foot, 1] += offset * np.cos(yaw)
        if rolls is not None:
            rolls[nodes, foot] = side * cfg.obstacle_swing_roll * profile

    def _clearance_beside(self, obstacles, swinging: np.ndarray, free: np.ndarray, position: np.ndarray,
                          terms) -> None:
        """``obstacle_clearance_legs`` "all": one foot's clearance terms ``terms`` ((soles, shank) per running node) on
        the "profile" of the obstacle of ``obstacles`` whose centre is nearest the foot's schedule position
        ``position`` (n + 1, 2) [m] (the first obstacle where that is unknown), at the running nodes ``free`` (n + 1,)
        of no crossing swing: the soles and the knee where ``swinging`` (n + 1,), the knee alone where the foot
        stands."""
        cfg = self.config
        centers = np.array([obstacle.center for obstacle in obstacles], dtype=float).reshape(-1, 2)
        for node in np.flatnonzero(free[:self.n_nodes]).tolist():
            where = position[node]
            nearest = int(np.argmin(np.linalg.norm(centers - where, axis=1))) if np.all(np.isfinite(where)) else 0
            obstacle = obstacles[nearest]
            soles, shank = terms[node]
            for item in soles if swinging[node] else ():
                self._hold_on_profile(item, obstacle, cfg.obstacle_clearance_margin)
            if shank is not None:
                self._hold_on_profile(shank, obstacle, cfg.obstacle_shank_margin)

    def _hold_on_profile(self, item, obstacle, margin: float) -> None:
        """Turn on the clearance term ``item`` (a :class:`~wbmpc.ocp.residuals.ResidualFramePointAboveBox` barrier) on
        ``obstacle``'s height profile, its top + ``margin`` [m] above the ground."""
        item.active = True
        item.cost.residual.set_box(obstacle.center, obstacle.axes[0], 0.5 * obstacle.depth, 0.5 * obstacle.width,
                                   float(obstacle.height) + margin - self.ground_height)

    def _clearance_residual(self, frame_id: int, point, profile: bool):
        """The residual of a clearance term on ``point`` (3,) [m] of frame ``frame_id``: on a box's height profile
        (``profile``, :class:`~wbmpc.ocp.residuals.ResidualFramePointAboveBox`) or a height reference
        (:class:`~wbmpc.ocp.residuals.ResidualFramePointHeight`)."""
        state, nu, cfg = self.state, self.nu, self.config
        if profile:
            return ResidualFramePointAboveBox(state, frame_id, point, nu, cfg.obstacle_footprint_margin,
                                              cfg.obstacle_profile_transition, self.ground_height)
        return ResidualFramePointHeight(state, frame_id, point, 0.0, nu)

    @staticmethod
    def _plateau_phases(region, liftoff_xy: np.ndarray, touchdown_xy: np.ndarray, timing: str, yaw: float,
                        points: np.ndarray, transition: float) -> tuple[float, float] | None:
        """Breakpoints (rise_end, fall_start) of a crossing swing's :func:`plateau_height_reference`, or None
        when no sole point's path meets ``region`` (the grown footprint).

        The foot's path from ``liftoff_xy`` to ``touchdown_xy`` (2,) [m] (:func:`swing_path` with ``timing``)
        is sampled at :data:`PLATEAU_SAMPLES` phases; rise_end is the last sample before any of the ``points``
        (n, 3) [m] (foot frame, turned by ``yaw`` [rad]) is in ``region``, fall_start the first after all have
        left it. Both are kept within [transition, 1 − transition] (``transition`` in (0, 0.5]: a rise and a
        fall of at least that fraction of the swing)."""
        grid = np.linspace(0.0, 1.0, PLATEAU_SAMPLES)
        centre = swing_path(liftoff_xy, touchdown_xy, grid, timing)
        inside = np.zeros(grid.size, dtype=bool)
        for point in points:
            inside |= region.contains(_turned_points(centre, np.full(grid.size, yaw), point))
        hit = np.flatnonzero(inside)
        if not hit.size:
            return None
        rise_end, fall_start = grid[max(hit[0] - 1, 0)], grid[min(hit[-1] + 1, grid.size - 1)]
        low, high = float(transition), 1.0 - float(transition)
        rise_end = float(np.clip(rise_end, low, high))
        return rise_end, float(np.clip(fall_start, rise_end, high))

    def _set_node_spacing(self, spacing) -> None:
        """Give running node k the spacing ``spacing[k]`` [s] (a timed schedule), or ``dt`` (None)."""
        if spacing is None:
            if self._timed:
                for model in self.problem.running_models:
                    model.dt = self.dt
                self._timed = False
            return
        spacing = np.asarray(spacing, dtype=float)
        if spacing.shape != (self.n_nodes,) or not np.all(np.isfinite(spacing) & (spacing > 0)):
            raise ParameterError(f"schedule node_spacing must be ({self.n_nodes},) finite and > 0, got {spacing}")
        if self.evaluation == "batched":
            raise ParameterError("a schedule with node_spacing (timed phases) needs evaluation='nodes' "
                                 "(the batched problem holds one spacing per node from its construction)")
        for model, h in zip(self.problem.running_models, spacing.tolist()):
            model.dt = h
        self._timed = True


def quasi_static_controls(ocp: WalkingOCP, x: np.ndarray, node: int = 0) -> np.ndarray:
    """Torques (nu,) [N·m] holding the configuration of x still on the stance feet of running node
    ``node`` (default 0): the torques of :func:`quasi_static_load`."""
    return quasi_static_load(ocp, x, node)[0]


def quasi_static_load(ocp: WalkingOCP, x: np.ndarray, node: int = 0) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Torques (nu,) [N·m] and contact wrenches holding the configuration of x still on the stance
    feet of running node ``node`` (default 0).

    Solves S^T tau + sum_c J_c^T f_c = g(q) (g the generalised gravity, S the actuated rows) for
    the torques and contact wrenches of least weighted norm, sum_i (tau_i / tau_max_i)^2 + sum_c
    sum_k (f_ck / s_k)^2 with s_k = m g for a force and m g times the sole's half size for a flat
    foot's moment (:func:`contact_wrench_scales`): where the contacts leave freedom (a humanoid's
    two flat feet: 12 wrench components for 6 base equations) the load goes to the contacts, the
    torques stay within the robot's limits and each sole's centre of pressure stays near its
    centre (the moment that puts it at the sole's edge costs as much as the whole weight; with
    moments scaled like forces the H1 got ±12.5 N·m of roll per sole, a centre of pressure 5 cm
    outside its 2 cm wide sole). With as many unknowns as equations (Bolt's two point feet, a
    single flat stance foot) it is the exact solution, whatever the weights.

    Returns:
        (torques (nu,) [N·m], stance foot -> its contact's force (3,) [N], world-aligned, for a
        point foot, or wrench (6,) (force [N], moment [N·m]) in the sole frame for a flat foot).
    """
    model = ocp.state.pinocchio
    pdata = model.createData()
    q = x[: model.nq]
    gravity = pin.computeGeneralizedGravity(model, pdata, q)
    pin.computeJointJacobians(model, pdata, q)
    pin.updateFramePlacements(model, pdata)
    dam = ocp.problem.running_models[node].differential
    columns = [np.vstack([np.zeros((6, ocp.nu)), np.eye(ocp.nu)])]
    scales = [ocp.torque_limit]
    wrench_scale = contact_wrench_scales(ocp.mass * GRAVITY, ocp.robot.sole_size)
    rows, row = {}, ocp.nu
    for name in dam.active_contacts:
        contact = dam.contacts[name]
        J = pin.getFrameJacobian(model, pdata, contact.frame_id, pin.LOCAL_WORLD_ALIGNED if contact.nc == 3 else pin.LOCAL)
        columns.append(J[: contact.nc].T)
        scales.append(wrench_scale[: contact.nc])
        rows[name] = slice(row, row + contact.nc)
        row += contact.nc
    scale = np.concatenate(scales)
    A = np.hstack(columns) * scale  # unknowns in units of their scale
    solution = scale * (np.linalg.pinv(A) @ gravity)
    return solution[: ocp.nu], {name: solution[r] for name, r in rows.items()}


def contact_wrench_scales(weight: float, sole_size=None) -> np.ndarray:
    """Scales (6,) of a contact wrench (f [N], m [N·m]) in the sole frame for
    :func:`quasi_static_controls`: ``weight`` [N] for the forces; for the moments about the
    sole's x (roll), y (pitch) and z (yaw) axes ``weight`` times the sole's lever arm about that
    axis (:func:`wbmpc.ocp.contacts.sole_lever_arms`: half the width, half the length, half the
    diagonal), the moment that moves the centre of pressure of that load to the sole's edge.
    ``sole_size`` (length, width) [m] along the sole frame's x and y; None (point feet, or a
    robot without a sole rectangle): ``weight`` for every component."""
    if sole_size is None:
        return np.full(6, float(weight))
    return float(weight) * np.concatenate([np.ones(3), sole_lever_arms(sole_size)])
