"""Campaign throughput: trials per minute in-process, on the local pool (1 and 2 workers) and on Ray.

Every configuration runs the same ``--trials`` closed-loop trials (push scenario, PD controller by
default or ``--controller walking``, ``--duration`` simulated seconds, no stop at the fall, so
every trial does the same work; the push of 0.1 s at 0.1 s) through
:func:`sim.campaigns.run_campaign`, records included. Each backend is started and warmed up first
(untimed: imports, forkserver preload, ``ray.init``); that start-up time is reported on its own.
The configurations then run in ``--rounds`` interleaved rounds and each ratio is the median of the
per-round ratios, so a change of the shared machine's load hits every configuration alike.

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
    parser.add_argument("--trials", type=int, default=8, help="timed trials per configuration and round")
    parser.add_argument("--duration", type=float, default=1.0, help="simulated time per trial [s]")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds (ratios: median over rounds)")
    parser.add_argument(
        "--controller", choices=("pd", "walking"), default="pd",
        help="trial controller: pd (pure simulation, default) or walking (MPC-bound, ~100x slower)",
    )
    parser.add_argument("--no-ray", action="store_true", help="skip the Ray configuration")


def _spec(n_trials: int, duration: float, name: str, controller: str = "pd"):
    from sim.campaigns import CampaignSpec

    return CampaignSpec(
        name=name,
        scenario="push",
        controller=controller,
        duration=duration,
        params={"stop_on_fall": False, "push_time": 0.1, "push_duration": 0.1, "direction": 90.0},
        grid={"force": [float(f) for f in range(n_trials)]},
    )


def _timed_run(backend, n_trials: int, duration: float, directory: str, controller: str) -> dict:
    from sim.campaigns import ResultStore, run_campaign

    run = run_campaign(_spec(n_trials, duration, "bench", controller), directory, backend=backend, progress=False)
    records = ResultStore(directory).records()
    cpu_time = sum(r["cpu_time"] for r in records)
    return {
        "trials_per_minute": run.trials_per_minute,
        "wall_time": run.wall_time,
        "cores_used": cpu_time / run.wall_time,
        "trial_cpu_over_wall": cpu_time / sum(r["wall_time"] for r in records),
    }


def run(args: argparse.Namespace) -> dict:
    import numpy as np

    from sim.campaigns.backends import make_backend
    from wbmpc.errors import ParameterError

    if args.trials < 2:
        raise ParameterError(f"--trials={args.trials} must be >= 2")
    if not args.duration > 0.2:
        raise ParameterError(f"--duration={args.duration} s must be > 0.2 s (the push ends at 0.2 s)")
    if args.rounds < 1:
        raise ParameterError(f"--rounds={args.rounds} must be >= 1")
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
    backends, startup = {}, {}
    rounds: list[dict[str, dict]] = []
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for label, (name, workers) in configurations.items():
                tic = time.perf_counter()
                backends[label] = make_backend(name, workers=workers)
                warm_up = os.path.join(tmp, f"warm-up-{name}-{workers}")
                _timed_run(backends[label], max(workers, 2), args.duration, warm_up, args.controller)
                startup[label] = time.perf_counter() - tic
            for k in range(args.rounds):  # interleaved, so that the machine's load drifts hit every configuration
                rounds.append(
                    {
                        label: _timed_run(
                            backend, args.trials, args.duration, os.path.join(tmp, f"round-{k}-{i}"), args.controller
                        )
                        for i, (label, backend) in enumerate(backends.items())
                    }
                )
    finally:
        for backend in backends.values():
            backend.close()

    def median(label: str, key: str) -> float:
        return float(np.median([r[label][key] for r in rounds]))

    def ratio(a: str, b: str) -> float:
        return float(np.median([r[a]["trials_per_minute"] / r[b]["trials_per_minute"] for r in rounds]))

    results = {
        label: {
            "backend": configurations[label][0],
            "workers": configurations[label][1],
            "trials_per_minute": median(label, "trials_per_minute"),
            "startup_time": startup[label],
            "cores_used": median(label, "cores_used"),
            "trial_cpu_over_wall": median(label, "trial_cpu_over_wall"),
        }
        for label in configurations
    }
    ratios = {
        "local 1 worker / in-process": ratio("local, 1 worker", "in-process"),
        "scaling: local 2 workers / 1 worker": ratio("local, 2 workers", "local, 1 worker"),
    }
    if "ray, 2 workers" in results:
        ratios["ray 2 workers / local 2 workers"] = ratio("ray, 2 workers", "local, 2 workers")
    return {
        "trials": args.trials,
        "trial_duration": args.duration,
        "controller": args.controller,
        "rounds": args.rounds,
        "cpu_count": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0],
        "configurations": results,
        "ratios": ratios,
        "per_round": rounds,
        "note": ray_note,
    }


def format_report(result: dict) -> str:
    lines = [
        f"campaign throughput: {result['trials']} push trials ({result['controller']} controller) "
        f"of {result['trial_duration']:.1f} s simulated per "
        f"configuration, {result['rounds']} interleaved round(s) ({result['cpu_count']} CPUs, load average "
        f"{result['load_average_1min']:.1f})",
        f"  {'configuration':<20} {'trials/min':>10} {'start-up [s]':>13} {'cores used':>11} {'trial CPU / wall':>17}",
    ]
    for label, r in result["configurations"].items():
        lines.append(
            f"  {label:<20} {r['trials_per_minute']:10.1f} {r['startup_time']:13.2f} {r['cores_used']:11.2f} "
            f"{r['trial_cpu_over_wall']:17.2f}"
        )
    lines.append("  ratios of trials/min (median over rounds, each round's configurations run back to back):")
    for label, value in result["ratios"].items():
        lines.append(f"    {label:<40} {value:5.2f}")
    if result.get("note"):
        lines.append(f"  note: {result['note']}")
    return "\n".join(lines)
