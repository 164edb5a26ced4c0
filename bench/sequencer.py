"""Footstep sequencer: one warm QP solve per backend and a full H_u = 3 s Algorithm-1 sequence.

Baseline, measured in the same run: the same sequence with a fresh OSQP setup per step (new
workspace, same settings, no warm start). Inputs are the Table I example with a small random
disturbance on the measured DCM at every repetition (seeded), so warm starts are realistic.
Figures are reported as medians and 99th percentiles [us] and as speed-up RATIOS against the
baseline (the machine is shared and noisy: the ratios are what the targets are checked against).
Targets: exact full sequence <= 300 us median and >= 5x faster than the baseline.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from sequencer.backends import BACKEND_NAMES, make_backend
from sequencer.backends.osqp_ import OsqpBackend
from sequencer.horizon import FootstepSequencer
from sequencer.nominal import other_foot
from sequencer.params import SequencerParams
from sequencer.step_qp import StepProblem

STANCE_POSITION = np.array([-0.12, 0.10])
DCM = np.array([-0.12, -0.07])
ELAPSED = 0.229
TARGET_SEQUENCE_MEDIAN_US = 300.0
TARGET_SPEEDUP = 5.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--repeats", type=int, default=300, help="timed repetitions per figure (default 300)")
    parser.add_argument("--seed", type=int, default=0)


def _stats(samples_s: list[float]) -> dict:
    us = np.asarray(samples_s) * 1e6
    return {"median_us": float(np.median(us)), "p99_us": float(np.percentile(us, 99)), "n": int(us.size)}


def naive_sequence(params: SequencerParams, dcm: np.ndarray) -> int:
    """Algorithm 1 with a fresh OSQP workspace per step (the baseline). Returns the number of steps."""
    stance, p0, elapsed, start = "left", STANCE_POSITION, ELAPSED, 0.0
    t_end = ELAPSED + params.horizon
    steps = 0
    while True:
        solution = OsqpBackend().solve(StepProblem.from_params(params, stance, p0, dcm, elapsed))
        steps += 1
        touchdown = start + solution.duration
        if touchdown >= t_end:
            return steps
        stance, p0, dcm, elapsed, start = (other_foot(stance), solution.step_position,
                                           solution.step_position + solution.dcm_offset, 0.0, touchdown)


def run(args: argparse.Namespace) -> dict:
    params = SequencerParams.table_i()
    rng = np.random.default_rng(args.seed)
    repeats = max(int(args.repeats), 10)
    dcms = DCM + rng.normal(0.0, 0.005, size=(repeats, 2))
    problems = [StepProblem.from_params(params, "left", STANCE_POSITION, d, ELAPSED) for d in dcms]

    single = {}
    for name in BACKEND_NAMES:
        backend = make_backend(name)
        backend.solve(problems[0])  # set up the workspace once
        times = []
        for problem in problems:
            t0 = time.perf_counter()
            backend.solve(problem)
            times.append(time.perf_counter() - t0)
        single[name] = _stats(times)

    sequence = {}
    n_steps = 0
    for name in BACKEND_NAMES:
        sequencer = FootstepSequencer(params, backend=name)
        plan = sequencer.plan(ELAPSED, "left", STANCE_POSITION, DCM, 0.0)
        n_steps = len(plan.steps)
        times = []
        for d in dcms:
            t0 = time.perf_counter()
            sequencer.plan(ELAPSED, "left", STANCE_POSITION, d, 0.0)
            times.append(time.perf_counter() - t0)
        sequence[name] = _stats(times)

    baseline_times = []
    for d in dcms[: max(repeats // 3, 10)]:
        t0 = time.perf_counter()
        naive_sequence(params, d)
        baseline_times.append(time.perf_counter() - t0)
    baseline = _stats(baseline_times)

    speedup = {name: baseline["median_us"] / sequence[name]["median_us"] for name in BACKEND_NAMES}
    exact = sequence["exact"]
    return {
        "steps_per_sequence": n_steps,
        "single_solve": single,
        "sequence": sequence,
        "baseline_fresh_osqp_sequence": baseline,
        "sequence_speedup_vs_baseline": speedup,
        "targets": {
            "exact_sequence_median_us": exact["median_us"],
            "exact_sequence_median_target_us": TARGET_SEQUENCE_MEDIAN_US,
            "exact_speedup": speedup["exact"],
            "exact_speedup_target": TARGET_SPEEDUP,
            "met": bool(exact["median_us"] <= TARGET_SEQUENCE_MEDIAN_US and speedup["exact"] >= TARGET_SPEEDUP),
        },
    }


def format_report(result: dict) -> str:
    lines = [f"footstep sequencer benchmark (Table I, H_u = 3 s: {result['steps_per_sequence']} steps per sequence)",
             f"{'':28} {'median [us]':>12} {'p99 [us]':>10} {'speed-up vs baseline':>22}"]
    base = result["baseline_fresh_osqp_sequence"]
    for name, stats in result["single_solve"].items():
        lines.append(f"one warm solve, {name:<12} {stats['median_us']:>12.1f} {stats['p99_us']:>10.1f}")
    for name, stats in result["sequence"].items():
        lines.append(f"full sequence, {name:<13} {stats['median_us']:>12.1f} {stats['p99_us']:>10.1f} "
                     f"{result['sequence_speedup_vs_baseline'][name]:>21.1f}x")
    lines.append(f"baseline (fresh OSQP/step)   {base['median_us']:>12.1f} {base['p99_us']:>10.1f} {1.0:>21.1f}x")
    t = result["targets"]
    lines.append(f"target: exact sequence <= {t['exact_sequence_median_target_us']:.0f} us median and >= "
                 f"{t['exact_speedup_target']:.0f}x the baseline -> {'met' if t['met'] else 'NOT met'}")
    return "\n".join(lines)
