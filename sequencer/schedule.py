"""Per-node contact schedule: the data the sequencer hands to the whole-body OCP.

A :class:`ContactSchedule` samples a footstep plan on the OCP's time grid. Node ``k`` is at
time ``t0 + k * dt``; there are ``n_nodes + 1`` rows (running nodes and the terminal node).
Feet are indexed in the order of ``feet`` (``("left", "right")`` for bipeds); the robot
description maps these names to its frames.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbmpc.errors import ParameterError


@dataclass(frozen=True)
class ContactSchedule:
    """Which feet touch the ground at each OCP node, and where each swing ends.

    Attributes:
        t0: time of node 0 [s] (same clock as the plan).
        dt: node spacing [s], > 0.
        feet: foot names, e.g. ``("left", "right")``.
        in_contact: shape (n_nodes + 1, n_feet), bool. True where the foot is in contact.
        swing_phase: shape (n_nodes + 1, n_feet), fraction of the current swing elapsed at
            the node, in [0, 1]; NaN where the foot is in contact.
        swing_duration: shape (n_nodes + 1, n_feet), total duration of the current swing [s];
            NaN where the foot is in contact.
        touchdown_position: shape (n_nodes + 1, n_feet, 2), world-frame (x, y) of the planned
            foothold ending the current swing [m]; NaN where the foot is in contact.
    """

    t0: float
    dt: float
    feet: tuple[str, ...]
    in_contact: np.ndarray
    swing_phase: np.ndarray
    swing_duration: np.ndarray
    touchdown_position: np.ndarray

    def __post_init__(self) -> None:
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise ParameterError(f"dt={self.dt} s must be a finite positive number")
        n_feet = len(self.feet)
        rows = self.in_contact.shape[0]
        expected = {
            "in_contact": (rows, n_feet),
            "swing_phase": (rows, n_feet),
            "swing_duration": (rows, n_feet),
            "touchdown_position": (rows, n_feet, 2),
        }
        for name, shape in expected.items():
            if getattr(self, name).shape != shape:
                raise ParameterError(f"{name} has shape {getattr(self, name).shape}, expected {shape}")

    @property
    def n_nodes(self) -> int:
        """Number of running nodes (the schedule has ``n_nodes + 1`` rows)."""
        return self.in_contact.shape[0] - 1

    @property
    def times(self) -> np.ndarray:
        """Node times [s], shape (n_nodes + 1,)."""
        return self.t0 + self.dt * np.arange(self.n_nodes + 1)
