"""Residuals of the contact forces: r = f − f_ref (regularisation) and r = A f (cones), [N, N·m]."""

from __future__ import annotations

import numpy as np

from wbmpc.ocp.residuals.base import DataCollector, ResidualData
from wbmpc.ocp.state import StateMultibody


class _ResidualOfContactForce:
    """What every residual of one contact's force shares: the contact it reads (by name in the
    node's contact set), its data and why it is not batched."""

    #: why :class:`~wbmpc.ocp.batched_problem.BatchedShootingProblem` cannot batch this term
    batch_unsupported = "it reads the contact forces of the node's dynamics data, not kept per node when batched"

    uses_contact_forces = True  # reads the force derivatives the dynamics computes

    def __init__(self, state: StateMultibody, contact_name: str, nr: int, nu: int):
        self.state = state
        self.contact_name = contact_name
        self.nr = int(nr)
        self.nu = nu

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)


class ResidualContactForce(_ResidualOfContactForce):
    """r = f_contact − f_reference in the contact's own frame (see :mod:`wbmpc.ocp.contacts`).

    Rx and Ru are the rows of ∂f/∂x and ∂f/∂u that the dynamics computes for this contact.

    Args:
        state: the multibody state.
        contact_name: name of the contact in the node's contact set.
        force_reference: reference force (nc,), 3 for point contacts, 6 (linear, angular) for
            flat contacts; mutable through ``reference``.
        nu: control dimension.
    """

    def __init__(self, state: StateMultibody, contact_name: str, force_reference: np.ndarray, nu: int):
        self.reference = np.asarray(force_reference, dtype=float).ravel().copy()
        super().__init__(state, contact_name, self.reference.size, nu)

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        np.subtract(shared.contacts[self.contact_name].force, self.reference, out=data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        contact = shared.contacts[self.contact_name]
        data.Rx[:] = contact.df_dx
        data.Ru[:] = contact.df_du


class ResidualLinearInContactForce(_ResidualOfContactForce):
    """r = A f_contact (A of shape (nr, nc)), Rx = A ∂f/∂x, Ru = A ∂f/∂u: what friction and wrench
    cones are (the force in the contact's own frame, see :mod:`wbmpc.ocp.contacts`).

    Args:
        state: the multibody state.
        contact_name: name of the contact in the node's contact set.
        A: the rows (nr, nc), nc = 3 (point) or 6 (flat contact).
        nu: control dimension.
    """

    def __init__(self, state: StateMultibody, contact_name: str, A: np.ndarray, nu: int):
        self.A = np.ascontiguousarray(A, dtype=float)
        super().__init__(state, contact_name, self.A.shape[0], nu)

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        force = shared.contacts[self.contact_name].force
        np.matmul(self.A, force[: self.A.shape[1]], out=data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        contact = shared.contacts[self.contact_name]
        nc = self.A.shape[1]
        np.matmul(self.A, contact.df_dx[:nc], out=data.Rx)
        np.matmul(self.A, contact.df_du[:nc], out=data.Ru)
