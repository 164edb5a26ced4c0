"""Residuals linear in one contact's force: r = A f − b [N, N·m] (regularisation f − f_ref, cones A f).

The force f is the contact's as the dynamics computes it (see :mod:`wbmpc.ocp.contacts`): for a
3D point contact (3,) [N] in world-aligned axes at the foot, for a 6D flat contact the wrench (6,)
= (force [N], torque [N·m]) in the sole frame (LOCAL). Its derivatives ∂f/∂x, ∂f/∂u are those of
the contact-constrained dynamics at the node (:mod:`wbmpc.ocp.dynamics`); the batched evaluation
reads the same numbers, kept per node by :class:`~wbmpc.ocp.batched_problem.BatchedShootingProblem`
(``HorizonData.contact_force``, ``contact_force_jacobian``).
"""

from __future__ import annotations

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.kernels.residuals import (
    jacobian_blocks,
    linear_force_jacobian,
    linear_force_jacobian_many,
    linear_force_rows,
    linear_force_rows_many,
)
from wbmpc.ocp.residuals.base import (
    BatchedResidual,
    DataCollector,
    HorizonData,
    ResidualData,
    dense_jacobian_pattern,
)
from wbmpc.ocp.state import StateMultibody


class ResidualLinearInContactForce(BatchedResidual):
    """r = A f_contact − b (A of shape (nr, m), the first m ≤ nc components of the contact's force),
    Rx = A ∂f/∂x, Ru = A ∂f/∂u: what friction and wrench cones are (b = 0) and what the force
    regularisation is (A = I, b = f_ref).

    Args:
        state: the multibody state.
        contact_name: name of the contact in the node's contact set (the term must be active only
            at nodes where that contact is).
        A: the rows (nr, m), m = 3 (point) or up to 6 (flat contact).
        nu: control dimension.
        b: offset (nr,) in the units of A f (default 0); mutable through ``reference``.
    """

    uses_contact_forces = True  # reads the force derivatives the dynamics computes

    def __init__(self, state: StateMultibody, contact_name: str, A: np.ndarray, nu: int, b: np.ndarray | None = None):
        A = np.ascontiguousarray(A, dtype=float)
        if A.ndim != 2 or not 1 <= A.shape[1] <= 6:
            raise ParameterError(f"A has shape {A.shape}: expected (nr, m) with 1 <= m <= 6 force components")
        self.A = A
        self.state = state
        self.contact_name = contact_name
        self.nr = int(A.shape[0])
        self.nu = nu
        self._reference = np.zeros(self.nr) if b is None else np.asarray(b, dtype=float).reshape(self.nr).copy()

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        linear_force_rows(self.A, shared.contacts[self.contact_name].force, self._reference, data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        contact = shared.contacts[self.contact_name]
        linear_force_jacobian(self.A, contact.df_dx, data.Rx)
        linear_force_jacobian(self.A, contact.df_du, data.Ru)

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)

    # ----------------------------------------------------------------- batched evaluation
    def batch_signature(self) -> tuple:
        return (type(self), self.nr, self.contact_name, self.A.tobytes())

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        n = self.state.ndx + self.nu  # ∂f/∂x and ∂f/∂u are dense
        return dense_jacobian_pattern(self.nr, n)

    def _inactive_contact(self, horizon: HorizonData, k: int) -> ParameterError:
        return ParameterError(f"cost on contact {self.contact_name!r} ({type(self).__name__}) is active at running "
                              f"node {k}, whose contact set {horizon.contact_sets[k]} does not hold it")

    def batch_calc(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray, r: np.ndarray) -> None:
        k = linear_force_rows_many(self.A, horizon.contact_force, horizon.contact_row[self.contact_name], references,
                                   mask, r)
        if k >= 0:
            raise self._inactive_contact(horizon, k)

    def batch_calc_diff(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray,
                        values: np.ndarray) -> None:
        k = linear_force_jacobian_many(self.A, horizon.contact_force_jacobian, horizon.contact_row[self.contact_name],
                                       mask, jacobian_blocks(values, self.nr))
        if k >= 0:
            raise self._inactive_contact(horizon, k)


class ResidualContactForce(ResidualLinearInContactForce):
    """r = f_contact − f_reference in the contact's own frame (see :mod:`wbmpc.ocp.contacts`):
    A = I, b = f_reference.

    Rx and Ru are the rows of ∂f/∂x and ∂f/∂u that the dynamics computes for this contact.

    Args:
        state: the multibody state.
        contact_name: name of the contact in the node's contact set.
        force_reference: reference force (nc,), 3 [N] for point contacts, 6 (linear [N], angular
            [N·m]) for flat contacts; mutable through ``reference``.
        nu: control dimension.
    """

    def __init__(self, state: StateMultibody, contact_name: str, force_reference: np.ndarray, nu: int):
        reference = np.asarray(force_reference, dtype=float).ravel()
        if reference.size not in (3, 6):
            raise ParameterError(f"force_reference has {reference.size} entries: 3 (point contact) or 6 (flat contact) "
                                 "allowed")
        super().__init__(state, contact_name, np.eye(reference.size), nu, reference)
