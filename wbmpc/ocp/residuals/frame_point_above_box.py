"""Height of a point fixed on a frame above a box's smoothed height profile, r = z_p − h(x_p, y_p) (1,) [m].

The box stands on the ground (world z = ``ground``): its footprint is a rectangle of centre c (2,) [m], unit axes
a_1 (along its depth) and a_2 (across it), half extents (d_1, d_2) [m]; its top is at ``height`` above the ground.
The profile is that top over the footprint grown by ``margin`` on every side, falling to the ground over
``transition`` [m] outside it with the quintic smoothstep q (C², q(0) = 0, q(1) = 1)::

    h(x, y) = ground + height S_1(u_1) S_2(u_2),   u_i = a_i · ((x, y) − c),
    S_i(u) = 1 for |u| <= e_i,  q((e_i + transition − |u|) / transition) for e_i < |u| < e_i + transition,  0 beyond,
    e_i = d_i + margin.

With an :class:`~wbmpc.ocp.activations.ActivationQuadraticBarrier` of bounds (0, +inf) it keeps the point above the
box wherever the point actually is, not where a planned path puts it: the walking OCP's profile clearance of a
crossing swing (``obstacle_clearance_gating = "profile"``, :mod:`wbmpc.walking.ocp`). The H1's trailing foot, 30 cm
behind its planned path, came down on the box while the path-gated clearance, switched off past the box, saw no
violation.

Jacobian: with J_p = J_v − [w]× J_ω the point's world velocity Jacobian (J: the frame's LOCAL_WORLD_ALIGNED
Jacobian, w = oRf p), Rx = [J_p[2] − ∇h · J_p[:2], 0], ∇h = height (S_1' S_2 a_1 + S_1 S_2' a_2).

Both evaluations (node-wise ``calc``/``calcDiff``, the batched one) and :meth:`ResidualFramePointAboveBox.profile`
compute h, ∇h and the rows with the same compiled kernels (:func:`~wbmpc.ocp.kernels.residuals.box_profile`,
``point_above_box_row``, ``point_above_box_jacobian_row``).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError, check_finite
from wbmpc.ocp.kernels.residuals import (
    box_profile,
    point_above_box_jacobian_many,
    point_above_box_jacobian_row,
    point_above_box_row,
    point_above_box_rows_many,
)
from wbmpc.ocp.residuals.base import BatchedResidual, DataCollector, HorizonData, ResidualData
from wbmpc.ocp.state import StateMultibody

#: the box's parameters in :attr:`ResidualFramePointAboveBox.reference`: footprint centre (2,) [m], unit axis along
#: its depth (2,), half extents grown by the margin (2,) [m], top above the ground [m]
BOX_SIZE = 7


class ResidualFramePointAboveBox(BatchedResidual):
    """r(x) = z_p − h(x_p, y_p) for the point p on a frame and a box's profile h (see the module docstring).

    Args:
        state: the multibody state.
        frame_id: Pinocchio frame index.
        point_local: the point in the frame, (3,) [m].
        nu: control dimension.
        margin: the footprint grown by this [m] (>= 0).
        transition: the profile's fall outside the grown footprint [m] (> 0).
        ground: world z of the ground the box stands on [m].

    The box is set by :meth:`set_box` (mutable, per node); until then, and after :meth:`clear`, there is none
    (h = ground). Its parameters are the residual's ``reference`` (:data:`BOX_SIZE`,): centre c (2,) [m, world],
    axis a_1 (2,), grown half extents (e_1, e_2) [m], height [m], written in place by :meth:`set_box` and
    :meth:`clear`, so that a batched problem that bound them (``bind_reference``) reads every node's box.
    """

    batch_frame_rotations = True

    def __init__(self, state: StateMultibody, frame_id: int, point_local, nu: int, margin: float,
                 transition: float, ground: float = 0.0):
        point = np.asarray(point_local, dtype=float).reshape(-1)
        if point.shape != (3,):
            raise ParameterError(f"point_local={point_local!r} must be 3 numbers [m]")
        check_finite("point_local", point)
        if not (np.isfinite(margin) and margin >= 0.0):
            raise ParameterError(f"margin={margin!r} m must be finite and >= 0")
        if not (np.isfinite(transition) and transition > 0.0):
            raise ParameterError(f"transition={transition!r} m must be finite and > 0")
        self.state = state
        self.frame_id = int(frame_id)
        self.batch_frames = (self.frame_id,)
        self.point_local = point
        self.margin, self.transition, self.ground = float(margin), float(transition), float(ground)
        self.nr = 1
        self.nu = nu
        self._reference = np.zeros(BOX_SIZE)
        self.clear()

    def set_box(self, center, axis, half_depth: float, half_width: float, height: float) -> None:
        """The box: footprint centre (2,) [m], world unit axis along its depth (2,), half extents along and
        across it [m], top above the ground [m]."""
        box = self._reference
        box[0:2] = center
        box[2:4] = axis
        box[4] = float(half_depth) + self.margin
        box[5] = float(half_width) + self.margin
        box[6] = height

    def clear(self) -> None:
        """No box: h = ground everywhere."""
        self._reference[:] = (0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0)

    def profile(self, xy) -> tuple[float, np.ndarray]:
        """h(x, y) [m] and its gradient (2,) at the world point ``xy`` (2,) [m]."""
        x, y = np.asarray(xy, dtype=float).reshape(2)
        value, g_x, g_y = box_profile(self._reference, self.transition, self.ground, x, y)
        return value, np.array([g_x, g_y])

    def _point(self, shared: DataCollector) -> np.ndarray:
        placement = pin.updateFramePlacement(self.state.pinocchio, shared.pinocchio, self.frame_id)
        return placement.translation + placement.rotation @ self.point_local

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        placement = pin.updateFramePlacement(self.state.pinocchio, shared.pinocchio, self.frame_id)
        data.r[0] = point_above_box_row(placement.translation, placement.rotation, self.point_local, self._reference,
                                        self.transition, self.ground)

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        model, pdata = self.state.pinocchio, shared.pinocchio
        placement = pin.updateFramePlacement(model, pdata, self.frame_id)
        jacobian = pin.getFrameJacobian(model, pdata, self.frame_id, pin.LOCAL_WORLD_ALIGNED)
        point_above_box_jacobian_row(placement.translation, jacobian, placement.rotation, self.point_local,
                                     self._reference, self.transition, self.ground, data.Rx[0, : self.state.nv])

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        nv = self.state.nv
        return np.zeros(nv, dtype=np.int64), np.arange(nv, dtype=np.int64)

    def batch_calc(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray, r: np.ndarray) -> None:
        slot = horizon.frame_slot[self.frame_id]
        point_above_box_rows_many(horizon.frame_position[:, slot], horizon.frame_rotation[:, slot], self.point_local,
                                  references, self.transition, self.ground, mask, r)

    def batch_calc_diff(self, horizon: HorizonData, mask: np.ndarray, references: np.ndarray,
                        values: np.ndarray) -> None:
        slot = horizon.frame_slot[self.frame_id]
        point_above_box_jacobian_many(horizon.frame_position[:, slot], horizon.frame_jacobian[:, slot],
                                      horizon.frame_rotation[:, slot], self.point_local, references, self.transition,
                                      self.ground, mask, values)

    def batch_signature(self) -> tuple:
        # what the batched evaluation reads from the first node's residual (the margin is in each node's box)
        return (type(self), self.nr, self.batch_frames, tuple(self.point_local), self.transition, self.ground)
