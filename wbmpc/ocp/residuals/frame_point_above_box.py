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
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbmpc.errors import ParameterError, check_finite
from wbmpc.ocp.residuals.base import DataCollector, ResidualData
from wbmpc.ocp.state import StateMultibody


def _smoothstep(s: float) -> tuple[float, float]:
    """q(s) = 10 s³ − 15 s⁴ + 6 s⁵ on [0, 1] (clamped outside) and dq/ds."""
    s = min(max(s, 0.0), 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s)), 30.0 * s * s * (1.0 - s) * (1.0 - s)


def _window(u: float, half: float, transition: float) -> tuple[float, float]:
    """S(u) and dS/du of the module docstring (``half`` = e, the grown half extent [m])."""
    distance = abs(u) - half
    if distance <= 0.0:
        return 1.0, 0.0
    if distance >= transition:
        return 0.0, 0.0
    value, slope = _smoothstep((transition - distance) / transition)
    return value, -slope / transition * (1.0 if u > 0.0 else -1.0)


class ResidualFramePointAboveBox:
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
    (h = ground).
    """

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
        self.point_local = point
        self.margin, self.transition, self.ground = float(margin), float(transition), float(ground)
        self.nr = 1
        self.nu = nu
        self.clear()

    def set_box(self, center, axis, half_depth: float, half_width: float, height: float) -> None:
        """The box: footprint centre (2,) [m], world unit axis along its depth (2,), half extents along and
        across it [m], top above the ground [m]."""
        self._center = np.asarray(center, dtype=float).reshape(2)
        along = np.asarray(axis, dtype=float).reshape(2)
        self._axes = np.array([along, [-along[1], along[0]]])
        self._half = (float(half_depth) + self.margin, float(half_width) + self.margin)
        self._height = float(height)

    def clear(self) -> None:
        """No box: h = ground everywhere."""
        self._center, self._axes = np.zeros(2), np.eye(2)
        self._half, self._height = (0.0, 0.0), 0.0

    def profile(self, xy) -> tuple[float, np.ndarray]:
        """h(x, y) [m] and its gradient (2,) at the world point ``xy`` (2,) [m]."""
        u = self._axes @ (np.asarray(xy, dtype=float) - self._center)
        s1, d1 = _window(float(u[0]), self._half[0], self.transition)
        s2, d2 = _window(float(u[1]), self._half[1], self.transition)
        return self.ground + self._height * s1 * s2, self._height * (d1 * s2 * self._axes[0] + s1 * d2 * self._axes[1])

    def _point(self, shared: DataCollector) -> np.ndarray:
        placement = pin.updateFramePlacement(self.state.pinocchio, shared.pinocchio, self.frame_id)
        return placement.translation + placement.rotation @ self.point_local

    def calc(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        point = self._point(shared)
        data.r[0] = point[2] - self.profile(point[:2])[0]

    def calcDiff(self, data: ResidualData, x: np.ndarray, u: np.ndarray | None, shared: DataCollector) -> None:
        pdata = shared.pinocchio
        point = self._point(shared)
        _, gradient = self.profile(point[:2])
        jacobian = pin.getFrameJacobian(self.state.pinocchio, pdata, self.frame_id, pin.LOCAL_WORLD_ALIGNED)
        w = pdata.oMf[self.frame_id].rotation @ self.point_local
        linear = jacobian[:3] - pin.skew(w) @ jacobian[3:]  # the point's velocity: v + ω × w
        data.Rx[0, : self.state.nv] = linear[2] - gradient @ linear[:2]

    def createData(self) -> ResidualData:
        return ResidualData(self.nr, self.state.ndx, self.nu)
