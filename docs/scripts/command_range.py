"""Walk a robot at the edges of its command range (12 s walks) and print what each command gives.

    python docs/scripts/command_range.py --robot bolt [--duration 12]

Used to choose the ``[command]`` range of a walking preset (docs/closed_loop.md): each command is
run with the range check widened, so that commands beyond the preset's range can be measured too.
"""

from __future__ import annotations

import argparse
import json

from sim import run_scenario

COMMANDS = [(0.5, 0.0, 0.0), (0.6, 0.0, 0.0), (-0.3, 0.0, 0.0), (-0.4, 0.0, 0.0), (0.0, 0.15, 0.0),
            (0.0, -0.15, 0.0), (0.0, 0.2, 0.0), (0.33, 0.1, 0.0)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="bolt")
    parser.add_argument("--duration", type=float, default=12.0)
    args = parser.parse_args()
    rows = []
    for command in COMMANDS:
        log = run_scenario("walk", robot=args.robot, duration=args.duration, seed=0, progress=False,
                           velocity_command=command, **{"command.v_x": (-2.0, 2.0), "command.v_y": (-2.0, 2.0)})
        m = log.metrics
        row = {"command": command, "status": log.status, "fall_time": log.fall_time,
               "mean_velocity": (m.get("mean_velocity_x"), m.get("mean_velocity_y")),
               "velocity_error": (m.get("velocity_error_x"), m.get("velocity_error_y"))}
        rows.append(row)
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
