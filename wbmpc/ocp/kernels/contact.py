"""Compiled pieces of the contact models (Crocoddyl's ContactModel3D and ContactModel6D) on the
KKT backend: the contact Jacobian and drift from the frame's LOCAL kinematics
(:mod:`wbmpc.ocp.kernels.tree`), their derivatives, and the joint-space terms of a point contact's
force."""

from __future__ import annotations

import numpy as np
from numba import njit

from wbmpc.ocp.kernels.linalg import skew3
from wbmpc.ocp.kernels.tree import frame_acceleration_derivatives, frame_motion, tree_accelerations, tree_motion


@njit(cache=True)
def contact3d_calc(fJf, oRf, opf, velocity, acceleration, reference, kp, kd, Jc, a0):
    """Jc (3, nv) and a0 (3,) of a LOCAL_WORLD_ALIGNED point contact: Jc = oRf J_f[:3] and the drift
    a0 = oRf (a_f + ω_f × v_f) + Kp (p_f − reference) + Kd oRf v_f (the frame's classical acceleration at
    zero joint accelerations plus the Baumgarte terms), from the frame's LOCAL Jacobian fJf (6, nv),
    placement oRf (3, 3), opf (3,), velocity and spatial acceleration (6,) (linear, angular)."""
    nv = fJf.shape[1]
    for a in range(3):
        for c in range(nv):
            Jc[a, c] = oRf[a, 0] * fJf[0, c] + oRf[a, 1] * fJf[1, c] + oRf[a, 2] * fJf[2, c]
    v0, v1, v2 = velocity[0], velocity[1], velocity[2]
    w0, w1, w2 = velocity[3], velocity[4], velocity[5]
    classical = np.empty(3)
    classical[0] = acceleration[0] + w1 * v2 - w2 * v1 + kd * v0
    classical[1] = acceleration[1] + w2 * v0 - w0 * v2 + kd * v1
    classical[2] = acceleration[2] + w0 * v1 - w1 * v0 + kd * v2
    for a in range(3):
        a0[a] = (oRf[a, 0] * classical[0] + oRf[a, 1] * classical[1] + oRf[a, 2] * classical[2]
                 + kp * (opf[a] - reference[a]))


@njit(cache=True)
def contact3d_drift_derivative(v_dq, a_dq, a_dv, fJf, v_linear, v_angular, position_error_local,
                               a0_local, oRf, kp, kd, out):
    """∂a0/∂x (3, 2 nv) of a LOCAL_WORLD_ALIGNED point contact (Crocoddyl's ContactModel3D).

    Args: v_dq, a_dq, a_dv (6, nv) the frame's velocity and acceleration derivatives (LOCAL,
    :func:`~wbmpc.ocp.kernels.tree.frame_acceleration_derivatives`); fJf (6, nv) frame Jacobian
    (LOCAL); frame velocity (linear, angular) (3,) LOCAL; position error (3,) LOCAL; drift a0 (3,)
    LOCAL evaluated with the current accelerations; oRf (3, 3); Baumgarte gains kp, kd.
    """
    nv = fJf.shape[1]
    vv = skew3(v_linear)
    vw = skew3(v_angular)
    da_dq = a_dq[:3] + np.dot(vw, v_dq[:3]) - np.dot(vv, v_dq[3:])
    da_dv = a_dv[:3] + np.dot(vw, fJf[:3]) - np.dot(vv, fJf[3:])
    if kp != 0.0:
        da_dq += kp * np.dot(skew3(position_error_local), fJf[3:]) + kp * fJf[:3]
    if kd != 0.0:
        da_dq += kd * v_dq[:3]
        da_dv += kd * fJf[:3]
    a0_world = np.dot(oRf, a0_local)
    out[:, :nv] = np.dot(oRf, da_dq) - np.dot(np.dot(skew3(a0_world), oRf), fJf[3:])
    out[:, nv:] = np.dot(oRf, da_dv)


