"""Frame velocity residual r = v_frame − v_reference (6,) = (linear [m/s], angular [rad/s]) in the
frame's own axes (LOCAL): touchdown velocity.

LOCAL on purpose: Pinocchio's LOCAL_WORLD_ALIGNED velocity derivatives leave out the rotation
of the axes (they differ from finite differences of the LWA velocity), and ‖v_local‖ equals the
norm of the velocity in world axes anyway.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.ocp.residuals.base import DataCollector, ResidualData
from wbmpc.ocp.state import StateMultibody


class ResidualFrameVelocity:
    """r(x) = v_frame(q, v) − reference, Rx = [∂v/∂q, ∂v/∂v] (LOCAL frame).

    The derivatives need the kinematic derivatives of the node (the contact dynamics' calcDiff
    computes them before the costs), so use it on running nodes.

    Args:
        state: the multibody state.
        frame_id: Pinocchio frame index.
        reference: reference spatial velocity (6,), default zero; mutable.
        nu: control dimension.
    """

    #: why :class:`~wbmpc.ocp.batched_problem.BatchedShootingProblem` cannot batch this term
    batch_unsupported = "the compiled horizon kinematics computes frame positions and their Jacobians, not frame velocities"

    def __init__(self, state: StateMultibody, frame_id: int, nu: int, reference: np.ndarray | None = None):
        self.state = state
        self.frame_id = int(frame_id)
        self.reference = np.zeros(6) if reference is None else np.asarray(reference, dtype=float).reshape(6).copy()
        self.nr = 6
        self.nu = nu

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        # From the world-frame joint velocity (data.ov): both dynamics backends compute it, while
        # Pinocchio's constraintDynamics leaves the LOCAL joint velocities (data.v) untouched.
        model, pdata = self.state.pinocchio, shared.pinocchio
        oMf = pin.updateFramePlacement(model, pdata, self.frame_id)
        velocity = oMf.actInv(pdata.ov[model.frames[self.frame_id].parentJoint])
        np.subtract(velocity.vector, self.reference, out=data.r)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        dv_dq, dv_dv = pin.getFrameVelocityDerivatives(self.state.pinocchio, shared.pinocchio, self.frame_id,
                                                       pin.LOCAL)
        nv = self.state.nv
        data.Rx[:, :nv] = dv_dq
        data.Rx[:, nv:] = dv_dv

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)
