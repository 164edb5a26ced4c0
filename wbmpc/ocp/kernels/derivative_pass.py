"""The dynamics part of a horizon's derivative pass over "kkt" contact-dynamics nodes in one compiled call: per
node, its torques [0, u], its dynamics and derivatives with M, b and the RNEA derivatives compiled
(:func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_dynamics_derivatives`), the Euler step
(:func:`~wbmpc.ocp.kernels.integration.free_flyer_euler_step`) and, when the costs read them, the stacked
contact forces and their derivatives copied out: what
:class:`~wbmpc.ocp.batched_problem.BatchedShootingProblem`'s ``calcDiff`` and ``prepare_dynamics`` run per node
from Python with ``derivative_dynamics="compiled"`` (``calc_and_diff_dynamics``), the same kernels in the same
order, so the same numbers, without a Python-to-compiled crossing per node (~6 µs of dispatch of ~80 arguments
and ~7 µs of Python a node on the H1).

Node t is computed with the contact set of a row s of the horizon's padded contact sets
(:class:`~wbmpc.ocp.kernels.horizon_contacts.HorizonContactSets`): s = t in ``calcDiff``, the row of a node with
the contact set node t will have in ``prepare_dynamics`` (the horizon shifted by one node). One set of buffers
serves every node; the KKT kernels' BLAS products want whole contiguous arrays of the node's nc contact rows:
the (nc, ·) buffers are the first nc rows of (nc_max, ·) arrays, the (nc, nc) ones the first nc² entries of a
flat array, reshaped. (numba caches :func:`kkt_derivative_pass` with the kernels it calls, keyed on this file's
contents: a change to those invalidates nothing here unless this file changes too, or its cache is removed.)
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit

from wbmpc.ocp.kernels.contact_dynamics import contact_kkt_tree_dynamics_derivatives
from wbmpc.ocp.kernels.horizon_contacts import HorizonContactSets
from wbmpc.ocp.kernels.integration import free_flyer_euler_step
from wbmpc.ocp.kernels.joint_space import LinkInertias
from wbmpc.ocp.kernels.rnea_derivatives import RNEADerivatives
from wbmpc.ocp.kernels.tree import KinematicTree


class KKTDerivativePass:
    """The buffers of :func:`kkt_derivative_pass` for a horizon whose nodes' contact sets are ``sets``.

    Args:
        model: the robot (a free-flyer root followed by revolute joints, nv velocities).
        sets: the horizon's padded contact sets (set by their owner; shared with the rollout).
        nu: the controls (nv − 6: a free-flyer actuation).

    Raises:
        ParameterError: the model is not a free-flyer root followed by revolute joints.
    """

    def __init__(self, model: pin.Model, sets: HorizonContactSets, nu: int):
        tree, links, rnea = KinematicTree(model), LinkInertias(model), RNEADerivatives(model)
        k, nc, nv = sets.k_max, sets.nc_max, model.nv
        ndx = 2 * nv
        self.sets = sets
        composite, body_force = links.composite, links.force  # the RNEA derivatives' scratch too
        # in the order of contact_kkt_tree_dynamics_derivatives' arguments after the contact set's (tau ... AtYA),
        # df_dx and df_du of nc_max rows, the (nc, nc) buffers flat (Y, G, G_factor, G_factor_inverse)
        self._buffers = (
            np.zeros(nv), np.zeros(nv), tree.parents, tree.placement_rotation, tree.placement_translation, tree.axes,
            tree.idx_q, tree.idx_v, tree.R, tree.p, tree.ov, tree.oa, tree.J, links.mass, links.lever,
            links.rotational, links.armature, links.gravity, links.body, composite, body_force,
            np.zeros((nv, nv)), np.zeros(nv),  # M, b
            np.zeros((k, 3, 3)), np.zeros((k, 3)), np.zeros((k, 6, nv)), np.zeros((k, 6)), np.zeros((k, 6)),
            np.zeros((nc, nv)), np.zeros(nc), np.zeros(nv), np.zeros(nc),  # Jc, a0, a, force
            np.zeros((nv, nv)), np.zeros((nv, nv)), np.zeros((nv, nv)),  # M⁻¹, its factor and the factor's inverse
            np.zeros((nc, nv)), np.zeros(nc * nc), np.zeros(nc * nc), np.zeros(nc * nc), np.zeros(nc * nc),  # A, Y, G..
            np.zeros((nc, nv)), np.zeros(nv), np.zeros(nv), np.zeros(nc), np.zeros(nc),  # J̃ ... force_scaled
            np.zeros((k, 6, nv)), np.zeros((k, 6, nv)), np.zeros((k, 6, nv)), np.zeros((nc, ndx)),  # v_dq ... da0_dx
            np.zeros((k, 6)), np.zeros((nv, nv)), rnea.variation, rnea.motions,  # fext, dtau_dq_extra, ...
            np.zeros((nv, nv)), np.zeros((nv, nv)), np.zeros((nc, ndx)), np.zeros((nc, nu)),  # dtau_dq ... df_du
            np.zeros((nv, ndx)), np.zeros((nv, ndx)), np.zeros((nc, ndx)), np.zeros((nc, ndx)),  # D, P, C, W
            np.zeros((nc, nv)), np.zeros((nv, ndx)), np.zeros((nv, nv)))  # YA, AtW, AtYA

    def run(self, nodes: np.ndarray, rows: np.ndarray, xs, us, dt, xnext, euler_dx, da_dx, da_du, keep_forces: bool,
            forces, force_jacobians) -> None:
        """:func:`kkt_derivative_pass` of ``nodes`` with the contact sets of ``rows``, the point contacts' moving
        references read first."""
        self.sets.refresh_references()
        kkt_derivative_pass(nodes, rows, xs, us, dt, xnext, euler_dx, da_dx, da_du, keep_forces, forces,
                            force_jacobians, *self.sets.arguments, *self._buffers)


@njit(cache=True)
def kkt_derivative_pass(nodes, sets, xs, us, dt, xnext, euler_dx, da_dx, da_du, keep_forces, forces, force_jacobians,
                        contacts, rows, mu, scales, kinds, joints, frame_rotations, frame_translations, kp, kd,
                        references, corners, spreads, inverse_arms, tau, zero_acceleration, parents,
                        placement_rotation, placement_translation, axes, idx_q, idx_v, R, p, ov, oa, J, mass, lever,
                        rotational, armature, gravity, body, composite, body_force, M, nle, oRf, opf, fJf, velocity,
                        acceleration, Jc, a0, a, force, Minv, factor, factor_inverse, A, Y, G, G_factor,
                        G_factor_inverse, J_scaled, a_free, tau_residual, residual, force_scaled, v_dq, a_dq, a_dv,
                        da0_dx, fext, dtau_dq_extra, variation, motions, dtau_dq, dtau_dv, df_dx, df_du, D, P, C, W,
                        YA, AtW, AtYA):
    """The dynamics and derivatives of the nodes t = nodes[i] (m,) int64, each with the contact set of row
    s = sets[i] (m,) int64 of the padded arrays, at (xs[t], us[t]).

    Args:
        xs (≥ N, nx), us (N, nu) [N·m]: the states and controls; dt (N,) [s].
        outputs, row t of each: xnext (N, nx) and euler_dx (N, ndx) (the Euler step), da_dx = ∂a/∂x (N, nv, ndx),
            da_du = ∂a/∂u (N, nv, nu); with ``keep_forces`` the stacked contact forces [N, N·m] into
            forces[t, :nc] (N, nc_max) and [∂λ/∂x, ∂λ/∂u] into force_jacobians[t, :nc] (N, nc_max, ndx + nu).
        contacts ... inverse_arms: :attr:`~wbmpc.ocp.kernels.horizon_contacts.HorizonContactSets.arguments`.
        tau ... AtYA: :class:`KKTDerivativePass`'s buffers (the arguments of
            :func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_dynamics_derivatives` after the contact
            set's, Fx and Fu left out (da_dx[t], da_du[t] instead); the (nc, ·) ones with nc_max rows, Y, G,
            G_factor and G_factor_inverse flat (nc_max²,)).

    A node whose KKT system is not positive definite gets NaN accelerations and derivatives from them, as the
    node-by-node pass.
    """
    nv = a.size
    nu = us.shape[1]
    n_base = nv - nu
    ndx = 2 * nv
    for i in range(nodes.size):
        t = nodes[i]
        s = sets[i]
        n = contacts[s]
        nc = rows[s]
        for r in range(n_base):  # the floating-base actuation's torques
            tau[r] = 0.0
        for r in range(nu):
            tau[n_base + r] = us[t, r]
        contact_kkt_tree_dynamics_derivatives(
            xs[t], mu[s], scales[s, :nc], kinds[s, :n], joints[s, :n], frame_rotations[s, :n],
            frame_translations[s, :n], kp[s, :n], kd[s, :n], references[s, :n], corners[s, :n], spreads[s, :n],
            inverse_arms[s, :n], tau, zero_acceleration, parents, placement_rotation, placement_translation, axes,
            idx_q, idx_v, R, p, ov, oa, J, mass, lever, rotational, armature, gravity, body, composite, body_force,
            M, nle, oRf[:n], opf[:n], fJf[:n], velocity[:n], acceleration[:n], Jc[:nc], a0[:nc], a, force[:nc], Minv,
            factor, factor_inverse, A[:nc], Y[:nc * nc].reshape((nc, nc)), G[:nc * nc].reshape((nc, nc)),
            G_factor[:nc * nc].reshape((nc, nc)), G_factor_inverse[:nc * nc].reshape((nc, nc)), J_scaled[:nc],
            a_free, tau_residual, residual[:nc], force_scaled[:nc], v_dq[:n], a_dq[:n], a_dv[:n], da0_dx[:nc],
            fext[:n], dtau_dq_extra, variation, motions, dtau_dq, dtau_dv, da_dx[t], da_du[t], df_dx[:nc],
            df_du[:nc], D, P, C[:nc], W[:nc], YA[:nc], AtW, AtYA)
        free_flyer_euler_step(xs[t], a, dt[t], euler_dx[t], xnext[t])
        if keep_forces:
            for r in range(nc):
                forces[t, r] = force[r]
                for c in range(ndx):
                    force_jacobians[t, r, c] = df_dx[r, c]
                for c in range(nu):
                    force_jacobians[t, r, ndx + c] = df_du[r, c]
