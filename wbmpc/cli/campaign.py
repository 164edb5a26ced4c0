"""``wbmpc campaign``: run campaigns of closed-loop trials and report on them.

    wbmpc campaign push-map --workers 2 --out runs/push-map              # Fig. 6-style push map (Bolt)
    wbmpc campaign push-map --robot g1 --out runs/push-map-g1            # another robot
    wbmpc campaign push-map --compare-timing fixed --out runs/timing     # adaptive vs fixed timing
    wbmpc campaign push-map --robot g1 --planner alip --set speed=0.0    # the G1 in place, the ALIP planner
    wbmpc campaign push-map --out runs/push-map --resume                 # after a kill: go on
    wbmpc campaign terrain --seeds 20 --backend ray                      # terrain seeds on Ray
    wbmpc campaign obstacles --robot h1 --heights 0.1 0.2 0.3 0.4 --trials 20   # step-over success by height
    wbmpc campaign run my_campaign.toml --backend ray --address auto     # a campaign file, on a cluster
    wbmpc campaign report runs/push-map                                  # summary.json + figures
    wbmpc campaign combine runs/h1-10cm runs/h1-40cm --out runs/h1       # one step-over figure from several

Every run writes the report (``summary.json``, figures) into its directory when it ends.
"""

from __future__ import annotations

import argparse
import sys

from wbmpc.cli.output import print_json


