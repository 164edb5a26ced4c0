"""``wbmpc walk`` and ``wbmpc run SCENARIO``: thin command lines over :func:`sim.run_scenario`.

    wbmpc walk --speed 0.33 --duration 20 --out runs/walk --json
    wbmpc run push --force 6.3 --direction 90 --plot runs/push.png
    wbmpc run terrain --seed 3 --set density=15

Scenario parameters have their own options where common (``--speed``, ``--force``...); any other
parameter of the scenario, runner or controller is passed with ``--set NAME=VALUE``.
"""

from __future__ import annotations

import argparse
import ast
import os

from wbmpc.cli.output import add_output_arguments, print_json


def _parse_assignment(text: str) -> tuple[str, object]:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"--set {text!r}: expected NAME=VALUE")
    name, raw = text.split("=", 1)
    try:
        value = ast.literal_eval(raw)
    except (ValueError, SyntaxError):
        value = raw
    return name.strip(), value


def add_run_arguments(parser: argparse.ArgumentParser) -> None:
    """Options shared by ``walk`` and ``run``."""
    parser.add_argument("--duration", type=float, default=None, help="simulated time [s] (default: scenario's)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (terrain, noise)")
    parser.add_argument("--out", default=None, metavar="DIR", help="write log.npz, metrics.json and figures.png")
    parser.add_argument("--speed", type=float, default=None, help="forward velocity command [m/s]")
    parser.add_argument(
        "--delay-nodes", type=int, choices=(0, 1), default=None, help="apply MPC node 1 (paper) or node 0"
    )
    parser.add_argument(
        "--computation-delay", type=float, default=None, metavar="S", help="simulated solver latency [s] (default 0)"
    )
    parser.add_argument("--interpolate", action="store_true", help="interpolate references between nodes")
    parser.add_argument("--no-feedback", action="store_true", help="feed-forward only (no Riccati gains)")
    parser.add_argument("--noise-q", type=float, default=None, help="configuration noise std [m, rad]")
    parser.add_argument("--noise-v", type=float, default=None, help="velocity noise std [m/s, rad/s]")
    parser.add_argument(
        "--mpc-failure-at", type=float, action="append", default=None, metavar="T", help="inject an MPC failure at T [s]"
    )
    parser.add_argument("--controller", choices=("walking", "pd"), default="walking")
    parser.add_argument("--render", metavar="FILE", default=None,
                        help="render an offscreen video of the run (.mp4 needs ffmpeg; .gif always works)")
    parser.add_argument(
        "--set", dest="overrides", action="append", type=_parse_assignment, default=[], metavar="NAME=VALUE",
        help="any other scenario/runner/controller parameter (repeatable)",
    )
    add_output_arguments(parser, plot=True)


def register(subparsers) -> None:
    walk = subparsers.add_parser("walk", help="closed-loop walking of Bolt in MuJoCo (the paper's main experiment)")
    add_run_arguments(walk)
    walk.set_defaults(func=_run, scenario="walk")

    from sim.scenarios import available_scenarios

    run = subparsers.add_parser("run", help="run a registered closed-loop scenario")
    run.add_argument("scenario", choices=available_scenarios())
    run.add_argument("--force", type=float, default=None, help="push: force magnitude [N]")
    run.add_argument("--direction", type=float, default=None, help="push: direction in the plane from +x [deg]")
    add_run_arguments(run)
    run.set_defaults(func=_run)


def params_from_args(args: argparse.Namespace) -> dict:
    """Scenario/runner/controller parameters given on the command line."""
    params: dict = {}
    for option, name in (
        ("speed", "speed"), ("delay_nodes", "delay_nodes"), ("noise_q", "noise_q"), ("noise_v", "noise_v"),
        ("computation_delay", "computation_delay"),
        ("force", "force"), ("direction", "direction"),
    ):
        value = getattr(args, option, None)
        if value is not None:
            params[name] = value
    if args.interpolate:
        params["interpolate"] = True
    if args.no_feedback:
        params["feedback"] = False
    if args.mpc_failure_at:
        params["mpc_failure_times"] = tuple(args.mpc_failure_at)
    params.update(dict(args.overrides))
    params["progress"] = None if not args.json else False
    return params


