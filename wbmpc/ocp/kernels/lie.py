"""Compiled Lie-group operations of a free-flyer root followed by 1-dof joints (nq = nv + 1).

Pinocchio conventions: q = [p (3) world, quaternion (x, y, z, w), joint angles], tangent
dq = [v (3), ω (3) in the base frame, joint increments]; q ⊕ dq = M(q) exp6(v, ω) on the base.
These replace ``pin.integrate``, ``pin.dIntegrate`` and ``pin.dDifference`` in the node-wise models
and the batched evaluation (:mod:`wbmpc.ocp.batched_problem`), where a binding call per node costs
more than the arithmetic. They agree with Pinocchio to rounding (see tests/test_wbmpc_lie_kernels.py).

The SE(3) Jacobians follow Barfoot's closed forms (State Estimation for Robotics, sec. 7.1.5):
exp6's right Jacobian J_r(ξ) = J_l(−ξ) = [[J3, Q], [0, J3]] with the SO(3) right Jacobian J3 and
the coupling block Q; dDifference is its inverse at ξ = log6(M0⁻¹ M1).

These kernels run for every node of every evaluation (rollouts, gaps, state residuals and their
Jacobians). Numba puts every array on the heap (~20 ns to allocate and release), so each kernel
takes its small temporaries as views of one ``work`` allocation.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from wbmpc.ocp.kernels.linalg import mat3_mul, mat3_tmul, mat3_tvec, mat3_vec, skew_into

# [rad] below it the coefficients come from their Taylor series (terms up to θ¹²): the closed
# forms of the higher ones cancel catastrophically (c3's numerator is ~θ⁵/60).
SERIES_ANGLE = 0.5


def _series_coefficients(offset: int, weight_step: float) -> np.ndarray:
    """Coefficients c_n = (−1)ⁿ (1 + weight_step·n) / (2n + offset)! of θ²ⁿ, n = 0..6."""
    return np.array([(-1.0) ** n * (1.0 + weight_step * n) / math.factorial(2 * n + offset) for n in range(7)])


# Taylor coefficients (in θ²) of sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³ and of the coupling
# block's c2 and c3 (constants of the compiled code)
_SIN_OVER = _series_coefficients(1, 0.0)
_ONE_MINUS_COS = _series_coefficients(2, 0.0)
_THETA_MINUS_SIN = _series_coefficients(3, 0.0)
_COUPLING_2 = _series_coefficients(4, 0.0)
_COUPLING_3 = _series_coefficients(5, 1.0)


@njit(cache=True, inline="always")
def _series(t2, coefficients):
    """Σ_n coefficients[n] θ²ⁿ (Horner)."""
    total = coefficients[6]
    for n in range(5, -1, -1):
        total = total * t2 + coefficients[n]
    return total


@njit(cache=True)
def _so3_coefficients(theta):
    """(sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³)."""
    t2 = theta * theta
    if theta < SERIES_ANGLE:
        return _series(t2, _SIN_OVER), _series(t2, _ONE_MINUS_COS), _series(t2, _THETA_MINUS_SIN)
    s, c = np.sin(theta), np.cos(theta)
    return s / theta, (1.0 - c) / t2, (theta - s) / (t2 * theta)


@njit(cache=True, inline="always")
def _so3_polynomial(w, s1, s2, out):
    """out (3, 3) = I + s1 [w]× + s2 [w]×², with [w]×² = w wᵀ − |w|² I."""
    w0, w1, w2 = w[0], w[1], w[2]
    t2 = w0 * w0 + w1 * w1 + w2 * w2
    out[0, 0] = 1.0 + s2 * (w0 * w0 - t2)
    out[1, 1] = 1.0 + s2 * (w1 * w1 - t2)
    out[2, 2] = 1.0 + s2 * (w2 * w2 - t2)
    out[0, 1] = -s1 * w2 + s2 * w0 * w1
    out[1, 0] = s1 * w2 + s2 * w0 * w1
    out[0, 2] = s1 * w1 + s2 * w0 * w2
    out[2, 0] = -s1 * w1 + s2 * w0 * w2
    out[1, 2] = -s1 * w0 + s2 * w1 * w2
    out[2, 1] = s1 * w0 + s2 * w1 * w2


@njit(cache=True)
def quaternion_matrix(q, R):
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
def _matrix_quaternion(R, out):
    """Unit quaternion (x, y, z, w) of a rotation matrix (Eigen's branch on the largest term)."""
    trace = R[0, 0] + R[1, 1] + R[2, 2]
    if trace > 0.0:
        t = np.sqrt(trace + 1.0)
        out[3] = 0.5 * t
        t = 0.5 / t
        out[0] = (R[2, 1] - R[1, 2]) * t
        out[1] = (R[0, 2] - R[2, 0]) * t
        out[2] = (R[1, 0] - R[0, 1]) * t
        return
    i = 0
    if R[1, 1] > R[0, 0]:
        i = 1
    if R[2, 2] > R[i, i]:
        i = 2
    j = (i + 1) % 3
    k = (j + 1) % 3
    t = np.sqrt(R[i, i] - R[j, j] - R[k, k] + 1.0)
    out[i] = 0.5 * t
    t = 0.5 / t
    out[3] = (R[k, j] - R[j, k]) * t
    out[j] = (R[j, i] + R[i, j]) * t
    out[k] = (R[k, i] + R[i, k]) * t


@njit(cache=True, inline="always")
def _negate_twist(xi, minus_v, minus_w):
    """minus_v (3,) = −ξ[:3], minus_w (3,) = −ξ[3:6]."""
    for i in range(3):
        minus_v[i] = -xi[i]
        minus_w[i] = -xi[3 + i]


@njit(cache=True)
def se3_exp(xi):
    """exp6 of ξ = (v, ω): rotation R = I + (sin θ/θ)[ω]× + ((1 − cos θ)/θ²)[ω]×² and
    translation p = (I + ((1 − cos θ)/θ²)[ω]× + ((θ − sin θ)/θ³)[ω]×²) v."""
    w = xi[3:6]
    theta = np.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    a, b, c = _so3_coefficients(theta)
    work = np.empty((3, 3, 3))  # R, V, p
    R, V, p = work[0], work[1], work[2, 0]
    _so3_polynomial(w, a, b, R)
    _so3_polynomial(w, b, c, V)
    mat3_vec(V, xi[:3], p)
    return R, p


@njit(cache=True)
def free_flyer_integrate(q, dq, out):
    """out (nq,) = q ⊕ dq: base M(q) exp6(dq[:6]), joints q + dq (Pinocchio's integrate)."""
    nq = q.size
    R_exp, p_exp = se3_exp(dq[:6])
    work = np.empty((3, 3, 4))  # R0, R1, p1, quat
    R0, R1, p1, quat = work[0, :, :3], work[1, :, :3], work[2, 0, :3], work[2, 1]
    quaternion_matrix(q[3:7], R0)
    mat3_vec(R0, p_exp, p1)
    for i in range(3):
        out[i] = q[i] + p1[i]
    mat3_mul(R0, R_exp, R1)
    _matrix_quaternion(R1, quat)
    dot = quat[0] * q[3] + quat[1] * q[4] + quat[2] * q[5] + quat[3] * q[6]
    sign = -1.0 if dot < 0.0 else 1.0  # same hemisphere as q's quaternion
    norm2 = quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]
    scale = sign * (3.0 - norm2) / 2.0  # first-order renormalisation
    for i in range(4):
        out[3 + i] = scale * quat[i]
    for i in range(7, nq):
        out[i] = q[i] + dq[i - 1]


