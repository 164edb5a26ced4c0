"""Numba kernels for the per-node glue of the contact dynamics (small dense products that cost
more in numpy call overhead than in arithmetic). Compiled on first use and cached on disk."""

from __future__ import annotations

import numpy as np
from numba import njit

from wbmpc.ocp.small_linalg import mat3_tmul, mat3_tvec, skew_into


@njit(cache=True)
def skew3(w):
    """[w]×, shape (3, 3)."""
    S = np.empty((3, 3))
    skew_into(w, S)
    return S


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
def euler_transition_jacobians(da_dx, da_du, J_q, J_dq, dt, Fx, Fu):
    """Fx (ndx, ndx), Fu (ndx, nu) of q⁺ = q ⊕ (v dt + a dt²), v⁺ = v + a dt.

    Args: da_dx (nv, ndx), da_du (nv, nu) acceleration derivatives; J_q, J_dq (nv, nv) the
    Jacobians of q ⊕ δ with respect to q and δ at δ = v dt + a dt².
    """
    nv = da_dx.shape[0]
    dt2 = dt * dt
    top = da_dx * dt2
    for i in range(nv):
        top[i, nv + i] += dt
    Fx[:nv] = np.dot(J_dq, top)
    Fx[:nv, :nv] += J_q
    Fx[nv:] = da_dx * dt
    for i in range(nv):
        Fx[nv + i, nv + i] += 1.0
    Fu[:nv] = np.dot(J_dq, da_du * dt2)
    Fu[nv:] = da_du * dt


@njit(cache=True)
def cost_rows_value(r, row_term, term_scale, w, lb, ub, term_cost):
    """Σ over rows of term_scale[term] · ½ w e², e = min(r − lb, 0) + max(r − ub, 0).

    Rows of inactive terms (term_scale 0) are skipped, whatever their stale residual holds.
    Fills term_cost (n_terms,) and returns the total.
    """
    term_cost[:] = 0.0
    for i in range(r.size):
        scale = term_scale[row_term[i]]
        if scale == 0.0:
            continue
        e = min(r[i] - lb[i], 0.0) + max(r[i] - ub[i], 0.0)
        term_cost[row_term[i]] += scale * 0.5 * w[i] * e * e
    total = 0.0
    for j in range(term_cost.size):
        total += term_cost[j]
    return total


@njit(cache=True)
def cost_rows_derivatives(r, R, row_term, term_scale, w, lb, ub, gradient, hessian):
    """Gauss-Newton gradient Rᵀ (c e) (n,) and Hessian Rᵀ diag(c m) R (n, n) of the stacked
    residual rows, c = term_scale · w, m = 1 where the row is outside its dead zone."""
    nrows, n = R.shape
    coef_g = np.zeros(nrows)
    coef_h = np.zeros(nrows)
    for i in range(nrows):
        scale = term_scale[row_term[i]]
        if scale == 0.0:
            continue
        below = r[i] - lb[i]
        above = r[i] - ub[i]
        e = min(below, 0.0) + max(above, 0.0)
        coef_g[i] = scale * w[i] * e
        if below <= 0.0 or above >= 0.0:
            coef_h[i] = scale * w[i]
    gradient[:] = 0.0
    hessian[:, :] = 0.0
    for i in range(nrows):
        cg = coef_g[i]
        ch = coef_h[i]
        if cg == 0.0 and ch == 0.0:
            continue
        Ri = R[i]
        for a in range(n):
            ra = Ri[a]
            if ra == 0.0:
                continue
            gradient[a] += ra * cg
            if ch != 0.0:
                v = ch * ra
                for b in range(a, n):
                    hessian[a, b] += v * Ri[b]
    for a in range(n):
        for b in range(a + 1, n):
            hessian[b, a] = hessian[a, b]


@njit(cache=True)
def euler_step_tangent(v, a, dt, dx, v_next):
    """dx = [v dt + a dt², a dt] (2 nv,) and v⁺ = v + a dt (nv,)."""
    nv = v.size
    dt2 = dt * dt
    for i in range(nv):
        dx[i] = v[i] * dt + a[i] * dt2
        dx[nv + i] = a[i] * dt
        v_next[i] = v[i] + a[i] * dt


@njit(cache=True)
def feedback_control(u, k, K, dx, alpha, out):
    """out = u − α k − K dx (Crocoddyl's sign); returns False if the result is not finite."""
    nu, ndx = K.shape
    ok = True
    for i in range(nu):
        s = u[i] - alpha * k[i]
        for j in range(ndx):
            s -= K[i, j] * dx[j]
        out[i] = s
        if not np.isfinite(s):
            ok = False
    return ok


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
def scale_cost_derivatives(dt, gradient, hessian, ndx, Lx, Lu, Lxx, Lxu, Luu):
    """Integrated cost derivatives: dt × the continuous gradient (ndx + nu,) and Hessian blocks."""
    n = gradient.size
    for i in range(ndx):
        Lx[i] = dt * gradient[i]
        for j in range(ndx):
            Lxx[i, j] = dt * hessian[i, j]
        for j in range(ndx, n):
            Lxu[i, j - ndx] = dt * hessian[i, j]
    for i in range(ndx, n):
        Lu[i - ndx] = dt * gradient[i]
        for j in range(ndx, n):
            Luu[i - ndx, j - ndx] = dt * hessian[i, j]


