"""Compiled pieces of the rigid point-contact model (Crocoddyl's ContactModel3D): the derivative
of the contact drift and the joint-space terms of a contact force."""

from __future__ import annotations

import numpy as np
from numba import njit

from wbmpc.ocp.kernels.linalg import skew3


@njit(cache=True)
def contact3d_drift_derivative(fXj, v_dq, a_dq, a_dv, fJf, v_linear, v_angular, position_error_local,
                               a0_local, oRf, kp, kd, out):
    """∂a0/∂x (3, 2 nv) of a LOCAL_WORLD_ALIGNED point contact (Crocoddyl's ContactModel3D).

    Args: fXj (6, 6) joint-to-frame action matrix; v_dq, a_dq, a_dv (6, nv) joint velocity and
    acceleration derivatives (LOCAL); fJf (6, nv) frame Jacobian (LOCAL); frame velocity
    (linear, angular) (3,) LOCAL; position error (3,) LOCAL; drift a0 (3,) LOCAL evaluated with
    the current accelerations; oRf (3, 3); Baumgarte gains kp, kd.
    """
    nv = fJf.shape[1]
    fXjdv_dq = np.dot(fXj, v_dq)
    fXjda_dq = np.dot(fXj, a_dq)
    fXjda_dv = np.dot(fXj, a_dv)
    vv = skew3(v_linear)
    vw = skew3(v_angular)
    da_dq = fXjda_dq[:3] + np.dot(vw, fXjdv_dq[:3]) - np.dot(vv, fXjdv_dq[3:])
    da_dv = fXjda_dv[:3] + np.dot(vw, fJf[:3]) - np.dot(vv, fJf[3:])
    if kp != 0.0:
        da_dq += kp * np.dot(skew3(position_error_local), fJf[3:]) + kp * fJf[:3]
    if kd != 0.0:
        da_dq += kd * fXjdv_dq[:3]
        da_dv += kd * fJf[:3]
    a0_world = np.dot(oRf, a0_local)
    out[:, :nv] = np.dot(oRf, da_dq) - np.dot(np.dot(skew3(a0_world), oRf), fJf[3:])
    out[:, nv:] = np.dot(oRf, da_dv)


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
