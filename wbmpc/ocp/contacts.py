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
from wbmpc.ocp.kernels.contact import contact_set_calc, contact_set_derivatives
from wbmpc.ocp.kernels.tree import KinematicTree
from wbmpc.ocp.state import StateMultibody


class ContactData:
    """What a contact's node data holds for the costs: its force (nc,) (world-aligned [N] for a point
    contact, the LOCAL wrench [N, N·m] for a 6D one) and the derivatives df_dx (nc, ndx), df_du (nc, nu)."""

    def __init__(self, model, nu: int):
        ndx, nc = model.state.ndx, model.nc
        self.force = np.zeros(nc)
        self.df_dx = np.zeros((nc, ndx))
        self.df_du = np.zeros((nc, nu))


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


class ContactSet:
    """The active contacts of a node as arrays for the compiled kernels of the KKT backend
    (:func:`~wbmpc.ocp.kernels.contact.contact_set_calc`, :func:`~wbmpc.ocp.kernels.contact.contact_set_derivatives`):
    per contact, in the node's (alphabetical) order, its kind (3 or 6 rows), parent joint, frame placement
    in it, Baumgarte gains, point reference (3D), sole-corner drift (6D, the "corners" damping) and first
    stacked row.

    Args:
        contacts: (name, contact model) of the active contacts, in order.
        corners: name -> :class:`SoleCorners` of the soles whose drift is the corners' (else absent).
    """

    def __init__(self, contacts: list, corners: dict):
        k = len(contacts)
        self.names = [name for name, _ in contacts]
        self.models = [contact for _, contact in contacts]
        self.kinds = np.array([contact.nc for contact in self.models], dtype=np.int64)
        self.rows = np.concatenate([[0], np.cumsum(self.kinds)]).astype(np.int64)
        self.joints = np.array([contact.joint_id for contact in self.models], dtype=np.int64)
        self.joint_ids = [int(j) for j in self.joints]  # as Python ints (Pinocchio's vectors index by them)
        self.frame_rotations = np.array([contact._jRf for contact in self.models]).reshape(k, 3, 3)
        self.frame_translations = np.array([contact._jpf for contact in self.models]).reshape(k, 3)
        self.kp = np.array([contact.gains[0] for contact in self.models])
        self.kd = np.array([contact.gains[1] for contact in self.models])
        self.references = np.zeros((k, 3))  # the point contacts' Kp references, refreshed per evaluation
        self.corners = np.array([name in corners for name in self.names], dtype=np.bool_)
        self.spreads = np.array([corners[name].spread_diagonal if name in corners else np.zeros(3)
                                 for name in self.names]).reshape(k, 3)
        self.inverse_arms = np.array([corners[name].inverse_arms if name in corners else np.zeros(3)
                                      for name in self.names]).reshape(k, 3)
        #: the point contacts with Kp > 0 (their reference is read at every evaluation) and the 6D ones
        #: (their Kp term, Kp log6(ref⁻¹ oMf), is added outside the kernels)
        self._moving_points = [c for c, contact in enumerate(self.models) if contact.nc == 3 and contact.gains[0] != 0.0]
        self._positioned_soles = [c for c, contact in enumerate(self.models)
                                  if contact.nc == 6 and contact.gains[0] != 0.0]
        #: True when a 6D contact has Kp > 0: its Kp term is added between the contacts' calc and the
        #: KKT solve, so the node cannot take the one-call :func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_dynamics`
        self.has_positioned_soles = bool(self._positioned_soles)
        #: True when a point contact has Kp > 0: :meth:`refresh_references` has something to read
        self.has_moving_references = bool(self._moving_points)
        #: the contact arrays of the kernels (kinds ... inverse_arms), in their argument order
        self.kernel_arguments = (self.kinds, self.joints, self.frame_rotations, self.frame_translations, self.kp,
                                 self.kd, self.references, self.corners, self.spreads, self.inverse_arms)

    def refresh_references(self) -> None:
        """Read the current reference of every point contact with Kp > 0 (moved between evaluations)."""
        for c in self._moving_points:
            self.references[c] = self.models[c].reference

    def calc(self, tree: KinematicTree, work: "ContactSetWork", q, v, a, Jc, a0) -> None:
        """The stacked Jc (nc, nv) and a0 (nc,) at (q, v, a) (a = 0: the drift); ``work`` keeps the
        contacts' frame kinematics for :meth:`derivatives`."""
        self.refresh_references()
        k = self.kinds.size
        contact_set_calc(q, v, a, tree.parents, tree.placement_rotation, tree.placement_translation, tree.axes,
                         tree.idx_q, tree.idx_v, tree.R, tree.p, tree.ov, tree.oa, tree.J, *self.kernel_arguments,
                         work.oRf[:k], work.opf[:k], work.fJf[:k], work.velocity[:k], work.acceleration[:k], Jc, a0)
        for c in self._positioned_soles:
            rows = slice(self.rows[c], self.rows[c + 1])
            work.rMf[c] = self.models[c].reference.actInv(pin.SE3(work.oRf[c], work.opf[c]))
            a0[rows] += self.kp[c] * pin.log6(work.rMf[c]).vector

    def derivatives(self, tree: KinematicTree, work: "ContactSetWork", v, a, forces, da0_dx) -> bool:
        """After :meth:`calc` at (q, v, 0) (``tree`` and ``work`` as calc left them) and the solve: da0_dx
        (nc, ndx) at fixed a, the contacts' spatial forces on their joints (``work.fext`` (k, 6)) and the point
        forces' RNEA rotation term (``work.dtau_dq_extra`` (nv, nv)); returns True when that term is there (a
        point contact). The tree's accelerations are updated to a."""
        k = self.kinds.size
        extra = contact_set_derivatives(
            v, a, tree.parents, tree.idx_v, tree.ov, tree.oa, tree.J, self.kinds, self.joints, self.frame_rotations,
            self.frame_translations, self.kp, self.kd, self.references, self.corners, self.spreads, self.inverse_arms,
            work.oRf[:k], work.opf[:k], work.fJf[:k], work.velocity[:k], forces, work.v_dq[:k], work.a_dq[:k],
            work.a_dv[:k], da0_dx, work.fext[:k], work.dtau_dq_extra)
        nv = tree.nv
        for c in self._positioned_soles:
            rows = slice(self.rows[c], self.rows[c + 1])
            da0_dx[rows, :nv] += self.kp[c] * pin.Jlog6(work.rMf[c]) @ work.fJf[c]
        return extra


class ContactSetWork:
    """Per-node buffers of :class:`ContactSet` for at most ``n_contacts`` contacts of ``nv`` velocities:
    each contact's frame placement oRf (3, 3), opf (3,), LOCAL Jacobian fJf (6, nv), velocity and
    acceleration (6,), their derivatives v_dq, a_dq, a_dv (6, nv), its spatial force on its joint
    fext (6,), and the point forces' RNEA rotation term dtau_dq_extra (nv, nv)."""

    def __init__(self, n_contacts: int, nv: int):
        k = n_contacts
        self.oRf = np.zeros((k, 3, 3))
        self.opf = np.zeros((k, 3))
        self.fJf = np.zeros((k, 6, nv))
        self.velocity = np.zeros((k, 6))
        self.acceleration = np.zeros((k, 6))
        self.v_dq = np.zeros((k, 6, nv))
        self.a_dq = np.zeros((k, 6, nv))
        self.a_dv = np.zeros((k, 6, nv))
        self.fext = np.zeros((k, 6))
        self.dtau_dq_extra = np.zeros((nv, nv))
        self.rMf = [pin.SE3.Identity() for _ in range(k)]
