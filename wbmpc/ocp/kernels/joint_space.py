"""Compiled joint-space terms of the equations of motion M(q) a + b(q, v) = τ of a kinematic tree: the
joint-space inertia M (Pinocchio's ``crba`` with ``pin.Convention.WORLD``: the upper triangle, the rotor
armature on the diagonal) and the nonlinear effects b = RNEA(q, v, 0) (``nonLinearEffects``: Coriolis,
centrifugal and gravity terms), from what :func:`~wbmpc.ocp.kernels.tree.tree_motion` leaves at
(q, v, a = 0) (world placements, velocities, bias accelerations and Jacobian columns), so that a node's
kinematics, M and b are one compiled pass over the tree.

Everything is in the world frame, about the world origin (Pinocchio's WORLD convention). A link i of mass
m_i, centre of mass l_i and rotational inertia I_i about it (both in the joint frame, ``model.inertias``)
has the world spatial inertia (m_i, h_i = m_i c_i, I_O,i) with c_i = p_i + R_i l_i [m] and
I_O,i = R_i I_i R_iᵀ + m_i (|c_i|² 1 − c_i c_iᵀ) [kg·m²]; applied to a motion (v, ω) (linear, angular) it
gives the force (m v + ω × h, I_O ω + h × v) [N, N·m], and inertias about one point add.

- M (:func:`joint_space_inertia`): the composite inertia Y_i of the subtree of joint i (leaves first),
  M[k, c] = S_kᵀ Y_i S_c for every column c of joint i and every column k ≤ c of its support (its
  ancestors' and its own), plus the armature on the diagonal;
- b (:func:`nonlinear_effects`): each link's force f_i = Y_i (oa_i − (g, 0)) + ov_i ×* (Y_i ov_i) at the
  bias acceleration oa_i (the tree's accelerations at a = 0) and gravity g (``model.gravity``), summed
  into the parents (leaves first), b[c] = S_cᵀ f_i for the columns c of joint i; (v, ω) ×* (f, n) =
  (ω × f, v × f + ω × n).

Agreement with Pinocchio: ~1e-15 relative (tests/test_wbmpc_joint_space_kernels.py).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.tree import KinematicTree, require_tree_support


class LinkInertias:
    """The link inertias of ``model`` as arrays for the kernels, and the kernels' scratch.

    Attributes (n joints, universe included): mass (n,) [kg], lever (n, 3) [m] centre of mass and
    rotational (n, 3, 3) [kg·m²] rotational inertia about it, both in the joint frame (``model.inertias``),
    armature (nv,) [kg·m², kg] (``model.armature``), gravity (3,) [m/s²] (``model.gravity.linear``);
    scratch body, composite (n, 10) (a world spatial inertia: m, h (3,), the upper triangle of I_O (6,),
    row by row) and force (n, 6).

    Raises:
        ParameterError: the model is not a free-flyer root followed by revolute joints.
    """

    def __init__(self, model: pin.Model):
        require_tree_support(model, "the compiled joint-space terms")
        n = model.njoints
        self.nv = model.nv
        self.mass = np.array([model.inertias[i].mass for i in range(n)])
        self.lever = np.array([model.inertias[i].lever for i in range(n)]).reshape(n, 3)
        self.rotational = np.array([model.inertias[i].inertia for i in range(n)]).reshape(n, 3, 3)
        self.armature = np.array(model.armature, dtype=float).reshape(model.nv)
        self.gravity = np.array(model.gravity.linear, dtype=float)
        self.body = np.zeros((n, 10))
        self.composite = np.zeros((n, 10))
        self.force = np.zeros((n, 6))

    def arguments(self) -> tuple:
        """The arguments of :func:`joint_space_terms` after the tree's (mass ... force)."""
        return (self.mass, self.lever, self.rotational, self.armature, self.gravity, self.body, self.composite,
                self.force)

    def evaluate(self, tree: KinematicTree, M: np.ndarray, b: np.ndarray) -> None:
        """M (nv, nv) (upper triangle; the strict lower one is left as it is) and b (nv,) at the state of the
        last ``tree.evaluate(q, v, 0)`` (zero joint accelerations: b reads the bias accelerations)."""
        nv = self.nv
        if tree.nv != nv:
            raise ParameterError(f"tree has nv={tree.nv}, the link inertias nv={nv}")
        if np.shape(M) != (nv, nv):
            raise ParameterError(f"M has shape {np.shape(M)}, expected ({nv}, {nv})")
        if np.shape(b) != (nv,):
            raise ParameterError(f"b has shape {np.shape(b)}, expected ({nv},)")
        joint_space_terms(tree.parents, tree.idx_v, tree.R, tree.p, tree.ov, tree.oa, tree.J, *self.arguments(), M, b)


