"""The contact sets of a horizon's "kkt" nodes as padded arrays, one row per node, for the kernels that run
a horizon in one compiled call (the rollout, :mod:`~wbmpc.ocp.kernels.rollout`; the derivative pass,
:mod:`~wbmpc.ocp.kernels.derivative_pass`): what each node's compiled calls read of its contact set
(:attr:`wbmpc.ocp.contacts.ContactSet.kernel_arguments`, the row count, the damping and the row scales), set
once per contact-set change (:meth:`HorizonContactSets.set_node`), row k of each array node k's, its first
``contacts[k]`` (contacts) or ``rows[k]`` (stacked rows) entries valid.

A node has a row when its dynamics are the "kkt" backend's with contacts whose 6D contacts have no Baumgarte
position gain (no "positioned soles": their Kp term is Pinocchio's ``log6``); the others are marked −1 and
left to the node-by-node path.
"""

from __future__ import annotations

import numpy as np


class HorizonContactSets:
    """The padded contact arrays of the module for ``n_nodes`` nodes.

    Args:
        n_nodes: N, the running nodes.
        k_max: the most contacts a node can enforce at once.
        nc_max: the most stacked contact rows a node can have.

    Attributes (per node k): contacts (N,) int64, the active contacts of node k, −1 when node k has no row
    (:meth:`set_node`); rows (N,) the stacked contact rows, mu (N,) the contact damping, scales (N, nc_max)
    the row scales, and the contact arrays of :attr:`wbmpc.ocp.contacts.ContactSet.kernel_arguments` with a
    leading (N, k_max) (kinds ... inverse_arms); :attr:`arguments`, all of them in that order (contacts,
    rows, mu, scales, kinds ... inverse_arms), the kernels' arguments.
    """

    def __init__(self, n_nodes: int, k_max: int, nc_max: int):
        N, k, nc = n_nodes, max(k_max, 1), max(nc_max, 1)
        self.k_max, self.nc_max = k, nc
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
        self.arguments = (self.contacts, self.rows, self.mu, self.scales, *self._contact_arrays)

    def set_node(self, k: int, dam) -> None:
        """Node k's dynamics are now ``dam``'s (a :class:`~wbmpc.ocp.dynamics.DifferentialActionModelContactFwdDynamics`
        with its current contact set): its arrays copied, or the node marked as having no row."""
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
        """Node k has a row (the compiled horizon kernels can run it)."""
        return self.contacts[k] >= 0

    def refresh_references(self) -> None:
        """Read the current references of the point contacts with Kp > 0 (moved since :meth:`set_node`, as
        ``ContactSet.refresh_references`` reads them before a node's compiled call)."""
        for node, contact_set in self._moving.items():
            contact_set.refresh_references()
            self.references[node, :contact_set.kinds.size] = contact_set.references
