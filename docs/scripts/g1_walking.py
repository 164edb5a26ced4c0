"""The G1's walking runs of docs/closed_loop.md ("The G1 (session 7)"): in place 20 s, 0.3 m/s for
10 and 20 s, 0.5 m/s for 10 s, each with the G1 preset as committed (seed 0), printed one JSON line
per run (status, fall time and reason, steady speed errors, MPC update median).

    python docs/scripts/g1_walking.py [--set section.name=value ...]
"""

from __future__ import annotations

import argparse
import json
import warnings

from sim import run_scenario

RUNS = [((0.0, 0.0, 0.0), 20.0), ((0.3, 0.0, 0.0), 10.0), ((0.3, 0.0, 0.0), 20.0), ((0.5, 0.0, 0.0), 10.0)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="walking-preset override (a number), e.g. ocp.wrench_cone_weight=1e3")
    args = parser.parse_args()
    overrides = {}
    for item in args.set:
        key, _, value = item.partition("=")
        overrides[key] = float(value) if "." in value or "e" in value else int(value)
    warnings.simplefilter("ignore")  # the node-wise evaluation warning, once per run
    for command, duration in RUNS:
        log = run_scenario("walk", robot="g1", duration=duration, seed=0, progress=False, velocity_command=command,
                           **overrides)
        m = log.metrics
        print(json.dumps({"command": command, "duration": duration, "status": log.status, "fall_time": log.fall_time,
                          "fall_reason": log.fall_reason,
                          "velocity_error_mm_s": [None if m.get(k) is None else round(1e3 * m[k], 1)
                                                  for k in ("velocity_error_x", "velocity_error_y")],
                          "mpc_update_median_ms": None if m.get("mpc_tick_time_median") is None
                          else round(1e3 * m["mpc_tick_time_median"], 1)}), flush=True)


if __name__ == "__main__":
    main()
