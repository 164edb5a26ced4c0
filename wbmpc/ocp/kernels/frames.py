"""Compiled forward kinematics of chosen frames over a whole horizon: world positions [m],
world rotations and LOCAL_WORLD_ALIGNED Jacobians (linear rows, optionally the angular ones:
(3 or 6, nv)), and optionally the centre of mass [m, world] and its Jacobian (3, nv), for a
free-flyer root followed by revolute joints.

Pinocchio gives the same numbers frame by frame (``updateFramePlacement``, ``getFrameJacobian``),
at a binding call each; the batched evaluation (:mod:`wbmpc.ocp.batched_problem`) needs them for the
swing feet at every node, so it reads the kinematic tree once (:class:`FrameKinematics`) and
evaluates all nodes in one compiled pass. Agreement with Pinocchio: ~1e-15
(tests/test_wbmpc_frame_kernels.py).

Conventions: joint i's world placement oMi = oM_parent · jointPlacement_i · exp(axis_i q_i); the
free flyer's joint transform is (R(quaternion), p) with its velocity (v, ω) in its own frame, so
a point p_f moving with the tree has ṗ_f = R₁ v + (R₁ ω) × (p_f − p₁) + Σ_j (R_j a_j) × (p_f − p_j) q̇_j
over the revolute joints j supporting it, and the frame's angular velocity in world axes is
ω_f = R₁ ω + Σ_j (R_j a_j) q̇_j (the angular rows of the LOCAL_WORLD_ALIGNED Jacobian).

Centre of mass (Pinocchio's ``centerOfMass`` / ``jacobianCenterOfMass``): c = Σ_i m_i c_i / M over
the joints' bodies i ≥ 1 (``model.inertias``: mass m_i [kg], centre c_i = p_i + R_i l_i of the
local lever l_i [m]; the universe's inertia is left out, as Pinocchio does), M = Σ_i m_i. With
S_j = Σ_{i ∈ subtree(j)} m_i c_i and M_j its mass, joint j's column of Jcom is
(R_j a_j) × (S_j − M_j p_j) / M for a revolute joint, and for the free flyer
[R₁ M₁ / M, −[(S₁ − M₁ p₁) / M]× R₁] (linear, angular velocity in its own frame).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.lie import quaternion_matrix
from wbmpc.ocp.kernels.linalg import mat3_mul, mat3_vec
from wbmpc.ocp.kernels.tree import KinematicTree, axis_rotation


class FrameKinematics:
    """The kinematic tree of ``model`` (its bodies' masses and centres too) and the frames
    ``frame_ids``, as arrays for the kernels.

    Args:
        model: Pinocchio model, free-flyer root followed by revolute joints (RX, RY, RZ,
            unaligned); raises :class:`~wbmpc.errors.ParameterError` otherwise.
        frame_ids: frames to evaluate; slot s of the outputs is ``frame_ids[s]`` (may be empty:
            the centre of mass only).
    """

    def __init__(self, model: pin.Model, frame_ids):
        tree = KinematicTree(model)  # the tree's arrays (raises for an unsupported model)
        n = model.njoints
        self.parents, self.axes, self.idx_q, self.idx_v = tree.parents, tree.axes, tree.idx_q, tree.idx_v
        self.placement_rotation, self.placement_translation = tree.placement_rotation, tree.placement_translation
        self.frame_ids = [int(f) for f in frame_ids]
        frames = [model.frames[f] for f in self.frame_ids]
        self.frame_joint = np.array([f.parentJoint for f in frames], dtype=np.int64)
        self.frame_rotation = np.array([f.placement.rotation for f in frames]).reshape(len(frames), 3, 3)
        self.frame_translation = np.array([f.placement.translation for f in frames]).reshape(len(frames), 3)
        self.support = np.zeros((len(frames), n), dtype=np.bool_)  # joints moving each frame
        for s, f in enumerate(frames):
            for j in model.supports[f.parentJoint]:
                self.support[s, j] = True
        self.nv = model.nv
        # each joint's body (Pinocchio's inertias, the universe's left out as centerOfMass does)
        self.mass = np.array([0.0] + [model.inertias[i].mass for i in range(1, n)])  # [kg]
        self.lever = np.array([np.zeros(3)] + [model.inertias[i].lever for i in range(1, n)])  # [m], joint frame
        self.total_mass = float(self.mass.sum())  # [kg]
        if not self.total_mass > 0.0:
            raise ParameterError(f"model {model.name!r} has a total mass of {self.total_mass!r} kg: > 0 needed")

    def evaluate(self, qs: np.ndarray, needed: np.ndarray, positions: np.ndarray,
                 jacobians: np.ndarray | None = None, rotations: np.ndarray | None = None,
                 com_needed: np.ndarray | None = None, com: np.ndarray | None = None,
                 com_jacobians: np.ndarray | None = None) -> None:
        """World positions (T, n_frames, 3) [m] and, if given, LOCAL_WORLD_ALIGNED Jacobians
        (T, n_frames, 3, nv) (linear rows) or (T, n_frames, 6, nv) (linear then angular rows) and
        world rotations (T, n_frames, 3, 3) of the frames with ``needed[t, s]`` at the
        configurations ``qs`` (T, nq); with ``com_needed`` (T,) the centre of mass com (T, 3) [m,
        world] and, if given, its Jacobian com_jacobians (T, 3, nv) at the t with com_needed[t];
        other entries are untouched."""
        if jacobians is not None and jacobians.shape[2] not in (3, 6):
            raise ParameterError(f"jacobians has shape {jacobians.shape}: 3 (linear) or 6 (linear, angular) rows allowed")
        with_com = com_needed is not None
        if with_com and com is None:
            raise ParameterError("com=None with com_needed given: the centre of mass needs its (T, 3) output array")
        frame_kinematics(qs, needed, self.parents, self.placement_rotation, self.placement_translation, self.axes,
                         self.idx_q, self.idx_v, self.frame_joint, self.frame_rotation, self.frame_translation,
                         self.support, positions, jacobians if jacobians is not None else np.zeros((0, 0, 3, 0)),
                         jacobians is not None, rotations if rotations is not None else np.zeros((0, 0, 3, 3)),
                         rotations is not None, self.mass, self.lever, self.total_mass,
                         com_needed if with_com else np.zeros(0, dtype=np.bool_), com if with_com else np.zeros((0, 3)),
                         com_jacobians if with_com and com_jacobians is not None else np.zeros((1, 3, 0)), with_com,
                         with_com and com_jacobians is not None)


@njit(cache=True)
def frame_kinematics(qs, needed, parents, placement_rotation, placement_translation, axes, idx_q, idx_v, frame_joint,
                     frame_rotation, frame_translation, support, positions, jacobians, with_jacobians, rotations,
                     with_rotations, mass, lever, total_mass, com_needed, com, com_jacobians, with_com,
                     with_com_jacobians):
    """Kernel of :meth:`FrameKinematics.evaluate` (angular Jacobian rows when jacobians has 6 rows;
    the centre of mass where with_com and com_needed[t], by :func:`_center_of_mass`)."""
    n_joints = parents.size
    n_frames = frame_joint.size
    R = np.zeros((n_joints, 3, 3))  # world rotation of each joint frame
    p = np.zeros((n_joints, 3))  # world position of each joint origin
    R[0] = np.eye(3)
    local = np.empty((3, 3))
    Rp = np.empty((3, 3))
    offset = np.empty(3)
    pf = np.empty(3)
    w = np.empty(3)
    subtree_moment = np.zeros((n_joints, 3))  # scratch of _center_of_mass
    subtree_mass = np.zeros(n_joints)
    for t in range(qs.shape[0]):
        any_needed = with_com and com_needed[t]
        for s in range(n_frames):
            if needed[t, s]:
                any_needed = True
        if not any_needed:
            continue
        q = qs[t]
        for i in range(1, n_joints):
            parent = parents[i]
            # parent · placement
            mat3_mul(R[parent], placement_rotation[i], Rp)
            mat3_vec(R[parent], placement_translation[i], offset)
            if i == 1:  # free flyer: (R(quaternion), position)
                quaternion_matrix(q[3:7], local)
                mat3_mul(Rp, local, R[i])
                for a in range(3):
                    p[i, a] = p[parent, a] + offset[a] + Rp[a, 0] * q[0] + Rp[a, 1] * q[1] + Rp[a, 2] * q[2]
            else:
                axis_rotation(axes[i], q[idx_q[i]], local)
                mat3_mul(Rp, local, R[i])
                for a in range(3):
                    p[i, a] = p[parent, a] + offset[a]
        if with_com and com_needed[t]:
            _center_of_mass(R, p, parents, axes, idx_v, mass, lever, total_mass, subtree_moment, subtree_mass, com[t],
                            com_jacobians[t if with_com_jacobians else 0], with_com_jacobians)
        for s in range(n_frames):
            if not needed[t, s]:
                continue
            j = frame_joint[s]
            mat3_vec(R[j], frame_translation[s], pf)
            for a in range(3):
                pf[a] += p[j, a]
                positions[t, s, a] = pf[a]
            if with_rotations:
                mat3_mul(R[j], frame_rotation[s], rotations[t, s])
            if not with_jacobians:
                continue
            J = jacobians[t, s]
            angular = J.shape[0] == 6
            J[:, :] = 0.0
            for i in range(1, n_joints):
                if not support[s, i]:
                    continue
                r0, r1, r2 = pf[0] - p[i, 0], pf[1] - p[i, 1], pf[2] - p[i, 2]
                if i == 1:  # base: linear R₁, angular −[r]× R₁ (linear rows), R₁ (angular rows)
                    v0 = idx_v[i]
                    for a in range(3):
                        for b in range(3):
                            J[a, v0 + b] = R[i, a, b]
                    for b in range(3):
                        w0, w1, w2 = R[i, 0, b], R[i, 1, b], R[i, 2, b]
                        J[0, v0 + 3 + b] = w1 * r2 - w2 * r1
                        J[1, v0 + 3 + b] = w2 * r0 - w0 * r2
                        J[2, v0 + 3 + b] = w0 * r1 - w1 * r0
                        if angular:
                            J[3, v0 + 3 + b] = w0
                            J[4, v0 + 3 + b] = w1
                            J[5, v0 + 3 + b] = w2
                else:  # revolute: (R_i a_i) × (p_f − p_i)
                    mat3_vec(R[i], axes[i], w)
                    col = idx_v[i]
                    J[0, col] = w[1] * r2 - w[2] * r1
                    J[1, col] = w[2] * r0 - w[0] * r2
                    J[2, col] = w[0] * r1 - w[1] * r0
                    if angular:
                        J[3, col] = w[0]
                        J[4, col] = w[1]
                        J[5, col] = w[2]


@njit(cache=True)
def _center_of_mass(R, p, parents, axes, idx_v, mass, lever, total_mass, moment, subtree_mass, com, J, with_jacobian):
    """The centre of mass com (3,) [m, world] and, with_jacobian, its Jacobian J (3, nv) (the module
    docstring) from the joints' world rotations R (n_joints, 3, 3) and origins p (n_joints, 3) [m];
    mass (n_joints,) [kg] (0 for the universe), lever (n_joints, 3) [m] in each joint's frame;
    moment (n_joints, 3) and subtree_mass (n_joints,) are scratch (S_j, M_j)."""
    n_joints = parents.size
    for i in range(n_joints):
        subtree_mass[i] = mass[i]
        for a in range(3):
            moment[i, a] = mass[i] * (p[i, a] + R[i, a, 0] * lever[i, 0] + R[i, a, 1] * lever[i, 1]
                                      + R[i, a, 2] * lever[i, 2])
    for i in range(n_joints - 1, 0, -1):  # children after their parents: S_j, M_j of every subtree
        parent = parents[i]
        subtree_mass[parent] += subtree_mass[i]
        for a in range(3):
            moment[parent, a] += moment[i, a]
    for a in range(3):
        com[a] = moment[0, a] / total_mass
    if not with_jacobian:
        return
    J[:, :] = 0.0
    for i in range(1, n_joints):
        if subtree_mass[i] == 0.0:
            continue
        # (S_i − M_i p_i) / M: the subtree's mass-weighted lever about the joint's origin
        r0 = (moment[i, 0] - subtree_mass[i] * p[i, 0]) / total_mass
        r1 = (moment[i, 1] - subtree_mass[i] * p[i, 1]) / total_mass
        r2 = (moment[i, 2] - subtree_mass[i] * p[i, 2]) / total_mass
        if i == 1:  # free flyer: linear R₁ M₁ / M, angular (R₁ e_b) × r
            v0 = idx_v[i]
            share = subtree_mass[i] / total_mass
            for b in range(3):
                w0, w1, w2 = R[i, 0, b], R[i, 1, b], R[i, 2, b]
                J[0, v0 + b] = w0 * share
                J[1, v0 + b] = w1 * share
                J[2, v0 + b] = w2 * share
                J[0, v0 + 3 + b] = w1 * r2 - w2 * r1
                J[1, v0 + 3 + b] = w2 * r0 - w0 * r2
                J[2, v0 + 3 + b] = w0 * r1 - w1 * r0
        else:  # revolute: (R_i a_i) × r
            w0 = R[i, 0, 0] * axes[i, 0] + R[i, 0, 1] * axes[i, 1] + R[i, 0, 2] * axes[i, 2]
            w1 = R[i, 1, 0] * axes[i, 0] + R[i, 1, 1] * axes[i, 1] + R[i, 1, 2] * axes[i, 2]
            w2 = R[i, 2, 0] * axes[i, 0] + R[i, 2, 1] * axes[i, 1] + R[i, 2, 2] * axes[i, 2]
            col = idx_v[i]
            J[0, col] = w1 * r2 - w2 * r1
            J[1, col] = w2 * r0 - w0 * r2
            J[2, col] = w0 * r1 - w1 * r0
