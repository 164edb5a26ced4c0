"""Rigid contact models with Baumgarte stabilisation (Crocoddyl's ContactModel3D / ContactModel6D).

A contact constrains the acceleration of a frame: Jc a + a0 = 0 with the drift

    a0 = a_frame(q, v, a = 0) + Kp · e_position + Kd · v_frame

(the Baumgarte gains Kp [1/s²] and Kd [1/s] pull a drifting contact back to its reference).

- :class:`ContactModel3D` — point foot (Bolt). Expressed in the LOCAL_WORLD_ALIGNED frame: the
  force (3,) [N] is in the world axes at the foot, so friction cones use the world normal.
  e_position = R_frameᵀ (p_frame − p_ref) taken in the local frame, as Crocoddyl does.
- :class:`ContactModel6D` — flat foot (humanoids). Expressed in the LOCAL frame: the wrench (6,)
  [N, N·m] = (force, torque) in the foot frame; e_position = log6(ref⁻¹ · oMf).

Contacts of a node are kept sorted by name (Crocoddyl stores them in a std::map), so rows of the
stacked contact Jacobian and force vector follow the alphabetical order of contact names.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.contact import (
    contact3d_calc,
    contact3d_drift_derivative,
    contact3d_force_terms,
    contact6d_drift,
    contact6d_drift_derivative,
)
from wbmpc.ocp.kernels.tree import KinematicTree, frame_acceleration_derivatives, frame_motion
from wbmpc.ocp.state import StateMultibody

_ZERO3 = np.zeros(3)


class ContactData:
    """Buffers of one contact: Jc (nc, nv), a0 (nc,), da0_dx (nc, ndx), force (nc,), df_dx, df_du."""

    def __init__(self, model, nu: int):
        nv, ndx, nc = model.state.nv, model.state.ndx, model.nc
        self.Jc = np.zeros((nc, nv))
        self.a0 = np.zeros(nc)
        self.da0_dx = np.zeros((nc, ndx))
        self.force = np.zeros(nc)
        self.df_dx = np.zeros((nc, ndx))
        self.df_du = np.zeros((nc, nu))
        self.fext = pin.Force.Zero()
        self.fext_vector = np.zeros(6)
        self.dtau_dq = None  # (nv, nv) extra RNEA derivative of a world-aligned force, or None
        self.fJf = np.zeros((6, nv))  # frame Jacobian, LOCAL
        self.oRf = np.eye(3)  # frame placement (world)
        self.opf = np.zeros(3)
        self.velocity = np.zeros(6)  # frame velocity (linear, angular), LOCAL
        self.acceleration = np.zeros(6)  # frame spatial acceleration, LOCAL
        self.v_dq = np.zeros((6, nv))  # ∂velocity/∂q, ∂acceleration/∂q and ∂acceleration/∂v (LOCAL)
        self.a_dq = np.zeros((6, nv))
        self.a_dv = np.zeros((6, nv))
        self.position_error_local = np.zeros(3)
        self.rMf = pin.SE3.Identity()


class _ContactBase:
    def __init__(self, state: StateMultibody, frame_id: int, gains: tuple[float, float]):
        model = state.pinocchio
        if not (0 <= frame_id < model.nframes):
            raise ParameterError(f"frame_id={frame_id} is not a frame of model {model.name!r} (0..{model.nframes - 1})")
        kp, kd = (float(g) for g in gains)
        if not (np.isfinite(kp) and np.isfinite(kd) and kp >= 0 and kd >= 0):
            raise ParameterError(f"Baumgarte gains={gains} must be finite and >= 0 (Kp [1/s^2], Kd [1/s])")
        self.state = state
        self.frame_id = int(frame_id)
        self.joint_id = model.frames[frame_id].parentJoint
        self.joint_placement_frame = model.frames[frame_id].placement  # jMf
        self._jRf = self.joint_placement_frame.rotation.copy()
        self._jpf = self.joint_placement_frame.translation.copy()
        self.gains = (kp, kd)

    def _frame_motion(self, data: ContactData, tree: KinematicTree) -> None:
        """The frame's placement, LOCAL Jacobian, velocity and spatial acceleration from ``tree``."""
        frame_motion(self.joint_id, self._jRf, self._jpf, tree.parents, tree.idx_v, tree.R, tree.p, tree.ov, tree.oa,
                     tree.J, data.oRf, data.opf, data.fJf, data.velocity, data.acceleration)

    def _frame_derivatives(self, data: ContactData, tree: KinematicTree) -> None:
        """∂velocity/∂q, ∂acceleration/∂q and ∂acceleration/∂v of the frame (LOCAL) from ``tree``
        evaluated at the solved accelerations (and the placement :meth:`_frame_motion` stored)."""
        frame_acceleration_derivatives(self.joint_id, data.oRf, data.opf, tree.parents, tree.idx_v, tree.ov, tree.oa,
                                       tree.J, data.v_dq, data.a_dq, data.a_dv)

    def createData(self, nu: int) -> ContactData:
        return ContactData(self, nu)


