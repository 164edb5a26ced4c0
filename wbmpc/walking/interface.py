"""The controller interface the closed loop drives, whatever runs behind it.

A controller is driven at two rates:

- ``replan(t, measurement)`` every ``replan_period`` (10 ms in the paper): the slow, expensive part
  (footstep planner + whole-body MPC). Returns a flat dict of scalars that the caller logs.
- ``compute(t, measurement)`` at every control tick (1 kHz): the torque command, shape (nu,) [N·m].
  The caller clips it to the torque limits.

Every state is in the Pinocchio convention (see :class:`wbmpc.walking.measurement.Measurement`).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

from sequencer.planner import VelocityCommand
from wbmpc.walking.measurement import Measurement


@runtime_checkable
class Controller(Protocol):
    """What the runner needs from a controller."""

    replan_period: float  # [s], period of ``replan``; a multiple of the simulation time step
    omega: float  # [1/s], pendulum frequency of the DCM the controller uses (after reset; logged by the runner)

    def reset(self, robot: Any, x0: np.ndarray, t0: float) -> None:
        """Prepare a new episode from state ``x0`` (nq + nv, Pinocchio) at time ``t0`` [s]."""

    def set_velocity_command(self, command: VelocityCommand) -> None:
        """The walking command (heading frame) from now on (a controller that does not walk ignores it)."""

    def replan(self, t: float, measurement: Measurement) -> dict[str, float]:
        """Slow update (planning); returns scalars to log (same keys at every call)."""

    def compute(self, t: float, measurement: Measurement) -> np.ndarray:
        """Torque command at time ``t``, shape (nu,) [N·m], before clipping."""
