"""Floating-base actuation: the first joint (free flyer) is unactuated, every other joint has a motor."""

from __future__ import annotations

import numpy as np

from wbmpc.errors import ParameterError
from wbmpc.ocp.state import StateMultibody


class ActuationFloatingBase:
    """tau = [0 (6,), u (nu,)] with nu = nv − 6; dtau_du = [0; I], dtau_dx = 0.

    Args:
        state: state of a model whose first joint is a free flyer (nq ≥ 7, nv ≥ 6).
    """

    def __init__(self, state: StateMultibody):
        model = state.pinocchio
        if model.njoints < 2 or model.joints[1].nv != 6 or model.joints[1].nq != 7:
            raise ParameterError(
                f"model {model.name!r} has no free-flyer root joint; floating-base actuation needs one"
            )
        self.state = state
        self.nu = state.nv - 6
        self.dtau_du = np.zeros((state.nv, self.nu))
        self.dtau_du[6:] = np.eye(self.nu)

    def calc(self, tau: np.ndarray, u: np.ndarray) -> None:
        """Write the generalised torque (nv,) for the control u (nu,) [N·m] into ``tau``."""
        tau[:6] = 0.0
        tau[6:] = u
