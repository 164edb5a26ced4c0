"""Compiled kinematics of a kinematic tree at one state (q, v, a): what the contact models of the
KKT contact dynamics read, in one compiled pass instead of a Pinocchio binding call per quantity.

For a free-flyer root followed by revolute joints (:func:`tree_support`), :func:`tree_motion`
computes every joint's world placement (R_i, p_i), world spatial velocity ov_i and acceleration
oa_i (Pinocchio's ``data.oMi``, ``data.ov``, ``data.oa`` after ``forwardKinematics(q, v, a)``) and
the world Jacobian columns S_k (Pinocchio's ``data.J``). Motions are (linear, angular) 6-vectors,
the cross product of motions is (v₁, ω₁) × (v₂, ω₂) = (ω₁ × v₂ + v₁ × ω₂, ω₁ × ω₂), and a placement
(R, p) acts on a motion as (R v + p × R ω, R ω). The recursion, with λ(i) the parent of joint i:

- free flyer (joint 1, velocity v_b and acceleration a_b in its own frame): ov_1 = X_1 v_b,
  oa_1 = X_1 a_b, S_{1,k} = X_1 e_k;
- revolute joint i of axis α_i: S_i = X_i (0, α_i), ov_i = ov_λ + S_i q̇_i,
  oa_i = oa_λ + S_i q̈_i + ov_i × S_i q̇_i.

From these, for a frame f on joint L with placement jMf (:func:`frame_motion`): its placement oMf,
its LOCAL Jacobian X_f⁻¹ [S_k]_{k ∈ support(L)} (6, nv), LOCAL velocity X_f⁻¹ ov_L and LOCAL
spatial acceleration X_f⁻¹ oa_L (Pinocchio's ``getFrameJacobian``, ``getFrameVelocity``,
``getFrameAcceleration`` in LOCAL); and (:func:`frame_acceleration_derivatives`) the derivatives
of that LOCAL velocity and acceleration with respect to q and v (Pinocchio's
``getJointAccelerationDerivatives`` in LOCAL, moved to the frame by jMf), column by column over
the support of L: for a revolute column k of joint j with parent p,

    ∂v_f/∂q_k = X_f⁻¹ (ov_p × S_k),
    ∂a_f/∂q_k = X_f⁻¹ (oa_j × S_k + (ov_p × S_k) × (ov_L − ov_j)),
    ∂a_f/∂v_k = X_f⁻¹ ((2 ov_j − ov_L) × S_k),

and for a free-flyer column (a rigid motion of the whole tree leaves LOCAL quantities unchanged)
∂v_f/∂q_k = ∂a_f/∂q_k = 0, ∂a_f/∂v_k = X_f⁻¹ ((ov_1 − ov_L) × S_k). Agreement with Pinocchio:
~1e-15 (tests/test_wbmpc_tree_kernels.py).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.lie import quaternion_matrix
from wbmpc.ocp.kernels.linalg import mat3_mul, mat3_vec

_AXES = {"JointModelRX": (1.0, 0.0, 0.0), "JointModelRY": (0.0, 1.0, 0.0), "JointModelRZ": (0.0, 0.0, 1.0)}


def tree_support(model: pin.Model) -> str | None:
    """None if the compiled tree kinematics handle ``model`` (a free-flyer root followed by revolute
    joints: RX, RY, RZ, unaligned), else the reason."""
    if model.njoints < 2 or model.joints[1].shortname() != "JointModelFreeFlyer" or model.parents[1] != 0:
        return "the root joint is not a free flyer"
    for i in range(2, model.njoints):
        name = model.joints[i].shortname()
        if name not in _AXES and name != "JointModelRevoluteUnaligned":
            return f"joint {model.names[i]!r} is a {name} (revolute joints only)"
    return None


def require_tree_support(model: pin.Model, user: str) -> None:
    """Raise a ParameterError naming ``model`` and ``user`` (what needs the tree, e.g. "the compiled tree
    kinematics") when :func:`tree_support` refuses the model."""
    reason = tree_support(model)
    if reason is not None:
        raise ParameterError(f"model {model.name!r} is not supported by {user}: {reason}")


class KinematicTree:
    """The kinematic tree of ``model`` as arrays for the kernels, and the state of one evaluation.

    Attributes (n joints, universe included): parents (n,), placement_rotation (n, 3, 3) and
    placement_translation (n, 3) (``model.jointPlacements``), axes (n, 3) (revolute axes in the
    joint frame), idx_q, idx_v (n,); after :meth:`evaluate`: R (n, 3, 3), p (n, 3) world placements,
    ov, oa (n, 6) world spatial velocities and accelerations, J (6, nv) world Jacobian columns.

    Raises:
        ParameterError: the model is not a free-flyer root followed by revolute joints.
    """

    def __init__(self, model: pin.Model):
        require_tree_support(model, "the compiled tree kinematics")
        n = model.njoints
        self.nv = model.nv
        self.parents = np.array([model.parents[i] for i in range(n)], dtype=np.int64)
        self.placement_rotation = np.array([model.jointPlacements[i].rotation for i in range(n)])
        self.placement_translation = np.array([model.jointPlacements[i].translation for i in range(n)])
        self.axes = np.zeros((n, 3))
        for i in range(2, n):
            joint = model.joints[i]
            name = joint.shortname()
            self.axes[i] = _AXES[name] if name in _AXES else np.asarray(joint.extract().axis, dtype=float)
        self.idx_q = np.array([model.idx_qs[i] for i in range(n)], dtype=np.int64)
        self.idx_v = np.array([model.idx_vs[i] for i in range(n)], dtype=np.int64)
        self.R = np.zeros((n, 3, 3))
        self.p = np.zeros((n, 3))
        self.ov = np.zeros((n, 6))
        self.oa = np.zeros((n, 6))
        self.J = np.zeros((6, model.nv))

    def evaluate(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> None:
        """Placements, velocities, accelerations and Jacobian columns at (q (nq,), v (nv,), a (nv,))."""
        tree_motion(q, v, a, self.parents, self.placement_rotation, self.placement_translation, self.axes, self.idx_q,
                    self.idx_v, self.R, self.p, self.ov, self.oa, self.J)


@njit(cache=True, inline="always")
def cross_motion(m1, m2, out):
    """out (6,) = m1 × m2, the cross product of motions (linear, angular)."""
    v0, v1, v2, w0, w1, w2 = m1[0], m1[1], m1[2], m1[3], m1[4], m1[5]
    u0, u1, u2, x0, x1, x2 = m2[0], m2[1], m2[2], m2[3], m2[4], m2[5]
    out[0] = w1 * u2 - w2 * u1 + v1 * x2 - v2 * x1
    out[1] = w2 * u0 - w0 * u2 + v2 * x0 - v0 * x2
    out[2] = w0 * u1 - w1 * u0 + v0 * x1 - v1 * x0
    out[3] = w1 * x2 - w2 * x1
    out[4] = w2 * x0 - w0 * x2
    out[5] = w0 * x1 - w1 * x0


@njit(cache=True, inline="always")
def _act_inverse(R, p, m, out):
    """out (6,) = (R, p)⁻¹ · m: the world motion m in the frame of placement (R, p)."""
    l0 = m[0] - (p[1] * m[5] - p[2] * m[4])
    l1 = m[1] - (p[2] * m[3] - p[0] * m[5])
    l2 = m[2] - (p[0] * m[4] - p[1] * m[3])
    for a in range(3):
        out[a] = R[0, a] * l0 + R[1, a] * l1 + R[2, a] * l2
        out[3 + a] = R[0, a] * m[3] + R[1, a] * m[4] + R[2, a] * m[5]


@njit(cache=True)
def axis_rotation(axis, angle, out):
    """Rotation by ``angle`` [rad] about the unit ``axis`` (Rodrigues)."""
    c, s = np.cos(angle), np.sin(angle)
    x, y, z = axis[0], axis[1], axis[2]
    t = 1.0 - c
    out[0, 0] = c + t * x * x
    out[0, 1] = t * x * y - s * z
    out[0, 2] = t * x * z + s * y
    out[1, 0] = t * x * y + s * z
    out[1, 1] = c + t * y * y
    out[1, 2] = t * y * z - s * x
    out[2, 0] = t * x * z - s * y
    out[2, 1] = t * y * z + s * x
    out[2, 2] = c + t * z * z


@njit(cache=True)
def tree_motion(q, v, a, parents, placement_rotation, placement_translation, axes, idx_q, idx_v, R, p, ov, oa, J):
    """Kernel of :meth:`KinematicTree.evaluate` (the module's recursion; joint 0 is the universe)."""
    n_joints = parents.size
    R[0] = np.eye(3)
    p[0, :] = 0.0
    ov[0, :] = 0.0
    local = np.empty((3, 3))
    Rp = np.empty((3, 3))
    offset = np.empty(3)
    S = np.empty(6)
    for i in range(1, n_joints):
        parent = parents[i]
        mat3_mul(R[parent], placement_rotation[i], Rp)
        mat3_vec(R[parent], placement_translation[i], offset)
        col = idx_v[i]
        if i == 1:  # free flyer: (R(quaternion), position), velocity and acceleration in its own frame
            quaternion_matrix(q[3:7], local)
            mat3_mul(Rp, local, R[i])
            for b in range(3):
                p[i, b] = p[parent, b] + offset[b] + Rp[b, 0] * q[0] + Rp[b, 1] * q[1] + Rp[b, 2] * q[2]
            Ri, pi = R[i], p[i]
            for k in range(6):  # S_k = X_1 e_k
                if k < 3:
                    for b in range(3):
                        S[b] = Ri[b, k]
                        S[3 + b] = 0.0
                else:
                    w0, w1, w2 = Ri[0, k - 3], Ri[1, k - 3], Ri[2, k - 3]
                    S[0] = pi[1] * w2 - pi[2] * w1
                    S[1] = pi[2] * w0 - pi[0] * w2
                    S[2] = pi[0] * w1 - pi[1] * w0
                    S[3], S[4], S[5] = w0, w1, w2
                for b in range(6):
                    J[b, col + k] = S[b]
            for b in range(6):
                ov_b = 0.0
                for k in range(6):
                    ov_b += J[b, col + k] * v[col + k]
                ov[i, b] = ov_b
        else:
            axis_rotation(axes[i], q[idx_q[i]], local)
            mat3_mul(Rp, local, R[i])
            for b in range(3):
                p[i, b] = p[parent, b] + offset[b]
            mat3_vec(R[i], axes[i], S[3:])
            S[0] = p[i, 1] * S[5] - p[i, 2] * S[4]
            S[1] = p[i, 2] * S[3] - p[i, 0] * S[5]
            S[2] = p[i, 0] * S[4] - p[i, 1] * S[3]
            for b in range(6):
                J[b, col] = S[b]
                ov[i, b] = ov[parent, b] + S[b] * v[col]
    tree_accelerations(v, a, parents, idx_v, ov, J, oa)


@njit(cache=True)
def tree_accelerations(v, a, parents, idx_v, ov, J, oa):
    """Every joint's world spatial acceleration oa (n, 6) at the accelerations a (nv,), from the velocities
    v (nv,), world velocities ov and Jacobian columns J that :func:`tree_motion` left at the same (q, v)
    (the module's recursion for oa alone: the placements, J and ov do not depend on a)."""
    oa[0, :] = 0.0
    S = np.empty(6)
    cross = np.empty(6)
    for i in range(1, parents.size):
        col = idx_v[i]
        if i == 1:  # free flyer: X_1 a_b
            for b in range(6):
                oa_b = 0.0
                for k in range(6):
                    oa_b += J[b, col + k] * a[col + k]
                oa[i, b] = oa_b
        else:
            for b in range(6):
                S[b] = J[b, col]
            cross_motion(ov[i], S, cross)
            parent = parents[i]
            for b in range(6):
                oa[i, b] = oa[parent, b] + S[b] * a[col] + cross[b] * v[col]


@njit(cache=True)
def frame_motion(joint, frame_rotation, frame_translation, parents, idx_v, R, p, ov, oa, J, oRf, opf, Jf, vf, af):
    """A frame on ``joint`` with placement (frame_rotation (3, 3), frame_translation (3,)) in it, after
    :func:`tree_motion`: its world placement oRf (3, 3), opf (3,), its LOCAL Jacobian Jf (6, nv) (zero
    outside the support of the joint), LOCAL velocity vf (6,) and LOCAL spatial acceleration af (6,)."""
    mat3_mul(R[joint], frame_rotation, oRf)
    mat3_vec(R[joint], frame_translation, opf)
    for b in range(3):
        opf[b] += p[joint, b]
    _act_inverse(oRf, opf, ov[joint], vf)
    _act_inverse(oRf, opf, oa[joint], af)
    Jf[:, :] = 0.0
    column = np.empty(6)
    j = joint
    while j > 0:
        first = idx_v[j]
        last = first + (6 if j == 1 else 1)
        for c in range(first, last):
            _act_inverse(oRf, opf, J[:, c], column)
            for b in range(6):
                Jf[b, c] = column[b]
        j = parents[j]


@njit(cache=True)
def frame_acceleration_derivatives(joint, oRf, opf, parents, idx_v, ov, oa, J, v_dq, a_dq, a_dv):
    """The derivatives (6, nv) of the LOCAL velocity and spatial acceleration of a frame on ``joint``
    (placement oRf, opf from :func:`frame_motion`) with respect to q (v_dq, a_dq) and v (a_dv), after
    :func:`tree_motion` at (q, v, a) (the module's formulas; zero outside the joint's support)."""
    v_dq[:, :] = 0.0
    a_dq[:, :] = 0.0
    a_dv[:, :] = 0.0
    ovL = ov[joint]
    S = np.empty(6)
    t1 = np.empty(6)
    t2 = np.empty(6)
    t3 = np.empty(6)
    out = np.empty(6)
    j = joint
    while j > 0:
        col = idx_v[j]
        if j == 1:  # free flyer columns: ∂a/∂v = X_f⁻¹ ((ov_1 − ov_L) × S_k), nothing in q
            for b in range(6):
                t1[b] = ov[1, b] - ovL[b]
            for k in range(6):
                for b in range(6):
                    S[b] = J[b, col + k]
                cross_motion(t1, S, t2)
                _act_inverse(oRf, opf, t2, out)
                for b in range(6):
                    a_dv[b, col + k] = out[b]
        else:
            parent = parents[j]
            for b in range(6):
                S[b] = J[b, col]
            cross_motion(ov[parent], S, t1)  # ov_p × S_k
            _act_inverse(oRf, opf, t1, out)
            for b in range(6):
                v_dq[b, col] = out[b]
            cross_motion(oa[j], S, t2)  # oa_j × S_k + (ov_p × S_k) × (ov_L − ov_j)
            for b in range(6):
                t3[b] = ovL[b] - ov[j, b]
            cross_motion(t1, t3, out)
            for b in range(6):
                t2[b] += out[b]
            _act_inverse(oRf, opf, t2, out)
            for b in range(6):
                a_dq[b, col] = out[b]
            for b in range(6):  # (2 ov_j − ov_L) × S_k
                t3[b] = 2.0 * ov[j, b] - ovL[b]
            cross_motion(t3, S, t2)
            _act_inverse(oRf, opf, t2, out)
            for b in range(6):
                a_dv[b, col] = out[b]
        j = parents[j]
