"""Compiled residual rows shared by the node-wise residuals and their batched evaluation: each
residual of :mod:`wbmpc.ocp.residuals` that can be batched computes its rows with these kernels
at one node (``calc``/``calcDiff``) and over every active node of a horizon (``batch_calc``/
``batch_calc_diff``, which loop over the same per-node kernel).

Kernels writing a dense Jacobian block take it as a 2-D array: the node-wise Rx/Ru (views of
the cost sum's stacked rows) or, in the batched evaluation, one node's Jacobian nonzeros viewed
as (nr, n) (:func:`jacobian_blocks`), so both are written by the same code."""

from __future__ import annotations

import numpy as np
from numba import njit

from wbmpc.ocp.kernels.lie import free_flyer_ddifference_second, free_flyer_state_difference, so3_log, so3_log_jacobian


@njit(cache=True, inline="always")
def subtract_rows(value, reference, r):
    """r = value − reference (the residual of every reference-tracking term)."""
    for i in range(r.size):
        r[i] = value[i] - reference[i]


@njit(cache=True)
def subtract_rows_many(values, references, mask, r):
    """r[k] = values[k] − references[k] for the nodes with mask[k], values, references, r (N, d)."""
    for k in range(mask.size):
        if mask[k]:
            subtract_rows(values[k], references[k], r[k])


@njit(cache=True)
def state_difference_many(references, xs, nq, mask, r, ok):
    """r[k] = xs[k] ⊖ references[k] (the free-flyer difference of ``StateMultibody.diff``) for the
    nodes with mask[k]; ok[k] False where Pinocchio must take over (half turn). True if none did."""
    all_ok = True
    for k in range(mask.size):
        ok[k] = True
        if mask[k] and not free_flyer_state_difference(references[k], xs[k], nq, r[k]):
            ok[k] = False
            all_ok = False
    return all_ok


@njit(cache=True)
def state_jacobian_many(references, xs, nq, mask, n_base, J, values, ok):
    """The Jacobian nonzeros values[k] of x ⊖ x_ref at the nodes with mask[k]: the n_base × n_base
    configuration block of ∂(xs[k] ⊖ references[k])/∂q (``StateMultibody.Jdiff_second_q``, computed
    in the scratch J (nv, nv)) row-major, then the identity entries. ok[k] False where Pinocchio
    must take over (half turn; values[k] then holds only the identity entries). True if none did."""
    all_ok = True
    nb2 = n_base * n_base
    for k in range(mask.size):
        ok[k] = True
        if not mask[k]:
            continue
        for i in range(nb2, values.shape[1]):
            values[k, i] = 1.0
        if not free_flyer_ddifference_second(references[k, :nq], xs[k, :nq], J):
            ok[k] = False
            all_ok = False
            continue
        for a in range(n_base):
            for b in range(n_base):
                values[k, a * n_base + b] = J[a, b]
    return all_ok


@njit(cache=True)
def frame_rows_many(positions, axes, references, mask, r):
    """Frame-position residual rows r[k, a] = positions[k, axes[a]] − references[k, a] [m] for
    the nodes with mask[k]; positions (N, 3) world."""
    for k in range(mask.size):
        if mask[k]:
            for a in range(axes.size):
                r[k, a] = positions[k, axes[a]] - references[k, a]


@njit(cache=True)
def frame_jacobian_rows_many(jacobians, axes, mask, values):
    """Their Jacobian rows values[k] = jacobians[k, axes, :] (row-major; jacobians (N, 3, nv), the
    world-aligned linear rows of a frame's Jacobian, or the centre of mass's) for the nodes with
    mask[k]."""
    nv = jacobians.shape[2]
    for k in range(mask.size):
        if mask[k]:
            for a in range(axes.size):
                for c in range(nv):
                    values[k, a * nv + c] = jacobians[k, axes[a], c]


@njit(cache=True)
def point_height_row(position, R, point, reference):
    """Height residual [m] of a point fixed on a frame: (position + R point)[2] − reference, the
    frame's world position (3,) and rotation R (3, 3), the point (3,) in the frame."""
    return position[2] + R[2, 0] * point[0] + R[2, 1] * point[1] + R[2, 2] * point[2] - reference