class ContactModel3D(_ContactBase):
    """Point contact on a frame, LOCAL_WORLD_ALIGNED.

    Args:
        state: the multibody state.
        frame_id: Pinocchio frame index of the foot.
        reference_world: contact point reference (3,) [m] used by the Kp term; mutable.
        gains: Baumgarte (Kp [1/s²], Kd [1/s]).
    """

    nc = 3

    def __init__(self, state: StateMultibody, frame_id: int, reference_world: np.ndarray, gains=(0.0, 0.0)):
        super().__init__(state, frame_id, gains)
        self.reference = np.asarray(reference_world, dtype=float).reshape(3).copy()

    def calc(self, data: ContactData, tree: KinematicTree) -> None:
        """Fill Jc (3, nv) and a0 (3,) from the tree kinematics at (q, v, a = 0)."""
        self._frame_motion(data, tree)
        contact3d_calc(data.fJf, data.oRf, data.opf, data.velocity, data.acceleration, self.reference, *self.gains,
                       data.Jc, data.a0)

    def calcDiff(self, data: ContactData, tree: KinematicTree) -> None:
        """Fill da0_dx (3, ndx) from the tree kinematics at the solved accelerations (after :meth:`calc`)."""
        self._frame_derivatives(data, tree)
        kp, kd = self.gains
        if kp != 0.0:
            data.position_error_local[:] = data.oRf.T @ (data.opf - self.reference)
        # The rotation term of ∂(oRf a0_local)/∂q multiplies a0_local evaluated at the solved
        # accelerations, J a + drift + Baumgarte = 0 for an enforced contact (Crocoddyl evaluates
        # it numerically, ~1e-15): it vanishes.
        contact3d_drift_derivative(data.v_dq, data.a_dq, data.a_dv, data.fJf, data.velocity[:3], data.velocity[3:],
                                   data.position_error_local, _ZERO3, data.oRf, kp, kd, data.da0_dx)

    def update_force(self, data: ContactData, force: np.ndarray) -> None:
        """Store the contact force (3,) [N, world axes] (from calc)."""
        data.force[:] = force

    def rigid_constraint_model(self) -> pin.RigidConstraintModel:
        """The same constraint as a Pinocchio RigidConstraintModel (CONTACT_3D, LOCAL_WORLD_ALIGNED,
        same Baumgarte gains, reference point on the universe)."""
        frame = self.state.pinocchio.frames[self.frame_id]
        constraint = pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, self.state.pinocchio, frame.parentJoint,
                                              frame.placement, 0, pin.SE3(np.eye(3), self.reference),
                                              pin.LOCAL_WORLD_ALIGNED)
        constraint.setBaumgarteCorrectorParameters(pin.BaumgarteCorrectorParameters(*self.gains))
        return constraint

    def reference_placement(self) -> pin.SE3:
        """Placement of the reference point (identity rotation), for the Baumgarte position term."""
        return pin.SE3(np.eye(3), self.reference)

    def force_derivative_terms(self, data: ContactData) -> None:
        """Frame Jacobian (LOCAL), external force on the parent joint and its RNEA derivative term.

        Called by the dynamics' calcDiff before the RNEA derivatives (and before :meth:`calcDiff`), after
        :meth:`calc` at the same configuration (its frame Jacobian and placement).
        """
        if data.dtau_dq is None:
            data.dtau_dq = np.zeros((self.state.nv, self.state.nv))
        contact3d_force_terms(data.fJf, data.oRf, data.force, self._jRf, self._jpf, data.fext_vector, data.dtau_dq)
        data.fext = pin.Force(data.fext_vector)


