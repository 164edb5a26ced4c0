"""What a controller sees of the simulated robot at one control tick.

The runner converts MuJoCo's state into the library's Pinocchio convention before any controller
sees it (see ``robots.conventions``), so controllers never deal with MuJoCo's quaternion order or
velocity frames.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sequencer.obstacles import Obstacle


@dataclass(frozen=True)
class Measurement:
    """Measured state at time ``t``.

    Attributes:
        t: simulation time [s].
        x: measured state, shape (nq + nv,), Pinocchio convention: q = [base position (world) [m],
            base quaternion (x, y, z, w), joint angles [rad]], v = [base linear velocity (base frame)
            [m/s], base angular velocity (base frame) [rad/s], joint velocities [rad/s]]. Includes the
            measurement noise, if any.
        foot_in_contact: shape (n_feet,), bool; True where the simulator reports a contact between
            that foot and the ground (order of ``robot.foot_frames``).
        obstacles: the obstacles the robot's perception has detected so far (world frame; see
            :mod:`sequencer.obstacles`), empty without perception. Estimated from the sensors'
            returns and the measured state only, never from the scene's ground truth.
    """

    t: float
    x: np.ndarray
    foot_in_contact: np.ndarray
    obstacles: tuple[Obstacle, ...] = ()