@njit(cache=True)
def contact6d_drift(velocity, acceleration, kd, spread, inverse_arms, corners, a0):
    """a0 (6,) of a LOCAL 6D contact: the frame's spatial acceleration at zero joint accelerations plus
    Kd times its velocity (both LOCAL, (linear, angular)), and with ``corners`` the drift of the sole as
    four corner point contacts δ(v, ω) = (ω × v, inverse_arms ∘ ((spread ∘ ω) × ω))
    (:class:`~wbmpc.ocp.contacts.SoleCorners`: spread = diag(a², b², 0), inverse_arms = 1 / r²)."""
    for b in range(6):
        a0[b] = acceleration[b] + kd * velocity[b]
    if corners:
        v0, v1, v2 = velocity[0], velocity[1], velocity[2]
        w0, w1, w2 = velocity[3], velocity[4], velocity[5]
        s0, s1, s2 = spread[0] * w0, spread[1] * w1, spread[2] * w2
        a0[0] += w1 * v2 - w2 * v1
        a0[1] += w2 * v0 - w0 * v2
        a0[2] += w0 * v1 - w1 * v0
        a0[3] += inverse_arms[0] * (s1 * w2 - s2 * w1)
        a0[4] += inverse_arms[1] * (s2 * w0 - s0 * w2)
        a0[5] += inverse_arms[2] * (s0 * w1 - s1 * w0)


@njit(cache=True)
def contact6d_drift_derivative(v_dq, a_dq, a_dv, fJf, velocity, kd, spread, inverse_arms, corners, out):
    """∂a0/∂x (6, 2 nv) of :func:`contact6d_drift` at fixed joint accelerations: [a_dq + Kd v_dq,
    a_dv + Kd J_f] (the frame's LOCAL derivatives, :func:`~wbmpc.ocp.kernels.tree.frame_acceleration_derivatives`)
    plus, with ``corners``, ∂δ/∂(v, ω) (6, 6) times [v_dq, J_f]."""
    nv = fJf.shape[1]
    for b in range(6):
        for c in range(nv):
            out[b, c] = a_dq[b, c] + kd * v_dq[b, c]
            out[b, nv + c] = a_dv[b, c] + kd * fJf[b, c]
    if corners:
        v, w = velocity[:3], velocity[3:]
        D = np.zeros((6, 6))
        D[:3, :3] = skew3(w)
        D[:3, 3:] = -skew3(v)
        sw = np.empty(3)
        for b in range(3):
            sw[b] = spread[b] * w[b]
        block = skew3(sw) - skew3(w) * spread.reshape(1, 3)  # [(spread ∘ ω)]× − [ω]× diag(spread)
        for b in range(3):
            for c in range(3):
                D[3 + b, 3 + c] = inverse_arms[b] * block[b, c]
        out[:, :nv] += np.dot(D, v_dq)
        out[:, nv:] += np.dot(D, np.ascontiguousarray(fJf))


@njit(cache=True)
def contact3d_force_terms(fJf, oRf, force_world, jRf, jpf, fext, dtau_dq):
    """For a world-aligned point force: the spatial force on the parent joint (6,) = jMf·(f_local, 0)
    and the RNEA derivative term −J_linᵀ [f_local]× J_ang (nv, nv)."""
    f_local = np.dot(oRf.T, force_world)
    linear = np.dot(jRf, f_local)
    fext[:3] = linear
    fext[3] = jpf[1] * linear[2] - jpf[2] * linear[1]
    fext[4] = jpf[2] * linear[0] - jpf[0] * linear[2]
    fext[5] = jpf[0] * linear[1] - jpf[1] * linear[0]
    dtau_dq[:, :] = -np.dot(np.ascontiguousarray(fJf[:3].T), np.dot(skew3(f_local), fJf[3:]))


@njit(cache=True)
def contact_set_calc(q, v, a, parents, placement_rotation, placement_translation, axes, idx_q, idx_v, R, p, ov, oa, J,
                     kinds, joints, frame_rotations, frame_translations, kp, kd, references, corners, spreads,
                     inverse_arms, oRf, opf, fJf, velocity, acceleration, Jc, a0):
    """The stacked Jacobian Jc (nc, nv) and drift a0 (nc,) of a node's active contacts, in one call.

    The tree kinematics at (q, v, a) (a = 0: the drift; :func:`~wbmpc.ocp.kernels.tree.tree_motion`,
    the tree arrays parents ... J of :class:`~wbmpc.ocp.kernels.tree.KinematicTree`), then for each
    contact c (kinds[c] = 3: a LOCAL_WORLD_ALIGNED point contact, :func:`contact3d_calc`; 6: a LOCAL 6D
    contact, :func:`contact6d_drift`, without its Kp term) on joint joints[c] with the frame placement
    (frame_rotations[c], frame_translations[c]), Baumgarte gains kp[c], kd[c], the point reference
    references[c] (3D), the sole-corner drift flag corners[c] with spreads[c], inverse_arms[c] (6D);
    rows stacked in the contacts' order. The per-contact frame kinematics stay in oRf (k, 3, 3),
    opf (k, 3), fJf (k, 6, nv), velocity, acceleration (k, 6) (LOCAL) for the derivatives."""
    tree_motion(q, v, a, parents, placement_rotation, placement_translation, axes, idx_q, idx_v, R, p, ov, oa, J)
    row = 0
    for c in range(kinds.size):
        frame_motion(joints[c], frame_rotations[c], frame_translations[c], parents, idx_v, R, p, ov, oa, J, oRf[c],
                     opf[c], fJf[c], velocity[c], acceleration[c])
        if kinds[c] == 3:
            contact3d_calc(fJf[c], oRf[c], opf[c], velocity[c], acceleration[c], references[c], kp[c], kd[c],
                           Jc[row:row + 3], a0[row:row + 3])
            row += 3
        else:
            Jc[row:row + 6] = fJf[c]
            contact6d_drift(velocity[c], acceleration[c], kd[c], spreads[c], inverse_arms[c], corners[c],
                            a0[row:row + 6])
            row += 6


