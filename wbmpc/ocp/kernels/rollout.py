"""The FDDP rollout of a horizon of "kkt" contact-dynamics nodes in one compiled call: per node, the start
(:func:`~wbmpc.ocp.kernels.feedback.rollout_node_start`: gap closing, the feedback law, the torques), the
contact dynamics with M and b on the contacts' tree
(:func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_solve`) and the Euler step
(:func:`~wbmpc.ocp.kernels.integration.free_flyer_euler_step`): the kernels the node-by-node rollout of
:class:`~wbmpc.ocp.batched_problem.BatchedShootingProblem` calls from Python, in the same order, so the
same numbers, without a Python-to-compiled crossing per node.

A node is compiled when its dynamics are the "kkt" backend's with contacts whose 6D contacts have no
Baumgarte position gain (no "positioned soles": their Kp term is Pinocchio's ``log6``); each such node's
contact set is a row of padded arrays (:class:`~wbmpc.ocp.kernels.horizon_contacts.HorizonContactSets`).
The kernel stops at the first node it cannot run (not compiled, a relative half turn the feedback law hands
to Pinocchio, a control not finite) and returns its index: the caller runs that node in Python and resumes
after it.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit

from wbmpc.ocp.kernels.contact_dynamics import contact_kkt_tree_solve
from wbmpc.ocp.kernels.feedback import rollout_node_start
from wbmpc.ocp.kernels.horizon_contacts import HorizonContactSets
from wbmpc.ocp.kernels.integration import free_flyer_euler_step
from wbmpc.ocp.kernels.joint_space import LinkInertias
from wbmpc.ocp.kernels.kkt import velocity_parents
from wbmpc.ocp.kernels.tree import KinematicTree


class KKTRollout:
    """The buffers of :func:`kkt_rollout` for a horizon whose nodes' contact sets are ``sets``.

    Args:
        model: the robot (a free-flyer root followed by revolute joints).
        sets: the horizon's padded contact sets (:class:`~wbmpc.ocp.kernels.horizon_contacts.HorizonContactSets`,
            set by their owner; shared with the derivative pass).

    Raises:
        ParameterError: the model is not a free-flyer root followed by revolute joints.
    """

    def __init__(self, model: pin.Model, sets: HorizonContactSets):
        tree, links = KinematicTree(model), LinkInertias(model)
        k, nc, nv = sets.k_max, sets.nc_max, model.nv
        self.sets = sets
        # the buffers, shared by the nodes: the tree, the link inertias, M, b, the contacts' frame kinematics,
        # Jc, a0, a, the forces and the KKT solve's (kernels/kkt.damped_kkt_solve)
        buffers = (np.zeros(nv), tree.parents, tree.placement_rotation, tree.placement_translation, tree.axes,
                   tree.idx_q, tree.idx_v, tree.R, tree.p, tree.ov, tree.oa, tree.J, *links.arguments(),
                   np.zeros((nv, nv)), np.zeros(nv), np.zeros((k, 3, 3)), np.zeros((k, 3)), np.zeros((k, 6, nv)),
                   np.zeros((k, 6)), np.zeros((k, 6)), np.zeros((nc, nv)), np.zeros(nc), np.zeros(nv), np.zeros(nc),
                   velocity_parents(model), np.zeros((nv, nv)), np.zeros((nv, nc)), np.zeros((nv, nc)),
                   np.zeros((nc, nc)), np.zeros(nv), np.zeros(nc))
        self._arguments = (*sets.arguments, *buffers)

    def compiled(self, k: int) -> bool:
        """Node k runs in :func:`kkt_rollout`."""
        return self.sets.compiled(k)

    def run(self, start: int, x0, fs, alpha: float, closing: bool, xs, us, k, K, xs_try, us_try, dx, tau, dt,
            euler_dx, xnext, keep_forces: bool, forces) -> int:
        """:func:`kkt_rollout` from node ``start``, the point contacts' moving references read first; returns
        the first node not run (N: all)."""
        self.sets.refresh_references()
        return kkt_rollout(start, x0, fs, alpha, closing, xs, us, k, K, xs_try, us_try, dx, tau, dt, euler_dx, xnext,
                           keep_forces, forces, *self._arguments)


@njit(cache=True)
def kkt_rollout(start, x0, fs, alpha, closing, xs, us, k, K, xs_try, us_try, dx, tau, dt, euler_dx, xnext,
                keep_forces, forces, contacts, rows, mu, scales, kinds, joints, frame_rotations, frame_translations, kp,
                kd, references, corners, spreads, inverse_arms, zero_acceleration, parents, placement_rotation,
                placement_translation, axes, idx_q, idx_v, R, p, ov, oa, J, mass, lever, rotational, armature, gravity,
                body, composite, body_force, M, nle, oRf, opf, fJf, velocity, acceleration, Jc, a0, a, force,
                velocity_parents, factor, W, U, G_factor, w, y):
    """The rollout of the nodes t = start, start + 1, ... (the module's three steps each) while they are
    compiled; returns the first node it did not finish (N: all done).

    Args:
        start: the first node; x0 (nx,) the initial state (the previous state of node 0, else xnext[t − 1]);
        fs ... tau: as :func:`~wbmpc.ocp.kernels.feedback.rollout_node_start` (fs (N + 1, ndx) the gaps, alpha,
            closing, xs (N + 1, nx), us (N, nu), k (N, nu), K (N, nu, ndx), outputs xs_try (N + 1, nx),
            us_try (N, nu), dx (N, ndx), the torques tau (nv,));
        dt (N,) [s]; outputs euler_dx (N, ndx) and xnext (N, nx) (:func:`~wbmpc.ocp.kernels.integration.free_flyer_euler_step`);
        keep_forces: write node t's stacked contact forces [N, N·m] into forces[t, :rows[t]];
        contacts ... inverse_arms: :attr:`~wbmpc.ocp.kernels.horizon_contacts.HorizonContactSets.arguments`,
            then the buffers: :class:`KKTRollout`'s.

    A node whose KKT system is not positive definite gets NaN accelerations (its successors NaN states), as
    the node-by-node rollout.
    """
    N = contacts.size
    for t in range(start, N):
        n = contacts[t]
        if n < 0:
            return t
        x_prev = x0 if t == 0 else xnext[t - 1]
        if rollout_node_start(t, x_prev, fs, alpha, closing, xs, us, k, K, xs_try[t], dx, us_try, tau) != 0:
            return t
        nc = rows[t]
        solved = contact_kkt_tree_solve(
            xs_try[t], mu[t], scales[t, :nc], kinds[t, :n], joints[t, :n], frame_rotations[t, :n],
            frame_translations[t, :n], kp[t, :n], kd[t, :n], references[t, :n], corners[t, :n], spreads[t, :n],
            inverse_arms[t, :n], tau, zero_acceleration, parents, placement_rotation, placement_translation, axes,
            idx_q, idx_v, R, p, ov, oa, J, mass, lever, rotational, armature, gravity, body, composite, body_force,
            M, nle, oRf[:n], opf[:n], fJf[:n], velocity[:n], acceleration[:n], Jc[:nc], a0[:nc], a, force[:nc],
            velocity_parents, factor, W[:, :nc], U[:, :nc], G_factor[:nc, :nc], w, y[:nc])
        if not solved:
            a[:] = np.nan
        if keep_forces:
            for r in range(nc):
                forces[t, r] = force[r]
        free_flyer_euler_step(xs_try[t], a, dt[t], euler_dx[t], xnext[t])
    return N