def _run(args: argparse.Namespace) -> int:
    if args.render:
        os.environ.setdefault("MUJOCO_GL", "egl")  # headless offscreen context; read when MuJoCo is imported
    from sim.metrics import paper_comparison
    from sim.runner import run_scenario

    params = params_from_args(args)
    log = run_scenario(
        args.scenario, duration=args.duration, seed=args.seed, out=args.out, controller=args.controller, **params
    )
    figures = []
    if args.out:
        from sim.plots import save_figures

        figures.append(save_figures(log, os.path.join(args.out, "figures.png")))
    if args.plot:
        from sim.plots import save_figures

        figures.append(save_figures(log, args.plot))
    if args.render:
        from sim.render import render_run

        figures.append(render_run(log, args.render))
    summary = log.summary()
    summary["paper"] = paper_comparison(log.metrics)
    summary["files"] = figures + ([os.path.join(args.out, n) for n in ("log.npz", "metrics.json")] if args.out else [])
    if args.json:
        print_json(summary)
    else:
        print(format_metrics(summary))
    return 0 if log.status == "completed" else 1


def format_metrics(summary: dict) -> str:
    """Human-readable table of a run's outcome and metrics."""
    m = summary["metrics"]
    lines = [f"{summary['scenario']} (seed {summary['seed']}): {summary['status']}"]
    if summary.get("fall_reason"):
        lines[0] += f" at t = {summary['fall_time']:.3f} s: {summary['fall_reason']}"
    if summary.get("error"):
        lines.append(f"  error: {summary['error']}")

    def row(label: str, value, unit: str = "", scale: float = 1.0, fmt: str = ".3f", paper=None) -> None:
        if value is None:
            text = "n/a"
        else:
            text = f"{value * scale:{fmt}} {unit}".rstrip()
        if paper is not None:
            text += f"   (paper: {paper * scale:{fmt}} {unit})".rstrip()
        lines.append(f"  {label:<28} {text}")

    paper = summary.get("paper", {})
    row("simulated time", m.get("simulated_time"), "s", fmt=".2f")
    row("distance along x", m.get("distance_x"), "m")
    for axis in "xy":
        key = f"velocity_error_{axis}"
        if key in m:
            row(f"velocity error {axis} (steady)", m[key], "mm/s", 1e3, ".1f", paper.get(key, {}).get("paper"))
    if "rise_time" in m:
        row("rise time", m["rise_time"], "s", fmt=".2f", paper=paper.get("rise_time", {}).get("paper"))
    if "push_recovered" in m:
        lines.append(f"  {'push recovered':<28} {m['push_recovered']}")
        row("push recovery time", m.get("push_recovery_time"), "s", fmt=".2f")
    row("max |tau| / limit", m.get("max_torque_ratio"), fmt=".2f")
    row("saturated ticks", m.get("saturated_fraction"), "%", 100.0, ".1f")
    if "mpc_updates" in m:
        lines.append(f"  {'MPC updates / failures':<28} {m['mpc_updates']} / {m['mpc_failures']}")
        row("MPC update median", m.get("mpc_tick_time_median"), "ms", 1e3, ".2f")  # measurement to solution
        row("MPC update p99", m.get("mpc_tick_time_p99"), "ms", 1e3, ".2f")
        if "mpc_cycle_time_median" in m:  # with the preparation made ahead (WalkingMPC.prepare)
            row("MPC cycle median", m["mpc_cycle_time_median"], "ms", 1e3, ".2f")
    if "steps" in m:
        lines.append(f"  {'steps':<28} {m['steps']}")
    row("real-time factor", m.get("real_time_factor"), "x", fmt=".2f")  # of the loop, setup excluded
    row("setup (models, cold solve)", m.get("setup_time"), "s", fmt=".2f")
    for path in summary.get("files", []):
        lines.append(f"  wrote {path}")
    return "\n".join(lines)
