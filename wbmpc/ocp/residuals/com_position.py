"""Centre-of-mass residual r = c_world − c_reference (3,) [m] (terminal CoM, eqs. 23-24)."""

from __future__ import annotations

import numpy as np

from wbmpc.ocp.residuals.base import DataCollector, ResidualData
from wbmpc.ocp.state import StateMultibody


class ResidualCoMPosition:
    """r(x) = com − reference (world frame), Rx = [Jcom, 0]. Needs computeAllTerms (done by calc).

    Args:
        state: the multibody state.
        reference_world: CoM reference (3,) [m]; mutable through ``reference``.
        nu: control dimension.
    """

    #: why :class:`~wbmpc.ocp.batched_problem.BatchedShootingProblem` cannot batch this term
    batch_unsupported = "the compiled horizon kinematics does not compute the centre of mass"

    def __init__(self, state: StateMultibody, reference_world: np.ndarray, nu: int):
        self.state = state
        self.reference = np.asarray(reference_world, dtype=float).reshape(3).copy()
        self.nr = 3
        self.nu = nu

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        np.subtract(shared.pinocchio.com[0], self.reference, out=data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        data.Rx[:, : self.state.nv] = shared.pinocchio.Jcom

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)
