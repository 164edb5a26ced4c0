"""The G1's yaw-disturbance study (ALIP paper, seed 001, section 4.2, Fig. 5): torso moments of 30-150 N·m
for 0.05 s while walking at 0.3 m/s, the pelvis's yaw error after the recovery in 10 N·m bins, the
whole-body MPC with the arms and waist free (the G1 preset as committed) against the same with them held
(a high posture weight), the analogue of the paper's DSRB-MPC against its SRB-MPC (docs/campaigns.md,
"The G1's yaw disturbances").

    python docs/scripts/g1_yaw_disturbance.py [--runs runs/g1_yaw] [--phases 0 0.5] [--moments 30 ... 150]
        [--variants free held] [--summary docs/figures/g1_yaw_disturbance.json]
        [--plot docs/figures/g1_yaw_disturbance.png] [--report-only]

One trial = one ``yaw_push`` run (sim.scenarios.push): the G1 walks at 0.3 m/s (2 s ramp from standing),
its ``torso_link`` receives +M about the world z axis (counter-clockwise seen from above) from
``PUSH_AFTER + phase * T_DES``, and the run goes on ``AFTER_PUSH`` seconds. Each trial writes
``RUNS/<variant>_m<M>_p<phase>.json`` (its parameters, status, the yaw metrics of
:func:`sim.metrics.yaw_disturbance_metrics` and the yaw error sampled at 100 Hz); a rerun skips the trials
already written, so a killed study resumes where it stopped. Moment 0 (an undisturbed walk, the same
measurement) is run once per variant and phase: the yaw error a walk has without any push. Trials run one
at a time, moments outer to variants (both variants of a bin are done before the next bin), phases
outermost (a stopped study has whole phases). The summary (per variant and moment: trials, successes, the
mean and standard deviation of |yaw error| after the recovery and of the peak, in degrees) and the figure
are rewritten from all the trial files at the end (``--report-only``: only that).
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np

from robots import load_robot
from robots.conventions import base_yaw
from sim import run_scenario
from sim.metrics import yaw_disturbance_metrics, yaw_error

MOMENTS = tuple(float(m) for m in range(30, 151, 10))  # [N·m], one per 10 N·m bin (the paper: 30-150 N·m)
SPEED = 0.3  # [m/s]
PUSH_DURATION = 0.05  # [s]
PUSH_AFTER = 4.0  # [s]: the 2 s ramp and 2 s (five steps) of steady walking
T_DES = 0.4  # [s], the G1's desired step period (sequencer/presets/alip/g1.toml): phase 1 = one step later
AFTER_PUSH = 4.0  # [s] simulated after the push's start: 2 s to settle (sim.metrics.YAW_SETTLE_TIME), then the 1.6 s window
HELD_WEIGHT = 1e3  # posture weight of the waist and arm joints when they are held (the preset: waist 10, arms 3)
UPPER_BODY = ("waist", "shoulder", "elbow", "wrist")  # joint-name parts: the G1's 3 waist and 2 x 7 arm joints
VARIANTS = {
    "free": {},  # the G1 preset as committed: joint_position_by_name = waist 10, shoulder/elbow/wrist 3
    "held": {"ocp.state_weights.joint_position_by_name": [[part, HELD_WEIGHT] for part in UPPER_BODY]},
}
VS = "metrics_vs_undisturbed"
TRACE_STEP = 10  # ticks (10 ms) between the samples of the yaw error kept in a trial file


def trial_name(variant: str, moment: float, phase: float) -> str:
    return f"{variant}_m{moment:g}_p{phase:g}"


def run_trial(variant: str, moment: float, phase: float, seed: int) -> dict:
    """One yaw push; returns the trial record written to its JSON file."""
    push_time = PUSH_AFTER + phase * T_DES
    params = {"speed": SPEED, "moment": moment, "push_time": push_time, "push_duration": PUSH_DURATION}
    wall = time.perf_counter()
    log = run_scenario("yaw_push", robot="g1", seed=seed, duration=push_time + AFTER_PUSH, progress=False,
                       **params, **VARIANTS[variant])
    wall = time.perf_counter() - wall
    t, yaw, command = log.ticks["t"], base_yaw(log.ticks["x"][:, 3:7]), log.ticks["velocity_command"][:, 2]
    events = log.params["events"]
    metrics = yaw_disturbance_metrics(t, yaw, command, events["push_start"], events["push_end"],
                                      log.status == "completed")
    trace = yaw_error(t, yaw, command, events["push_start"])
    # how far the waist turned the torso away from the pelvis: the free upper body's share of the impulse
    waist = log.ticks["x"][:, 7 + load_robot("g1").actuated_joint_names.index("waist_yaw_joint")]
    before = (t >= events["push_start"] - 1.0) & (t < events["push_start"])
    waist_peak = float(np.max(np.abs(waist[t >= events["push_start"]] - np.mean(waist[before])))) if before.any() else None
    return {
        "variant": variant, "moment": moment, "phase": phase, "seed": seed, "params": params,
        "overrides": VARIANTS[variant], "status": log.status, "fall_time": log.fall_time,
        "fall_reason": log.fall_reason, "error": log.error, "success": log.status == "completed",
        "metrics": metrics, "mean_velocity_x": log.metrics.get("mean_velocity_x"),
        "real_time_factor": log.metrics.get("real_time_factor"), "wall_time": wall,
        "waist_yaw_peak": waist_peak,  # [rad], max |waist yaw - its mean over the second before the push|
        "trace": {"t": [round(float(v), 3) for v in t[::TRACE_STEP]],
                  "yaw_error": [round(float(v), 5) for v in trace[::TRACE_STEP]]},
    }


def _degrees(group: list[dict], key: str, metrics: str = "metrics") -> list[float | None]:
    """The metric ``key`` [rad] of each trial of ``group`` in degrees (None where it was not measured),
    from the trial's ``metrics`` (against the heading) or ``metrics_vs_undisturbed``."""
    return [None if not t.get(metrics) or t[metrics][key] is None else float(np.degrees(t[metrics][key]))
            for t in group]


