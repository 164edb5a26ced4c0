"""``wbmpc plan``: run Algorithm 1 and print / plot the footstep plan (Fig. 3).

Every SequencerParams field can be overridden from the command line (``--alpha1``, ``--z-c``,
``--w-left-min``, ...; ``--vx``/``--vy`` are aliases of ``--v-x``/``--v-y``) on top of a preset
(``--preset``) or a TOML file (``--params FILE``).

``--robot NAME`` plans for a robot standing still: its left foot in stance at its reference
position, the DCM at its CoM (at rest), t = 0, with the planner of the robot's walking preset
(``wbmpc/walking/presets/NAME.toml``; unless ``--preset`` or ``--params`` is given).
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from sequencer.horizon import FootstepPlan, FootstepSequencer
from sequencer.params import PRESET_DIR, SequencerParams
from wbmpc.cli.arguments import FINITE, NON_NEGATIVE
from wbmpc.cli.output import add_output_arguments, print_json

# Table I example state (p0, zeta_hat, t) used as the default initial condition.
TABLE_I_STANCE_FOOT = "left"
TABLE_I_STANCE_POSITION = (-0.12, 0.10)
TABLE_I_DCM = (-0.12, -0.07)
TABLE_I_ELAPSED = 0.229

_ALIASES = {"v_x": ["--vx"], "v_y": ["--vy"]}
_HELP = {
    "alpha1": "weight of the step position error [-]",
    "alpha2": "weight of the step timing error [-]",
    "alpha3": "weight of the DCM offset error [-]",
    "z_c": "CoM height of the LIPM [m]",
    "gravity": "gravitational acceleration [m/s^2]",
    "v_x": "commanded forward velocity [m/s] (l_nom = v_x t_nom)",
    "v_y": "commanded lateral velocity [m/s]",
    "l_min": "min step length [m]",
    "l_max": "max step length [m]",
    "pelvis_width": "nominal lateral distance between the feet l_p [m]",
    "w_left_min": "min lateral step while the LEFT foot is in stance [m]",
    "w_left_max": "max lateral step while the LEFT foot is in stance [m]",
    "w_right_min": "min lateral step while the RIGHT foot is in stance [m]",
    "w_right_max": "max lateral step while the RIGHT foot is in stance [m]",
    "t_min": "min step duration [s]",
    "t_nom": "nominal step duration [s]",
    "t_max": "max step duration [s]",
    "horizon": "H_u: plan until a touchdown at or after t + horizon [s]",
    "double_support": "time both feet stay on the ground after each touchdown, in [0, t_min) (0 = point feet) [s]",
    "swing_drift": "kappa: DCM gain over the LIPM per unit of step length (0 = the paper's LIPM) [-]",
    "dcm_offset_bias": "measured minus planned sagittal DCM offset at touchdown, aimed off (0 = none) [m]",
    "stance_drift": "forward DCM gain beyond the LIPM over a stance, whatever the step length (0 = none) [m]",
    "obstacle_margin": "obstacles' footprints grown by this for the footholds [m]",
    "obstacle_approach_margin": "an obstacle's near side grown by this much more [m]",
    "obstacle_step_length_max": "length bound of a step beyond an obstacle (with l_max) [m]",
    "obstacle_step_duration_min": "duration lower bound of a step over an obstacle (with t_min) [s]",
    "obstacle_step_duration_max": "duration upper bound of a step over an obstacle (with t_max; 0: t_max) [s]",
    "obstacle_swing_length_max": "travel bound of a foot swinging over an obstacle, lift-off to touchdown (0: none) [m]",
    "obstacle_offset_tolerance": "a step crosses only with its DCM offset this close to the nominal one [m]",
    "sole_front": "sole extent ahead of the foot frame [m]",
    "sole_rear": "sole extent behind the foot frame [m]",
    "obstacle_double_support": "quasi-static crossing: double support before a crossing swing [s] (0: off)",
    "obstacle_trailing_double_support": "double support before the trailing crossing swing and the step after it "
                                        "[s] (0: off)",
    "obstacle_resume_double_support": "double support before the step resuming the walk after the trailing "
                                      "crossing swing [s] (0: off)",
    "obstacle_aim_duration": "crossing duration the last step before an obstacle aims for [s] (0: the longest)",
    "obstacle_crossing_drift": "DCM gain of a swing over an obstacle per metre of its travel [-] (0: the LIPM's)",
    "obstacle_lateral_aim_duration": "crossing duration [s] whose lateral DCM offset the last step before an "
                                     "obstacle aims at (0: off)",
    "obstacle_crossing_cop": "bound of a crossing swing's centre of pressure from its stance foothold along the "
                             "heading [m] (0: the foothold)",
    "obstacle_passed_cop": "bound of the centre of pressure from the stance foothold of a step pinned beyond an "
                           "obstacle just crossed [m] (0: off)",
    "obstacle_crossing_offset": "DCM offset the lead crossing aims at beyond the nominal one [m] (0: the nominal)",
    "obstacle_trailing_duration_min": "duration lower bound of the trailing swing over an obstacle [s] (0: "
                                      "obstacle_step_duration_min's)",
    "obstacle_trailing_height_max": "obstacles up to this high get the trailing swing's own duration bound [m] (0: "
                                    "any height)",
    "obstacle_landing_room": "the lead crossing lands at least this beyond the obstacle's far bound [m] (0: on it)",
    "obstacle_far_margin_reduction": "an obstacle's side further along the heading grown by obstacle_margin minus this [m]",
    "obstacle_approach_distance": "even steps to the last foothold before an obstacle within this distance [m] "
                                  "(0: greedy)",
    "obstacle_width_min": "inner width bound of every step while obstacles are planned around [m] (0: the walk's)",
    "sole_half_width": "sole half width [m]",
    "swing_commit_time": "the swing's foothold committed in its last this long [s] (0: re-planned to touchdown)",
    "swing_commit_rate": "lateral speed of the committed swing foothold [m/s]",
    "fast_speed_start": "speed schedule: |v_x| up to which t_nom, t_min, double_support, l_max hold [m/s]",
    "fast_speed_full": "speed schedule: |v_x| from which the fast_* values hold [m/s] (0: off)",
    "fast_t_nom": "t_nom at fast_speed_full [s] (0: not scheduled)",
    "fast_t_min": "t_min at fast_speed_full [s] (0: not scheduled)",
    "fast_double_support": "double_support at fast_speed_full [s] (0: not scheduled)",
    "fast_l_max": "l_max at fast_speed_full [m] (0: not scheduled)",
}


def add_params_arguments(parser: argparse.ArgumentParser) -> None:
    """Add --preset, --params FILE and one --<field> option per SequencerParams field."""
    presets = sorted(p.stem for p in PRESET_DIR.glob("*.toml"))
    group = parser.add_argument_group("sequencer parameters (defaults: the chosen preset)")
    group.add_argument("--preset", choices=presets, default=None,
                       help="named parameter set (default table_i, or the --robot's walking preset)")
    group.add_argument("--params", metavar="FILE", default=None, help="TOML parameter file (overrides --preset)")
    for field in dataclasses.fields(SequencerParams):
        if field.name == "name":
            continue
        flags = [f"--{field.name.replace('_', '-')}"] + _ALIASES.get(field.name, [])
        group.add_argument(*flags, dest=f"param_{field.name}", type=FINITE, default=None, metavar="VALUE",
                           help=_HELP[field.name])


def params_from_args(args: argparse.Namespace) -> SequencerParams:
    """Build SequencerParams from --preset/--params and the per-field overrides."""
    robot = getattr(args, "robot", None)
    if args.params:
        base = SequencerParams.from_toml(args.params)
    elif args.preset is None and robot is not None:
        from wbmpc.walking.preset import load_walking_preset

        base = load_walking_preset(robot).planner  # the planner the robot walks with
    else:
        base = SequencerParams.preset(args.preset or "table_i")
    overrides = {
        field.name: getattr(args, f"param_{field.name}")
        for field in dataclasses.fields(SequencerParams)
        if field.name != "name" and getattr(args, f"param_{field.name}", None) is not None
    }
    return dataclasses.replace(base, **overrides) if overrides else base


def add_state_arguments(parser: argparse.ArgumentParser, elapsed_name: str = "--t") -> None:
    """Measured state: stance foot, its position, the measured DCM and the elapsed time (None: see state_from_args)."""
    group = parser.add_argument_group("measured state (defaults: the Table I example, or the --robot standing)")
    group.add_argument("--stance-foot", choices=("left", "right"), default=None)
    group.add_argument("--stance-position", nargs=2, type=FINITE, metavar=("X", "Y"), default=None,
                       help="support foot p0 [m] (world)")
    group.add_argument("--dcm", nargs=2, type=FINITE, metavar=("X", "Y"), default=None,
                       help="measured DCM zeta_hat [m] (world)")
    group.add_argument(elapsed_name, dest="elapsed", type=NON_NEGATIVE, default=None,
                       help="time elapsed since the stance began t [s]")
    group.add_argument("--robot", default=None, metavar="NAME",
                       help="start from this robot standing still (feet, CoM) with its sequencer preset")


def state_from_args(args: argparse.Namespace) -> tuple[str, tuple[float, float], tuple[float, float], float]:
    """(stance foot, stance position [m], measured DCM [m], elapsed time [s]): the options given, the
    rest from the --robot standing still (DCM = CoM at rest, t = 0) or from the Table I example."""
    if args.robot is not None:
        from robots.registry import load_robot

        robot = load_robot(args.robot)
        foot = args.stance_foot or "left"
        defaults = (foot, tuple(robot.foot_positions_reference()[foot][:2]), tuple(robot.com_position_reference[:2]), 0.0)
    else:
        defaults = (TABLE_I_STANCE_FOOT, TABLE_I_STANCE_POSITION, TABLE_I_DCM, TABLE_I_ELAPSED)
    given = (args.stance_foot, args.stance_position, args.dcm, args.elapsed)
    foot, position, dcm, elapsed = (d if g is None else g for g, d in zip(given, defaults))
    return foot, tuple(float(c) for c in position), tuple(float(c) for c in dcm), float(elapsed)


def plan_table(plan: FootstepPlan) -> str:
    """Human-readable table of a plan."""
    lines = [
        f"plan at t0={plan.t0:.3f} s: stance {plan.stance_foot} at ({plan.stance_position[0]:+.4f}, "
        f"{plan.stance_position[1]:+.4f}) m, DCM ({plan.dcm_measured[0]:+.4f}, {plan.dcm_measured[1]:+.4f}) m",
        f"{'#':>3} {'foot':>5} {'touchdown [s]':>13} {'T [s]':>7} {'p_T x [m]':>10} {'p_T y [m]':>10} "
        f"{'b_T x [m]':>10} {'b_T y [m]':>10}  active",
    ]
    for k, s in enumerate(plan.steps):
        lines.append(
            f"{k + 1:>3} {s.foot:>5} {s.touchdown_time:>13.4f} {s.duration:>7.4f} {s.position[0]:>+10.4f} "
            f"{s.position[1]:>+10.4f} {s.dcm_offset[0]:>+10.5f} {s.dcm_offset[1]:>+10.5f}  {','.join(s.active) or '-'}"
        )
    if len(plan.steps) >= 3:
        v = plan.mean_velocity()
        lines.append(f"mean foothold velocity: ({v[0]:+.4f}, {v[1]:+.4f}) m/s")
    return "\n".join(lines)


def alip_params_from_args(args: argparse.Namespace):
    """``--planner alip``'s AlipParams: ``--params FILE`` (an ALIP TOML) or the preset of ``--robot`` (default g1).

    Raises:
        ParameterError: a DCM sequencer option (``--alpha1``, ``--preset``, ...; not --vx/--vy) was given.
    """
    from sequencer.alip.params import AlipParams
    from wbmpc.errors import ParameterError

    given = sorted(f"--{f.name.replace('_', '-')}" for f in dataclasses.fields(SequencerParams)
                   if f.name not in ("name", "v_x", "v_y") and getattr(args, f"param_{f.name}", None) is not None)
    if given or args.preset is not None:
        raise ParameterError(f"{given or ['--preset']} are DCM sequencer options; with --planner alip use --params FILE "
                             "(an ALIP TOML) or --robot NAME")
    return AlipParams.from_toml(args.params) if args.params else AlipParams.preset(args.robot or "g1")


def run_alip_plan(args: argparse.Namespace) -> int:
    """``--planner alip``: the ALIP NMPC from the robot standing (left stance, CoM at rest) or the given state."""
    from robots.registry import load_robot
    from sequencer.alip.planner import AlipFootstepPlanner
    from sequencer.planner import ReducedState, StanceState, VelocityCommand

    params = alip_params_from_args(args)
    robot_name = args.robot or "g1"
    robot = load_robot(robot_name)
    foot = args.stance_foot or "left"
    position = args.stance_position or tuple(robot.foot_positions_reference()[foot][:2])
    com = np.array([*robot.com_position_reference[:2], params.com_height])
    if args.dcm is not None:
        com[:2] = args.dcm
    elapsed = 0.0 if args.elapsed is None else float(args.elapsed)
    command = VelocityCommand(args.param_v_x or 0.0, args.param_v_y or 0.0, args.yaw_rate)
    planner = AlipFootstepPlanner(params, solver=args.alip_solver)
    planner.check_command(command)
    stance = StanceState(foot, position, 0.0, 0.0)
    plan = planner.plan(elapsed, stance, ReducedState(com, np.zeros(3), com[:2]), command)
    solution = planner.last_solution
    if args.plot:
        from sequencer.alip.plots import plot_alip_plan

        plot_alip_plan(plan, solution, com[:2], args.plot, planner.model)
    if args.json:
        print_json({"planner": "alip", "params": params.to_dict(), "solver": args.alip_solver,
                    "command": command.as_tuple(),
                    "solution": {"periods": solution.periods, "torques": solution.torques, "steps": solution.steps,
                                 "states": solution.states, "cost": solution.cost, "iterations": solution.iterations,
                                 "active": solution.active},
                    "plan": plan})
    else:
        print(plan_table(plan))
        print("NMPC: T = " + ", ".join(f"{v:.3f}" for v in solution.periods) + " s; tau (y, x) = "
              + ", ".join(f"({a:+.2f}, {b:+.2f})" for a, b in solution.torques) + " N·m; active: "
              + (", ".join(solution.active) or "-"))
        if args.plot:
            print(f"wrote {args.plot}")
    return 0


def run_plan(args: argparse.Namespace) -> int:
    if args.planner == "alip":
        return run_alip_plan(args)
    params = params_from_args(args)
    sequencer = FootstepSequencer(params, backend=args.backend)
    foot, position, dcm, elapsed = state_from_args(args)
    plan = sequencer.plan(t=elapsed, stance_foot=foot, stance_position=position, dcm_measured=dcm, t_stance_start=0.0,
                          yaw_rate=args.yaw_rate)
    if args.plot:
        from sequencer.plots import plot_plan

        plot_plan(plan, params, args.plot)
    if args.json:
        result = {"params": params.to_dict(), "backend": args.backend, "plan": plan}
        if len(plan.steps) >= 3:
            result["mean_velocity"] = plan.mean_velocity()
        print_json(result)
    else:
        print(plan_table(plan))
        if args.plot:
            print(f"wrote {args.plot}")
    return 0


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "plan", help="plan footsteps with the DCM sequencer (Algorithm 1) and draw Fig. 3",
        description="Run Algorithm 1 from a measured state (default: the Table I example, t_stance_start = 0).",
    )
    add_params_arguments(parser)
    add_state_arguments(parser)
    parser.add_argument("--backend", choices=("exact", "osqp", "proxqp"), default="exact", help="QP backend")
    parser.add_argument("--planner", choices=("dcm", "alip"), default="dcm",
                        help="dcm: the DCM step QP (Algorithm 1, default); alip: the ALIP S2S NMPC (sequencer.alip, "
                             "preset sequencer/presets/alip/ROBOT.toml, --robot default g1)")
    parser.add_argument("--alip-solver", choices=("sqp", "ipopt"), default="sqp", help="ALIP NMPC solver")
    parser.add_argument("--yaw-rate", type=FINITE, default=0.0, help="commanded turning rate [rad/s]")
    add_output_arguments(parser, plot=True)
    parser.set_defaults(func=run_plan)
