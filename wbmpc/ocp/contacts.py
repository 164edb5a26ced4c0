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
from wbmpc.ocp.kernels.contact import contact3d_drift_derivative, contact3d_force_terms
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
        self.fJf = np.zeros((6, nv))
        self.velocity = pin.Motion.Zero()
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
        self.fXj = self.joint_placement_frame.inverse().toActionMatrix()
        self._jRf = self.joint_placement_frame.rotation.copy()
        self._jpf = self.joint_placement_frame.translation.copy()
        self.gains = (kp, kd)

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

    def calc(self, data: ContactData, pdata: pin.Data) -> None:
        """Fill Jc (3, nv) and a0 (3,) from Pinocchio data after computeAllTerms."""
        model = self.state.pinocchio
        fid = self.frame_id
        oMf = pin.updateFramePlacement(model, pdata, fid)
        data.Jc[:] = pin.getFrameJacobian(model, pdata, fid, pin.LOCAL_WORLD_ALIGNED)[:3]
        a0 = pin.getFrameClassicalAcceleration(model, pdata, fid, pin.LOCAL_WORLD_ALIGNED).linear
        kp, kd = self.gains
        if kp != 0.0:
            a0 += kp * (oMf.translation - self.reference)
        if kd != 0.0:
            a0 += kd * pin.getFrameVelocity(model, pdata, fid, pin.LOCAL_WORLD_ALIGNED).linear
        data.a0[:] = a0

    def calcDiff(self, data: ContactData, pdata: pin.Data) -> None:
        """Fill da0_dx (3, ndx). Needs computeRNEADerivatives (kinematic derivatives) first."""
        model = self.state.pinocchio
        fid = self.frame_id
        v_dq, a_dq, a_dv, _ = pin.getJointAccelerationDerivatives(model, pdata, self.joint_id, pin.LOCAL)
        fJf = data.fJf
        velocity = pin.getFrameVelocity(model, pdata, fid, pin.LOCAL)
        oMf = pdata.oMf[fid]
        oRf = oMf.rotation
        kp, kd = self.gains
        if kp != 0.0:
            data.position_error_local[:] = oRf.T @ (oMf.translation - self.reference)
        # The rotation term of ∂(oRf a0_local)/∂q multiplies a0_local evaluated at the solved
        # accelerations, J a + drift + Baumgarte = 0 for an enforced contact (Crocoddyl evaluates
        # it numerically, ~1e-15): it vanishes.
        contact3d_drift_derivative(self.fXj, v_dq, a_dq, a_dv, fJf, velocity.linear, velocity.angular,
                                   data.position_error_local, _ZERO3, oRf, kp, kd, data.da0_dx)

    def update_force(self, data: ContactData, pdata: pin.Data, force: np.ndarray) -> None:
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

    def force_derivative_terms(self, data: ContactData, pdata: pin.Data) -> None:
        """Frame Jacobian (LOCAL), external force on the parent joint and its RNEA derivative term.

        Called by the dynamics' calcDiff before the RNEA derivatives (and before :meth:`calcDiff`).
        """
        data.fJf[:] = pin.getFrameJacobian(self.state.pinocchio, pdata, self.frame_id, pin.LOCAL)
        if data.dtau_dq is None:
            data.dtau_dq = np.zeros((self.state.nv, self.state.nv))
        contact3d_force_terms(data.fJf, pdata.oMf[self.frame_id].rotation, data.force, self._jRf, self._jpf,
                              data.fext_vector, data.dtau_dq)
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

    def calc(self, data: ContactData, pdata: pin.Data) -> None:
        model = self.state.pinocchio
        fid = self.frame_id
        oMf = pin.updateFramePlacement(model, pdata, fid)
        data.fJf[:] = pin.getFrameJacobian(model, pdata, fid, pin.LOCAL)
        a0 = pin.getFrameAcceleration(model, pdata, fid, pin.LOCAL).vector
        kp, kd = self.gains
        if kp != 0.0:
            data.rMf = self.reference.actInv(oMf)
            a0 += kp * pin.log6(data.rMf).vector
        if kd != 0.0:
            data.velocity = pin.getFrameVelocity(model, pdata, fid, pin.LOCAL)
            a0 += kd * data.velocity.vector
        data.Jc[:] = data.fJf
        data.a0[:] = a0

    def calcDiff(self, data: ContactData, pdata: pin.Data) -> None:
        model = self.state.pinocchio
        nv = self.state.nv
        v_dq, a_dq, a_dv, _ = pin.getJointAccelerationDerivatives(model, pdata, self.joint_id, pin.LOCAL)
        fXj = self.fXj
        np.matmul(fXj, a_dq, out=data.da0_dx[:, :nv])
        np.matmul(fXj, a_dv, out=data.da0_dx[:, nv:])
        kp, kd = self.gains
        if kp != 0.0:
            data.da0_dx[:, :nv] += kp * pin.Jlog6(data.rMf) @ data.fJf
        if kd != 0.0:
            data.da0_dx[:, :nv] += kd * fXj @ v_dq
            data.da0_dx[:, nv:] += kd * data.fJf

    def update_force(self, data: ContactData, pdata: pin.Data, force: np.ndarray) -> None:
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

    def force_derivative_terms(self, data: ContactData, pdata: pin.Data) -> None:
        """External force on the parent joint (a LOCAL wrench adds no RNEA derivative term)."""
        data.fext = self.joint_placement_frame.act(pin.Force(data.force))
        data.dtau_dq = None


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
