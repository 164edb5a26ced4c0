"""``wbmpc ocp``: solve one whole-body walking OCP from a standing start and report the plan.

    wbmpc ocp --speed 0.33 --nodes 100 --iterations 100 --json --plot runs/ocp.png

The footsteps come from the robot's walking preset's DCM planner (Algorithm 1)
sampled on the OCP grid; the terminal CoM reference is the plan's LIPM prediction at the end of
the horizon (eq. 24). Prints the FDDP log, the cost of every named term, the swing apex
heights, the CoM displacement and the torque peak; ``--plot`` draws foot heights, CoM and
torques over the horizon.
"""

from __future__ import annotations

import argparse

import numpy as np

from wbmpc.cli.arguments import COUNT, FINITE, NON_NEGATIVE, POSITIVE
from wbmpc.cli.output import add_output_arguments, print_json
from wbmpc.cli.walk import add_robot_argument
from wbmpc.walking.standing_start import solve_walking_ocp


def register(subparsers) -> None:
    parser = subparsers.add_parser("ocp", help="solve one whole-body walking OCP (FDDP) and report the plan")
    add_robot_argument(parser)
    parser.add_argument("--speed", type=FINITE, default=None, help="forward velocity command [m/s] (default: the preset's)")
    parser.add_argument("--nodes", type=COUNT, default=100, help="horizon length N (running nodes)")
    parser.add_argument("--dt", type=POSITIVE, default=0.01, help="node spacing [s]")
    parser.add_argument("--iterations", type=COUNT, default=100, help="FDDP iteration cap")
    parser.add_argument("--foothold-weight", type=NON_NEGATIVE, default=0.0,
                        help="planned-foothold tracking weight (0: footholds emerge, the paper's choice)")
    add_output_arguments(parser, plot=True)
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    result = solve_walking_ocp(args.robot, args.speed, args.nodes, args.dt, args.iterations, args.foothold_weight)
    if args.plot:
        _plot(result, args.plot)
    if args.json:
        print_json({k: v for k, v in result.items() if k not in ("xs", "us")})
        return 0
    print(f"{result['robot']} walking OCP, N={result['n_nodes']}, dt={result['dt_s'] * 1e3:.0f} ms: "
          f"{'converged' if result['converged'] else 'not converged'} in {result['iterations']} iterations, "
          f"cost {result['cost']:.6g}")
    print("  iter        cost        stop   step        reg   infeas")
    for e in result["log"]:
        print(f"  {e['iteration']:4d} {e['cost']:11.5g} {e['stop']:11.3e} {e['step_length']:6.3f} "
              f"{e['regularization']:10.1e} {e['infeasibility']:8.1e}")
    print("  cost terms: " + ", ".join(f"{k} {v:.4g}" for k, v in result["term_costs"].items()))
    print("  swing apex [m]: " + ", ".join(f"{k} {v:.3f}" for k, v in result["swing_apex_height_m"].items())
          + f" (reference H = {result['swing_apex_reference_m']:.3f})")
    d = result["com_displacement_m"]
    print(f"  CoM displacement [m]: ({d[0]:.3f}, {d[1]:.3f}, {d[2]:.3f}); peak torque {result['peak_torque_Nm']:.2f} "
          f"N·m (limit {result['torque_limit_Nm']:.2f})")
    return 0


def _plot(result: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.asarray(result["times_s"])
    fig, axes = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    for j, foot in enumerate(result["feet"]):
        axes[0].plot(t, result["foot_heights_m"][:, j], label=foot)
    axes[0].axhline(result["swing_apex_reference_m"], color="k", ls=":", lw=0.8, label="apex H")
    axes[0].set_ylabel("foot height [m]")
    axes[0].legend()
    axes[1].plot(t, result["com_m"][:, 0], label="CoM x")
    axes[1].plot(t, result["com_m"][:, 1], label="CoM y")
    axes[1].set_ylabel("CoM [m]")
    axes[1].legend()
    axes[2].plot(t[:-1], result["us"])
    axes[2].set_ylabel("torque [N·m]")
    axes[2].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