@njit(cache=True)
def contact_set_derivatives(v, a, parents, idx_v, ov, oa, J, kinds, joints, frame_rotations, frame_translations, kp,
                            kd, references, corners, spreads, inverse_arms, oRf, opf, fJf, velocity, forces, v_dq, a_dq,
                            a_dv, da0_dx, fext, dtau_dq_extra):
    """After :func:`contact_set_calc` at (q, v, 0) and the KKT solve (accelerations a, stacked contact
    forces ``forces`` (nc,)): the stacked drift derivatives da0_dx (nc, ndx) at fixed a (the tree's
    accelerations updated to a, :func:`~wbmpc.ocp.kernels.tree.tree_accelerations`: its placements,
    Jacobian columns and velocities are calc's; 6D contacts without their Kp term), the spatial force each
    contact puts on its joint fext (k, 6) (the frame force moved by jMf: for RNEA with external forces) and the rotation term of
    the point contacts' world-aligned forces in the RNEA derivative, summed into dtau_dq_extra (nv, nv);
    returns True when there is one (a point contact). Scratch v_dq, a_dq, a_dv (k, 6, nv)."""
    tree_accelerations(v, a, parents, idx_v, ov, J, oa)
    nv = v.size
    extra = False
    term = np.empty((nv, nv))
    position_error = np.zeros(3)
    zero = np.zeros(3)
    row = 0
    for c in range(kinds.size):
        frame_acceleration_derivatives(joints[c], oRf[c], opf[c], parents, idx_v, ov, oa, J, v_dq[c], a_dq[c],
                                       a_dv[c])
        jRf, jpf = frame_rotations[c], frame_translations[c]
        if kinds[c] == 3:
            if kp[c] != 0.0:
                for b in range(3):
                    position_error[b] = (oRf[c, 0, b] * (opf[c, 0] - references[c, 0])
                                         + oRf[c, 1, b] * (opf[c, 1] - references[c, 1])
                                         + oRf[c, 2, b] * (opf[c, 2] - references[c, 2]))
            # the rotation term of ∂(oRf a0_local)/∂q multiplies a0_local at the solved accelerations,
            # J a + drift + Baumgarte = 0 for an enforced contact (Crocoddyl evaluates it numerically): 0
            contact3d_drift_derivative(v_dq[c], a_dq[c], a_dv[c], fJf[c], velocity[c, :3], velocity[c, 3:],
                                       position_error, zero, oRf[c], kp[c], kd[c], da0_dx[row:row + 3])
            contact3d_force_terms(fJf[c], oRf[c], forces[row:row + 3], jRf, jpf, fext[c], term)
            if extra:
                dtau_dq_extra += term
            else:
                dtau_dq_extra[:, :] = term
                extra = True
            row += 3
        else:
            contact6d_drift_derivative(v_dq[c], a_dq[c], a_dv[c], fJf[c], velocity[c], kd[c], spreads[c],
                                       inverse_arms[c], corners[c], da0_dx[row:row + 6])
            f = forces[row:row + 6]  # jMf · (force, torque): (jRf f, jRf τ + jpf × jRf f)
            for b in range(3):
                fext[c, b] = jRf[b, 0] * f[0] + jRf[b, 1] * f[1] + jRf[b, 2] * f[2]
                fext[c, 3 + b] = jRf[b, 0] * f[3] + jRf[b, 1] * f[4] + jRf[b, 2] * f[5]
            fext[c, 3] += jpf[1] * fext[c, 2] - jpf[2] * fext[c, 1]
            fext[c, 4] += jpf[2] * fext[c, 0] - jpf[0] * fext[c, 2]
            fext[c, 5] += jpf[0] * fext[c, 1] - jpf[1] * fext[c, 0]
            row += 6
    return extra
