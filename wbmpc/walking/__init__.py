"""The walking application: the walking OCP built from a contact schedule, the walking MPC, and
the controller that composes a footstep planner, the MPC, the 1 kHz feedback law and the online
estimators. It is what would run on hardware: it needs nothing of MuJoCo (``sim`` sits on top).
"""

from wbmpc.walking.controller import WalkingController, WalkingControllerConfig
from wbmpc.walking.mpc import WalkingMPC
from wbmpc.walking.ocp import StateWeights, WalkingOCP, WalkingOCPConfig

__all__ = ["StateWeights", "WalkingController", "WalkingControllerConfig", "WalkingMPC", "WalkingOCP",
           "WalkingOCPConfig"]
