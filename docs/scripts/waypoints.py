"""The waypoint and push runs of docs/closed_loop.md ("Waypoints and pushes"): each robot round the
circle (1 m radius) and the square (2 m side) at the scenario's speed, and the G1 and the H1 pushed at
their pelvis, each with the robot's preset as committed (seed 0); one JSON line per run (status, fall
time and reason, path metrics or push outcome). With ``--out DIR`` each run's log and figure
(path, footholds, CoM) go to ``DIR/<robot>_<scenario>[_<path>]/``.

    python docs/scripts/waypoints.py [--robot g1] [--only waypoints|push] [--speed 0.25] [--out runs/waypoints]
"""

from __future__ import annotations

import argparse
import json
import os
import warnings

from sim import run_scenario
from sim.plots import save_figures

# (robot, path, duration [s]): a lap at 0.25 m/s, with the time Bolt needs sideways (v_y <= 0.1 m/s)
# and the G1 its turns in place at the square's corners
WAYPOINT_RUNS = [("g1", "circle", 45.0), ("g1", "square", 80.0), ("bolt", "circle", 50.0), ("bolt", "square", 65.0),
                 ("h1", "circle", 45.0), ("h1", "square", 80.0)]
# pushes at the pelvis, 0.1 s while walking at 0.3 m/s: (robot, force [N], direction [deg], push time [s]) (the
# five gait phases: sim/campaigns/examples/*_push_*.toml)
PUSH_RUNS = [("g1", 30.0, 90.0, 4.0), ("g1", 60.0, 90.0, 4.0), ("g1", 60.0, 0.0, 4.0),
             ("h1", 90.0, 90.0, 4.0), ("h1", 150.0, 0.0, 4.0)]
PATH_METRICS = ("path_deviation_max", "path_deviation_mean", "heading_error_max", "heading_error_mean",
                "path_progress", "path_completion")


def _rounded(metrics: dict, names) -> dict:
    def rounded(value):
        return value if value is None or isinstance(value, bool) else round(float(value), 3)

    return {name: rounded(metrics.get(name)) for name in names}


def _save(log, out: str | None, name: str) -> None:
    if out is not None:
        directory = os.path.join(out, name)
        log.save(directory)
        save_figures(log, os.path.join(directory, "figures.png"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", choices=("g1", "bolt", "h1"), default=None, help="only this robot's runs")
    parser.add_argument("--only", choices=("waypoints", "push"), default=None, help="only these runs")
    parser.add_argument("--speed", type=float, default=None, help="waypoints: speed along the path [m/s]")
    parser.add_argument("--out", default=None, metavar="DIR", help="write each run's log and figure under DIR")
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # the node-wise evaluation warning, once per G1 run
    speed = {} if args.speed is None else {"speed": args.speed}
    if args.only in (None, "waypoints"):
        for robot, path, duration in WAYPOINT_RUNS:
            if args.robot not in (None, robot):
                continue
            log = run_scenario("waypoints", robot=robot, path=path, duration=duration, seed=0, progress=False, **speed)
            _save(log, args.out, f"{robot}_waypoints_{path}")
            print(json.dumps({"robot": robot, "path": path, "duration": duration, "status": log.status,
                              "fall_time": log.fall_time, "fall_reason": log.fall_reason,
                              **_rounded(log.metrics, PATH_METRICS)}), flush=True)
    if args.only in (None, "push"):
        for robot, force, direction, push_time in PUSH_RUNS:
            if args.robot not in (None, robot):
                continue
            log = run_scenario("push", robot=robot, duration=push_time + 4.0, seed=0, progress=False, speed=0.3,
                               force=force, direction=direction, push_time=push_time)
            _save(log, args.out, f"{robot}_push_{force:g}N_{direction:g}deg")
            print(json.dumps({"robot": robot, "force": force, "direction": direction, "push_time": push_time,
                              "status": log.status, "fall_time": log.fall_time, "fall_reason": log.fall_reason,
                              **_rounded(log.metrics, ("push_recovered", "push_recovery_time",
                                                       "push_max_dcm_deviation_y"))}), flush=True)


if __name__ == "__main__":
    main()