@njit(cache=True)
def _so3_right_jacobian(w, J):
    """J (3, 3) = I − (1 − cos θ)/θ² [ω]× + (θ − sin θ)/θ³ [ω]×², θ = |ω|."""
    theta = np.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    _, b, c = _so3_coefficients(theta)
    _so3_polynomial(w, -b, c, J)


@njit(cache=True)
def _se3_left_coupling(rho, phi, Q):
    """Barfoot's Q(ρ, φ) (3, 3), the off-diagonal block of SE(3)'s left Jacobian."""
    theta = np.sqrt(phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2])
    t2 = theta * theta
    if theta < SERIES_ANGLE:
        c1 = _series(t2, _THETA_MINUS_SIN)
        c2 = _series(t2, _COUPLING_2)
        c3 = _series(t2, _COUPLING_3)
    else:
        s, c = np.sin(theta), np.cos(theta)
        c1 = (theta - s) / (t2 * theta)
        c2 = (t2 + 2.0 * c - 2.0) / (2.0 * t2 * t2)
        c3 = (2.0 * theta - 3.0 * s + theta * c) / (2.0 * t2 * t2 * theta)
    work = np.empty((9, 3, 3))  # the nine products
    P, Rh, PR, RP, PRP, PPR, RPP, PRPP, PPRP = (work[0], work[1], work[2], work[3], work[4], work[5], work[6],
                                                work[7], work[8])
    skew_into(phi, P)
    skew_into(rho, Rh)
    mat3_mul(P, Rh, PR)
    mat3_mul(Rh, P, RP)
    mat3_mul(PR, P, PRP)
    mat3_mul(P, PR, PPR)
    mat3_mul(RP, P, RPP)
    mat3_mul(PRP, P, PRPP)
    mat3_mul(P, PRP, PPRP)
    for i in range(3):
        for j in range(3):
            Q[i, j] = (0.5 * Rh[i, j] + c1 * (PR[i, j] + RP[i, j] + PRP[i, j])
                       + c2 * (PPR[i, j] + RPP[i, j] - 3.0 * PRP[i, j]) + c3 * (PRPP[i, j] + PPRP[i, j]))