def register(subparsers) -> None:
    from sim.campaigns.backends import BACKENDS
    from sim.campaigns.spec import (
        OBSTACLE_HEIGHTS,
        OBSTACLE_TRIALS,
        PUSH_AFTER,
        PUSH_FORCE_MAX,
        PUSH_FORCE_STEPS_X,
        PUSH_FORCE_STEPS_Y,
        PUSH_PHASES,
        TERRAIN_DURATION,
        TERRAIN_SEEDS,
        TIMING_FROM,
    )
    from sim.campaigns.trial import STEP_TIMINGS
    from wbmpc.cli.arguments import COUNT, DURATION, NON_NEGATIVE, PHASE, POSITIVE, output_directory, parse_assignment
    from wbmpc.cli.walk import add_planner_arguments, add_robot_argument

    campaign = subparsers.add_parser("campaign", help="campaigns of closed-loop trials (push maps, terrain, obstacles), "
                                                              "local or Ray")
    commands = campaign.add_subparsers(dest="campaign_command", metavar="CAMPAIGN", required=True)

    def add_run_options(parser: argparse.ArgumentParser) -> None:
        parser.add_argument("--workers", type=COUNT, default=None, help="parallel workers (default: 2)")
        parser.add_argument("--backend", choices=BACKENDS, default="local", help="where trials run (default: local pool)")
        parser.add_argument("--address", default=None, help="Ray cluster address (ray backend; default: start Ray here)")
        parser.add_argument("--out", type=output_directory, default=None, metavar="DIR",
                            help="campaign directory (default: runs/campaigns/NAME)")
        parser.add_argument("--resume", action="store_true", help="continue the campaign in DIR (skip recorded trials)")
        parser.add_argument("--max-trials", type=COUNT, default=None, metavar="N", help="run at most N of the remaining trials")
        parser.add_argument("--no-progress", action="store_true", help="no progress bar")
        parser.add_argument("--no-plots", action="store_true", help="write summary.json only")
        parser.add_argument("--json", action="store_true", help="print the run and the summary as JSON")

    def add_trial_options(parser: argparse.ArgumentParser, duration_default, robot_default: str = "bolt") -> None:
        add_robot_argument(parser, default=robot_default)
        parser.add_argument("--controller", choices=("walking", "pd"), default="walking")
        add_planner_arguments(parser)
        parser.add_argument("--duration", type=DURATION, default=duration_default, help="simulated time per trial [s]")
        parser.add_argument(
            "--set", dest="overrides", action="append", type=parse_assignment, default=[], metavar="NAME=VALUE",
            help="a parameter shared by every trial (scenario, runner or controller; repeatable)",
        )

    push = commands.add_parser("push-map", help="push-recovery map over (Fx, Fy) and gait phases (ALIP paper, Fig. 6)")
    push.add_argument("--force-max-x", type=POSITIVE, default=PUSH_FORCE_MAX, help="Fx from -F to F [N]")
    push.add_argument("--force-max-y", type=POSITIVE, default=PUSH_FORCE_MAX, help="Fy from 0 to F [N]")
    push.add_argument("--steps-x", type=COUNT, default=PUSH_FORCE_STEPS_X, help="force values along x")
    push.add_argument("--steps-y", type=COUNT, default=PUSH_FORCE_STEPS_Y, help="force values along y")
    push.add_argument("--phases", type=PHASE, nargs="+", default=list(PUSH_PHASES), help="gait phases in [0, 1)")
    push.add_argument("--seeds", type=COUNT, default=1, help="seeds per point (matter only with noise)")
    push.add_argument("--push-after", type=NON_NEGATIVE, default=PUSH_AFTER, help="walking time before the pushes [s]")
    push.add_argument(
        "--compare-timing", nargs="?", const="fixed", choices=STEP_TIMINGS[1:], default=None,
        help="also run fixed step timing ('fixed': T_min = T_max = T_nom, the default; 'stiff': huge alpha_2)",
    )
    push.add_argument(
        "--timing-from", type=NON_NEGATIVE, default=TIMING_FROM,
        help=f"with --compare-timing: the compared timing applies from the first touchdown after this time [s] "
        f"(default {TIMING_FROM}; 0: from the start)",
    )
    add_trial_options(push, None)
    add_run_options(push)
    push.set_defaults(func=_run_builtin, campaign="push-map")

    terrain = commands.add_parser("terrain", help="walking over random box layouts, one per seed (Bolt paper, IV.C)")
    terrain.add_argument("--seeds", type=COUNT, default=TERRAIN_SEEDS, help="number of terrain layouts")
    terrain.add_argument("--densities", type=POSITIVE, nargs="+", default=[10.0], help="box densities [1/m²]")
    add_trial_options(terrain, TERRAIN_DURATION)
    add_run_options(terrain)
    terrain.set_defaults(func=_run_builtin, campaign="terrain")

    obstacles = commands.add_parser("obstacles", help="step over a box across the path, by height (issue 15, seed 000 "
                                                      "Fig. 5.13)")
    obstacles.add_argument("--heights", type=POSITIVE, nargs="+", default=list(OBSTACLE_HEIGHTS),
                           help=f"box heights [m] (default {' '.join(map(str, OBSTACLE_HEIGHTS))})")
    obstacles.add_argument("--trials", type=COUNT, default=OBSTACLE_TRIALS,
                           help=f"seeds per height: box distance, depth, friction (default {OBSTACLE_TRIALS})")
    add_trial_options(obstacles, None, robot_default="h1")
    add_run_options(obstacles)
    obstacles.set_defaults(func=_run_builtin, campaign="obstacles")

    from_file = commands.add_parser("run", help="run a campaign file (TOML, see sim.campaigns.spec)")
    from_file.add_argument("file", help="campaign file")
    add_robot_argument(from_file, default=None)
    add_run_options(from_file)
    from_file.set_defaults(func=_run_file)

    report = commands.add_parser("report", help="summary.json and figures of a campaign directory")
    report.add_argument("directory")
    report.add_argument("--no-plots", action="store_true", help="write summary.json only")
    report.add_argument("--json", action="store_true", help="print the summary as JSON")
    report.set_defaults(func=_report)

    combine = commands.add_parser("combine", help="one step-over summary and figure from several obstacle campaigns "
                                                  "(heights or seeds run apart)")
    combine.add_argument("directories", nargs="+", help="obstacle campaign directories (two or more)")
    combine.add_argument("--out", required=True, help="directory for summary.json and obstacle_success.png")
    combine.add_argument("--name", default=None, help="the combined campaign's label (default: the --out name)")
    combine.add_argument("--no-plots", action="store_true", help="write summary.json only")
    combine.add_argument("--json", action="store_true", help="print the summary as JSON")
    combine.set_defaults(func=_combine)


