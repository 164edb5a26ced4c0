"""One node's damped KKT contact dynamics in one compiled call (the "kkt" backend's calc for a node
with contacts): the contacts' Jacobian and drift (:func:`~wbmpc.ocp.kernels.contact.contact_set_calc`)
and the damped KKT solve (:func:`~wbmpc.ocp.kernels.kkt.damped_kkt_dynamics`) under the generalised
torques the actuation model wrote, the same kernels in the same order as two separate calls, so the
same numbers to the last bit; one Python-to-compiled crossing per node instead of two, and none of
the Python between them. :func:`contact_kkt_solve` is the same with the rollout's solve
(:func:`~wbmpc.ocp.kernels.kkt.damped_kkt_solve`: triangular solves, the same numbers to rounding, nothing
left for the derivatives); :func:`contact_kkt_tree_solve` is that solve with M and b computed on the tree
the contacts' kinematics just evaluated (:func:`~wbmpc.ocp.kernels.joint_space.joint_space_terms`) instead
of given by Pinocchio: a rollout node without a binding call. :func:`contact_kkt_tree_dynamics` is
:func:`contact_kkt_dynamics` with those compiled M and b (the explicit-inverse solve, whose factors the
derivatives read), and :func:`contact_kkt_derivatives` the node's derivatives after it in one call: the
contacts' drift derivatives and forces on their joints (:func:`~wbmpc.ocp.kernels.contact.contact_set_derivatives`),
the RNEA derivatives with those forces (:func:`~wbmpc.ocp.kernels.rnea_derivatives.rnea_derivatives`, not
Pinocchio's ``computeRNEADerivatives``) and the KKT derivatives (:func:`~wbmpc.ocp.kernels.kkt.damped_kkt_derivatives`):
the derivative pass of a node without a binding call; :func:`contact_kkt_tree_dynamics_derivatives` is the two
in one call (the same kernels in the same order: the same numbers to the bit).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from wbmpc.ocp.kernels.contact import contact_set_calc, contact_set_derivatives
from wbmpc.ocp.kernels.joint_space import joint_space_terms
from wbmpc.ocp.kernels.kkt import damped_kkt_derivatives, damped_kkt_dynamics, damped_kkt_solve
from wbmpc.ocp.kernels.rnea_derivatives import rnea_derivatives


@njit(cache=True)
def contact_kkt_dynamics(x, M, nle, mu, scales, kinds, joints, frame_rotations, frame_translations, kp, kd,
                         references, corners, spreads, inverse_arms, tau, zero_acceleration, parents,
                         placement_rotation, placement_translation, axes, idx_q, idx_v, R, p, ov, oa, J, oRf, opf, fJf,
                         velocity, acceleration, Jc, a0, a, force, Minv, factor, factor_inverse, A, Y, G, G_factor,
                         G_factor_inverse, J_scaled, a_free, tau_residual, residual, force_scaled):
    """Accelerations a (nv,) and stacked contact forces ``force`` (nc,) of a free-flyer robot at the
    state x (nx,) under the generalised torques ``tau`` (nv,) [N, N·m].

    Args:
        x: the state.
        M (nv, nv) (upper triangle read), nle (nv,): Pinocchio's ``crba`` and ``nonLinearEffects`` at x.
        mu, scales (nc,): the damping and the row scales of :func:`~wbmpc.ocp.kernels.kkt.damped_kkt_dynamics`.
        kinds ... inverse_arms: the contact set's arrays (:attr:`wbmpc.ocp.contacts.ContactSet.kernel_arguments`),
            Kp terms of 6D contacts excluded (the caller adds them, then solves apart).
        tau (nv,): the actuation model's torques (``ActuationFloatingBase.calc``); zero_acceleration (nv,)
            zeros, then parents ... acceleration: the node data's buffers
            (:meth:`wbmpc.ocp.dynamics.DifferentialActionDataContactFwdDynamics.contact_kkt_arguments`):
            the tree and the contacts' frame kinematics, left for the derivatives, Jc (nc, nv), a0 (nc,),
            a, force, and the KKT buffers (:meth:`~wbmpc.ocp.kernels.kkt.KKTBuffers.dynamics_buffers`).

    Returns:
        True, or False when M or the contacts' damped Delassus matrix is not positive definite.
    """
    nq = x.size - a.size
    contact_set_calc(x[:nq], x[nq:], zero_acceleration, parents, placement_rotation, placement_translation, axes,
                     idx_q, idx_v, R, p, ov, oa, J, kinds, joints, frame_rotations, frame_translations, kp, kd,
                     references, corners, spreads, inverse_arms, oRf, opf, fJf, velocity, acceleration, Jc, a0)
    return damped_kkt_dynamics(M, nle, tau, Jc, a0, scales, mu, a, force, Minv, factor, factor_inverse, A, Y, G,
                               G_factor, G_factor_inverse, J_scaled, a_free, tau_residual, residual, force_scaled)


@njit(cache=True)
def contact_kkt_solve(x, M, nle, mu, scales, kinds, joints, frame_rotations, frame_translations, kp, kd,
                      references, corners, spreads, inverse_arms, tau, zero_acceleration, parents,
                      placement_rotation, placement_translation, axes, idx_q, idx_v, R, p, ov, oa, J, oRf, opf, fJf,
                      velocity, acceleration, Jc, a0, a, force, velocity_parents, factor, W, U, G_factor, w, y):
    """:func:`contact_kkt_dynamics` for a rollout: the same arguments up to ``force``, then the parent
    of each velocity row (:func:`~wbmpc.ocp.kernels.kkt.velocity_parents`) and
    :meth:`~wbmpc.ocp.kernels.kkt.KKTBuffers.solve_buffers`; the KKT solve by triangular solves
    (:func:`~wbmpc.ocp.kernels.kkt.damped_kkt_solve`), M⁻¹, A, Y and J̃ not formed.

    Returns:
        True, or False when M or the contacts' damped Delassus matrix is not positive definite.
    """
    nq = x.size - a.size
    contact_set_calc(x[:nq], x[nq:], zero_acceleration, parents, placement_rotation, placement_translation, axes,
                     idx_q, idx_v, R, p, ov, oa, J, kinds, joints, frame_rotations, frame_translations, kp, kd,
                     references, corners, spreads, inverse_arms, oRf, opf, fJf, velocity, acceleration, Jc, a0)
    return damped_kkt_solve(M, nle, tau, Jc, a0, scales, mu, velocity_parents, a, force, factor, W, U, G_factor, w,
                            y)


@njit(cache=True)
def contact_kkt_tree_solve(x, mu, scales, kinds, joints, frame_rotations, frame_translations, kp, kd, references,
                           corners, spreads, inverse_arms, tau, zero_acceleration, parents, placement_rotation,
                           placement_translation, axes, idx_q, idx_v, R, p, ov, oa, J, mass, lever, rotational,
                           armature, gravity, body, composite, body_force, M, nle, oRf, opf, fJf, velocity,
                           acceleration, Jc, a0, a, force, velocity_parents, factor, W, U, G_factor, w, y):
    """:func:`contact_kkt_solve` with M (nv, nv) and nle (nv,) outputs: computed from the tree kinematics the
    contacts' pass leaves at (q, v, 0) (:func:`~wbmpc.ocp.kernels.joint_space.joint_space_terms`, the link
    inertias mass ... body_force of :class:`~wbmpc.ocp.kernels.joint_space.LinkInertias`), not Pinocchio's;
    the other arguments as :func:`contact_kkt_solve`'s, in its order.

    Returns:
        True, or False when M or the contacts' damped Delassus matrix is not positive definite.
    """
    nq = x.size - a.size
    contact_set_calc(x[:nq], x[nq:], zero_acceleration, parents, placement_rotation, placement_translation, axes,
                     idx_q, idx_v, R, p, ov, oa, J, kinds, joints, frame_rotations, frame_translations, kp, kd,
                     references, corners, spreads, inverse_arms, oRf, opf, fJf, velocity, acceleration, Jc, a0)
    joint_space_terms(parents, idx_v, R, p, ov, oa, J, mass, lever, rotational, armature, gravity, body, composite,
                      body_force, M, nle)
    return damped_kkt_solve(M, nle, tau, Jc, a0, scales, mu, velocity_parents, a, force, factor, W, U, G_factor, w,
                            y)


@njit(cache=True)
def contact_kkt_tree_dynamics(x, mu, scales, kinds, joints, frame_rotations, frame_translations, kp, kd, references,
                              corners, spreads, inverse_arms, tau, zero_acceleration, parents, placement_rotation,
                              placement_translation, axes, idx_q, idx_v, R, p, ov, oa, J, mass, lever, rotational,
                              armature, gravity, body, composite, body_force, M, nle, oRf, opf, fJf, velocity,
                              acceleration, Jc, a0, a, force, Minv, factor, factor_inverse, A, Y, G, G_factor,
                              G_factor_inverse, J_scaled, a_free, tau_residual, residual, force_scaled):
    """:func:`contact_kkt_dynamics` with M (nv, nv) and nle (nv,) outputs computed on the tree the contacts' pass
    leaves at (q, v, 0) (:func:`~wbmpc.ocp.kernels.joint_space.joint_space_terms`, as :func:`contact_kkt_tree_solve`),
    then the explicit-inverse solve, which leaves M⁻¹, A, Y and J̃ for :func:`contact_kkt_derivatives`; the
    arguments as :func:`contact_kkt_tree_solve`'s up to ``force``, then
    :meth:`~wbmpc.ocp.kernels.kkt.KKTBuffers.dynamics_buffers`.

    Returns:
        True, or False when M or the contacts' damped Delassus matrix is not positive definite.
    """
    nq = x.size - a.size
    contact_set_calc(x[:nq], x[nq:], zero_acceleration, parents, placement_rotation, placement_translation, axes,
                     idx_q, idx_v, R, p, ov, oa, J, kinds, joints, frame_rotations, frame_translations, kp, kd,
                     references, corners, spreads, inverse_arms, oRf, opf, fJf, velocity, acceleration, Jc, a0)
    joint_space_terms(parents, idx_v, R, p, ov, oa, J, mass, lever, rotational, armature, gravity, body, composite,
                      body_force, M, nle)
    return damped_kkt_dynamics(M, nle, tau, Jc, a0, scales, mu, a, force, Minv, factor, factor_inverse, A, Y, G,
                               G_factor, G_factor_inverse, J_scaled, a_free, tau_residual, residual, force_scaled)


@njit(cache=True)
def kkt_rnea_derivatives(parents, idx_v, R, p, ov, oa, J, mass, lever, rotational, gravity, body, joints, fext, extra,
                         dtau_dq_extra, composite, variation, body_force, motions, dtau_dq, dtau_dv, da0_dx, scales, Fx,
                         Fu, df_dx, df_du, Minv, A, Y, J_scaled, D, P, C, W, YA, AtW, AtYA):
    """The RNEA derivatives dtau_dq, dtau_dv (nv, nv) at the tree's (q, v, a) with the contact forces fext (k, 6) on
    their joints (:func:`~wbmpc.ocp.kernels.rnea_derivatives.rnea_derivatives`; the tree, the link inertias mass
    ... gravity, body and :class:`~wbmpc.ocp.kernels.rnea_derivatives.RNEADerivatives`'s scratch composite ...
    motions), plus dtau_dq_extra (nv, nv) when ``extra`` (the point forces' rotation term), then
    :func:`~wbmpc.ocp.kernels.kkt.damped_kkt_derivatives` (da0_dx ... AtYA: its arguments after dtau_dv) after
    the explicit-inverse solve at the same point."""
    rnea_derivatives(parents, idx_v, R, p, ov, oa, J, mass, lever, rotational, gravity, body, joints, fext, composite,
                     variation, body_force, motions, dtau_dq, dtau_dv)
    if extra:
        dtau_dq += dtau_dq_extra
    damped_kkt_derivatives(dtau_dq, dtau_dv, da0_dx, scales, Fx, Fu, df_dx, df_du, Minv, A, Y, J_scaled, D, P, C, W,
                           YA, AtW, AtYA)


@njit(cache=True)
def contact_kkt_derivatives(x, scales, kinds, joints, frame_rotations, frame_translations, kp, kd, references, corners,
                            spreads, inverse_arms, a, force, parents, idx_v, R, p, ov, oa, J, oRf, opf, fJf, velocity,
                            v_dq, a_dq, a_dv, da0_dx, fext, dtau_dq_extra, mass, lever, rotational, gravity, body,
                            composite, variation, body_force, motions, dtau_dq, dtau_dv, Fx, Fu, df_dx, df_du, Minv, A,
                            Y, J_scaled, D, P, C, W, YA, AtW, AtYA):
    """A node's dynamics derivatives after :func:`contact_kkt_dynamics` or :func:`contact_kkt_tree_dynamics` at the
    state x (nx,) (the tree and the contacts' frame kinematics as it left them, its accelerations a (nv,) and
    stacked forces ``force`` (nc,)): the contacts' drift derivatives da0_dx (nc, ndx), their forces on their joints
    fext (k, 6) and the point forces' rotation term (:func:`~wbmpc.ocp.kernels.contact.contact_set_derivatives`,
    its scratch v_dq, a_dq, a_dv; the tree's accelerations updated to a), then :func:`kkt_rnea_derivatives`: Fx =
    ∂a/∂x (nv, ndx), Fu = ∂a/∂u (nv, nu), df_dx = ∂λ/∂x (nc, ndx), df_du = ∂λ/∂u (nc, nu). The contact arrays
    (kinds ... inverse_arms) are the contact set's, without positioned soles (their Kp term is Pinocchio's)."""
    nq = x.size - a.size
    extra = contact_set_derivatives(x[nq:], a, parents, idx_v, ov, oa, J, kinds, joints, frame_rotations,
                                    frame_translations, kp, kd, references, corners, spreads, inverse_arms, oRf, opf,
                                    fJf, velocity, force, v_dq, a_dq, a_dv, da0_dx, fext, dtau_dq_extra)
    kkt_rnea_derivatives(parents, idx_v, R, p, ov, oa, J, mass, lever, rotational, gravity, body, joints, fext, extra,
                         dtau_dq_extra, composite, variation, body_force, motions, dtau_dq, dtau_dv, da0_dx, scales, Fx,
                         Fu, df_dx, df_du, Minv, A, Y, J_scaled, D, P, C, W, YA, AtW, AtYA)


@njit(cache=True)
def contact_kkt_tree_dynamics_derivatives(x, mu, scales, kinds, joints, frame_rotations, frame_translations, kp, kd,
                                          references, corners, spreads, inverse_arms, tau, zero_acceleration, parents,
                                          placement_rotation, placement_translation, axes, idx_q, idx_v, R, p, ov, oa,
                                          J, mass, lever, rotational, armature, gravity, body, composite, body_force,
                                          M, nle, oRf, opf, fJf, velocity, acceleration, Jc, a0, a, force, Minv,
                                          factor, factor_inverse, A, Y, G, G_factor, G_factor_inverse, J_scaled,
                                          a_free, tau_residual, residual, force_scaled, v_dq, a_dq, a_dv, da0_dx,
                                          fext, dtau_dq_extra, variation, motions, dtau_dq, dtau_dv, Fx, Fu, df_dx,
                                          df_du, D, P, C, W, YA, AtW, AtYA):
    """:func:`contact_kkt_tree_dynamics` then :func:`contact_kkt_derivatives` at the state x in one call: a node's
    dynamics and derivatives with M, b and the RNEA derivatives compiled. The arguments are
    :func:`contact_kkt_tree_dynamics`'s, then the derivatives' buffers (v_dq ... AtYA: the contacts' scratch and
    outputs, the RNEA derivatives' variation and motions (their composite and force scratch are the link
    inertias' composite, body_force), dtau_dq, dtau_dv, the outputs Fx ... df_du and the rest of
    :meth:`~wbmpc.ocp.kernels.kkt.KKTBuffers.derivative_buffers`). When the solve fails (M or the damped Delassus
    matrix not positive definite) the accelerations are NaN and the derivatives computed from them, as the two
    calls with the calc's NaN between them. The two calls' kernels are called here directly, in their order (the
    same numbers; ~1 µs less of argument passing per level of calls on the H1).

    Returns:
        True, or False when the solve failed.
    """
    nq = x.size - a.size
    contact_set_calc(x[:nq], x[nq:], zero_acceleration, parents, placement_rotation, placement_translation, axes,
                     idx_q, idx_v, R, p, ov, oa, J, kinds, joints, frame_rotations, frame_translations, kp, kd,
                     references, corners, spreads, inverse_arms, oRf, opf, fJf, velocity, acceleration, Jc, a0)
    joint_space_terms(parents, idx_v, R, p, ov, oa, J, mass, lever, rotational, armature, gravity, body, composite,
                      body_force, M, nle)
    solved = damped_kkt_dynamics(M, nle, tau, Jc, a0, scales, mu, a, force, Minv, factor, factor_inverse, A, Y, G,
                                 G_factor, G_factor_inverse, J_scaled, a_free, tau_residual, residual, force_scaled)
    if not solved:
        a[:] = np.nan
    extra = contact_set_derivatives(x[nq:], a, parents, idx_v, ov, oa, J, kinds, joints, frame_rotations,
                                    frame_translations, kp, kd, references, corners, spreads, inverse_arms, oRf, opf,
                                    fJf, velocity, force, v_dq, a_dq, a_dv, da0_dx, fext, dtau_dq_extra)
    rnea_derivatives(parents, idx_v, R, p, ov, oa, J, mass, lever, rotational, gravity, body, joints, fext, composite,
                     variation, body_force, motions, dtau_dq, dtau_dv)
    if extra:
        dtau_dq += dtau_dq_extra
    damped_kkt_derivatives(dtau_dq, dtau_dv, da0_dx, scales, Fx, Fu, df_dx, df_du, Minv, A, Y, J_scaled, D, P, C, W,
                           YA, AtW, AtYA)
    return solved
