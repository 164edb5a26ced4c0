"""Scenario interface and registry (dm_control style: seeded, registered by name).

A scenario is a dataclass of parameters (with units) that shapes one experiment of the paper:

- ``setup(robot, command_range)``: read what the scenario needs of the robot (the body to push,
  its size) and the velocity commands the controller accepts, before anything is built;
- ``modify_spec(spec, rng)``: edit the MuJoCo ``MjSpec`` before it is compiled (terrain, patches);
- ``initialize_episode(model, data, rng)``: set the initial state (default: reference posture
  lowered until the feet touch the ground, both feet on the ground as in the paper);
- ``before_step(t, model, data)``: act on the simulation before each step (pushes);
- ``velocity_command(t, pose)``: the walking command (v_x [m/s], v_y [m/s], yaw_rate [rad/s]) at
  time t, in the robot's heading frame; ``pose`` is the measured planar pose of the base
  (x [m], y [m], yaw [rad], world frame), which scenarios that steer the robot (``waypoints``) use
  and the others ignore.

All randomness comes from the ``rng`` the runner derives from the run's seed.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar, Mapping, Sequence

import numpy as np

from wbmpc.errors import ParameterError

_REGISTRY: dict[str, type["Scenario"]] = {}


def register(name: str):
    """Class decorator: make a :class:`Scenario` subclass available as ``name``."""

    def decorator(cls: type[Scenario]) -> type[Scenario]:
        if name in _REGISTRY:
            raise ValueError(f"scenario {name!r} is already registered by {_REGISTRY[name].__name__}")
        cls.name = name
        _REGISTRY[name] = cls
        return cls

    return decorator


def available_scenarios() -> list[str]:
    """Names of the registered scenarios."""
    return sorted(_REGISTRY)


def scenario_class(name: str) -> type["Scenario"]:
    if name not in _REGISTRY:
        raise ParameterError(f"scenario={name!r} is unknown (available: {', '.join(available_scenarios())})")
    return _REGISTRY[name]


def scenario_parameters(name: str) -> dict[str, Any]:
    """Parameter names of scenario ``name`` with their defaults."""
    return {f.name: f.default for f in dataclasses.fields(scenario_class(name))}


def make_scenario(name: str, **params: Any) -> "Scenario":
    """Instantiate scenario ``name``; unknown parameters raise a ParameterError listing the allowed ones."""
    cls = scenario_class(name)
    allowed = scenario_parameters(name)
    unknown = sorted(set(params) - set(allowed))
    if unknown:
        raise ParameterError(f"scenario {name!r} has no parameter {unknown} (allowed: {sorted(allowed)})")
    return cls(**params)


@dataclass(frozen=True)
class Scenario:
    """Base scenario: flat ground, constant velocity command (``speed``, ``lateral_speed``,
    ``yaw_rate``) in the heading frame, reached by a linear ramp from standing."""

    name: ClassVar[str] = "base"
    default_duration: ClassVar[float] = 10.0  # [s]
    steady_start: ClassVar[float] = 3.0  # [s] after the last command change: start of the steady part

    speed: float = 0.33  # [m/s], forward velocity command v_x
    ramp_time: float = 2.0  # [s], the command rises linearly from 0 to its value over this time
    lateral_speed: float = 0.0  # [m/s], lateral velocity command v_y (to the left)
    yaw_rate: float = 0.0  # [rad/s], yaw-rate command (counter-clockwise)

    def __post_init__(self) -> None:
        _check_range("speed", self.speed, -2.0, 2.0, "m/s")
        _check_range("lateral_speed", self.lateral_speed, -2.0, 2.0, "m/s")
        _check_range("yaw_rate", self.yaw_rate, -3.0, 3.0, "rad/s")
        _check_range("ramp_time", self.ramp_time, 0.0, 100.0, "s")

    def setup(self, robot: Any, command_range: Mapping[str, tuple[float, float]] | None) -> None:
        """Read what the scenario needs before the run (default: nothing).

        Args:
            robot: the :class:`robots.description.RobotDescription` of the run.
            command_range: {"v_x": (min, max) [m/s], "v_y": (min, max) [m/s], "yaw_rate": (min, max)
                [rad/s]}, heading frame: the commands the controller accepts (None: no limits known).
        """

    def modify_spec(self, spec: Any, rng: np.random.Generator) -> None:
        """Edit the MuJoCo model specification before compilation (default: nothing)."""

    def initialize_episode(self, model: Any, data: Any, rng: np.random.Generator) -> None:
        """Adjust the initial state in ``data`` (the runner already set the standing posture)."""

    def before_step(self, t: float, model: Any, data: Any) -> None:
        """Act on the simulation before the step at time ``t`` [s] (default: nothing)."""

    def velocity_command(self, t: float, pose: Sequence[float] | None = None) -> tuple[float, float, float]:
        """Walking command (v_x [m/s], v_y [m/s], yaw_rate [rad/s]), heading frame, at time ``t`` [s];
        ``pose``: measured base (x [m], y [m], yaw [rad]), world frame (unused here)."""
        command = (self.speed, self.lateral_speed, self.yaw_rate)
        if self.ramp_time > 0.0 and t < self.ramp_time:
            return tuple(value * t / self.ramp_time for value in command)
        return command

    def commands(self) -> list[tuple[float, float, float]]:
        """The commands the scenario holds after its ramps (checked against the robot's range before a run)."""
        return [(self.speed, self.lateral_speed, self.yaw_rate)]

    def events(self) -> dict[str, float]:
        """Times [s] of the scenario's events (push start, speed change...) for metrics and plots."""
        return {}


def _check_range(name: str, value: float, low: float, high: float, unit: str) -> None:
    if not (np.isfinite(value) and low <= value <= high):
        raise ParameterError(f"{name}={value} {unit} must be in [{low}, {high}] {unit}")
