"""``transition``: step in place, then walk (paper, section IV.D, Fig. 8: 0 -> 0.3 m/s at t = 5 s)."""

from __future__ import annotations

from dataclasses import dataclass

from sim.scenarios.base import Scenario, _check_range, register


@register("transition")
@dataclass(frozen=True)
class Transition(Scenario):
    """Command ``speed_before`` until ``switch_time``, then ``speed`` [m/s] (a step: ``ramp_time`` unused)."""

    default_duration = 15.0

    speed: float = 0.3  # [m/s], command after the switch
    speed_before: float = 0.0  # [m/s], command before the switch (0 = stepping in place)
    switch_time: float = 5.0  # [s]

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_range("speed_before", self.speed_before, -2.0, 2.0, "m/s")
        _check_range("switch_time", self.switch_time, 0.0, 1e4, "s")

    def velocity_command(self, t: float, pose=None) -> tuple[float, float, float]:
        return (self.speed_before if t < self.switch_time else self.speed, self.lateral_speed, self.yaw_rate)

    def commands(self) -> list[tuple[float, float, float]]:
        return [(self.speed_before, self.lateral_speed, self.yaw_rate), (self.speed, self.lateral_speed, self.yaw_rate)]

    def events(self) -> dict[str, float]:
        return {"speed_switch": self.switch_time}
