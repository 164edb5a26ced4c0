"""``wbmpc ocp``: solve one whole-body walking OCP from a standing start and report the plan.

    wbmpc ocp --speed 0.33 --nodes 100 --iterations 100 --json --plot runs/ocp.png

The footsteps come from the DCM sequencer (Algorithm 1, ``SequencerParams.bolt_walking()``)
sampled on the OCP grid; the terminal CoM reference is the plan's LIPM prediction at the end of
the horizon (eq. 24). Prints the FDDP log, the cost of every named term, the swing apex
heights, the CoM displacement and the torque peak; ``--plot`` draws foot heights, CoM and
torques over the horizon.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from wbmpc.cli import add_output_arguments, print_json


def register(subparsers) -> None:
    parser = subparsers.add_parser("ocp", help="solve one whole-body walking OCP (FDDP) and report the plan")
    parser.add_argument("--robot", default="bolt", help="robot name (default bolt)")
    parser.add_argument("--speed", type=float, default=None, help="forward velocity command [m/s] (default: the preset's)")
    parser.add_argument("--nodes", type=int, default=100, help="horizon length N (running nodes)")
    parser.add_argument("--dt", type=float, default=0.01, help="node spacing [s]")
    parser.add_argument("--iterations", type=int, default=100, help="FDDP iteration cap")
    parser.add_argument("--foothold-weight", type=float, default=0.0,
                        help="planned-foothold tracking weight (0: footholds emerge, the paper's choice)")
    add_output_arguments(parser, plot=True)
    parser.set_defaults(func=_run)


def solve_walking_ocp(robot_name: str = "bolt", speed: float | None = None, n_nodes: int = 100, dt: float = 0.01,
                      iterations: int = 100, foothold_weight: float = 0.0) -> dict:
    """Plan footsteps from a standing start, solve the walking OCP, summarise the solution.

    Returns a dict with the solver log, term costs, swing apex heights [m] above the ground,
    CoM displacement [m], peak torque [N·m], and the trajectories (times [s], xs, us, foot
    heights (N + 1, 2) [m], CoM (N + 1, 3) [m]).
    """
    import pinocchio as pin

    from robots import load_robot
    from sequencer import FootstepSequencer, SequencerParams, contact_schedule
    from wbmpc.errors import ParameterError
    from wbmpc.solvers import SolverFDDP
    from wbmpc.walking import WalkingOCP, WalkingOCPConfig, quasi_static_controls

    if int(iterations) != iterations or iterations < 1:
        raise ParameterError(f"iterations={iterations} must be an integer >= 1")
    robot = load_robot(robot_name)
    model = robot.pinocchio_model
    data = model.createData()
    x0 = np.concatenate([robot.q_reference, np.zeros(model.nv)])
    q0 = x0[: model.nq]
    pin.framesForwardKinematics(model, data, q0)
    com0 = pin.centerOfMass(model, data, q0).copy()
    feet = {foot: data.oMf[model.getFrameId(name)].translation.copy() for foot, name in robot.foot_frames.items()}
    params = SequencerParams.bolt_walking()
    if speed is not None:
        params = dataclasses.replace(params, v_x=float(speed))
    plan = FootstepSequencer(params).plan(t=0.0, stance_foot="left", stance_position=feet["left"][:2],
                                          dcm_measured=com0[:2], t_stance_start=0.0)
    schedule = contact_schedule(plan, 0.0, dt, n_nodes)
    com_terminal = np.append(plan.lipm_com_at(n_nodes * dt, com0[:2]), com0[2])
    ocp = WalkingOCP(robot, WalkingOCPConfig(foothold_weight=foothold_weight), n_nodes=n_nodes, dt=dt)
    ocp.update(x0, schedule, com_terminal)
    solver = SolverFDDP(ocp.problem)
    u0 = quasi_static_controls(ocp, x0)
    converged = solver.solve([x0] * (n_nodes + 1), [u0] * n_nodes, maxiter=iterations)
    ocp.problem.calc(solver.xs, solver.us)
    heights = np.zeros((n_nodes + 1, len(feet)))
    coms = np.zeros((n_nodes + 1, 3))
    for k, x in enumerate(solver.xs):
        q = x[: model.nq]
        pin.framesForwardKinematics(model, data, q)
        coms[k] = pin.centerOfMass(model, data, q)
        for j, name in enumerate(robot.foot_frames.values()):
            heights[k, j] = data.oMf[model.getFrameId(name)].translation[2] - robot.contact_frame_height
    in_contact = np.asarray(schedule.in_contact)
    apex = {foot: float(np.max(np.where(in_contact[:, j], -np.inf, heights[:, j]), initial=0.0))
            for j, foot in enumerate(feet)}
    return {
        "robot": robot_name, "n_nodes": n_nodes, "dt_s": dt, "converged": bool(converged),
        "iterations": len(solver.log), "cost": float(solver.cost),
        "log": [dataclasses.asdict(entry) for entry in solver.log],
        "term_costs": ocp.problem.term_costs(),
        "swing_apex_height_m": apex, "swing_apex_reference_m": ocp.config.swing_apex_height,
        "com_displacement_m": (coms[-1] - coms[0]).tolist(), "com_terminal_reference_m": com_terminal.tolist(),
        "peak_torque_Nm": float(np.max(np.abs(solver.us))), "torque_limit_Nm": float(np.max(robot.torque_limit)),
        "times_s": (dt * np.arange(n_nodes + 1)).tolist(), "foot_heights_m": heights, "com_m": coms,
        "feet": list(feet), "xs": solver.xs, "us": solver.us,
    }


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
