"""Registered closed-loop scenarios, one per experiment of the paper (see ``sim.scenarios.base``)."""

from sim.scenarios import obstacle, push, slip, terrain, transition, walk, waypoints  # noqa: F401  (registration)
from sim.scenarios.base import (
    Scenario,
    available_scenarios,
    make_scenario,
    register,
    scenario_class,
    scenario_parameters,
)

__all__ = [
    "Scenario",
    "available_scenarios",
    "make_scenario",
    "register",
    "scenario_class",
    "scenario_parameters",
]
