"""``wbmpc demo``: the main job end to end — Bolt walks at 0.33 m/s in MuJoCo under the paper's controller.

Runs the ``walk`` scenario (footstep sequencer -> whole-body MPC at 100 Hz -> Riccati feedback at
1 kHz), prints its metrics beside the paper's, and writes ``log.npz``, ``metrics.json`` and
``figures.png`` (Figs. 5-6 layout) into ``--out``. ``--robot g1`` runs the same job on another robot
with a walking preset (its own MPC rate and tuning, ``wbmpc/walking/presets/ROBOT.toml``); the
paper's figures are Bolt's, so they are printed beside Bolt's run only. The footstep-plan figures of the interim demo
are ``wbmpc plan`` (Fig. 3) and ``wbmpc sensitivity`` (Fig. 2).
"""

from __future__ import annotations

import argparse
import os

from wbmpc.cli.arguments import DURATION, FINITE, SEED, output_directory
from wbmpc.cli.output import add_output_arguments, print_json

DEMO_DURATION = 20.0  # [s] of simulated walking (the speed integral settles within ~10 s)
PAPER_ROBOT = "bolt"  # the robot of the Bolt paper, whose figures the demo prints beside ours


def register(subparsers) -> None:
    parser = subparsers.add_parser("demo", help="main job: Bolt walks in MuJoCo (sequencer + MPC + feedback), metrics")
    parser.add_argument("--out", type=output_directory, default="runs/demo", help="output directory (default runs/demo)")
    parser.add_argument("--duration", type=DURATION, default=DEMO_DURATION, help="simulated time [s]")
    parser.add_argument("--seed", type=SEED, default=0)
    parser.add_argument("--robot", default=PAPER_ROBOT, metavar="NAME",
                        help="robot with a walking preset (default bolt, the paper's; e.g. g1)")
    parser.add_argument("--speed", type=FINITE, default=None, metavar="V",
                        help="forward velocity command v_x [m/s] (default: the walk scenario's 0.33)")
    add_output_arguments(parser, plot=False)
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from sim.metrics import paper_comparison
    from sim.plots import save_figures
    from sim.runner import run_scenario
    from wbmpc.cli.walk import format_metrics
    from wbmpc.walking.preset import load_walking_preset

    load_walking_preset(args.robot)  # a robot without a walking preset: the one-line error listing those that walk
    params = {} if args.speed is None else {"speed": args.speed}
    log = run_scenario("walk", robot=args.robot, duration=args.duration, seed=args.seed, out=args.out,
                       progress=None if not args.json else False, **params)
    figure = save_figures(log, os.path.join(args.out, "figures.png"))
    summary = log.summary()
    if args.robot == PAPER_ROBOT:
        summary["paper"] = paper_comparison(log.metrics)
    summary["files"] = [figure] + [os.path.join(args.out, name) for name in ("log.npz", "metrics.json")]
    if args.json:
        print_json(summary)
    else:
        print(format_metrics(summary))
    return 0 if log.status == "completed" else 1
