"""``wbmpc walk`` and ``wbmpc run SCENARIO``: thin command lines over :func:`sim.run_scenario`.

    wbmpc walk --robot bolt --vx 0.3 --yaw-rate 0.2 --duration 20 --out runs/walk --json
    wbmpc run push --force 6.3 --direction 90 --plot runs/push.png
    wbmpc run terrain --seed 3 --set density=15
    wbmpc run push --robot g1 --force 300 --direction 90 --push-time 5
    wbmpc run waypoints --robot g1 --path square --set speed=0.2 --out runs/g1_square
    wbmpc walk --viewer                       # MuJoCo's viewer, live (needs a display)
    wbmpc walk --robot g1 --vx 0 --planner alip   # the ALIP step-to-step NMPC plans the steps
    wbmpc run obstacle --robot h1 --height 0.2 --seed 3   # a box across the path, seen by the rangefinders

Scenario parameters have their own options where common (``--force``...); any other parameter of
the scenario, runner or controller is passed with ``--set NAME=VALUE``. ``--vx`` (alias
``--speed``), ``--vy`` and ``--yaw-rate`` give ``run_scenario(..., velocity_command=(v_x, v_y,
yaw_rate))``; a component left out is the scenario's default (``speed`` for v_x, 0 for the others).
Without any of them the scenario's own command applies.
"""

from __future__ import annotations

import argparse
import os
import sys

from wbmpc.cli.arguments import DURATION, FINITE, NON_NEGATIVE, SEED, output_directory, parse_assignment
from wbmpc.cli.output import add_output_arguments, print_json
from wbmpc.errors import ParameterError


def add_robot_argument(parser: argparse.ArgumentParser, default: str | None = "bolt") -> None:
    """``--robot NAME``: a registered robot (an unknown name is refused with the list of known ones)."""
    from robots.registry import available_robots

    parser.add_argument("--robot", default=default, metavar="NAME",
                        help=f"robot ({', '.join(available_robots())}; default {default})")


def add_run_arguments(parser: argparse.ArgumentParser) -> None:
    """Options shared by ``walk`` and ``run``."""
    add_robot_argument(parser)
    parser.add_argument("--duration", type=DURATION, default=None, help="simulated time [s] (default: scenario's)")
    parser.add_argument("--seed", type=SEED, default=0, help="random seed (terrain, noise)")
    parser.add_argument("--out", type=output_directory, default=None, metavar="DIR",
                        help="write log.npz, metrics.json and figures.png into DIR")
    command = parser.add_argument_group("velocity command (default: the scenario's)")
    command.add_argument("--vx", "--speed", dest="vx", type=FINITE, default=None, metavar="V",
                         help="forward velocity v_x [m/s] (--speed is an alias)")
    command.add_argument("--vy", type=FINITE, default=None, metavar="V", help="lateral velocity v_y [m/s]")
    command.add_argument("--yaw-rate", type=FINITE, default=None, metavar="W", help="yaw rate [rad/s]")
    parser.add_argument(
        "--delay-nodes", type=int, choices=(0, 1), default=None, help="apply MPC node 1 (paper) or node 0"
    )
    parser.add_argument("--computation-delay", type=NON_NEGATIVE, default=None, metavar="S",
                        help="simulated solver latency [s] (default 0)")
    parser.add_argument("--interpolate", action="store_true", help="interpolate references between nodes")
    parser.add_argument("--no-feedback", action="store_true", help="feed-forward only (no Riccati gains)")
    parser.add_argument("--noise-q", type=NON_NEGATIVE, default=None, help="configuration noise std [m, rad]")
    parser.add_argument("--noise-v", type=NON_NEGATIVE, default=None, help="velocity noise std [m/s, rad/s]")
    parser.add_argument("--mpc-failure-at", type=NON_NEGATIVE, action="append", default=None, metavar="T",
                        help="inject an MPC failure at T [s] (repeatable)")
    parser.add_argument("--controller", choices=("walking", "pd"), default="walking")
    add_planner_arguments(parser)
    parser.add_argument("--render", metavar="FILE", type=_video_path, default=None,
                        help="render an offscreen video of the run (.mp4 or .gif)")
    parser.add_argument("--viewer", action="store_true", help="show the run live in MuJoCo's viewer (needs a display)")
    parser.add_argument(
        "--set", dest="overrides", action="append", type=parse_assignment, default=[], metavar="NAME=VALUE",
        help="any other scenario/runner/controller parameter (repeatable)",
    )
    add_output_arguments(parser, plot=True)


PLANNER_OPTIONS = {"planner": "footstep_planner.kind", "alip_solver": "footstep_planner.alip_solver"}
"""The footstep-planner options of ``walk``, ``run`` and ``campaign`` -> the walking-preset keys they set."""


