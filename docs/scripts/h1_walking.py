"""The H1's walking runs of docs/closed_loop.md ("The H1"): standing 10 s, in place 20 s, 0.3 and
0.5 m/s for 20 s, each with the H1 preset as committed (seed 0), printed one JSON line per run
(status, fall time and reason, steady speed errors, steps, mean forward speed over the second
half, MPC update median). Needs the optional extra ``wbmpc[h1]``.

    python docs/scripts/h1_walking.py [--duration 20] [--set section.name=value ...]
"""

from __future__ import annotations

import argparse
import json
import warnings

import numpy as np

from sim import run_scenario
from wbmpc.cli.arguments import parse_assignment

STAND = {"start_double_support": 10.5}  # both feet down for the whole 10 s run: standing
RUNS = [((0.0, 0.0, 0.0), 10.0, STAND), ((0.0, 0.0, 0.0), None, {}), ((0.3, 0.0, 0.0), None, {}),
        ((0.5, 0.0, 0.0), None, {})]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=20.0, help="length of the stepping runs [s]")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", type=parse_assignment,
                        help="walking-preset override (a TOML value), e.g. planner.double_support=0.15")
    args = parser.parse_args()
    overrides = dict(args.set)
    warnings.simplefilter("ignore")  # the node-wise evaluation warning (the KKT backend), once per run
    for command, duration, extra in RUNS:
        duration = args.duration if duration is None else duration
        log = run_scenario("walk", robot="h1", duration=duration, seed=0, progress=False, velocity_command=command,
                           **{**overrides, **extra})
        m = log.metrics
        t, com = log.ticks["t"], log.ticks["com"]
        half = len(t) // 2
        print(json.dumps({"command": command, "duration": duration, "overrides": {**overrides, **extra},
                          "status": log.status, "fall_time": log.fall_time, "fall_reason": log.fall_reason,
                          "velocity_error_mm_s": [None if m.get(k) is None else round(1e3 * m[k], 1)
                                                  for k in ("velocity_error_x", "velocity_error_y")],
                          "steps": int((log.replans["stance_switched"] > 0).sum()),
                          "mean_v_x_second_half": round(float((com[-1, 0] - com[half, 0]) / max(1e-9, t[-1] - t[half])), 3),
                          "com_displacement_m": np.round(com[-1, :2] - com[0, :2], 3).tolist(),
                          "mpc_update_median_ms": None if m.get("mpc_tick_time_median") is None
                          else round(1e3 * m["mpc_tick_time_median"], 1)}), flush=True)


if __name__ == "__main__":
    main()