@njit(cache=True, inline="always")
def apply_inertia(Y, v0, v1, v2, w0, w1, w2, out):
    """out (6,) = the force of the world spatial inertia Y (10,) applied to the motion (v, ω)."""
    m, h0, h1, h2 = Y[0], Y[1], Y[2], Y[3]
    out[0] = m * v0 + w1 * h2 - w2 * h1
    out[1] = m * v1 + w2 * h0 - w0 * h2
    out[2] = m * v2 + w0 * h1 - w1 * h0
    out[3] = Y[4] * w0 + Y[5] * w1 + Y[6] * w2 + h1 * v2 - h2 * v1
    out[4] = Y[5] * w0 + Y[7] * w1 + Y[8] * w2 + h2 * v0 - h0 * v2
    out[5] = Y[6] * w0 + Y[8] * w1 + Y[9] * w2 + h0 * v1 - h1 * v0


@njit(cache=True)
def body_inertias(R, p, mass, lever, rotational, body):
    """Every link's world spatial inertia body (n, 10) (the module's (m, h, I_O)) at the world placements
    R (n, 3, 3), p (n, 3) of :func:`~wbmpc.ocp.kernels.tree.tree_motion` (row 0, the universe, zero)."""
    body[0, :] = 0.0
    c = np.empty(3)
    RI = np.empty((3, 3))
    for i in range(1, mass.size):
        Ri, m = R[i], mass[i]
        for a in range(3):
            c[a] = p[i, a] + Ri[a, 0] * lever[i, 0] + Ri[a, 1] * lever[i, 1] + Ri[a, 2] * lever[i, 2]
        for a in range(3):
            for k in range(3):
                RI[a, k] = Ri[a, 0] * rotational[i, 0, k] + Ri[a, 1] * rotational[i, 1, k] + Ri[a, 2] * rotational[i, 2, k]
        c2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2]
        Y = body[i]
        Y[0] = m
        Y[1], Y[2], Y[3] = m * c[0], m * c[1], m * c[2]
        slot = 4
        for a in range(3):
            for k in range(a, 3):
                s = RI[a, 0] * Ri[k, 0] + RI[a, 1] * Ri[k, 1] + RI[a, 2] * Ri[k, 2] - m * c[a] * c[k]
                if a == k:
                    s += m * c2
                Y[slot] = s
                slot += 1


