"""The FDDP rollout of a horizon of "kkt" contact-dynamics nodes in one compiled call: per node, the start
(:func:`~wbmpc.ocp.kernels.feedback.rollout_node_start`: gap closing, the feedback law, the torques), the
contact dynamics with M and b on the contacts' tree
(:func:`~wbmpc.ocp.kernels.contact_dynamics.contact_kkt_tree_solve`) and the Euler step
(:func:`~wbmpc.ocp.kernels.integration.free_flyer_euler_step`): the kernels the node-by-node rollout of
:class:`~wbmpc.ocp.batched_problem.BatchedShootingProblem` calls from Python, in the same order, so the
same numbers, without a Python-to-compiled crossing per node.

A node is compiled when its dynamics are the "kkt" backend's with contacts whose 6D contacts have no
Baumgarte position gain (no "positioned soles": their Kp term is Pinocchio's ``log6``); each such node's
contact set is a row of padded arrays (:class:`KKTRollout`). The kernel stops at the first node it cannot
run (not compiled, a relative half turn the feedback law hands to Pinocchio, a control not finite) and
returns its index: the caller runs that node in Python and resumes after it.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit

from wbmpc.ocp.kernels.contact_dynamics import contact_kkt_tree_solve
from wbmpc.ocp.kernels.feedback import rollout_node_start
from wbmpc.ocp.kernels.integration import free_flyer_euler_step
from wbmpc.ocp.kernels.joint_space import LinkInertias
from wbmpc.ocp.kernels.kkt import velocity_parents
from wbmpc.ocp.kernels.tree import KinematicTree


class KKTRollout:
    """The contact sets of a horizon's nodes as padded arrays for :func:`kkt_rollout`, and its buffers.

    Args:
        model: the robot (a free-flyer root followed by revolute joints).
        n_nodes: N, the running nodes.
        k_max: the most contacts a node can enforce at once.
        nc_max: the most stacked contact rows a node can have.

    Attributes (per node k): contacts (N,) int64, the active contacts of node k, −1 when node k is not
    compiled (:meth:`set_node`); rows (N,) the stacked contact rows, mu (N,) the contact damping,
    scales (N, nc_max) the row scales, and the contact arrays of
    :attr:`wbmpc.ocp.contacts.ContactSet.kernel_arguments` with a leading (N, k_max) (kinds ... inverse_arms).

    Raises:
        ParameterError: the model is not a free-flyer root followed by revolute joints.
    """

    def __init__(self, model: pin.Model, n_nodes: int, k_max: int, nc_max: int):
        tree, links = KinematicTree(model), LinkInertias(model)
        N, k, nc, nv = n_nodes, max(k_max, 1), max(nc_max, 1), model.nv
        self.contacts = np.full(N, -1, dtype=np.int64)
        self.rows = np.zeros(N, dtype=np.int64)
        self.mu = np.zeros(N)
        self.scales = np.ones((N, nc))
        self.kinds = np.zeros((N, k), dtype=np.int64)
        self.joints = np.zeros((N, k), dtype=np.int64)
        self.frame_rotations = np.zeros((N, k, 3, 3))
        self.frame_translations = np.zeros((N, k, 3))
        self.kp = np.zeros((N, k))
        self.kd = np.zeros((N, k))
        self.references = np.zeros((N, k, 3))
        self.corners = np.zeros((N, k), dtype=np.bool_)
        self.spreads = np.zeros((N, k, 3))
        self.inverse_arms = np.zeros((N, k, 3))
        self._moving: dict = {}  # node -> its contact set, whose point references move (Kp > 0)
        # in the order of ContactSet.kernel_arguments
        self._contact_arrays = (self.kinds, self.joints, self.frame_rotations, self.frame_translations, self.kp,
                                self.kd, self.references, self.corners, self.spreads, self.inverse_arms)
        # the buffers, shared by the nodes: the tree, the link inertias, M, b, the contacts' frame kinematics,
        # Jc, a0, a, the forces and the KKT solve's (kernels/kkt.damped_kkt_solve)
        buffers = (np.zeros(nv), tree.parents, tree.placement_rotation, tree.placement_translation, tree.axes,
                   tree.idx_q, tree.idx_v, tree.R, tree.p, tree.ov, tree.oa, tree.J, *links.arguments(),
                   np.zeros((nv, nv)), np.zeros(nv), np.zeros((k, 3, 3)), np.zeros((k, 3)), np.zeros((k, 6, nv)),
                   np.zeros((k, 6)), np.zeros((k, 6)), np.zeros((nc, nv)), np.zeros(nc), np.zeros(nv), np.zeros(nc),
                   velocity_parents(model), np.zeros((nv, nv)), np.zeros((nv, nc)), np.zeros((nv, nc)),
                   np.zeros((nc, nc)), np.zeros(nv), np.zeros(nc))
        self._arguments = (self.contacts, self.rows, self.mu, self.scales, *self._contact_arrays, *buffers)

    def set_node(self, k: int, dam) -> None:
        """Node k's dynamics are now ``dam``'s (a :class:`~wbmpc.ocp.dynamics.DifferentialActionModelContactFwdDynamics`
        with its current contact set): its arrays copied, or the node marked as not compiled."""
        self._moving.pop(k, None)
        contact_set = dam.contact_set
        if dam.backend != "kkt" or not dam.nc or contact_set.has_positioned_soles:
            self.contacts[k] = -1
            return
        n, nc = contact_set.kinds.size, dam.nc
        for array, value in zip(self._contact_arrays, contact_set.kernel_arguments):
            array[k, :n] = value
        self.rows[k] = nc
        self.mu[k] = dam.contact_damping
        self.scales[k, :nc] = dam.row_scales
        self.contacts[k] = n
        if contact_set.has_moving_references:
            self._moving[k] = contact_set

    def compiled(self, k: int) -> bool:
        """Node k runs in :func:`kkt_rollout`."""
        return self.contacts[k] >= 0

    def run(self, start: int, x0, fs, alpha: float, closing: bool, xs, us, k, K, xs_try, us_try, dx, tau, dt,
            euler_dx, xnext, keep_forces: bool, forces) -> int:
        """:func:`kkt_rollout` from node ``start``, the point contacts' moving references read first; returns
        the first node not run (N: all)."""
        for node, contact_set in self._moving.items():
            contact_set.refresh_references()
            self.references[node, :contact_set.kinds.size] = contact_set.references
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
        contacts ... inverse_arms, then the buffers: :class:`KKTRollout`'s.

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
