"""Joint-position residual r = q_j − q_ref (n_j,): the robot's 1-dof joint angles, for the joint-limit barrier.

Under :class:`~wbmpc.ocp.activations.ActivationQuadraticBarrier` with the model's position limits as
bounds (reference 0) it is Crocoddyl's state-bound cost restricted to the joints: zero inside the limits,
quadratic beyond them. The free flyer's coordinates are not joint angles and have no rows.
"""

from __future__ import annotations

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.residuals.base import BatchedResidual, DataCollector, HorizonData, ResidualData
from wbmpc.ocp.state import StateMultibody


def one_dof_joint_rows(state: StateMultibody) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The 1-dof joints of ``state``'s model after its root: (configuration indices (n_j,), tangent indices
    (n_j,), joint names). A joint with nq ≠ 1 or nv ≠ 1 other than a free-flyer root (a continuous joint's
    (cos, sin), a spherical joint) is refused: its coordinates are not an angle with limits."""
    model = state.pinocchio
    q_rows, v_rows, names = [], [], []
    for j in range(1, model.njoints):
        joint = model.joints[j]
        if j == 1 and joint.nq == 7 and joint.nv == 6:
            continue  # free-flyer root
        if joint.nq != 1 or joint.nv != 1:
            raise ParameterError(f"joint {model.names[j]!r} has nq={joint.nq}, nv={joint.nv}: joint-position "
                                 "residuals need 1-dof joints (revolute or prismatic with limits)")
        q_rows.append(joint.idx_q)
        v_rows.append(joint.idx_v)
        names.append(model.names[j])
    return np.array(q_rows, dtype=np.int64), np.array(v_rows, dtype=np.int64), names


class ResidualJointPosition(BatchedResidual):
    """r(x) = q_j − q_ref [rad or m], one row per 1-dof joint (model order); Rx = [S 0] with S the
    selection of those joints' tangent columns (constant), Ru = 0.

    Args:
        state: the multibody state (a free-flyer root, if any, then 1-dof joints).
        nu: control dimension.
        q_reference: (n_j,) reference joint positions; default zeros. Mutable through ``reference``.
    """

    def __init__(self, state: StateMultibody, nu: int, q_reference: np.ndarray | None = None):
        self.state = state
        self.nu = nu
        self.q_rows, self.v_rows, self.joint_names = one_dof_joint_rows(state)
        self.nr = self.q_rows.size
        if q_reference is None:
            q_reference = np.zeros(self.nr)
        q_reference = np.asarray(q_reference, dtype=float).ravel()
        if q_reference.shape != (self.nr,) or not np.all(np.isfinite(q_reference)):
            raise ParameterError(f"q_reference of shape {q_reference.shape} must be {self.nr} finite joint positions")
        self._reference = q_reference.copy()

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        np.subtract(x[self.q_rows], self._reference, out=data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        """Rx is constant (written by createData)."""

    def createData(self) -> ResidualData:
        data = ResidualData(self.nr, self.state.ndx, self.nu)
        data.Rx[np.arange(self.nr), self.v_rows] = 1.0
        return data

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        return np.arange(self.nr, dtype=np.int64), self.v_rows.copy()

    def batch_calc(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray, r: np.ndarray) -> None:
        nodes = np.flatnonzero(mask)
        r[nodes] = horizon.xs[nodes[:, None], self.q_rows] - references[nodes]

    def batch_calc_diff(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray,
                        values: np.ndarray) -> None:
        values[:] = 1.0
