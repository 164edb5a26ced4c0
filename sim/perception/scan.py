"""One scan of the rangefinder array: the ranges of every ray at one time, and their world points."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robots.conventions import base_rotation


@dataclass(frozen=True)
class Scan:
    """The ranges of the rays at time ``t``.

    Attributes:
        t: time of the scan [s].
        ranges: distance along each ray to the surface it hit [m], shape (n_rays,); NaN where the
            ray returned nothing (no surface within range, a dropout, a blackout).
        origin_base: the rays' common origin, base frame [m], shape (3,).
        directions_base: unit ray directions, base frame, shape (n_rays, 3).
    """

    t: float
    ranges: np.ndarray
    origin_base: np.ndarray
    directions_base: np.ndarray

    @property
    def n_returns(self) -> int:
        """Rays that returned a range."""
        return int(np.count_nonzero(np.isfinite(self.ranges)))

    def points_world(self, q_base) -> np.ndarray:
        """World points of the returns, shape (n_returns, 3) [m], from a base pose.

        Args:
            q_base: the base's configuration, Pinocchio convention: q[0:3] position (world) [m],
                q[3:7] quaternion (x, y, z, w); a full configuration q or measured state x also
                works (only its first 7 entries are read). Pass the *measured* state: the robot
                knows where it is only through it.
        """
        valid = np.isfinite(self.ranges)
        local = self.origin_base + self.ranges[valid, None] * self.directions_base[valid]
        q = np.asarray(q_base, dtype=float)
        return q[:3] + local @ base_rotation(q).T