def _spec_from_args(args: argparse.Namespace):
    from sim.campaigns.spec import builtin_campaign
    from wbmpc.cli.walk import planner_params_from_args
    from wbmpc.errors import ParameterError

    params = dict(args.overrides)
    planner = planner_params_from_args(args)
    both = sorted(set(planner) & set(params))
    if both:
        raise ParameterError(f"--set {both[0]}=... and its option (--planner/--alip-solver) both given: give one")
    params.update(planner)
    if args.campaign == "push-map":
        return builtin_campaign(
            "push-map",
            force_max_x=args.force_max_x,
            force_max_y=args.force_max_y,
            steps_x=args.steps_x,
            steps_y=args.steps_y,
            phases=tuple(args.phases),
            seeds=tuple(range(args.seeds)),
            compare_timing=args.compare_timing,
            timing_from=args.timing_from,
            controller=args.controller,
            robot=args.robot,
            push_after=args.push_after,
            duration=args.duration,
            params=params,
        )
    if args.campaign == "obstacles":
        return builtin_campaign(
            "obstacles",
            heights=tuple(args.heights),
            trials=args.trials,
            controller=args.controller,
            robot=args.robot,
            duration=args.duration,
            params=params,
        )
    return builtin_campaign(
        "terrain",
        seeds=args.seeds,
        densities=tuple(args.densities),
        controller=args.controller,
        robot=args.robot,
        duration=args.duration,
        params=params,
    )


def _run_builtin(args: argparse.Namespace) -> int:
    return _run(args, _spec_from_args(args))


def _run_file(args: argparse.Namespace) -> int:
    import dataclasses

    from sim.campaigns.spec import CampaignSpec

    spec = CampaignSpec.from_toml(args.file)
    return _run(args, spec if args.robot is None else dataclasses.replace(spec, robot=args.robot))


def _run(args: argparse.Namespace, spec) -> int:
    import os

    from sim.campaigns.errors import CampaignError
    from sim.campaigns.report import format_summary, write_report
    from sim.campaigns.run import run_campaign

    if spec.scenario == "obstacle" and spec.controller == "walking":
        from wbmpc.cli.walk import obstacle_negotiation_note

        note = obstacle_negotiation_note(spec.robot, spec.params)
        if note is not None:
            print(f"wbmpc campaign: {note}", file=sys.stderr)
    out = args.out or os.path.join("runs", "campaigns", spec.name)
    try:
        outcome = run_campaign(
            spec,
            out,
            backend=args.backend,
            workers=args.workers,
            address=args.address,
            resume=args.resume,
            max_trials=args.max_trials,
            progress=False if (args.no_progress or args.json) else None,
        )
    except CampaignError as err:
        if isinstance(err, ValueError):
            raise
        print(f"wbmpc campaign: error: {err}", file=sys.stderr)
        return 1
    summary = write_report(out, plots=not args.no_plots)
    if args.json:
        print_json({"run": outcome, "trials_per_minute": outcome.trials_per_minute, "summary": summary})
    else:
        print(
            f"{outcome.n_run} trial(s) run on {outcome.backend} ({outcome.workers} worker(s)) in "
            f"{outcome.wall_time:.1f} s, {outcome.n_skipped} already recorded, {outcome.n_remaining} remaining"
        )
        print(format_summary(summary))
    return 0


def _combine(args: argparse.Namespace) -> int:
    from sim.campaigns.report import combine_obstacle_campaigns, format_summary

    summary = combine_obstacle_campaigns(args.directories, args.out, name=args.name, plots=not args.no_plots)
    print_json(summary) if args.json else print(format_summary(summary))
    return 0


def _report(args: argparse.Namespace) -> int:
    from sim.campaigns.report import format_summary, write_report

    summary = write_report(args.directory, plots=not args.no_plots)
    if args.json:
        print_json(summary)
    else:
        print(format_summary(summary))
    return 0
