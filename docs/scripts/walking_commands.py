"""The omnidirectional walking runs of docs/closed_loop.md ("The G1 (session 8)", "The H1's commands"): the
commands of issue 13 (in place 20 s, 0.3 m/s for 60 s, 0.5 m/s, lateral 0.15 m/s, backwards 0.2 m/s, turning
in place and while walking at 0.3 rad/s), each with the robot's preset as committed, printed one JSON line
per run (status, fall time and reason, steady speed and yaw-rate errors, mean velocities, MPC update
median, real-time factor). ``--robot h1`` needs the optional extra ``wbmpc[h1]``.

    python docs/scripts/walking_commands.py [--robot g1|h1] [--seed S] [--noise] [--only NAME ...]
                                            [--set section.name=value ...]

``--noise`` adds measurement noise (0.1 mrad / 1 mm/s std, seeded): runs are chaotic, a second
seed shows how far one run's fall time speaks for the preset.
"""

from __future__ import annotations

import argparse
import json
import warnings

from sim import run_scenario
from wbmpc.cli.arguments import parse_assignment

# name -> ((v_x [m/s], v_y [m/s], yaw_rate [rad/s]), duration [s])
RUNS = {
    "in_place": ((0.0, 0.0, 0.0), 20.0),
    "forward_0.3": ((0.3, 0.0, 0.0), 60.0),
    "forward_0.5": ((0.5, 0.0, 0.0), 20.0),
    "lateral_0.15": ((0.0, 0.15, 0.0), 15.0),
    "backwards_0.2": ((-0.2, 0.0, 0.0), 15.0),
    "turn_in_place_0.3": ((0.0, 0.0, 0.3), 15.0),
    "walk_and_turn": ((0.3, 0.0, 0.3), 15.0),
}
NOISE = {"noise_q": 1e-4, "noise_v": 1e-3}  # [rad or m], [rad/s or m/s] std of the measurement noise




def _milli(metrics: dict, key: str):
    """metrics[key] x 1000, rounded to 0.1 (None when the run has no such metric, e.g. it fell early)."""
    return None if metrics.get(key) is None else round(1e3 * metrics[key], 1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", choices=("g1", "h1"), default="g1")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--noise", action="store_true", help="measurement noise (see the module docstring)")
    parser.add_argument("--only", nargs="+", choices=sorted(RUNS), default=None, help="run only these")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", type=parse_assignment,
                        help="walking-preset override, e.g. ocp.wrench_cone_weight=1e3 or footstep_planner.kind=alip")
    args = parser.parse_args()
    overrides = dict(args.set)
    options = NOISE if args.noise else {}
    warnings.simplefilter("ignore")
    for name in args.only or RUNS:
        command, duration = RUNS[name]
        log = run_scenario("walk", robot=args.robot, duration=duration, seed=args.seed, progress=False,
                           velocity_command=command, **options, **overrides)
        m = log.metrics
        print(json.dumps({
            "robot": args.robot, "run": name, "command": command, "duration": duration, "seed": args.seed, "noise": args.noise,
            "status": log.status, "fall_time": log.fall_time, "fall_reason": log.fall_reason,
            "velocity_error_mm_s": [_milli(m, "velocity_error_x"), _milli(m, "velocity_error_y")],
            "mean_velocity": [m.get("mean_velocity_x"), m.get("mean_velocity_y")],
            "velocity_error_heading_mm_s": [_milli(m, "velocity_error_heading_x"), _milli(m, "velocity_error_heading_y")],
            "mean_yaw_rate": m.get("mean_yaw_rate"), "yaw_rate_error": m.get("yaw_rate_error"),
            "mpc_update_median_ms": _milli(m, "mpc_tick_time_median"), "real_time_factor": m.get("real_time_factor"),
        }), flush=True)


if __name__ == "__main__":
    main()