@njit(cache=True)
def se3_right_jacobian(xi, J):
    """J (6, 6): Pinocchio's Jexp6 at ξ = (v, ω), the right Jacobian of exp6."""
    J[:, :] = 0.0
    work = np.empty((3, 3, 3))  # J3, Q and −ξ
    J3, Q, minus_v, minus_w = work[0], work[1], work[2, 0], work[2, 1]
    _negate_twist(xi, minus_v, minus_w)
    _so3_right_jacobian(xi[3:6], J3)
    _se3_left_coupling(minus_v, minus_w, Q)
    J[:3, :3] = J3
    J[3:, 3:] = J3
    J[:3, 3:] = Q


@njit(cache=True, inline="always")
def _write_base_block(J, A, C):
    """J[:6, :6] = [[A, −C], [0, A]] (the lower-left block is left as it is)."""
    for i in range(3):
        for j in range(3):
            J[i, j] = A[i, j]
            J[3 + i, 3 + j] = A[i, j]
            J[i, 3 + j] = -C[i, j]


@njit(cache=True)
def free_flyer_dintegrate(q, dq, J_q, J_dq):
    """Jacobians (nv, nv) of q ⊕ dq with respect to q (J_q) and dq (J_dq) (Pinocchio's
    dIntegrate ARG0 and ARG1): the base blocks are Ad(exp6(dq)⁻¹) and Jexp6(dq); joints identity."""
    nv = J_q.shape[0]
    J_q[:, :] = 0.0
    J_dq[:, :] = 0.0
    for i in range(6, nv):
        J_q[i, i] = 1.0
        J_dq[i, i] = 1.0
    R, p = se3_exp(dq[:6])
    work = np.empty((3, 3, 3))  # S, Rᵀ, Rᵀ S
    S, RT, RTS = work[0], work[1], work[2]
    skew_into(p, S)
    for i in range(3):
        for j in range(3):
            RT[i, j] = R[j, i]
    mat3_mul(RT, S, RTS)
    _write_base_block(J_q, RT, RTS)
    se3_right_jacobian(dq[:6], J_dq[:6, :6])