def add_planner_arguments(parser: argparse.ArgumentParser) -> None:
    """``--planner dcm|alip`` and ``--alip-solver sqp|ipopt``: the walking preset's ``[footstep_planner]``
    (default: the preset's, the DCM step QP unless its file says otherwise)."""
    from wbmpc.walking.preset import ALIP_SOLVERS, PLANNER_KINDS

    parser.add_argument("--planner", choices=PLANNER_KINDS, default=None,
                        help="footstep planner: dcm (the DCM step QP of the preset's [planner]) or alip (the ALIP "
                             "NMPC, parameters sequencer/presets/alip/ROBOT.toml; --set footstep_planner.alip_preset="
                             "NAME|FILE, footstep_planner.alip.FIELD=VALUE); default: the walking preset's")
    parser.add_argument("--alip-solver", choices=ALIP_SOLVERS, default=None, help="the ALIP NMPC's solver (default sqp)")


def planner_params_from_args(args: argparse.Namespace) -> dict:
    """The walking-preset overrides of ``--planner`` and ``--alip-solver`` (only those given)."""
    return {key: getattr(args, option) for option, key in PLANNER_OPTIONS.items()
            if getattr(args, option, None) is not None}


def _video_path(text: str) -> str:
    from sim.render import check_video_path

    try:
        check_video_path(text)
    except ParameterError as err:
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: {err}") from None
    return text


def register(subparsers) -> None:
    walk = subparsers.add_parser("walk", help="closed-loop walking in MuJoCo (the paper's main experiment)")
    add_run_arguments(walk)
    walk.set_defaults(func=_run, scenario="walk")

    from sim.scenarios import available_scenarios

    run = subparsers.add_parser("run", help="run a registered closed-loop scenario")
    run.add_argument("scenario", choices=available_scenarios())
    run.add_argument("--force", type=FINITE, default=None, help="push: force magnitude [N]")
    run.add_argument("--direction", type=FINITE, default=None, help="push: direction in the plane from +x [deg]")
    run.add_argument("--push-time", type=NON_NEGATIVE, default=None, metavar="T", help="push: start of the push [s]")
    run.add_argument("--path", default=None, metavar="NAME", help="waypoints: the path to follow (circle, square)")
    run.add_argument("--height", type=FINITE, default=None, metavar="H", help="obstacle: box height [m]")
    add_run_arguments(run)
    run.set_defaults(func=_run)


# run_scenario's own arguments -> the option that gives each (not --set NAME=VALUE)
RUN_SCENARIO_OPTIONS = {"robot": "--robot", "duration": "--duration", "seed": "--seed", "out": "--out",
                        "controller": "--controller", "on_tick": "--viewer"}


def velocity_command_from_args(args: argparse.Namespace) -> tuple[float, float, float] | None:
    """(v_x, v_y, yaw_rate) when any of --vx/--speed, --vy, --yaw-rate is given, else None."""
    if args.vx is None and args.vy is None and args.yaw_rate is None:
        return None
    from sim.scenarios import scenario_parameters

    v_x = scenario_parameters(args.scenario)["speed"] if args.vx is None else args.vx
    return (float(v_x), float(args.vy or 0.0), float(args.yaw_rate or 0.0))


