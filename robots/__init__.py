"""Robot descriptions: Pinocchio and MuJoCo models of the same robot file (URDF or MJCF), contacts, limits.

    >>> from robots import load_robot
    >>> robot = load_robot("bolt")
    >>> robot.nq, robot.nv, robot.nu
    (13, 12, 6)

Each robot is one module registering a builder (see :mod:`robots.registry`); importing this
package registers them all.
"""

from robots import bolt as _bolt  # noqa: F401  (registers "bolt")
from robots import g1 as _g1  # noqa: F401  (registers "g1")
from robots import h1 as _h1  # noqa: F401  (registers "h1"; loading it needs the extra wbmpc[h1])
from robots.description import CONTACT_TYPES, MujocoContactSettings, RobotDescription
from robots.registry import available_robots, load_robot, register_robot

__all__ = [
    "CONTACT_TYPES",
    "MujocoContactSettings",
    "RobotDescription",
    "available_robots",
    "load_robot",
    "register_robot",
]