def _stats(values: list[float]) -> dict:
    values = [v for v in values if v is not None]
    if not values:
        return {"mean": None, "std": None}
    return {"mean": float(np.mean(values)), "std": float(np.std(values))}


def with_undisturbed(trials: list[dict]) -> list[dict]:
    """Each trial with ``metrics_vs_undisturbed``: the yaw metrics against the moment-0 trial of the same
    variant, phase and seed (the same run up to the push: the walk's own heading drift taken out), from the
    100 Hz traces; None when that trial is missing or fell."""
    reference = {(t["variant"], t["phase"], t["seed"]): t for t in trials if t["moment"] == 0.0}
    out = []
    for trial in trials:
        base = reference.get((trial["variant"], trial["phase"], trial["seed"]))
        vs = None
        if trial["moment"] != 0.0 and base is not None and base["success"] and trial["trace"]["yaw_error"] is not None:
            n = min(len(trial["trace"]["t"]), len(base["trace"]["t"]))
            t = np.array(trial["trace"]["t"][:n])
            start = trial["params"]["push_time"]
            vs = yaw_disturbance_metrics(t, np.array(trial["trace"]["yaw_error"][:n]), np.zeros(n), start,
                                         start + trial["params"]["push_duration"], trial["success"],
                                         undisturbed_yaw=np.array(base["trace"]["yaw_error"][:n]))
        out.append({**trial, "metrics_vs_undisturbed": vs})
    return out


