"""One node's damped KKT contact dynamics in one compiled call (the "kkt" backend's calc for a node
with contacts): the contacts' Jacobian and drift (:func:`~wbmpc.ocp.kernels.contact.contact_set_calc`)
and the damped KKT solve (:func:`~wbmpc.ocp.kernels.kkt.damped_kkt_dynamics`) under the generalised
torques the actuation model wrote, the same kernels in the same order as two separate calls, so the
same numbers to the last bit; one Python-to-compiled crossing per node instead of two, and none of
the Python between them. :func:`contact_kkt_solve` is the same with the rollout's solve
(:func:`~wbmpc.ocp.kernels.kkt.damped_kkt_solve`: triangular solves, the same numbers to rounding, nothing
left for the derivatives); :func:`contact_kkt_tree_solve` is that solve with M and b computed on the tree
the contacts' kinematics just evaluated (:func:`~wbmpc.ocp.kernels.joint_space.joint_space_terms`) instead
of given by Pinocchio: a rollout node without a binding call.
"""

from __future__ import annotations

from numba import njit

from wbmpc.ocp.kernels.contact import contact_set_calc
from wbmpc.ocp.kernels.joint_space import joint_space_terms
from wbmpc.ocp.kernels.kkt import damped_kkt_dynamics, damped_kkt_solve


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
