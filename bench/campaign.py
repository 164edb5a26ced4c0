"""Campaign throughput: trials per minute in-process, on the local pool (1 and 2 workers) and on Ray.

Every configuration runs the same ``--trials`` closed-loop trials (push scenario, PD controller,
``--duration`` simulated seconds, no stop at the fall, so every trial does the same work) through
:func:`sim.campaigns.run_campaign`, records included. Each backend is started and warmed up first
(one trial per worker, untimed: imports, forkserver preload, ``ray.init``); that start-up time is
reported on its own.

Figures are ratios of trials per minute measured in the same run:

- local pool, 1 worker / in-process: the cost of running trials in worker processes (~1.0);
- local pool, 2 workers / 1 worker: the scaling ratio (2.0 is perfect; the machine is shared);
- Ray, 2 workers on this machine / local pool, 2 workers: what Ray's scheduling costs here.

``cores used`` = CPU time of the trials / wall time: how many cores the trials actually got. On
a shared machine it explains a scaling ratio below 2 (the other cores' load is not ours to take),
and ``trial CPU / wall`` below 1 shows a trial waiting for a core.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--trials", type=int, default=8, help="timed trials per configuration")
    parser.add_argument("--duration", type=float, default=1.0, help="simulated time per trial [s]")
    parser.add_argument("--no-ray", action="store_true", help="skip the Ray configuration")


def _spec(n_trials: int, duration: float, name: str):
    from sim.campaigns import CampaignSpec

    return CampaignSpec(
        name=name,
        scenario="push",
        controller="pd",
        duration=duration,
        params={"stop_on_fall": False, "push_time": 0.2, "push_duration": 0.1, "direction": 90.0},
        grid={"force": [float(f) for f in range(n_trials)]},
    )


def _measure(backend_name: str, workers: int, n_trials: int, duration: float) -> dict:
    from sim.campaigns import ResultStore, run_campaign
    from sim.campaigns.backends import make_backend

    tic = time.perf_counter()
    backend = make_backend(backend_name, workers=workers)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            run_campaign(_spec(workers, duration, "warm-up"), os.path.join(tmp, "warm-up"), backend=backend, progress=False)
            startup = time.perf_counter() - tic
            run = run_campaign(_spec(n_trials, duration, "bench"), os.path.join(tmp, "bench"), backend=backend, progress=False)
            records = ResultStore(os.path.join(tmp, "bench")).records()
    finally:
        backend.close()
    cpu_time = sum(r["cpu_time"] for r in records)
    return {
        "backend": backend_name,
        "workers": workers,
        "trials": run.n_run,
        "wall_time": run.wall_time,
        "trials_per_minute": run.trials_per_minute,
        "startup_time": startup,
        "trial_cpu_time_mean": cpu_time / len(records),
        "trial_wall_time_mean": sum(r["wall_time"] for r in records) / len(records),
        "cores_used": cpu_time / run.wall_time,
    }


def run(args: argparse.Namespace) -> dict:
    from wbmpc.errors import ParameterError

    if args.trials < 2:
        raise ParameterError(f"--trials={args.trials} must be >= 2")
    configurations = {
        "in-process": ("inline", 1),
        "local, 1 worker": ("local", 1),
        "local, 2 workers": ("local", 2),
    }
    ray_note = None
    if not args.no_ray:
        try:
            import ray  # noqa: F401

            configurations["ray, 2 workers"] = ("ray", 2)
        except ImportError:
            ray_note = "ray is not installed (pip install ray): Ray figures skipped"
    results = {label: _measure(name, workers, args.trials, args.duration) for label, (name, workers) in configurations.items()}
    rate = {label: r["trials_per_minute"] for label, r in results.items()}
    ratios = {
        "local 1 worker / in-process": rate["local, 1 worker"] / rate["in-process"],
        "scaling: local 2 workers / 1 worker": rate["local, 2 workers"] / rate["local, 1 worker"],
    }
    if "ray, 2 workers" in rate:
        ratios["ray 2 workers / local 2 workers"] = rate["ray, 2 workers"] / rate["local, 2 workers"]
    return {
        "trials": args.trials,
        "trial_duration": args.duration,
        "cpu_count": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0],
        "configurations": results,
        "ratios": ratios,
        "note": ray_note,
    }


def format_report(result: dict) -> str:
    lines = [
        f"campaign throughput: {result['trials']} PD push trials of {result['trial_duration']:.1f} s simulated "
        f"({result['cpu_count']} CPUs, load average {result['load_average_1min']:.1f})",
        f"  {'configuration':<20} {'trials/min':>10} {'wall [s]':>9} {'start-up [s]':>13} {'cores used':>11} "
        f"{'trial CPU / wall':>17}",
    ]
    for label, r in result["configurations"].items():
        lines.append(
            f"  {label:<20} {r['trials_per_minute']:10.1f} {r['wall_time']:9.2f} {r['startup_time']:13.2f} "
            f"{r['cores_used']:11.2f} {r['trial_cpu_time_mean'] / r['trial_wall_time_mean']:17.2f}"
        )
    lines.append("  ratios (same run):")
    for label, value in result["ratios"].items():
        lines.append(f"    {label:<40} {value:5.2f}")
    if result.get("note"):
        lines.append(f"  note: {result['note']}")
    return "\n".join(lines)