def params_from_args(args: argparse.Namespace) -> dict:
    """Scenario/runner/controller parameters given on the command line."""
    params: dict = {}
    for option, name in (
        ("delay_nodes", "delay_nodes"), ("noise_q", "noise_q"), ("noise_v", "noise_v"),
        ("computation_delay", "computation_delay"), ("force", "force"), ("direction", "direction"),
        ("push_time", "push_time"), ("path", "path"), ("height", "height"),
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
    command = velocity_command_from_args(args)
    if command is not None:
        params["velocity_command"] = command
    planner = planner_params_from_args(args)
    params.update(planner)
    overrides = dict(args.overrides)
    both = sorted(set(planner) & set(overrides))
    if both:
        raise ParameterError(f"--set {both[0]}=... and its option (--planner/--alip-solver) both given: give one")
    own = sorted(set(overrides) & set(RUN_SCENARIO_OPTIONS))
    if own:
        raise ParameterError(f"--set {own[0]}=...: {own[0]} is not a scenario/runner/controller parameter; "
                             f"use {RUN_SCENARIO_OPTIONS[own[0]]}")
    check_numeric_overrides(args.scenario, overrides)
    params.update(overrides)
    params["progress"] = None if not args.json else False
    return params


def check_numeric_overrides(scenario: str, overrides: dict) -> None:
    """Refuse ``--set NAME=VALUE`` whose parameter is a number (declared ``float``/``int``) and VALUE is not.

    The parameter's own range is checked where it is defined (scenario, runner, controller); this
    only turns the command line's text into the declared kind, as every typed option does.

    Raises:
        ParameterError: e.g. ``--set speed='fast': speed is a number (scenario 'walk'), got a string``.
    """
    import dataclasses
    import typing

    from sim.runner import RunnerOptions
    from sim.scenarios.base import scenario_class
    from wbmpc.walking.controller import WalkingControllerConfig

    owners = (("scenario " + repr(scenario), scenario_class(scenario)), ("runner", RunnerOptions),
              ("controller", WalkingControllerConfig))
    for name, value in overrides.items():
        for owner, cls in owners:
            if name not in {f.name for f in dataclasses.fields(cls)}:
                continue
            kind = typing.get_type_hints(cls).get(name)
            if kind in (int, float) and (isinstance(value, bool) or not isinstance(value, (int, float))):
                raise ParameterError(
                    f"--set {name}={value!r}: {name} is {'an integer' if kind is int else 'a number'} ({owner}), "
                    f"got {type(value).__name__} {value!r}"
                )
            break


def obstacle_negotiation_note(robot: str, params: dict) -> str | None:
    """A one-line note when ``robot``'s walking preset for obstacle runs (its ``[scenarios.obstacle]`` overrides
    applied) with the overrides in ``params`` negotiates no obstacle (``controller.negotiation_lookahead`` = 0: the
    box of an obstacle run is not planned around or stepped over); None when it negotiates."""
    from sim.campaigns.trial import trial_preset

    preset = trial_preset(robot, "obstacle", params)
    if preset.controller.negotiation_lookahead > 0:
        return None
    why = "; it plans with the ALIP planner, which avoids no obstacle" \
        if preset.footstep_planner.kind == "alip" else ""
    return (f"note: robot {robot!r} negotiates no obstacle with these settings (controller.negotiation_lookahead = 0"
            f"{why}): the box is not planned around or stepped over")


def _run(args: argparse.Namespace) -> int:
    on_tick = None
    if args.viewer:
        from sim.render import LiveViewer, viewer_unavailable

        reason = viewer_unavailable()
        if reason is not None:
            raise ParameterError(f"--viewer: {reason}")
        on_tick = LiveViewer()
    from sim.metrics import paper_comparison
    from sim.runner import run_scenario

    params = params_from_args(args)
    if args.scenario == "obstacle" and args.controller == "walking":
        note = obstacle_negotiation_note(args.robot, params)
        if note is not None:
            print(note, file=sys.stderr)
    extra = {} if on_tick is None else {"on_tick": on_tick}
    try:
        log = run_scenario(args.scenario, robot=args.robot, duration=args.duration, seed=args.seed, out=args.out,
                           controller=args.controller, **extra, **params)
    finally:
        if on_tick is not None:
            on_tick.close()
    figures = []
    for path in ([os.path.join(args.out, "figures.png")] if args.out else []) + ([args.plot] if args.plot else []):
        from sim.plots import save_figures

        figures.append(save_figures(log, path))
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
    applied = (summary.get("params") or {}).get("preset_scenario_overrides")
    if applied:  # the preset's [scenarios.<name>] table: this kind of run is configured apart from the others
        settings = ", ".join(f"{key}={value}" for key, value in applied.items())
        lines.append(f"  {'preset [scenarios.' + summary['scenario'] + ']':<28} {settings}")

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
    if "path_deviation_max" in m:
        row("path deviation max", m["path_deviation_max"], "m")
        row("path deviation mean", m["path_deviation_mean"], "m")
        row("heading error max", m.get("heading_error_max"), "rad")  # away from corners (sim.metrics)
        row("path completion", m["path_completion"], "%", 100.0, ".1f")
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
    if "crossed" in m:  # scenario "obstacle" (sim.obstacle_metrics)
        lines.append(f"  {'obstacle success':<28} {m['success']} (crossed {m['crossed']}, touched {m['touched']}, "
                     f"resting on it {m['resting_on_obstacle']})")
        row("crossing time", m.get("crossing_time"), "s", fmt=".2f")
        if "detected" in m:
            lines.append(f"  {'obstacle detected':<28} {m['detected']}")
            row("detection time", m.get("detection_time"), "s", fmt=".2f")
            row("detection distance", m.get("detection_distance"), "m", fmt=".2f")
            row("height estimate error", m.get("height_error"), "mm", 1e3, ".1f")
            row("near edge estimate error", m.get("near_edge_error"), "mm", 1e3, ".1f")
    row("real-time factor", m.get("real_time_factor"), "x", fmt=".2f")  # of the loop, setup excluded
    row("setup (models, cold solve)", m.get("setup_time"), "s", fmt=".2f")
    for path in summary.get("files", []):
        lines.append(f"  wrote {path}")
    return "\n".join(lines)
