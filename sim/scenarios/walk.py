"""``walk``: nominal walking on flat ground at V* = 0.33 m/s (paper, section IV.B, Figs. 5-6 top)."""

from __future__ import annotations

from dataclasses import dataclass

from sim.scenarios.base import Scenario, register


@register("walk")
@dataclass(frozen=True)
class Walk(Scenario):
    """Walk straight ahead on flat ground at ``speed`` [m/s]."""

    default_duration = 20.0

    speed: float = 0.33  # [m/s]