@njit(cache=True)
def point_height_jacobian_row(jacobian, R, point, out):
    """Its Jacobian row out (nv,) from the frame's LOCAL_WORLD_ALIGNED Jacobian (6, nv) (linear,
    angular rows): the point's world velocity is v + ω × (R point), whose z row is
    J_v[2] + w_y J_ω[0] − w_x J_ω[1] with w = R point."""
    w_x = R[0, 0] * point[0] + R[0, 1] * point[1] + R[0, 2] * point[2]
    w_y = R[1, 0] * point[0] + R[1, 1] * point[1] + R[1, 2] * point[2]
    for c in range(out.size):
        out[c] = jacobian[2, c] + w_y * jacobian[3, c] - w_x * jacobian[4, c]


@njit(cache=True)
def point_height_rows_many(positions, rotations, point, references, mask, r):
    """:func:`point_height_row` r[k, 0] at the nodes with mask[k]; positions (N, 3), rotations
    (N, 3, 3), references (N, 1)."""
    for k in range(mask.size):
        if mask[k]:
            r[k, 0] = point_height_row(positions[k], rotations[k], point, references[k, 0])


@njit(cache=True)
def point_height_jacobian_many(jacobians, rotations, point, mask, values):
    """:func:`point_height_jacobian_row` into values[k] (nv,) at the nodes with mask[k];
    jacobians (N, 6, nv)."""
    for k in range(mask.size):
        if mask[k]:
            point_height_jacobian_row(jacobians[k], rotations[k], point, values[k])


@njit(cache=True, inline="always")
def _smoothstep(s):
    """(q(s), dq/ds) of the quintic smoothstep q(s) = 10 s³ − 15 s⁴ + 6 s⁵ on [0, 1], clamped outside."""
    s = min(max(s, 0.0), 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s)), 30.0 * s * s * (1.0 - s) * (1.0 - s)


@njit(cache=True, inline="always")
def _box_window(u, half, transition):
    """(S(u), dS/du) of a box's profile along one axis: 1 within ``half`` [m] of the centre, falling to 0 over
    ``transition`` [m] beyond by the smoothstep, 0 farther (u [m] along the axis from the centre)."""
    distance = abs(u) - half
    if distance <= 0.0:
        return 1.0, 0.0
    if distance >= transition:
        return 0.0, 0.0
    value, slope = _smoothstep((transition - distance) / transition)
    return value, -slope / transition * (1.0 if u > 0.0 else -1.0)


@njit(cache=True)
def box_profile(box, transition, ground, x, y):
    """(h, ∂h/∂x, ∂h/∂y) of a box's smoothed height profile at the world point (x, y) [m]:
    h = ground + height S_1(u_1) S_2(u_2), u_i = a_i · ((x, y) − c)
    (:mod:`wbmpc.ocp.residuals.frame_point_above_box`). box (7,): footprint centre c (2,) [m], world
    unit axis a_1 along its depth (2,) (a_2 = a_1 turned by +90°), half extents grown by the margin
    (e_1, e_2) [m], height of the top above the ground [m]; transition [m] (> 0), ground world z [m]."""
    dx, dy = x - box[0], y - box[1]
    a_x, a_y = box[2], box[3]
    s1, d1 = _box_window(a_x * dx + a_y * dy, box[4], transition)
    s2, d2 = _box_window(-a_y * dx + a_x * dy, box[5], transition)
    height = box[6]
    return (ground + height * s1 * s2, height * (d1 * s2 * a_x - s1 * d2 * a_y),
            height * (d1 * s2 * a_y + s1 * d2 * a_x))


@njit(cache=True)
def point_above_box_row(position, R, point, box, transition, ground):
    """Residual [m] of a point fixed on a frame above a box's profile: z_p − h(x_p, y_p), the point
    p = position + R point (the frame's world position (3,), rotation R (3, 3), the point (3,) in
    the frame), h of :func:`box_profile`."""
    x = position[0] + R[0, 0] * point[0] + R[0, 1] * point[1] + R[0, 2] * point[2]
    y = position[1] + R[1, 0] * point[0] + R[1, 1] * point[1] + R[1, 2] * point[2]
    z = position[2] + R[2, 0] * point[0] + R[2, 1] * point[1] + R[2, 2] * point[2]
    return z - box_profile(box, transition, ground, x, y)[0]


