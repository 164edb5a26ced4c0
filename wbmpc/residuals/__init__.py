"""Residual functions r(x, u), one per module, with their Jacobians Rx (nr, ndx) and Ru (nr, nu).

A residual reads the shared node data (Pinocchio data after the dynamics' calc, contact data)
through a :class:`wbmpc.residuals.base.DataCollector`; it never runs kinematics itself except the
frame placement it needs.
"""

from wbmpc.residuals.base import DataCollector, ResidualData
from wbmpc.residuals.com_position import ResidualCoMPosition
from wbmpc.residuals.contact_force import ResidualContactForce
from wbmpc.residuals.control import ResidualControl
from wbmpc.residuals.frame_height import ResidualFrameHeight
from wbmpc.residuals.frame_translation import ResidualFrameTranslation
from wbmpc.residuals.frame_velocity import ResidualFrameVelocity
from wbmpc.residuals.friction_cone import ResidualFrictionCone
from wbmpc.residuals.state import ResidualState

__all__ = [
    "DataCollector",
    "ResidualData",
    "ResidualCoMPosition",
    "ResidualContactForce",
    "ResidualControl",
    "ResidualFrameHeight",
    "ResidualFrameTranslation",
    "ResidualFrameVelocity",
    "ResidualFrictionCone",
    "ResidualState",
]