@njit(cache=True)
def joint_space_inertia(parents, idx_v, J, armature, body, composite, M):
    """M (nv, nv), its upper triangle (the strict lower triangle untouched), from the links' world inertias
    body (n, 10) (:func:`body_inertias`) and the world Jacobian columns J (6, nv) of
    :func:`~wbmpc.ocp.kernels.tree.tree_motion`; composite (n, 10) scratch (the subtrees' inertias)."""
    nv = M.shape[0]
    for r in range(nv):
        for c in range(r, nv):
            M[r, c] = 0.0
        M[r, r] = armature[r]
    composite[:, :] = body
    F = np.empty(6)
    for i in range(parents.size - 1, 0, -1):
        Y = composite[i]
        first = idx_v[i]
        count = 6 if i == 1 else 1
        for c in range(first, first + count):
            apply_inertia(Y, J[0, c], J[1, c], J[2, c], J[3, c], J[4, c], J[5, c], F)
            for k in range(first, c + 1):  # the joint's own columns up to c
                M[k, c] += (J[0, k] * F[0] + J[1, k] * F[1] + J[2, k] * F[2] + J[3, k] * F[3] + J[4, k] * F[4]
                            + J[5, k] * F[5])
            j = parents[i]
            while j > 0:  # the ancestors' columns
                start = idx_v[j]
                for k in range(start, start + (6 if j == 1 else 1)):
                    M[k, c] += (J[0, k] * F[0] + J[1, k] * F[1] + J[2, k] * F[2] + J[3, k] * F[3] + J[4, k] * F[4]
                                + J[5, k] * F[5])
                j = parents[j]
        parent = parents[i]
        if parent > 0:
            for s in range(10):
                composite[parent, s] += Y[s]


@njit(cache=True)
def nonlinear_effects(parents, idx_v, ov, oa, J, gravity, body, force, b):
    """b (nv,) = RNEA(q, v, 0) from the links' world inertias body (n, 10) (:func:`body_inertias`), the world
    velocities ov (n, 6), bias accelerations oa (n, 6) (at zero joint accelerations) and Jacobian columns
    J (6, nv) of :func:`~wbmpc.ocp.kernels.tree.tree_motion`, gravity (3,) [m/s²]; force (n, 6) scratch (the
    subtrees' forces, world, about the origin)."""
    h = np.empty(6)
    f = np.empty(6)
    n = parents.size
    for i in range(1, n):
        Y = body[i]
        vi = ov[i]
        apply_inertia(Y, oa[i, 0] - gravity[0], oa[i, 1] - gravity[1], oa[i, 2] - gravity[2], oa[i, 3], oa[i, 4],
                       oa[i, 5], f)
        apply_inertia(Y, vi[0], vi[1], vi[2], vi[3], vi[4], vi[5], h)
        v0, v1, v2, w0, w1, w2 = vi[0], vi[1], vi[2], vi[3], vi[4], vi[5]
        force[i, 0] = f[0] + w1 * h[2] - w2 * h[1]
        force[i, 1] = f[1] + w2 * h[0] - w0 * h[2]
        force[i, 2] = f[2] + w0 * h[1] - w1 * h[0]
        force[i, 3] = f[3] + v1 * h[2] - v2 * h[1] + w1 * h[5] - w2 * h[4]
        force[i, 4] = f[4] + v2 * h[0] - v0 * h[2] + w2 * h[3] - w0 * h[5]
        force[i, 5] = f[5] + v0 * h[1] - v1 * h[0] + w0 * h[4] - w1 * h[3]
    for i in range(n - 1, 0, -1):
        fi = force[i]
        first = idx_v[i]
        for c in range(first, first + (6 if i == 1 else 1)):
            b[c] = (J[0, c] * fi[0] + J[1, c] * fi[1] + J[2, c] * fi[2] + J[3, c] * fi[3] + J[4, c] * fi[4]
                    + J[5, c] * fi[5])
        parent = parents[i]
        if parent > 0:
            for s in range(6):
                force[parent, s] += fi[s]


@njit(cache=True)
def joint_space_terms(parents, idx_v, R, p, ov, oa, J, mass, lever, rotational, armature, gravity, body, composite,
                      force, M, b):
    """M (nv, nv) (upper triangle) and b (nv,) (:func:`joint_space_inertia`, :func:`nonlinear_effects`) after
    :func:`~wbmpc.ocp.kernels.tree.tree_motion` at (q, v, 0) (its parents ... J), from the link inertias
    mass ... gravity and scratch body, composite, force of :class:`LinkInertias`."""
    body_inertias(R, p, mass, lever, rotational, body)
    joint_space_inertia(parents, idx_v, J, armature, body, composite, M)
    nonlinear_effects(parents, idx_v, ov, oa, J, gravity, body, force, b)