@njit(cache=True)
def _quaternion_matrix(q, R):
    """Rotation matrix of the quaternion (x, y, z, w) (Eigen's toRotationMatrix)."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    tx, ty, tz = 2.0 * x, 2.0 * y, 2.0 * z
    twx, twy, twz = tx * w, ty * w, tz * w
    txx, txy, txz = tx * x, ty * x, tz * x
    tyy, tyz, tzz = ty * y, tz * y, tz * z
    R[0, 0] = 1.0 - (tyy + tzz)
    R[0, 1] = txy - twz
    R[0, 2] = txz + twy
    R[1, 0] = txy + twz
    R[1, 1] = 1.0 - (txx + tzz)
    R[1, 2] = tyz - twx
    R[2, 0] = txz - twy
    R[2, 1] = tyz + twx
    R[2, 2] = 1.0 - (txx + tyy)


@njit(cache=True)
def free_flyer_difference(q0, q1, nq, out):
    """pin.difference for a free-flyer root followed by 1-dof joints (nq = nv + 1), written in out
    (nv,). Returns False (out untouched beyond use) when the relative rotation is within 1e-2 rad
    of π, where Pinocchio's log3 takes a special branch: the caller then uses Pinocchio."""
    R0 = np.empty((3, 3))
    R1 = np.empty((3, 3))
    _quaternion_matrix(q0[3:7], R0)
    _quaternion_matrix(q1[3:7], R1)
    R = np.empty((3, 3))
    mat3_tmul(R0, R1, R)
    dp = np.empty(3)
    for i in range(3):
        dp[i] = q1[i] - q0[i]
    p = np.empty(3)
    mat3_tvec(R0, dp, p)
    trace = R[0, 0] + R[1, 1] + R[2, 2]
    if trace >= 3.0:
        theta = 0.0
    elif trace <= -1.0:
        return False
    else:
        theta = np.arccos((trace - 1.0) / 2.0)
    if theta >= np.pi - 1e-2:
        return False
    # log3 (Pinocchio): w = θ / (2 sin θ) vee(R − Rᵀ), with the limit 1/2 for small θ
    eps3 = 1e-5  # a safe small-angle threshold; the Taylor limit is exact to 1e-11 below it
    t = (theta / np.sin(theta) if theta > eps3 else 1.0) / 2.0
    w0 = t * (R[2, 1] - R[1, 2])
    w1 = t * (R[0, 2] - R[2, 0])
    w2 = t * (R[1, 0] - R[0, 1])
    t2 = theta * theta
    if t2 < 1e-8:
        alpha = 1.0 - t2 / 12.0 - t2 * t2 / 720.0
        beta = 1.0 / 12.0 + t2 / 720.0
    else:
        st = np.sin(theta)
        ct = np.cos(theta)
        alpha = theta * st / (2.0 * (1.0 - ct))
        beta = 1.0 / t2 - st / (2.0 * theta * (1.0 - ct))
    wp = w0 * p[0] + w1 * p[1] + w2 * p[2]
    cross0 = w1 * p[2] - w2 * p[1]
    cross1 = w2 * p[0] - w0 * p[2]
    cross2 = w0 * p[1] - w1 * p[0]
    out[0] = alpha * p[0] - 0.5 * cross0 + beta * wp * w0
    out[1] = alpha * p[1] - 0.5 * cross1 + beta * wp * w1
    out[2] = alpha * p[2] - 0.5 * cross2 + beta * wp * w2
    out[3] = w0
    out[4] = w1
    out[5] = w2
    for i in range(7, nq):
        out[i - 1] = q1[i] - q0[i]
    return True


@njit(cache=True)
def free_flyer_state_difference(x0, x1, nq, out):
    """x1 ⊖ x0 (2 nv,) for a free-flyer root followed by 1-dof joints; False near a half turn."""
    nv = nq - 1
    if not free_flyer_difference(x0[:nq], x1[:nq], nq, out[:nv]):
        return False
    for i in range(nv):
        out[nv + i] = x1[nq + i] - x0[nq + i]
    return True


@njit(cache=True)
def sum_quadratic_forms(a, M, b):
    """Σ_t a[t]ᵀ M[t] b[t] for a, b (T, n) and M (T, n, n)."""
    total = 0.0
    T, n = a.shape
    for t in range(T):
        for i in range(n):
            ai = a[t, i]
            if ai == 0.0:
                continue
            s = 0.0
            for j in range(n):
                s += M[t, i, j] * b[t, j]
            total += ai * s
    return total


@njit(cache=True)
def free_flyer_state_differences(X0, X1, nq, out):
    """out[k] = X1[k] ⊖ X0[k] for every row; returns the first row needing Pinocchio (half turn), or −1."""
    for k in range(out.shape[0]):
        if not free_flyer_state_difference(X0[k], X1[k], nq, out[k]):
            return k
    return -1


@njit(cache=True)
def free_flyer_feedback_control(x_ref, x, u, k, K, alpha, nq, dx, out):
    """dx = x ⊖ x_ref (free-flyer models) and out = u − α k − K dx (Crocoddyl's sign) in one call.

    Returns 0 on success, 1 when the difference needs Pinocchio (relative rotation near a half
    turn; nothing written to out), 2 when the control is not finite.
    """
    if not free_flyer_state_difference(x_ref, x, nq, dx):
        return 1
    return 0 if feedback_control(u, k, K, dx, alpha, out) else 2