@njit(cache=True)
def so3_log(R, w):
    """w (3,) = log3(R) [rad] of a rotation matrix R (3, 3) (Pinocchio's log3: w = θ / (2 sin θ)
    vee(R − Rᵀ), the limit 1/2 for small θ); returns the angle θ as Pinocchio takes it, from the
    trace (so only to ~1e-8 rad near 0, where it is used for series branches). Within 1e-2 rad of a half turn,
    where Pinocchio takes a special branch, returns −1 (w untouched): the caller then uses
    Pinocchio."""
    trace = R[0, 0] + R[1, 1] + R[2, 2]
    if trace >= 3.0:
        theta = 0.0
    elif trace <= -1.0:
        return -1.0
    else:
        theta = np.arccos((trace - 1.0) / 2.0)
    if theta >= np.pi - 1e-2:
        return -1.0
    eps3 = 1e-5  # a safe small-angle threshold; the Taylor limit is exact to 1e-11 below it
    t = (theta / np.sin(theta) if theta > eps3 else 1.0) / 2.0
    w[0] = t * (R[2, 1] - R[1, 2])
    w[1] = t * (R[0, 2] - R[2, 0])
    w[2] = t * (R[1, 0] - R[0, 1])
    return theta


@njit(cache=True)
def so3_log_jacobian(w, J):
    """J (3, 3) = Pinocchio's Jlog3 at w = log3(R) (3,) [rad]: the inverse of the SO(3) right
    Jacobian, I + ½[ω]× + (1/θ² − (1 + cos θ)/(2θ sin θ)) [ω]×², θ = |ω| (the derivative of
    log3(R exp(δ)) in δ at 0)."""
    theta = np.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    if theta < 0.1:  # series of the closed form (cancellation ~ eps/θ²)
        t2 = theta * theta
        d = 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0 + t2 * t2 * t2 / 1209600.0
    else:
        d = 1.0 / (theta * theta) - (1.0 + np.cos(theta)) / (2.0 * theta * np.sin(theta))
    _so3_polynomial(w, 0.5, d, J)


@njit(cache=True)
def free_flyer_ddifference_second(q0, q1, J):
    """J (nv, nv) = ∂(q1 ⊖ q0)/∂q1 (Pinocchio's dDifference ARG1): the base block is Jlog6 of
    M0⁻¹ M1 (inverse of Jexp6 at the difference), joints identity. False near a half turn (the
    caller then uses Pinocchio)."""
    nv = J.shape[0]
    xi = np.empty(nv)
    if not free_flyer_difference(q0, q1, q0.size, xi):
        return False
    J[:, :] = 0.0
    for i in range(6, nv):
        J[i, i] = 1.0
    work = np.empty((5, 3, 3))  # A⁻¹, Q, A⁻¹Q, A⁻¹QA⁻¹ and −ξ
    A_inv, Q, AQ, AQA, minus_v, minus_w = work[0], work[1], work[2], work[3], work[4, 0], work[4, 1]
    so3_log_jacobian(xi[3:6], A_inv)
    _negate_twist(xi, minus_v, minus_w)
    _se3_left_coupling(minus_v, minus_w, Q)
    mat3_mul(A_inv, Q, AQ)
    mat3_mul(AQ, A_inv, AQA)
    _write_base_block(J, A_inv, AQA)
    return True


@njit(cache=True)
def free_flyer_difference(q0, q1, nq, out):
    """pin.difference for a free-flyer root followed by 1-dof joints (nq = nv + 1), written in out
    (nv,). Returns False (out untouched beyond use) when the relative rotation is within 1e-2 rad
    of π, where Pinocchio's log3 takes a special branch: the caller then uses Pinocchio."""
    work = np.empty((4, 3, 3))  # R0, R1, R0ᵀ R1, Δp, p
    R0, R1, R, dp, p = work[0], work[1], work[2], work[3, 0], work[3, 1]
    quaternion_matrix(q0[3:7], R0)
    quaternion_matrix(q1[3:7], R1)
    mat3_tmul(R0, R1, R)
    for i in range(3):
        dp[i] = q1[i] - q0[i]
    mat3_tvec(R0, dp, p)
    theta = so3_log(R, out[3:6])
    if theta < 0.0:
        return False
    w0, w1, w2 = out[3], out[4], out[5]
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
def free_flyer_interpolate(q0, q1, alpha, dq, out):
    """out (nq,) = q0 ⊕ α (q1 ⊖ q0) (Pinocchio's interpolate), dq (nv,) scratch. False (out
    untouched) near a half-turn relative rotation: the caller then uses Pinocchio."""
    if not free_flyer_difference(q0, q1, q0.size, dq):
        return False
    for i in range(dq.size):
        dq[i] *= alpha
    free_flyer_integrate(q0, dq, out)
    return True
