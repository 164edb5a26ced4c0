"""The walking application: the walking OCP built from a contact schedule, the walking MPC, and
the controller that composes a footstep planner, the MPC, the 1 kHz feedback law and the online
estimators, tuned by one preset file per robot. It is what would run on hardware: it needs
nothing of MuJoCo (``sim`` sits on top).
"""

from wbmpc.walking.controller import WalkingController
from wbmpc.walking.controller_config import WalkingControllerConfig
from wbmpc.walking.interface import Controller
from wbmpc.walking.mpc import WalkingMPC
from wbmpc.walking.ocp import StateWeights, WalkingOCP, WalkingOCPConfig
from wbmpc.walking.pd import JointPDController
from wbmpc.walking.preset import WalkingPreset, available_walking_presets, load_walking_preset

__all__ = ["Controller", "JointPDController", "StateWeights", "WalkingController", "WalkingControllerConfig",
           "WalkingMPC", "WalkingOCP", "WalkingOCPConfig", "WalkingPreset", "available_walking_presets",
           "load_walking_preset"]
