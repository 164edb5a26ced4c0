"""Compiled pieces of the contact models (Crocoddyl's ContactModel3D and ContactModel6D) on the
KKT backend: the contact Jacobian and drift from the frame's LOCAL kinematics
(:mod:`wbmpc.ocp.kernels.tree`), their derivatives, and the joint-space terms of a point contact's
force."""

from __future__ import annotations

import numpy as np
from numba import njit

from wbmpc.ocp.kernels.linalg import skew3


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