class ContactModel6D(_ContactBase):
    """Flat (6D) contact on a frame, LOCAL.

    Args:
        state: the multibody state.
        frame_id: Pinocchio frame index of the sole.
        reference_placement: reference placement of the sole (pin.SE3) used by the Kp term.
        gains: Baumgarte (Kp [1/s²], Kd [1/s]).
    """

    nc = 6

    def __init__(self, state: StateMultibody, frame_id: int, reference_placement: pin.SE3, gains=(0.0, 0.0)):
        super().__init__(state, frame_id, gains)
        self.reference = pin.SE3(reference_placement)

    def calc(self, data: ContactData, tree: KinematicTree, corners: "SoleCorners | None" = None) -> None:
        """Jc (6, nv) and a0 (6,) from the tree kinematics at (q, v, a = 0); with ``corners`` the drift is
        that of the sole as four corner point contacts, a0 + δ (:class:`SoleCorners`)."""
        self._frame_motion(data, tree)
        kp, kd = self.gains
        data.Jc[:] = data.fJf
        if corners is None:
            contact6d_drift(data.velocity, data.acceleration, kd, _ZERO3, _ZERO3, False, data.a0)
        else:
            contact6d_drift(data.velocity, data.acceleration, kd, corners.spread_diagonal, corners.inverse_arms, True,
                            data.a0)
        if kp != 0.0:
            data.rMf = self.reference.actInv(pin.SE3(data.oRf, data.opf))
            data.a0 += kp * pin.log6(data.rMf).vector

    def calcDiff(self, data: ContactData, tree: KinematicTree, corners: "SoleCorners | None" = None) -> None:
        """da0_dx (6, ndx) from the tree kinematics at the solved accelerations, after :meth:`calc` (with the
        same ``corners``)."""
        self._frame_derivatives(data, tree)
        kp, kd = self.gains
        if corners is None:
            contact6d_drift_derivative(data.v_dq, data.a_dq, data.a_dv, data.fJf, data.velocity, kd, _ZERO3, _ZERO3,
                                       False, data.da0_dx)
        else:
            contact6d_drift_derivative(data.v_dq, data.a_dq, data.a_dv, data.fJf, data.velocity, kd,
                                       corners.spread_diagonal, corners.inverse_arms, True, data.da0_dx)
        if kp != 0.0:
            data.da0_dx[:, :self.state.nv] += kp * pin.Jlog6(data.rMf) @ data.fJf

    def update_force(self, data: ContactData, force: np.ndarray) -> None:
        """Store the contact wrench (6,) = (force [N], torque [N·m]) in the LOCAL sole frame."""
        data.force[:] = force

    def rigid_constraint_model(self) -> pin.RigidConstraintModel:
        """The same constraint as a Pinocchio RigidConstraintModel (CONTACT_6D, LOCAL, same
        Baumgarte gains, reference placement on the universe)."""
        frame = self.state.pinocchio.frames[self.frame_id]
        constraint = pin.RigidConstraintModel(pin.ContactType.CONTACT_6D, self.state.pinocchio, frame.parentJoint,
                                              frame.placement, 0, pin.SE3(self.reference), pin.LOCAL)
        constraint.setBaumgarteCorrectorParameters(pin.BaumgarteCorrectorParameters(*self.gains))
        return constraint

    def reference_placement(self) -> pin.SE3:
        return pin.SE3(self.reference)

    def force_derivative_terms(self, data: ContactData) -> None:
        """External force on the parent joint (a LOCAL wrench adds no RNEA derivative term)."""
        data.fext = self.joint_placement_frame.act(pin.Force(data.force))
        data.dtau_dq = None


