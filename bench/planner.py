"""Footstep planner: the ALIP NMPC's IPOPT reference against its warm-started SQP fast path on the same instances.

Instances: ``sequencer.alip.instances.random_instances`` (the G1 preset, commands within the range, pushes
on the angular momentum, t_curr over the stance). IPOPT runs cold (the paper's setup); the fast path is timed
warm (the receding-horizon case: started from the solution of the same instance measured 10 ms earlier)
and cold. Figures: medians and 99th percentiles [ms] and the ratio IPOPT / fast (the machine is shared:
the ratio is the robust figure). Target: fast path (warm) p99 <= 2 ms.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from sequencer.alip.instances import random_instances
from sequencer.alip.ipopt_ import IpoptSolver
from sequencer.alip.nlp import AlipNlp, AlipSolverError
from sequencer.alip.params import AlipParams
from sequencer.alip.sqp_ import SqpSolver

TARGET_P99_MS = 2.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--planner", choices=("alip",), default="alip", help="planner to time (alip)")
    parser.add_argument("--repeats", type=int, default=200, help="instances (default 200)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--preset", default="g1", help="ALIP preset (sequencer/presets/alip/NAME.toml)")


def _stats(samples_s: list[float]) -> dict:
    ms = np.asarray(samples_s) * 1e3
    return {"median_ms": float(np.median(ms)), "p99_ms": float(np.percentile(ms, 99)), "n": int(ms.size)}


def run(args: argparse.Namespace) -> dict:
    params = AlipParams.preset(args.preset)
    nlp = AlipNlp(params)
    ipopt, sqp = IpoptSolver(nlp), SqpSolver(nlp)
    rng = np.random.default_rng(args.seed)
    times = {"ipopt": [], "sqp_warm": [], "sqp_cold": []}
    worst, failures, iterations = 0.0, {"ipopt": 0, "sqp": 0}, []
    for instance in random_instances(params, max(int(args.repeats), 10), seed=args.seed):
        before = dataclasses.replace(instance, x0=instance.x0 + rng.normal(size=4) * [0.002, 0.3, 0.002, 0.3],
                                     t_curr=max(0.0, instance.t_curr - 0.01))
        try:
            t0 = time.perf_counter()
            reference = ipopt.solve(instance)
            times["ipopt"].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            cold = sqp.solve(instance)
            times["sqp_cold"].append(time.perf_counter() - t0)
            previous = sqp.solve(before, cold)
            t0 = time.perf_counter()
            warm = sqp.solve(instance, previous)
            times["sqp_warm"].append(time.perf_counter() - t0)
        except AlipSolverError as error:
            failures[error.solver] += 1
            continue
        iterations.append(warm.iterations)
        worst = max(worst, float(np.max(np.abs(warm.w - reference.w))), float(np.max(np.abs(cold.w - reference.w))))
    stats = {name: _stats(samples) for name, samples in times.items()}
    return {
        "planner": args.planner, "preset": args.preset, "steps": params.steps, "instances": len(times["ipopt"]),
        "ipopt": stats["ipopt"], "sqp_warm": stats["sqp_warm"], "sqp_cold": stats["sqp_cold"],
        "ratio_median_ipopt_over_warm": stats["ipopt"]["median_ms"] / stats["sqp_warm"]["median_ms"],
        "ratio_p99_ipopt_over_warm": stats["ipopt"]["p99_ms"] / stats["sqp_warm"]["p99_ms"],
        "warm_iterations_max": int(max(iterations)), "max_abs_difference": worst, "failures": failures,
        "target": {"sqp_warm_p99_ms": TARGET_P99_MS, "met": bool(stats["sqp_warm"]["p99_ms"] <= TARGET_P99_MS)},
    }


def format_report(result: dict) -> str:
    lines = [f"ALIP NMPC ({result['preset']} preset, K = {result['steps']}): {result['instances']} instances",
             f"{'':22} {'median [ms]':>12} {'p99 [ms]':>10}"]
    for name in ("ipopt", "sqp_warm", "sqp_cold"):
        lines.append(f"{name:<22} {result[name]['median_ms']:>12.3f} {result[name]['p99_ms']:>10.3f}")
    lines.append(f"ratio IPOPT / SQP warm: median {result['ratio_median_ipopt_over_warm']:.1f}x, "
                 f"p99 {result['ratio_p99_ipopt_over_warm']:.1f}x; max |w_sqp - w_ipopt| = {result['max_abs_difference']:.2e}; "
                 f"warm iterations <= {result['warm_iterations_max']}; failures {result['failures']}")
    t = result["target"]
    lines.append(f"target: SQP warm p99 <= {t['sqp_warm_p99_ms']:.0f} ms -> {'met' if t['met'] else 'NOT met'}")
    return "\n".join(lines)