def summarise(trials: list[dict]) -> dict:
    """Per variant and moment: trials, successes, |yaw error| after recovery and peak [deg] (mean, std),
    against the heading (``metrics``) and against the undisturbed run (``metrics_vs_undisturbed``)."""
    table: dict[str, dict[str, dict]] = {}
    for variant in VARIANTS:
        rows = {}
        for moment in sorted({t["moment"] for t in trials if t["variant"] == variant}):
            group = [t for t in trials if t["variant"] == variant and t["moment"] == moment]
            recovered = [t for t in group if t["success"]]  # a fall's peak is the fall's, not the disturbance's
            rows[f"{moment:g}"] = {
                "trials": len(group), "successes": sum(t["success"] for t in group),
                "phases": sorted(t["phase"] for t in group),
                "yaw_error_deg": _stats(_degrees(group, "yaw_push_error_abs")),
                "yaw_error_signed_deg": _stats(_degrees(group, "yaw_push_error")),
                "peak_yaw_error_deg": _stats(_degrees(recovered, "yaw_push_error_peak")),
                "yaw_error_vs_undisturbed_deg": _stats(_degrees(group, "yaw_push_error_abs", VS)),
                "yaw_error_vs_undisturbed_signed_deg": _stats(_degrees(group, "yaw_push_error", VS)),
                "peak_yaw_error_vs_undisturbed_deg": _stats(_degrees(recovered, "yaw_push_error_peak", VS)),
                "fall_times": [t["fall_time"] for t in group if not t["success"]],
            }
        table[variant] = rows
    return {
        "protocol": {"robot": "g1", "scenario": "yaw_push", "speed": SPEED, "push_duration": PUSH_DURATION,
                     "push_after": PUSH_AFTER, "t_des": T_DES, "after_push": AFTER_PUSH, "body": "torso_link",
                     "moment_sign": "+z (counter-clockwise seen from above)", "variants": VARIANTS,
                     "metric": "sim.metrics.yaw_disturbance_metrics: |mean pelvis yaw error| over the last 1.6 s "
                               "(>= 2 s after the push), relative to the pre-push heading plus the commanded turn "
                               "(yaw_error_*) or to the same run without the push (*_vs_undisturbed_*)"},
        "bins": table,
        "free_smaller_in_bins": _comparison(table, "yaw_error_deg"),
        "free_smaller_vs_undisturbed_in_bins": _comparison(table, "yaw_error_vs_undisturbed_deg"),
        "free_smaller_peak_in_bins": _comparison(table, "peak_yaw_error_deg"),
    }


def markdown_table(summary: dict) -> str:
    """The summary's bins as the table of docs/campaigns.md: per moment and variant, successes / trials,
    |yaw error| after recovery against the undisturbed run and against the heading, and the peak (mean ± std, deg)."""
    def cell(row: dict, key: str) -> str:
        stats = row[key]
        return "—" if stats["mean"] is None else f"{stats['mean']:.2f} ± {stats['std']:.2f}"

    lines = ["| M_z [N·m] | free: no fall | held: no fall | free: after recovery, vs undisturbed | held: vs "
             "undisturbed | free: vs heading | held: vs heading | free: peak | held: peak |",
             "|---|---|---|---|---|---|---|---|---|"]
    free, held = summary["bins"].get("free", {}), summary["bins"].get("held", {})
    for moment in sorted(set(free) | set(held), key=float):
        f, h = free.get(moment), held.get(moment)
        row = [moment]
        row += [f"{r['successes']}/{r['trials']}" if r else "—" for r in (f, h)]
        for key in ("yaw_error_vs_undisturbed_deg", "yaw_error_deg", "peak_yaw_error_deg"):
            row += [cell(r, key) if r else "—" for r in (f, h)]
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def _comparison(table: dict, key: str) -> dict:
    """{"bins": n compared, "free_smaller": n where the free upper body's mean is smaller} over the disturbed bins."""
    compared = smaller = 0
    for moment, free in table.get("free", {}).items():
        held = table.get("held", {}).get(moment)
        if float(moment) == 0.0 or held is None or free[key]["mean"] is None or held[key]["mean"] is None:
            continue
        compared += 1
        smaller += free[key]["mean"] < held[key]["mean"]
    return {"bins": compared, "free_smaller": smaller}


