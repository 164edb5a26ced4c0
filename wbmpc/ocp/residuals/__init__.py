"""Residual functions r(x, u), one per module, with their Jacobians Rx (nr, ndx) and Ru (nr, nu).

A residual reads the shared node data (Pinocchio data after the dynamics' calc, contact data)
through a :class:`wbmpc.ocp.residuals.base.DataCollector`; it never runs kinematics itself except the
frame placement it needs.
"""

from wbmpc.ocp.residuals.base import DataCollector, ResidualData
from wbmpc.ocp.residuals.com_position import ResidualCoMPosition
from wbmpc.ocp.residuals.contact_force import ResidualContactForce, ResidualLinearInContactForce
from wbmpc.ocp.residuals.control import ResidualControl
from wbmpc.ocp.residuals.frame_height import ResidualFrameHeight
from wbmpc.ocp.residuals.frame_point_above_box import ResidualFramePointAboveBox
from wbmpc.ocp.residuals.frame_point_height import ResidualFramePointHeight
from wbmpc.ocp.residuals.frame_rotation import ResidualFrameRotation
from wbmpc.ocp.residuals.frame_translation import ResidualFrameTranslation
from wbmpc.ocp.residuals.frame_velocity import ResidualFrameVelocity
from wbmpc.ocp.residuals.friction_cone import ResidualFrictionCone
from wbmpc.ocp.residuals.joint_position import ResidualJointPosition
from wbmpc.ocp.residuals.state import ResidualState
from wbmpc.ocp.residuals.wrench_cone import ResidualWrenchCone

__all__ = [
    "DataCollector",
    "ResidualData",
    "ResidualCoMPosition",
    "ResidualContactForce",
    "ResidualLinearInContactForce",
    "ResidualControl",
    "ResidualFrameHeight",
    "ResidualFramePointAboveBox",
    "ResidualFramePointHeight",
    "ResidualFrameRotation",
    "ResidualFrameTranslation",
    "ResidualFrameVelocity",
    "ResidualFrictionCone",
    "ResidualJointPosition",
    "ResidualState",
    "ResidualWrenchCone",
]
