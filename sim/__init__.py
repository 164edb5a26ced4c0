"""MuJoCo closed loop: controllers, the 1 kHz runner, the paper's scenarios, metrics and plots.

    from sim import run_scenario
    log = run_scenario("walk", robot="bolt", speed=0.33, duration=20.0, seed=0)
    log.metrics["velocity_error_x"]
"""

from sim.log import RunLog, load_run
from sim.runner import RunnerOptions, run_scenario
from sim.scenarios import Scenario, available_scenarios, make_scenario, register

__all__ = [
    "RunLog",
    "RunnerOptions",
    "Scenario",
    "available_scenarios",
    "load_run",
    "make_scenario",
    "register",
    "run_scenario",
]