def _bins(group: list[dict], key: str, metrics: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(moments, mean, std) [N·m, deg, deg] of metric ``key`` over the trials of each moment that have it."""
    rows = []
    for moment in sorted({t["moment"] for t in group}):
        values = [v for v in _degrees([t for t in group if t["moment"] == moment], key, metrics) if v is not None]
        if values:
            rows.append((moment, np.mean(values), np.std(values)))
    return tuple(np.array(column) for column in zip(*rows)) if rows else (np.zeros(0),) * 3


def plot(trials: list[dict], path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {"free": "tab:green", "held": "tab:red"}
    labels = {"free": "arms and waist free (preset)", "held": f"arms and waist held (posture weight {HELD_WEIGHT:g})"}
    fig, axes = plt.subplots(2, 2, figsize=(13, 9))
    (after_ax, peak_ax), (success_ax, trace_ax) = axes
    # the traces: at the largest moment every trial of both variants recovered from (else the largest)
    all_recovered = [m for m in {t["moment"] for t in trials} if all(t["success"] for t in trials if t["moment"] == m)]
    shown = max(all_recovered, default=max((t["moment"] for t in trials), default=0.0))
    for variant, offset in (("free", -1.5), ("held", 1.5)):
        group = [t for t in trials if t["variant"] == variant]
        recovered = [t for t in group if t["success"]]
        for ax, key in ((after_ax, "yaw_push_error_abs"), (peak_ax, "yaw_push_error_peak")):
            moments, mean, std = _bins(recovered, key, VS)
            ax.errorbar(moments + offset, mean, yerr=std, fmt="o-", color=colours[variant], capsize=3,
                        label=f"{labels[variant]}, against the undisturbed run")
            moments, mean, std = _bins(recovered, key, "metrics")
            ax.errorbar(moments + offset, mean, yerr=std, fmt="s--", color=colours[variant], capsize=2, alpha=0.45,
                        ms=4, label=f"{variant}, against the heading before the push")
        moments = sorted({t["moment"] for t in group})
        rate = [np.mean([t["success"] for t in group if t["moment"] == m]) for m in moments]
        success_ax.plot(np.array(moments) + offset / 3, 100 * np.array(rate), "o-", color=colours[variant],
                        label=labels[variant])
        for t in group:
            if t["moment"] == shown:
                trace_ax.plot(np.array(t["trace"]["t"]) - t["params"]["push_time"], np.degrees(t["trace"]["yaw_error"]),
                              color=colours[variant], alpha=0.8, lw=1,
                              label=f"{variant}, phase {t['phase']:g}" + ("" if t["success"] else " (fell)"))
    moment_label = "torso moment M_z [N·m] (0.05 s)"
    after_ax.set(xlabel=moment_label, ylabel="|pelvis yaw error| after recovery [deg]",
                 title="after recovery (mean of the run's last 1.6 s), trials without a fall")
    peak_ax.set(xlabel=moment_label, ylabel="peak |pelvis yaw error| [deg]", title="peak after the push, trials without a fall")
    success_ax.set(xlabel=moment_label, ylabel="trials without a fall [%]", ylim=(-5, 105), title="success")
    trace_ax.set(xlabel="time from the push's start [s]", ylabel="pelvis yaw error (against the heading) [deg]",
                 title=f"{shown:g} N·m")
    for ax in axes.flat:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("G1 walking at 0.3 m/s, a torso yaw moment for 0.05 s (the ALIP paper's Fig. 5 on the whole-body MPC)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", default="runs/g1_yaw", help="directory of the trial files")
    parser.add_argument("--phases", type=float, nargs="+", default=[0.0], help="gait phases, fractions of T_DES")
    parser.add_argument("--moments", type=float, nargs="+", default=list(MOMENTS), help="torso moments [N·m]")
    parser.add_argument("--variants", nargs="+", choices=sorted(VARIANTS), default=list(VARIANTS))
    parser.add_argument("--reference", action=argparse.BooleanOptionalAction, default=True,
                        help="also run moment 0 (no push) per variant and phase")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--summary", default="docs/figures/g1_yaw_disturbance.json")
    parser.add_argument("--plot", default="docs/figures/g1_yaw_disturbance.png")
    parser.add_argument("--report-only", action="store_true", help="only rewrite the summary and figure")
    parser.add_argument("--table", action="store_true", help="also print the summary as a markdown table")
    args = parser.parse_args()
    runs = Path(args.runs)
    runs.mkdir(parents=True, exist_ok=True)
    warnings.simplefilter("ignore")
    if not args.report_only:
        moments = ([0.0] if args.reference else []) + [m for m in args.moments if m != 0.0]
        for phase in args.phases:
            for moment in moments:
                for variant in args.variants:
                    path = runs / f"{trial_name(variant, moment, phase)}.json"
                    if path.exists():
                        continue
                    record = run_trial(variant, moment, phase, args.seed)
                    path.write_text(json.dumps(record) + "\n")
                    print(json.dumps({k: record[k] for k in ("variant", "moment", "phase", "status", "wall_time")}
                                     | {k: record["metrics"][k] for k in ("yaw_push_error", "yaw_push_error_peak")}),
                          flush=True)
    trials = with_undisturbed([json.loads(p.read_text()) for p in sorted(runs.glob("*.json"))])
    summary = summarise(trials)
    Path(args.summary).write_text(json.dumps(summary, indent=1) + "\n")
    plot(trials, args.plot)
    if args.table:
        print(markdown_table(summary))
    print(json.dumps({"trials": len(trials)} | {k: v for k, v in summary.items() if k.startswith("free_smaller")}))


if __name__ == "__main__":
    main()
