"""Obstacle negotiation mode: walking -> negotiation -> walking, triggered by the perceived obstacles.

At every replan the controller looks at ``Measurement.obstacles`` (what perception has detected; never
the scene's ground truth). Along the stance heading u (world unit vector of the stance yaw) and across
it, from the CoM c:

- an obstacle *counts* when its footprint reaches into the corridor |across - c_across| <=
  ``negotiation_corridor`` and its near edge (the footprint corners' least u-coordinate) is at most
  ``negotiation_lookahead`` ahead of c, and it is not yet *passed*: both feet more than
  ``negotiation_release`` beyond its far edge (the corners' largest u-coordinate);
- the mode is *negotiation* (code 1) while some obstacle counts, else *walking* (code 0). In
  negotiation the counting obstacles go to the footstep planner (footholds before/beyond,
  :mod:`sequencer.footholds`) and, through the plan's crossing steps, to the OCP (apex and clearance),
  and the forward command is bounded by ``negotiation_speed_max``, or by 0 when one of them is too deep for one
  crossing step (the planner's ``can_cross``; ``PlanningStage.blocked``, logged ``negotiation_blocked``): the
  robot stops before it, stepping in place;
- a *passed* obstacle is still *avoided* (:attr:`NegotiationMode.avoided`: handed to the footstep planner,
  not counted for the mode) while its far edge lies less than ``negotiation_lookahead`` behind the rearmost
  foot: a robot that has just crossed a box with its DCM behind its feet must not be planned a step back
  onto it (the H1 was, at 0.2 m/s: both feet across, then a step planned 16 cm back onto the box, and a fall).
  With no obstacle counting or avoided nothing is handed on: the plan and the OCP are the ones without
  obstacles.

Every switch is kept with its time (:attr:`NegotiationMode.switches`) and the replan record carries the
mode code (``negotiation_mode``) and the switch (``negotiation_switch``: +1 entering, -1 leaving, 0).
"""

from __future__ import annotations

import math

import numpy as np

from sequencer.obstacles import Obstacle
from wbmpc.errors import ParameterError

WALKING, NEGOTIATION = 0, 1
"""Mode codes of the replan record's ``negotiation_mode``."""


class NegotiationMode:
    """The walking/negotiation mode of a run (see the module docstring).

    Args:
        lookahead, corridor, release: ``negotiation_lookahead``, ``negotiation_corridor``,
            ``negotiation_release`` [m] of the controller's configuration.

    Attributes:
        mode: WALKING or NEGOTIATION.
        switches: (time [s], new mode) of every switch so far.
        active: the obstacles of the current negotiation (empty while walking).
        avoided: the obstacles the footstep planner keeps its footholds off: the active ones and the passed
            ones still within ``lookahead`` behind the rearmost foot (see the module docstring).
    """

    def __init__(self, lookahead: float, corridor: float, release: float) -> None:
        self.lookahead, self.corridor, self.release = float(lookahead), float(corridor), float(release)
        self.reset()

    def reset(self) -> None:
        """Walking, no switch, no obstacle."""
        self.mode = WALKING
        self.switches: list[tuple[float, int]] = []
        self.active: tuple[Obstacle, ...] = ()
        self.avoided: tuple[Obstacle, ...] = ()

    def update(self, t: float, obstacles, com_xy, feet_xy, heading_yaw: float) -> int:
        """The mode at ``t`` [s] from the perceived ``obstacles``, the CoM (x, y) [m], the feet (n_feet, 2) [m]
        (world frame) and the stance heading [rad]; returns the switch (+1 entering negotiation, -1 leaving, 0).

        Raises:
            ParameterError: an obstacle is not a :class:`sequencer.obstacles.Obstacle`.
        """
        direction = np.array([math.cos(heading_yaw), math.sin(heading_yaw)])
        normal = np.array([-direction[1], direction[0]])
        com = np.asarray(com_xy, dtype=float)
        feet = np.asarray(feet_xy, dtype=float).reshape(-1, 2)
        counting, passed = [], []
        if self.lookahead > 0.0:
            for obstacle in obstacles:
                if not isinstance(obstacle, Obstacle):
                    raise ParameterError(f"measurement obstacles must be sequencer.obstacles.Obstacle, "
                                         f"got {type(obstacle).__name__}")
                corners = obstacle.footprint_corners()
                along, across = corners @ direction, (corners - com) @ normal
                if across.max() < -self.corridor or across.min() > self.corridor:
                    continue
                if along.min() - com @ direction > self.lookahead:
                    continue
                behind = float(np.min(feet @ direction)) - along.max()  # rearmost foot beyond the far edge [m]
                if behind > self.release:
                    if behind < self.lookahead:
                        passed.append(obstacle)
                    continue
                counting.append(obstacle)
        self.active = tuple(counting)
        self.avoided = tuple(counting + passed)
        mode = NEGOTIATION if counting else WALKING
        switch = mode - self.mode
        if switch:
            self.switches.append((float(t), mode))
            self.mode = mode
        return switch
