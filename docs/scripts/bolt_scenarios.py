"""The Bolt paper's closed-loop scenarios, seed 0, one line of metrics each (docs/reproduction.md):
a 60 s walk at 0.33 m/s, the 6.3 N lateral push at 5 s, cluttered terrain, the slip and the
0 -> 0.3 m/s transition.

    python docs/scripts/bolt_scenarios.py [--only walk60 push ...]
"""

from __future__ import annotations

import argparse
import json

from sim import run_scenario

RUNS = {
    "walk20": dict(name="walk", duration=20.0),
    "walk60": dict(name="walk", duration=60.0),
    "push": dict(name="push"),
    "terrain": dict(name="terrain", duration=10.0),
    "slip": dict(name="slip", duration=8.0),
    "transition": dict(name="transition", duration=13.0),
}
KEYS = ("velocity_error_x", "velocity_error_y", "distance_x", "steps", "rise_time", "push_recovered",
        "push_recovery_time", "max_stance_slide", "real_time_factor")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="*", choices=sorted(RUNS), default=sorted(RUNS))
    args = parser.parse_args()
    for label in args.only:
        spec = dict(RUNS[label])
        log = run_scenario(spec.pop("name"), seed=0, progress=False, **spec)
        row = {"run": label, "status": log.status, "fall_time": log.fall_time}
        row.update({k: log.metrics.get(k) for k in KEYS if k in log.metrics})
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
