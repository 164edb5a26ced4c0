"""Shared pieces of every residual: its data buffers and the node data it reads."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin


@dataclass
class DataCollector:
    """What residuals may read at a node.

    Attributes:
        pinocchio: Pinocchio data after the dynamics' calc (kinematics, CoM, Jacobians computed).
        contacts: contact name -> contact data (forces and their derivatives), empty for the
            terminal node.
    """

    pinocchio: pin.Data
    contacts: dict = field(default_factory=dict)


class ResidualData:
    """Buffers of one residual: r (nr,), Rx (nr, ndx), Ru (nr, nu)."""

    def __init__(self, nr: int, ndx: int, nu: int):
        self.r = np.zeros(nr)
        self.Rx = np.zeros((nr, ndx))
        self.Ru = np.zeros((nr, nu))
