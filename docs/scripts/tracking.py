"""Velocity tracking of a robot over a set of commands (12 s walks, steady window): the table of
docs/closed_loop.md ("Tracking at low speed, backwards and sideways").

    python docs/scripts/tracking.py --robot bolt [--duration 12]
"""

from __future__ import annotations

import argparse
import json

from sim import run_scenario

COMMANDS = [(0.1, 0.0, 0.0), (0.0, 0.0, 0.0), (-0.2, 0.0, 0.0), (0.33, 0.0, 0.0), (0.0, 0.1, 0.0),
            (0.0, -0.1, 0.0), (0.0, 0.05, 0.0), (0.2, 0.05, 0.0), (0.33, -0.05, 0.0)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="bolt")
    parser.add_argument("--duration", type=float, default=12.0)
    args = parser.parse_args()
    for command in COMMANDS:
        log = run_scenario("walk", robot=args.robot, duration=args.duration, seed=0, progress=False,
                           velocity_command=command, **{"command.v_x": (-2.0, 2.0), "command.v_y": (-2.0, 2.0)})
        m = log.metrics
        print(json.dumps({"command": command, "status": log.status, "fall_time": log.fall_time,
                          "velocity_error_mm_s": [None if m.get(k) is None else round(1e3 * m[k], 1)
                                                  for k in ("velocity_error_x", "velocity_error_y")],
                          "distance_x": round(m.get("distance_x", float("nan")), 3)}), flush=True)


if __name__ == "__main__":
    main()
