"""Compiled derivatives of the inverse dynamics τ = RNEA(q, v, a, f_ext) of a kinematic tree with respect to
q and v (Pinocchio's ``computeRNEADerivatives(model, data, q, v, a, fext)``: ∂τ/∂q and ∂τ/∂v (nv, nv)), from
what :func:`~wbmpc.ocp.kernels.tree.tree_motion` leaves at (q, v, a) (world placements, velocities,
accelerations and Jacobian columns): the world-frame algorithm of Carpentier & Mansard 2018, "Analytical
derivatives of rigid body dynamics algorithms", rearranged so that a body's inertia variation is 12 numbers.

Everything is in the world frame, about the world origin, in the conventions of
:mod:`~wbmpc.ocp.kernels.joint_space` (motions and forces (linear, angular), a link's world spatial inertia
Y = (m, h, I_O), m × m' the cross product of motions, m ×* f that of a motion on a force). With gravity g
(``model.gravity``) in the accelerations, oa_i^g = oa_i − (g, 0) (Pinocchio's ``a_gf``; the universe's is
(−g, 0)), each link's force is f_i = Y_i oa_i^g + ov_i ×* (Y_i ov_i) − f_ext,i, the external force f_ext,i
given in joint i's LOCAL frame [N, N·m] (Pinocchio's ``fext``) and moved to the world; F_i is their sum over
the subtree of joint i, and τ_j = S_jᵀ F_i for the columns j of joint i.

A column c (joint k, parent λ(k), world column S_c) moves the subtree of k rigidly by the twist S_c δq_c:
Pinocchio's tangent space, the free flyer's (q ⊕ δ) = q · exp(δ) in its LOCAL frame, whose columns are
S_c = X_1 e_c. Everything in that subtree moves with it (Y, f_ext, the columns S), but the velocities and
accelerations of its links change by more than that rigid motion, by the same motions for every link
(the module's per-column motions):

    ∂v/∂q_c = ov_λ × S_c,  ∂a/∂q_c = oa^g_λ × S_c + ov_λ × (ov_λ × S_c)   (zero, and (−g, 0) × S_c, at the root),
    ∂v/∂v_c = S_c,          ∂a/∂v_c = ov_k × S_c + ov_λ × S_c,

plus a link-dependent part that folds into the link's inertia variation B_i, the derivative of its force
with respect to a velocity change δv of the link: B_i δv = δv ×* h_i + ov_i ×* (Y_i δv) − Y_i (ov_i × δv),
h_i = Y_i ov_i = (l_i, k_i) its momentum. Written out, B_i (u, x) = (−2 l_i × x, D_i x − k_i × x) with the
symmetric D_i = [ω_i]× I_O,i − I_O,i [ω_i]× − (h_i v_iᵀ + v_i h_iᵀ) + 2 (v_i · h_i) 1, ov_i = (v_i, ω_i) and
h_i = m_i c_i the first moment: B_i reads the angular part only, and a subtree's Σ B_i is its summed momentum
and D (3 + 3 + 6 numbers). With Y, B, F the subtree sums of joint i and the rigid motion cancelling on
S_j and on F (S_jᵀ (S_c ×* F) = −(S_c × S_j)ᵀ F), for a column j of joint i and c of joint k:

- k an ancestor of i, or i itself (c in the support of i): ∂τ_j/∂q_c = S_jᵀ (B_i ∂v/∂q_c + Y_i ∂a/∂q_c),
  ∂τ_j/∂v_c = S_jᵀ (B_i S_c + Y_i ∂a/∂v_c);
- k a strict descendant of i: ∂τ_j/∂q_c = S_jᵀ (B_k ∂v/∂q_c + Y_k ∂a/∂q_c + S_c ×* F_k) and
  ∂τ_j/∂v_c = S_jᵀ (B_k S_c + Y_k ∂a/∂v_c) (the subtree of k moves, f_ext included; the first formula at k);
- otherwise 0.

Agreement with Pinocchio: ~1e-16 relative to the largest entry near the origin, ~5e-14 with the base 10 m away
(both compute about the world origin) (tests/test_wbmpc_rnea_derivatives.py). ~6.5 µs on the H1 inside a kernel,
where the binding call takes 25-30 µs.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.joint_space import LinkInertias, apply_inertia, body_inertias
from wbmpc.ocp.kernels.tree import KinematicTree, cross_motion, require_tree_support


class RNEADerivatives:
    """The scratch of :func:`rnea_derivatives` for ``model`` (n joints, universe included, nv velocities):
    composite (n, 10) (the subtrees' world inertias, :mod:`~wbmpc.ocp.kernels.joint_space`'s layout),
    variation (n, 12) (the subtrees' inertia variations: summed momentum (l, k) and D's upper triangle, row by
    row), force (n, 6) (the subtrees' forces F), motions (4, nv, 6) (per column: S, ∂v/∂q, ∂a/∂q, ∂a/∂v).

    Raises:
        ParameterError: the model is not a free-flyer root followed by revolute joints.
    """

    def __init__(self, model: pin.Model):
        require_tree_support(model, "the compiled RNEA derivatives")
        n = model.njoints
        self.nv = model.nv
        self.composite = np.zeros((n, 10))
        self.variation = np.zeros((n, 12))
        self.force = np.zeros((n, 6))
        self.motions = np.zeros((4, model.nv, 6))

    def arguments(self) -> tuple:
        """The scratch arguments of :func:`rnea_derivatives` (composite ... motions)."""
        return self.composite, self.variation, self.force, self.motions

    def evaluate(self, tree: KinematicTree, links: LinkInertias, fext_joints: np.ndarray, fext: np.ndarray,
                 dtau_dq: np.ndarray, dtau_dv: np.ndarray) -> None:
        """∂τ/∂q and ∂τ/∂v (nv, nv) at the state of the last ``tree.evaluate(q, v, a)``, with the external
        forces fext (k, 6) [N, N·m] on the joints fext_joints (k,) (LOCAL frames, Pinocchio's ``fext``; a joint
        may appear more than once, its forces add)."""
        nv = self.nv
        if tree.nv != nv or links.nv != nv:
            raise ParameterError(f"tree has nv={tree.nv}, the link inertias nv={links.nv}, the derivatives nv={nv}")
        for name, array in (("dtau_dq", dtau_dq), ("dtau_dv", dtau_dv)):
            if np.shape(array) != (nv, nv):
                raise ParameterError(f"{name} has shape {np.shape(array)}, expected ({nv}, {nv})")
        fext_joints = np.asarray(fext_joints, dtype=np.int64).reshape(-1)
        fext = np.asarray(fext, dtype=float).reshape(fext_joints.size, 6)
        if fext_joints.size and not (fext_joints.min() >= 1 and fext_joints.max() < tree.parents.size):
            raise ParameterError(f"fext_joints={fext_joints.tolist()} must be joints 1 .. {tree.parents.size - 1}")
        rnea_derivatives(tree.parents, tree.idx_v, tree.R, tree.p, tree.ov, tree.oa, tree.J, links.mass, links.lever,
                         links.rotational, links.gravity, links.body, fext_joints, fext, *self.arguments(), dtau_dq,
                         dtau_dv)


@njit(cache=True, inline="always")
def _variation_apply(B, x0, x1, x2, out):
    """out (6,) = the inertia variation B (12,) (the module's B, its momentum (l, k) then D's upper triangle)
    applied to a motion of angular part (x0, x1, x2) (B reads no linear part)."""
    l0, l1, l2, k0, k1, k2 = B[0], B[1], B[2], B[3], B[4], B[5]
    out[0] = -2.0 * (l1 * x2 - l2 * x1)
    out[1] = -2.0 * (l2 * x0 - l0 * x2)
    out[2] = -2.0 * (l0 * x1 - l1 * x0)
    out[3] = B[6] * x0 + B[7] * x1 + B[8] * x2 - (k1 * x2 - k2 * x1)
    out[4] = B[7] * x0 + B[9] * x1 + B[10] * x2 - (k2 * x0 - k0 * x2)
    out[5] = B[8] * x0 + B[10] * x1 + B[11] * x2 - (k0 * x1 - k1 * x0)


@njit(cache=True, inline="always")
def _cross_force(m, f, out):
    """out (6,) = m × f, a motion (linear, angular) on a force (linear, angular)."""
    v0, v1, v2, w0, w1, w2 = m[0], m[1], m[2], m[3], m[4], m[5]
    f0, f1, f2, n0, n1, n2 = f[0], f[1], f[2], f[3], f[4], f[5]
    out[0] = w1 * f2 - w2 * f1
    out[1] = w2 * f0 - w0 * f2
    out[2] = w0 * f1 - w1 * f0
    out[3] = v1 * f2 - v2 * f1 + w1 * n2 - w2 * n1
    out[4] = v2 * f0 - v0 * f2 + w2 * n0 - w0 * n2
    out[5] = v0 * f1 - v1 * f0 + w0 * n1 - w1 * n0


@njit(cache=True)
def rnea_derivatives(parents, idx_v, R, p, ov, oa, J, mass, lever, rotational, gravity, body, fext_joints, fext,
                     composite, variation, force, motions, dtau_dq, dtau_dv):
    """∂τ/∂q and ∂τ/∂v (nv, nv) of τ = RNEA(q, v, a, f_ext) (the module's formulas), every entry written.

    Args:
        parents ... J: :func:`~wbmpc.ocp.kernels.tree.tree_motion`'s outputs at (q, v, a) (the accelerations a
            of the node, e.g. after :func:`~wbmpc.ocp.kernels.tree.tree_accelerations`), J (6, nv).
        mass, lever, rotational, gravity: :class:`~wbmpc.ocp.kernels.joint_space.LinkInertias`'s; body (n, 10)
            scratch (the links' world inertias at q).
        fext_joints (k,) int64, fext (k, 6): external spatial forces [N, N·m] on those joints, each in its
            joint's LOCAL frame (repeated joints add).
        composite, variation, force, motions: :class:`RNEADerivatives`'s scratch.
        dtau_dq, dtau_dv (nv, nv): outputs.
    """
    n = parents.size
    body_inertias(R, p, mass, lever, rotational, body)
    dtau_dq[:, :] = 0.0  # the entries of two joints neither of which supports the other
    dtau_dv[:, :] = 0.0
    g0, g1, g2 = gravity[0], gravity[1], gravity[2]
    momentum = np.empty(6)
    acceleration = np.empty(6)
    # the links: composite = Y, variation = (h, D), force = Y oa^g + ov ×* h
    for i in range(1, n):
        Y = body[i]
        vi = ov[i]
        composite[i, :] = Y
        apply_inertia(Y, vi[0], vi[1], vi[2], vi[3], vi[4], vi[5], momentum)
        apply_inertia(Y, oa[i, 0] - g0, oa[i, 1] - g1, oa[i, 2] - g2, oa[i, 3], oa[i, 4], oa[i, 5], acceleration)
        _cross_force(vi, momentum, force[i])
        for b in range(6):
            force[i, b] += acceleration[b]
        B = variation[i]
        for b in range(6):
            B[b] = momentum[b]
        # D = [ω]× I − I [ω]× − (h vᵀ + v hᵀ) + 2 (v · h) 1, upper triangle
        v0, v1, v2, w0, w1, w2 = vi[0], vi[1], vi[2], vi[3], vi[4], vi[5]
        h0, h1, h2 = Y[1], Y[2], Y[3]
        I00, I01, I02, I11, I12, I22 = Y[4], Y[5], Y[6], Y[7], Y[8], Y[9]
        # W I (row a, column b) with W = [ω]×: rows (0, −w2, w1), (w2, 0, −w0), (−w1, w0, 0)
        WI00 = -w2 * I01 + w1 * I02
        WI01 = -w2 * I11 + w1 * I12
        WI02 = -w2 * I12 + w1 * I22
        WI11 = w2 * I01 - w0 * I12
        WI12 = w2 * I02 - w0 * I22
        WI22 = -w1 * I02 + w0 * I12
        WI10 = w2 * I00 - w0 * I02
        WI20 = -w1 * I00 + w0 * I01
        WI21 = -w1 * I01 + w0 * I11
        vh = 2.0 * (v0 * h0 + v1 * h1 + v2 * h2)
        # (W I − I W)[a, b] = WI[a, b] + WI[b, a] (I W = −(W I)ᵀ)
        B[6] = 2.0 * WI00 - 2.0 * h0 * v0 + vh
        B[7] = WI01 + WI10 - (h0 * v1 + v0 * h1)
        B[8] = WI02 + WI20 - (h0 * v2 + v0 * h2)
        B[9] = 2.0 * WI11 - 2.0 * h1 * v1 + vh
        B[10] = WI12 + WI21 - (h1 * v2 + v1 * h2)
        B[11] = 2.0 * WI22 - 2.0 * h2 * v2 + vh
    for e in range(fext_joints.size):  # − X_i^* f_ext: (R f, R n + p × R f)
        i = fext_joints[e]
        Ri, pi = R[i], p[i]
        fe = fext[e]
        for b in range(3):
            lin = Ri[b, 0] * fe[0] + Ri[b, 1] * fe[1] + Ri[b, 2] * fe[2]
            acceleration[b] = lin
            acceleration[3 + b] = Ri[b, 0] * fe[3] + Ri[b, 1] * fe[4] + Ri[b, 2] * fe[5]
        acceleration[3] += pi[1] * acceleration[2] - pi[2] * acceleration[1]
        acceleration[4] += pi[2] * acceleration[0] - pi[0] * acceleration[2]
        acceleration[5] += pi[0] * acceleration[1] - pi[1] * acceleration[0]
        for b in range(6):
            force[i, b] -= acceleration[b]
    # per column c: S_c and the motions ∂v/∂q (dV), ∂a/∂q (dAq), ∂a/∂v (dAv), each a contiguous 6-vector
    S_all, dV, dAq, dAv = motions[0], motions[1], motions[2], motions[3]
    t = np.empty(6)
    u = np.empty(6)
    oa_parent = np.empty(6)
    for i in range(1, n):
        parent = parents[i]
        first = idx_v[i]
        if parent > 0:
            for b in range(6):
                oa_parent[b] = oa[parent, b]
            oa_parent[0] -= g0
            oa_parent[1] -= g1
            oa_parent[2] -= g2
        else:
            oa_parent[:] = 0.0
            oa_parent[0], oa_parent[1], oa_parent[2] = -g0, -g1, -g2
        for c in range(first, first + (6 if i == 1 else 1)):
            S = S_all[c]
            for b in range(6):
                S[b] = J[b, c]
            cross_motion(oa_parent, S, t)
            if parent > 0:
                cross_motion(ov[parent], S, dV[c])
                cross_motion(ov[parent], dV[c], u)
                for b in range(6):
                    dAq[c, b] = t[b] + u[b]
            else:
                for b in range(6):
                    dV[c, b] = 0.0
                    dAq[c, b] = t[b]
            cross_motion(ov[i], S, u)
            for b in range(6):
                dAv[c, b] = u[b] + dV[c, b]
    # leaves first: the subtree sums of joint i are complete when it is reached
    Fq = np.empty(6)
    Fv = np.empty(6)
    w = np.empty(6)
    for i in range(n - 1, 0, -1):
        Y = composite[i]
        B = variation[i]
        Fi = force[i]
        first = idx_v[i]
        last = first + (6 if i == 1 else 1)
        l0, l1, l2, k0, k1, k2 = B[0], B[1], B[2], B[3], B[4], B[5]
        for m in range(first, last):
            # row m of joint i, the columns c of its support: u = Bᵀ S_m (angular part), w = Y S_m
            S = S_all[m]
            s0, s1, s2, x0, x1, x2 = S[0], S[1], S[2], S[3], S[4], S[5]
            u0 = 2.0 * (l1 * s2 - l2 * s1) + B[6] * x0 + B[7] * x1 + B[8] * x2 + (k1 * x2 - k2 * x1)
            u1 = 2.0 * (l2 * s0 - l0 * s2) + B[7] * x0 + B[9] * x1 + B[10] * x2 + (k2 * x0 - k0 * x2)
            u2 = 2.0 * (l0 * s1 - l1 * s0) + B[8] * x0 + B[10] * x1 + B[11] * x2 + (k0 * x1 - k1 * x0)
            apply_inertia(Y, s0, s1, s2, x0, x1, x2, w)
            w0, w1, w2, w3, w4, w5 = w[0], w[1], w[2], w[3], w[4], w[5]
            j = i
            while j > 0:
                start = idx_v[j]
                for c in range(start, start + (6 if j == 1 else 1)):
                    Vc, Aq, Av, Sc = dV[c], dAq[c], dAv[c], S_all[c]
                    dtau_dq[m, c] = (u0 * Vc[3] + u1 * Vc[4] + u2 * Vc[5] + w0 * Aq[0] + w1 * Aq[1] + w2 * Aq[2]
                                     + w3 * Aq[3] + w4 * Aq[4] + w5 * Aq[5])
                    dtau_dv[m, c] = (u0 * Sc[3] + u1 * Sc[4] + u2 * Sc[5] + w0 * Av[0] + w1 * Av[1] + w2 * Av[2]
                                     + w3 * Av[3] + w4 * Av[4] + w5 * Av[5])
                j = parents[j]
        parent = parents[i]
        if parent > 0:
            # the ancestors' rows r, columns c of joint i: S_rᵀ (B dV_c + Y dAq_c + S_c ×* F_i), S_rᵀ (B S_c + Y dAv_c)
            for c in range(first, last):
                S, Vc, Aq, Av = S_all[c], dV[c], dAq[c], dAv[c]
                _variation_apply(B, Vc[3], Vc[4], Vc[5], Fq)
                apply_inertia(Y, Aq[0], Aq[1], Aq[2], Aq[3], Aq[4], Aq[5], w)
                _cross_force(S, Fi, t)
                for b in range(6):
                    Fq[b] += w[b] + t[b]
                _variation_apply(B, S[3], S[4], S[5], Fv)
                apply_inertia(Y, Av[0], Av[1], Av[2], Av[3], Av[4], Av[5], w)
                for b in range(6):
                    Fv[b] += w[b]
                j = parent
                while j > 0:
                    start = idx_v[j]
                    for r in range(start, start + (6 if j == 1 else 1)):
                        Sr = S_all[r]
                        dtau_dq[r, c] = (Sr[0] * Fq[0] + Sr[1] * Fq[1] + Sr[2] * Fq[2] + Sr[3] * Fq[3]
                                         + Sr[4] * Fq[4] + Sr[5] * Fq[5])
                        dtau_dv[r, c] = (Sr[0] * Fv[0] + Sr[1] * Fv[1] + Sr[2] * Fv[2] + Sr[3] * Fv[3]
                                         + Sr[4] * Fv[4] + Sr[5] * Fv[5])
                    j = parents[j]
            for s in range(10):
                composite[parent, s] += Y[s]
            for s in range(12):
                variation[parent, s] += B[s]
            for s in range(6):
                force[parent, s] += Fi[s]