class SoleCorners:
    """A rectangular sole as four point contacts at its corners, each damped by 4 μ: the model of
    the "sole" contact damping (:mod:`wbmpc.ocp.dynamics`), in the two forms its backends solve.

    For lever arms r = (b, a, √(a² + b²)) [m] (half width, half length, half diagonal:
    :func:`sole_lever_arms`) the corners are c_i = (±a, ±b, 0) in the sole frame (centred on it).
    Corner i's velocity is v + ω × c_i = G_i (v, ω) with G_i = [I, −[c_i]×] (the sole's LOCAL
    velocity (v, ω)), and the sole's wrench is W = Σ G_iᵀ f_i = ``force_map`` · (f_1, ..., f_4),
    each f_i [N] in the corner's LOCAL frame (the sole's axes). Since Σ G_iᵀ G_i =
    4 diag(1, 1, 1, r²), the four corner contacts damped by 4 μ, solved for W, are exactly the
    sole's 6D contact damped by μ S⁻² (S = diag(1, 1, 1, r)) whose drift gains

        δ(v, ω) = (ω × v, diag(1/b², 1/a², 1/(a² + b²)) ((diag(a², b², 0) ω) × ω)),

    the part of the corners' classical accelerations (ω × v_ci) that a spatial 6D drift lacks
    (zero for a sole at rest). Pinocchio's ``constraintDynamics`` takes the corners
    (:meth:`constraint_models`, one μ for every row: 4 μ), the KKT backend the scaled 6D contact
    with δ (:func:`~wbmpc.ocp.kernels.contact.contact6d_drift` and its derivative, from
    ``spread_diagonal`` and ``inverse_arms``): same results to ~1e-13 (tests).

    Args:
        lever_arms: (3,) [m], > 0, the third the hypotenuse of the first two.
    """

    def __init__(self, lever_arms):
        r = np.asarray(lever_arms, dtype=float).reshape(-1)
        if r.shape != (3,) or not np.all(np.isfinite(r) & (r > 0)):
            raise ParameterError(f"lever_arms={np.asarray(lever_arms).tolist()} must be 3 finite lever arms > 0 [m]")
        if abs(r[2] - np.hypot(r[0], r[1])) > 1e-9 * r[2]:
            raise ParameterError(f"lever_arms={r.tolist()} are not a rectangle's (half width b, half length a, "
                                 f"half diagonal sqrt(a^2 + b^2) = {np.hypot(r[0], r[1])})")
        b, a = r[0], r[1]
        self.lever_arms = r
        #: (4, 3) [m] corner positions in the sole frame
        self.offsets = np.array([[a, b, 0.0], [a, -b, 0.0], [-a, b, 0.0], [-a, -b, 0.0]])
        #: (6, 12): the sole wrench (force, torque) from the four corner forces
        self.force_map = np.zeros((6, 12))
        for i, c in enumerate(self.offsets):
            self.force_map[:3, 3 * i:3 * i + 3] = np.eye(3)
            self.force_map[3:, 3 * i:3 * i + 3] = pin.skew(c)
        #: diag(a², b², 0) = Σ c_i c_iᵀ / 4 and diag(1/b², 1/a², 1/(a² + b²)), as (3,) arrays
        self.spread_diagonal = np.array([a * a, b * b, 0.0])
        self.inverse_arms = 1.0 / (r * r)

    def constraint_models(self, contact: "ContactModel6D") -> list[pin.RigidConstraintModel]:
        """Pinocchio's four CONTACT_3D LOCAL constraints of ``contact``'s corners, with its Kd
        (its Kp must be 0: a corner's position error is not the sole's log6)."""
        kp, kd = contact.gains
        if kp != 0.0:
            raise ParameterError(f"Baumgarte Kp={kp} of the sole on frame {contact.frame_id}: the four corner "
                                 "contacts need Kp = 0 (a corner's position error is not the sole's log6)")
        model = contact.state.pinocchio
        frame = model.frames[contact.frame_id]
        constraints = []
        for c in self.offsets:
            corner = pin.SE3(np.eye(3), c)
            constraint = pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, frame.parentJoint,
                                                  frame.placement * corner, 0, contact.reference * corner, pin.LOCAL)
            constraint.setBaumgarteCorrectorParameters(pin.BaumgarteCorrectorParameters(0.0, kd))
            constraints.append(constraint)
        return constraints


def sole_lever_arms(sole_size) -> np.ndarray:
    """Lever arms (3,) [m] of a rectangular sole about its frame's x (roll), y (pitch) and z (yaw)
    axes: half the width, half the length and half the diagonal, for ``sole_size`` (length along
    the sole frame's x, width along its y) [m].

    A wrench (f, m) spread over the sole's four corners with the least sum of squared corner
    forces weighs m by exactly these arms: the corner forces' Gram matrix is
    4 diag(1, 1, 1, r_roll², r_pitch², r_yaw²). The quasi-static load split and the "sole"
    contact damping use them.
    """
    length, width = (float(v) for v in sole_size)
    if not (np.isfinite(length) and np.isfinite(width) and length > 0 and width > 0):
        raise ParameterError(f"sole_size={tuple(sole_size)} must be (length > 0, width > 0) [m]")
    return np.array([0.5 * width, 0.5 * length, 0.5 * np.hypot(length, width)])