@njit(cache=True)
def point_above_box_jacobian_row(position, jacobian, R, point, box, transition, ground, out):
    """Its Jacobian row out (nv,) from the frame's LOCAL_WORLD_ALIGNED Jacobian (6, nv) (linear,
    angular rows): with w = R point, the point's velocity Jacobian J_p = J_v − [w]× J_ω and
    out = J_p[2] − ∇h · J_p[:2]."""
    w_x = R[0, 0] * point[0] + R[0, 1] * point[1] + R[0, 2] * point[2]
    w_y = R[1, 0] * point[0] + R[1, 1] * point[1] + R[1, 2] * point[2]
    w_z = R[2, 0] * point[0] + R[2, 1] * point[1] + R[2, 2] * point[2]
    _, g_x, g_y = box_profile(box, transition, ground, position[0] + w_x, position[1] + w_y)
    for c in range(out.size):
        o_x, o_y, o_z = jacobian[3, c], jacobian[4, c], jacobian[5, c]
        p_x = jacobian[0, c] - (w_y * o_z - w_z * o_y)
        p_y = jacobian[1, c] - (w_z * o_x - w_x * o_z)
        p_z = jacobian[2, c] - (w_x * o_y - w_y * o_x)
        out[c] = p_z - g_x * p_x - g_y * p_y


@njit(cache=True)
def point_above_box_rows_many(positions, rotations, point, boxes, transition, ground, mask, r):
    """:func:`point_above_box_row` r[k, 0] at the nodes with mask[k]; positions (N, 3), rotations
    (N, 3, 3), boxes (N, 7) (each node's box, :func:`box_profile`)."""
    for k in range(mask.size):
        if mask[k]:
            r[k, 0] = point_above_box_row(positions[k], rotations[k], point, boxes[k], transition, ground)


@njit(cache=True)
def point_above_box_jacobian_many(positions, jacobians, rotations, point, boxes, transition, ground, mask, values):
    """:func:`point_above_box_jacobian_row` into values[k] (nv,) at the nodes with mask[k];
    jacobians (N, 6, nv)."""
    for k in range(mask.size):
        if mask[k]:
            point_above_box_jacobian_row(positions[k], jacobians[k], rotations[k], point, boxes[k], transition,
                                         ground, values[k])


@njit(cache=True, inline="always")
def _rotation_error(reference, R, E):
    """E (3, 3) = R_refᵀ R, the reference R_ref given row-major as reference (9,)."""
    for a in range(3):
        for b in range(3):
            E[a, b] = reference[a] * R[0, b] + reference[3 + a] * R[1, b] + reference[6 + a] * R[2, b]


@njit(cache=True)
def frame_rotation_rows(reference, R, r):
    """Frame-rotation residual r (3,) = log3(R_refᵀ R) [rad] (the rotation from the reference to
    the frame, in the frame's axes) of the world rotation R (3, 3) and the reference R_ref
    (row-major (9,)). False (r untouched) within 1e-2 rad of a half turn: the caller then uses
    Pinocchio's log3."""
    E = np.empty((3, 3))
    _rotation_error(reference, R, E)
    return so3_log(E, r) >= 0.0


@njit(cache=True)
def frame_rotation_jacobian(reference, R, J_angular, out):
    """Its Jacobian out (3, nv) = Jlog3(R_refᵀ R) Rᵀ J_angular: J_angular (3, nv) the angular rows
    of the frame's LOCAL_WORLD_ALIGNED Jacobian (Rᵀ J_angular is the LOCAL one). False (out
    untouched) near a half turn, as :func:`frame_rotation_rows`."""
    work = np.empty((4, 3, 3))  # E, Jlog3, Jlog3 Rᵀ and log3(E)
    E, J_log, M, w = work[0], work[1], work[2], work[3, 0]
    _rotation_error(reference, R, E)
    if so3_log(E, w) < 0.0:
        return False
    so3_log_jacobian(w, J_log)
    for a in range(3):
        for b in range(3):
            M[a, b] = J_log[a, 0] * R[b, 0] + J_log[a, 1] * R[b, 1] + J_log[a, 2] * R[b, 2]
    for a in range(3):
        m0, m1, m2 = M[a, 0], M[a, 1], M[a, 2]
        for c in range(J_angular.shape[1]):
            out[a, c] = m0 * J_angular[0, c] + m1 * J_angular[1, c] + m2 * J_angular[2, c]
    return True


@njit(cache=True)
def frame_rotation_rows_many(rotations, references, mask, r, ok):
    """:func:`frame_rotation_rows` at the nodes with mask[k]: rotations (N, 3, 3), references
    (N, 9), r (N, 3); ok[k] False where Pinocchio must take over. True if none did."""
    all_ok = True
    for k in range(mask.size):
        ok[k] = True
        if mask[k] and not frame_rotation_rows(references[k], rotations[k], r[k]):
            ok[k] = False
            all_ok = False
    return all_ok


@njit(cache=True)
def frame_rotation_jacobian_many(rotations, jacobians, references, mask, values, ok):
    """:func:`frame_rotation_jacobian` at the nodes with mask[k]: jacobians (N, 6, nv) the
    LOCAL_WORLD_ALIGNED frame Jacobians (angular rows 3..5), values (N, 3, nv); ok[k] False where
    Pinocchio must take over. True if none did."""
    all_ok = True
    for k in range(mask.size):
        ok[k] = True
        if mask[k] and not frame_rotation_jacobian(references[k], rotations[k], jacobians[k, 3:], values[k]):
            ok[k] = False
            all_ok = False
    return all_ok


@njit(cache=True)
def linear_force_rows(A, force, b, r):
    """Residual rows r (nr,) = A force[:m] − b of a contact force: A (nr, m), force (≥ m,) [N, N·m]
    in the contact's frame, b (nr,)."""
    for i in range(r.size):
        total = -b[i]
        for j in range(A.shape[1]):
            total += A[i, j] * force[j]
        r[i] = total


@njit(cache=True)
def linear_force_jacobian(A, D, out):
    """Their Jacobian out (nr, n) = A D[:m] from the force derivatives D (≥ m, n) (columns: state
    tangent then control, or one of them)."""
    m, n = A.shape[1], D.shape[1]
    for i in range(A.shape[0]):
        for c in range(n):
            out[i, c] = 0.0
        for j in range(m):
            a = A[i, j]
            if a == 0.0:
                continue
            for c in range(n):
                out[i, c] += a * D[j, c]


@njit(cache=True)
def linear_force_rows_many(A, forces, offsets, references, mask, r):
    """:func:`linear_force_rows` at the nodes with mask[k], the contact's force at
    forces[k, offsets[k]:] (forces (N, nc_max), the node's stacked contact forces); returns −1,
    or the first such node whose contact is not in its contact set (offsets[k] < 0)."""
    m = A.shape[1]
    for k in range(mask.size):
        if mask[k]:
            o = offsets[k]
            if o < 0:
                return k
            linear_force_rows(A, forces[k, o:o + m], references[k], r[k])
    return -1


@njit(cache=True)
def linear_force_jacobian_many(A, force_jacobians, offsets, mask, values):
    """:func:`linear_force_jacobian` at the nodes with mask[k], the force derivatives at
    force_jacobians[k, offsets[k]:] ((N, nc_max, ndx + nu): ∂λ/∂x then ∂λ/∂u), values
    (N, nr, ndx + nu); returns −1, or the first such node whose contact is not in its contact set."""
    m = A.shape[1]
    for k in range(mask.size):
        if mask[k]:
            o = offsets[k]
            if o < 0:
                return k
            linear_force_jacobian(A, force_jacobians[k, o:o + m], values[k])
    return -1


def jacobian_blocks(values: np.ndarray, nr: int) -> np.ndarray:
    """The Jacobian nonzeros (N, nr · n) of a term whose pattern is dense row-major over n
    columns, as (N, nr, n) without copying (each node's block written in place by the kernels)."""
    blocks = values.view()
    blocks.shape = (values.shape[0], nr, values.shape[1] // nr)  # raises rather than copy
    return blocks
